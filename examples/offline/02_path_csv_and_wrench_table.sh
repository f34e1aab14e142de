#!/bin/sh
# A path given as TCP poses in CSV (orientation per point) with a per-point wrench table, exported
# as MoveL over robtargets with confdata and 1 mm fly-by zones at 30 mm/s.
# Usage: 02_path_csv_and_wrench_table.sh [DEFLEX] [OUTDIR]
set -eu
DEFLEX=${1:-deflex}
OUT=${2:-.}
HERE=$(dirname "$0")
"$DEFLEX" offline --path "$HERE/square_path.csv" --force "table:$HERE/square_wrench.csv" \
  --motion movel --zone z1 --speed-mm-s 30 --module SquareComp \
  -o "$OUT/square_compensated.csv" --rapid "$OUT/square_compensated.mod"
