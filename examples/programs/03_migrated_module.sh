#!/bin/sh
# A RAPID module taught on another cell: its confdata do not fit this robot, and it runs with
# ConfJ\Off and ConfL\Off, so the controller takes the configuration nearest the arm's. deflex does
# the same from where those instructions stand (each target the solution nearest the previous
# target's) and says which targets it solved so; without them it refuses the first target.
# Usage: 03_migrated_module.sh [DEFLEX] [OUTDIR] (example-out/ and the script's name when omitted)
set -eu
DEFLEX=${1:-deflex}
OUT=${2:-example-out/03_migrated_module}
mkdir -p "$OUT"
HERE=$(dirname "$0")
"$DEFLEX" offline --program-in "$HERE/migrated_pocket.mod" --force "tool:fz_N=-300" \
  --program-out "$OUT/migrated_pocket.mod"
