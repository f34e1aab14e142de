#!/bin/sh
# The 2.5D pocket and contour (pocket_contour.nc) cut from a 100 x 80 mm aluminium block by the
# IRB6700 with a spindle on a bracket: the milling force from the block as the program cuts it away,
# the spindle angle chosen for stiffness, the compensated G-code, the CSV and the chart.
# Usage: compensate_pocket.sh [DEFLEX] [OUTDIR] (example-out/ and the script's name when omitted)
set -eu
DEFLEX=${1:-deflex}
OUT=${2:-example-out/compensate_pocket}
mkdir -p "$OUT"
HERE=$(dirname "$0")
"$DEFLEX" offline --robot "$HERE/irb6700_spindle.yaml" --toolpath "$HERE/pocket_contour.nc" \
  --workpiece "x_mm=2000,y_mm=0,z_mm=800" --cutter "diameter_mm=10,flutes=3,helix_deg=30" \
  --force "milling:file=$HERE/../../data/machining/al7075-t6.yaml" \
  --stock "box:min_mm=-50;-40;-20,max_mm=50;40;0,cell_mm=0.25" --toolpath-options step_mm=1 \
  -o "$OUT/pocket.csv" --program-out "$OUT/pocket_compensated.nc" --plot "$OUT/pocket.svg"
