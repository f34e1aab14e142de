#!/bin/sh
# deflex online over ABB EGM position guidance, against a stand-in controller that behaves like the
# real one (examples/online/egm_position_guidance_standin.py): deflex offline writes the nominal
# program, deflex online streams it minus the bounded correction of a CSV force replay.
#   sh examples/online/01_egm_position_guidance.sh DEFLEX OUTDIR
set -eu
deflex=$1
out=$2
here=$(dirname "$0")
mkdir -p "$out"
"$deflex" offline --circle "centre_mm=1800;0;900,radius_mm=129.9,points=81" \
    --force "ldbb:phi_deg=30,force_N=400,mode=push" --speed-mm-s 30 --hold-start-s 0.5 \
    --nominal-trajectory "$out/nominal.csv" > "$out/offline.txt"
port=$(( 20000 + $$ % 20000 ))
"$deflex" online --link egm-joint --program "$out/nominal.csv" --egm-port $port \
    --force-source "csv:$here/force_replay.csv" --loop --log "$out/online.csv" --log-report --duration-s 6 \
    --status-interval-s 1 2> "$out/online.txt" &
pid=$!
sleep 0.5
python3 "$here/egm_position_guidance_standin.py" --port $port --program "$out/nominal.csv" --seconds 3
kill -INT $pid
wait $pid
tail -n 2 "$out/online.txt"
