#!/bin/sh
# SPDX-License-Identifier: MIT
# Instructions (valgrind's callgrind) that GHDL and the bench's Python spend on `make bench`'s move on one top, per
# VHDL process: the figure that does not move with the machine's load, for comparing two versions of the RTL
# (docs/conventions.md, "RTL that simulates fast"). Counts only the simulation cycles (not the build, the start of
# Python, or the model). About two minutes for a bus top.
#
#     scripts/simcount.sh [TOP [RAMP [LINES]]]    TOP: stepramp_plb (default) ...; RAMP: 0 AVR446, 1 exact
#
# STEPRAMP_HDL_DIR=<a copy of hdl/> measures that copy instead (its own build); SIMCOUNT_OUT names the output folder
# (default build/simcount/TOP-RAMP).
set -eu
top=${1:-stepramp_plb}
ramp=${2:-0}
lines=${3:-25}
cd "$(dirname "$0")/.."
out=${SIMCOUNT_OUT:-build/simcount/$top-$ramp}
rm -rf "$out" && mkdir -p "$out"
exact=""
[ "$ramp" = 1 ] && exact="$top"
# Build outside valgrind (shared with the regression's build).
GHDL_BACKEND=llvm .venv/bin/python -c "from stepramp.sim.runner import build_once; build_once('$top')" >"$out/build.log" 2>&1
if [ "$ramp" = 1 ]; then
  set -- --tops "$top" --exact "$top"
else
  set -- --tops "$top" --exact
fi
GHDL_BACKEND=llvm valgrind --tool=callgrind --trace-children=yes --collect-atstart=no \
  --toggle-collect='grt__processes__simulation_cycle' --callgrind-out-file="$PWD/$out/cg.%p" \
  .venv/bin/python -m stepramp.tools.simbench "$@" --repeat 1 --out "$out/run" >"$out/valgrind.log" 2>&1
# The simulators' profiles are the largest files; with RAMP 1 simbench runs the AVR446 move first, then the exact
# one (the later process).
if [ "$ramp" = 1 ]; then
  profile=$(ls -S "$out"/cg.* | head -2 | sort -t. -k2 -n | tail -1)
else
  profile=$(ls -S "$out"/cg.* | head -1)
fi
echo "$top, ramp $ramp: $(basename "$profile")"
callgrind_annotate --inclusive=yes "$profile" 2>/dev/null | grep -E "PROGRAM TOTALS|PROC|toggle_cb|call_valuechange|_PyEval_EvalFrameDefault " |
  grep -v "^ *[0-9,]* *([0-9. %]*) *hdl/" | sed 's#/[^ ]*/hdl/##; s#top__##; s#__ARCH__rtl##; s# \[/.*##' | head -"$lines"
