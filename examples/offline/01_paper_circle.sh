#!/bin/sh
# The paper's offline case: a 100 mm circle in 81 configurations (4.5 deg apart) at the built-in
# IRB6700's reference position, pushed by the LDBB inclined 45 deg (pivot 100 mm below the circle
# centre, bar 141.4 mm) with the paper's three loads. Writes one CSV and one RAPID module per load.
# Usage: 01_paper_circle.sh [DEFLEX] [OUTDIR] (example-out/ and the script's name when omitted)
set -eu
DEFLEX=${1:-deflex}
OUT=${2:-example-out/01_paper_circle}
mkdir -p "$OUT"
"$DEFLEX" offline --circle "centre_mm=1500;0;1000,radius_mm=100,points=81,direction=ccw" \
  --force "ldbb:phi_deg=45,force_N=125;375;625,mode=push" \
  --speed-mm-s 10 -o "$OUT/paper_circle.csv" --rapid "$OUT/paper_circle.mod"
