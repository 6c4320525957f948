#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Start the size check's yosys run (tb/test_synth_size.py: about 45 s of one core) in the background, into the
# content-keyed cache build/synth_size, where the test finds it (or waits for it on the cache's lock).
# `make prefetch` runs this before the bootstrap, which leaves a core idle while it installs; when GHDL or yosys is
# not there yet, it leaves build/synth_size/prefetch.wanted, and the bootstrap runs this again once its Debian
# packages are in, before it creates the venv. System python3: the synthesis script needs no package.
set -u
mkdir -p build/synth_size
if command -v ghdl >/dev/null 2>&1 && command -v yosys >/dev/null 2>&1; then
  rm -f build/synth_size/prefetch.wanted
  (PYTHONPATH=sw python3 -m stepramp.tools.synth --size-cache build/synth_size stepramp_plb \
    >build/synth_size/prefetch.log 2>&1 &)
else
  touch build/synth_size/prefetch.wanted
fi
