#!/bin/sh
# An existing ABB RAPID module (RobotStudio style: tooldata, wobjdata, robtargets, an array, Offs,
# RelTool, MoveC, MoveAbsJ, a target computed at run time) compensated for a deburring spindle's
# thrust, constant in the tool frame, on the built-in IRB 6700. Only the targets change; a target
# used under different loads gets a copy per use; the run-time target is listed and left alone.
# Usage: 01_rapid_module.sh [DEFLEX] [OUTDIR] (example-out/ and the script's name when omitted)
set -eu
DEFLEX=${1:-deflex}
OUT=${2:-example-out/01_rapid_module}
mkdir -p "$OUT"
HERE=$(dirname "$0")
"$DEFLEX" offline --program-in "$HERE/deburr_housing.mod" --force "tool:fz_N=-150,fx_N=40" \
  --program-out "$OUT/deburr_housing.mod"
