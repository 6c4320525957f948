#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Make sure what the regression needs is here: python3 with venv, GHDL, yosys, iverilog, tcl, then the .venv with pinned
# packages; with "synth" also nextpnr-ice40 (for `make synth`).
# Installs Debian packages only when they are missing and we are root; otherwise stops with what to install.
# Usage: scripts/bootstrap.sh [VENV] [synth]
set -euo pipefail
venv=${1:-.venv}
what=${2:-test}

need_apt=()
python3 -c 'import ensurepip, venv' 2>/dev/null || need_apt+=(python3-venv)
command -v ghdl >/dev/null 2>&1 || need_apt+=(ghdl)
command -v yosys >/dev/null 2>&1 || need_apt+=(yosys)
command -v make >/dev/null 2>&1 || need_apt+=(make)
command -v gcc >/dev/null 2>&1 || need_apt+=(gcc)
command -v tclsh >/dev/null 2>&1 || need_apt+=(tcl)  # sw/tests/test_vivado_tcl.py runs the Vivado script's IP-XACT reader
command -v iverilog >/dev/null 2>&1 || need_apt+=(iverilog)  # the second simulator: tb/test_netlist.py runs ghdl synth's netlist
# GHDL's LLVM back end simulates about twice as fast as mcode: worth its install time, but optional.
want_llvm=0
if [ ! -x /usr/bin/ghdl-llvm ] && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
  want_llvm=1
fi
if [ "$what" = synth ]; then
  command -v nextpnr-ice40 >/dev/null 2>&1 || need_apt+=(nextpnr-ice40 fpga-icestorm)
fi

if [ ${#need_apt[@]} -gt 0 ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "bootstrap: installing Debian packages: ${need_apt[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -q >/dev/null
    apt-get install -y -q "${need_apt[@]}" >/dev/null
  else
    echo "bootstrap: missing ${need_apt[*]}." >&2
    echo "  Install them first, e.g.: sudo apt-get install ${need_apt[*]}" >&2
    echo "  (GHDL 2.0 or newer with its VPI library, and yosys: Debian 12's packages are what this project is tested with.)" >&2
    exit 1
  fi
fi

# `make test` asked for the size check's yosys run before GHDL or yosys was here: start it now, beside the venv.
if [ -f build/synth_size/prefetch.wanted ]; then
  scripts/prefetch.sh
fi

if [ "$want_llvm" = 1 ]; then
  echo "bootstrap: installing Debian's ghdl-llvm (faster simulation; optional)"
  export DEBIAN_FRONTEND=noninteractive
  { apt-get install -y -q ghdl-llvm >/dev/null 2>&1 || { apt-get update -q >/dev/null 2>&1 && apt-get install -y -q ghdl-llvm >/dev/null 2>&1; }; } ||
    echo "bootstrap: ghdl-llvm not available; simulating with GHDL's default back end"
fi

if [ ! -f "$venv/.stamp" ] || [ pyproject.toml -nt "$venv/.stamp" ]; then
  echo "bootstrap: creating $venv and installing the pinned Python packages"
  python3 -m venv "$venv"
  # uv (from PyPI, pinned) installs the pinned packages and compiles their byte code on every core: about 15 s where
  # pip takes 35 to 50. Should uv fail, pip does it (its byte code compiled afterwards on every core).
  if ! { "$venv/bin/pip" install -q --disable-pip-version-check uv==0.13.9 &&
    "$venv/bin/uv" pip install -q --python "$venv/bin/python" --compile-bytecode -e '.[dev]'; }; then
    echo "bootstrap: uv failed; installing with pip"
    "$venv/bin/pip" install -q --disable-pip-version-check --no-compile -e '.[dev]'
    "$venv/bin/python" -m compileall -q -j 0 "$venv/lib" >/dev/null
  fi
  touch "$venv/.stamp"
fi
