#!/bin/sh
# A path given as TCP poses in CSV (orientation per point) with a per-point wrench table, exported
# as MoveL over robtargets with confdata and 1 mm fly-by zones at 30 mm/s.
# Usage: 02_path_csv_and_wrench_table.sh [DEFLEX] [OUTDIR] (example-out/ and the script's name when omitted)
set -eu
DEFLEX=${1:-deflex}
OUT=${2:-example-out/02_path_csv_and_wrench_table}
mkdir -p "$OUT"
HERE=$(dirname "$0")
"$DEFLEX" offline --path "$HERE/square_path.csv" --force "table:$HERE/square_wrench.csv" \
  --motion movel --zone z1 --speed-mm-s 30 --module SquareComp \
  -o "$OUT/square_compensated.csv" --rapid "$OUT/square_compensated.mod"
