#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Render the demo's GTKWave layout to docs/img/waves.png (for the README) on a virtual display.
# Needs: gtkwave, xvfb, x11-apps (xwd), imagemagick (convert); run `make demo` first.
set -euo pipefail
GTKW=${1:-build/demo/stepramp_demo.gtkw}
OUT=${2:-docs/img/waves.png}
DISPLAY_NUM=:${DISPLAY_NUM:-91}
Xvfb "$DISPLAY_NUM" -screen 0 1600x1000x24 >/dev/null 2>&1 &
XVFB=$!
GTK=""
trap 'kill $GTK $XVFB 2>/dev/null || true' EXIT
sleep 2
DISPLAY=$DISPLAY_NUM gtkwave "$GTKW" >/dev/null 2>&1 &
GTK=$!
sleep "${WAIT:-8}"
DISPLAY=$DISPLAY_NUM xwd -root -silent | convert xwd:- -crop 1512x955+0+0 +repage "$OUT"
echo "$OUT"
