#!/bin/sh
# The 5-axis swarf pass (swarf_wall.apt): the tool leans with the wall, which the stock models cannot
# follow, so the engagement is given (ae 0.5 mm, ap 20 mm, climb) for every feed move. Writes an ABB
# RAPID module (MoveL in the workpiece's work object at the program's feed), the CSV and the chart.
# Usage: compensate_swarf.sh [DEFLEX] [OUTDIR] (example-out/ and the script's name when omitted)
set -eu
DEFLEX=${1:-deflex}
OUT=${2:-example-out/compensate_swarf}
mkdir -p "$OUT"
HERE=$(dirname "$0")
"$DEFLEX" offline --robot "$HERE/irb6700_spindle.yaml" --toolpath "$HERE/swarf_wall.apt" \
  --workpiece "x_mm=2000,y_mm=0,z_mm=800" --cutter "diameter_mm=10,flutes=3,helix_deg=30" \
  --force "milling:file=$HERE/../../data/machining/al7075-t6.yaml,ae_mm=0.5,ap_mm=20" \
  --toolpath-options step_mm=1 -o "$OUT/swarf.csv" --program-out "$OUT/swarf.mod" --plot "$OUT/swarf.svg"
