#!/bin/sh
# An existing KUKA KRL program (inline forms with FDAT, E6POS points with Status/Turn in the .dat,
# LIN, CIRC, an inline E6AXIS, a second pass with another tool) compensated for a spindle's thrust
# against its working direction (KUKA tools work along x), on the KR 210 R3100-2 from its
# ROS-Industrial URDF. TOOL_DATA and BASE_DATA live in the controller's $config.dat, so they are
# given on the command line in KRL syntax. Writes deburr_bracket.src and .dat.
# Usage: 02_krl_program.sh [DEFLEX] [OUTDIR] (example-out/ and the script's name when omitted)
set -eu
DEFLEX=${1:-deflex}
OUT=${2:-example-out/02_krl_program}
mkdir -p "$OUT"
HERE=$(dirname "$0")
"$DEFLEX" offline --robot "$HERE/../robots/kuka_kr210_r3100_2_flange.yaml" \
  --program-in "$HERE/deburr_bracket.src" --force "tool:fx_N=-150" \
  --tooldata "TOOL_DATA[1]={X 250,Y 0,Z 0,A 0,B 0,C 0}" \
  --tooldata "TOOL_DATA[2]={X 320,Y 0,Z 40,A 0,B -10,C 0}" \
  --wobjdata "BASE_DATA[1]={X 1800,Y -300,Z 500,A 0,B 0,C 0}" \
  --program-out "$OUT/deburr_bracket.src" --json
