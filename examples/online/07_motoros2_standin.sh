#!/bin/sh
# deflex online --link motoros2-rt against the Python stand-in of a Yaskawa controller in MotoROS2's
# real-time mode (4 ms, lock-step: one joint increment taken a period and answered once, the session
# dropped on a sequence jump, a second sender or an increment above the axes' maximum), over loopback
# UDP. Passes when the session ended on its time limit and the stand-in never dropped its session. The
# link is lock-step: a machine that stalls deflex only pauses the stream, so no run is repeated.
#   sh examples/online/07_motoros2_standin.sh build/bin/deflex /tmp/motoros2-example
set -eu
DEFLEX=$1
OUT=$2
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
# The paper's circle as a nominal program, held 10 s at its start.
"$DEFLEX" offline --circle "centre_mm=1800;0;900,radius_mm=129.9,points=81" --force "ldbb:phi_deg=30,force_N=400" \
    --speed-mm-s 30 --hold-start-s 10 --nominal-trajectory "$OUT/nominal.csv" > /dev/null
# A free UDP port for the controller.
PORT=$(python3 -c 'import socket; s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
python3 "$HERE/motoros2_rt_standin.py" --port "$PORT" --program "$OUT/nominal.csv" --seconds 6 > "$OUT/standin.txt" &
STANDIN=$!
sleep 0.3
"$DEFLEX" online --link motoros2-rt --robot-host 127.0.0.1 --robot-port "$PORT" --program "$OUT/nominal.csv" \
    --force-source "csv:$HERE/force_replay.csv" --loop --duration-s 4 --log "$OUT/cycles.csv" \
    --log-file "$OUT/online.log" --json > "$OUT/summary.json" || true
STATUS=0
wait "$STANDIN" || STATUS=$?
cat "$OUT/standin.txt"
python3 - "$OUT/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
assert s["link"] == "motoros2-rt", s
assert s["counters"]["replies"] > 300, s["counters"]
assert s["counters"]["guard_trips"] == 0, s["counters"]
assert s["exit_code"] == 0, (s["exit_code"], s["stop_reason"])
print("deflex: %d commands, exit %d (%s)" % (s["counters"]["replies"], s["exit_code"], s["stop_reason"]))
PY
exit "$STATUS"
