#!/bin/sh
# A real force sensor's protocol end to end, without the hardware: the Python stand-in of an ATI Net F/T
# (RDT on UDP, its calibration page over HTTP, counts in lbf) and the Python stand-in of an ABB
# controller in EGM position guidance. deflex records a static pose off the sensor for the payload
# identification, then compensates with the sensor's force (counts to N by its own calibration page).
#   sh examples/online/05_rdt_sensor.sh DEFLEX OUTDIR
set -eu
DEFLEX=$1
OUT=$2
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
rm -f "$OUT/poses.csv"
# The sensor: 1 kHz, counts of 1/1000 lbf, a steady 90 lbf (400 N) push with 0.05 lbf of noise.
python3 "$HERE/rdt_sensor_standin.py" --port 0 --http-port 0 --rate 1000 --force-unit lbf --counts-per-force 1000 \
    --wrench=20,-10,-90,0,0,0 --noise 0.05 --seconds 20 2> "$OUT/sensor.txt" &
SENSOR=$!
trap 'kill $SENSOR 2>/dev/null || true' EXIT
for i in $(seq 1 100); do grep -q "HTTP on" "$OUT/sensor.txt" && break; sleep 0.05; done
RDT_PORT=$(sed -n 's/.*RDT on 127\.0\.0\.1:\([0-9]*\);.*/\1/p' "$OUT/sensor.txt")
HTTP_PORT=$(sed -n 's/.*HTTP on 127\.0\.0\.1:\([0-9]*\);.*/\1/p' "$OUT/sensor.txt")
SENSOR_ARGS="--force-source rdt:127.0.0.1:$RDT_PORT --rdt-calibration http://127.0.0.1:$HTTP_PORT/netftapi2.xml"

# 1. One static pose for the payload identification (repeat at 6 or more poses on a real cell).
"$DEFLEX" identify-payload $SENSOR_ARGS --joints-deg 0,20,10,0,60,0 --record "$OUT/poses.csv" --window-s 0.5

# 2. The program, and deflex online on EGM with the sensor's force (a real cell would add --tare with the
#    identified payload, the arm still at the program's start).
"$DEFLEX" offline --circle "centre_mm=1800;0;900,radius_mm=129.9,points=81" \
    --force "ldbb:phi_deg=30,force_N=400,mode=push" --speed-mm-s 30 --hold-start-s 0.5 \
    --nominal-trajectory "$OUT/nominal.csv" > "$OUT/offline.txt"
PORT=$(python3 -c 'import socket; s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"$DEFLEX" online --link egm-joint --program "$OUT/nominal.csv" --egm-port "$PORT" $SENSOR_ARGS \
    --log "$OUT/online.csv" --duration-s 5 --json > "$OUT/summary.json" 2> "$OUT/online.txt" &
ONLINE=$!
sleep 1
python3 "$HERE/egm_position_guidance_standin.py" --port "$PORT" --program "$OUT/nominal.csv" --seconds 3
wait "$ONLINE"
grep -E "RDT sensor at|session ended" "$OUT/online.txt"
python3 - "$OUT/summary.json" "$OUT/online.csv" <<'PY'
import csv, json, math, sys
s = json.load(open(sys.argv[1]))
assert s["exit_code"] == 0 and s["counters"]["replies"] > 300, s
rows = list(csv.DictReader(line for line in open(sys.argv[2]) if not line.startswith("#")))
f = [math.dist((0, 0, 0), (float(r["meas_fx_N"]), float(r["meas_fy_N"]), float(r["meas_fz_N"]))) for r in rows[len(rows) // 2:]]
expected = math.dist((0, 0, 0), (20, -10, -90)) * 4.4482216152605
print(f"measured |F| {min(f):.1f}..{max(f):.1f} N (the sensor streams {expected:.1f} N in lbf counts)")
assert all(abs(v - expected) < 2.0 for v in f)
PY
