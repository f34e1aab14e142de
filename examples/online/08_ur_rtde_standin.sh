#!/bin/sh
# deflex online --link ur-rtde against the Python stand-in of a Universal Robots controller serving RTDE
# and playing deflex's servo program (CB3 here: one output package every 8 ms; the script hands the
# newest registers to servoj, whose lookahead delays the motion; its watchdog stops the program when
# deflex's counter stops changing; a target beyond the joint speed limit is a protective stop), over
# loopback TCP. Passes when the session ended on its time limit, servoj took targets and the stand-in's
# program was never stopped by a fault.
#   sh examples/online/08_ur_rtde_standin.sh build/bin/deflex /tmp/ur-example
set -eu
DEFLEX=$1
OUT=$2
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
# The paper's circle as a nominal program, held 10 s at its start.
"$DEFLEX" offline --circle "centre_mm=1800;0;900,radius_mm=129.9,points=81" --force "ldbb:phi_deg=30,force_N=400" \
    --speed-mm-s 30 --hold-start-s 10 --nominal-trajectory "$OUT/nominal.csv" > /dev/null
# A free TCP port for the controller's RTDE server.
PORT=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
rm -f "$OUT/ready"
python3 "$HERE/ur_rtde_standin.py" --port "$PORT" --series cb3 --program "$OUT/nominal.csv" --seconds 6 \
    --ready-file "$OUT/ready" > "$OUT/standin.txt" &
STANDIN=$!
# deflex connects once the stand-in listens (at most 5 s).
i=0
while [ ! -s "$OUT/ready" ] && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
"$DEFLEX" online --link ur-rtde --period-ms 8 --robot-host 127.0.0.1 --robot-port "$PORT" \
    --program "$OUT/nominal.csv" --force-source "csv:$HERE/force_replay.csv" --loop --duration-s 4 \
    --log "$OUT/cycles.csv" --log-file "$OUT/online.log" --json > "$OUT/summary.json" || true
STATUS=0
wait "$STANDIN" || STATUS=$?
cat "$OUT/standin.txt"
python3 - "$OUT/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
assert s["link"] == "ur-rtde", s
assert s["counters"]["replies"] > 300, s["counters"]
assert s["counters"]["guard_trips"] == 0, s["counters"]
assert s["exit_code"] == 0, (s["exit_code"], s["stop_reason"])
print("deflex: %d targets, exit %d (%s)" % (s["counters"]["replies"], s["exit_code"], s["stop_reason"]))
PY
exit "$STATUS"
