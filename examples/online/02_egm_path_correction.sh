#!/bin/sh
# deflex online over ABB EGM path correction, against a stand-in controller that runs its own program
# and takes deflex's absolute offsets (examples/online/egm_path_correction_standin.py).
#   sh examples/online/02_egm_path_correction.sh DEFLEX OUTDIR
set -eu
deflex=$1
out=$2
here=$(dirname "$0")
mkdir -p "$out"
"$deflex" offline --circle "centre_mm=1800;0;900,radius_mm=129.9,points=81" \
    --force "ldbb:phi_deg=30,force_N=400,mode=push" --speed-mm-s 30 \
    --nominal-trajectory "$out/program.csv" > "$out/offline.txt"
port=$(( 20000 + ($$ + 7) % 20000 ))
"$deflex" online --link egm-path --period-ms 48 --egm-port $port \
    --force-source "csv:$here/force_replay.csv" --loop --log "$out/online.csv" --duration-s 6 \
    --status-interval-s 1 2> "$out/online.txt" &
pid=$!
sleep 0.5
python3 "$here/egm_path_correction_standin.py" --port $port --program "$out/program.csv" --seconds 3
kill -INT $pid
wait $pid
tail -n 2 "$out/online.txt"
