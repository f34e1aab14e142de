#!/bin/sh
# deflex online --link fanuc-j519 against the Python stand-in of a FANUC controller (Stream Motion,
# protocol 1, 8 ms: statuses numbered in turn, a command queue that must never run dry, every target's
# velocity, acceleration and jerk checked), over loopback UDP. Passes when the session ended on its
# time limit with the last-data command and the stand-in never alarmed.
#   sh examples/online/06_fanuc_standin.sh build/bin/deflex /tmp/fanuc-example
set -eu
DEFLEX=$1
OUT=$2
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
# The paper's circle as a nominal program, held 10 s at its start.
"$DEFLEX" offline --circle "centre_mm=1800;0;900,radius_mm=129.9,points=81" --force "ldbb:phi_deg=30,force_N=400" \
    --speed-mm-s 30 --hold-start-s 10 --nominal-trajectory "$OUT/nominal.csv" > /dev/null
# A run in which this machine stalled deflex longer than the stand-in's queue ends in MOTN-603, as on a
# real controller; that is the host (not a real-time PC), so the run is repeated, at most twice.
for ATTEMPT in 1 2 3; do
  # A free UDP port for the controller.
  PORT=$(python3 -c 'import socket; s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  # --start-buffer 9 (a protocol-3 controller's deepest start_move): 64 ms of slack for a test machine
  # that is not a real-time PC; a real cell runs deflex online --realtime.
  python3 "$HERE/fanuc_j519_standin.py" --port "$PORT" --program "$OUT/nominal.csv" --seconds 7 --start-buffer 9 \
      > "$OUT/standin.txt" &
  STANDIN=$!
  sleep 0.3
  "$DEFLEX" online --link fanuc-j519 --robot-host 127.0.0.1 --robot-port "$PORT" --program "$OUT/nominal.csv" \
      --force-source "csv:$HERE/force_replay.csv" --loop --duration-s 4 --log "$OUT/cycles.csv" \
      --log-file "$OUT/online.log" --json > "$OUT/summary.json" || true
  STATUS=0
  wait "$STANDIN" || STATUS=$?
  cat "$OUT/standin.txt"
  grep -q "MOTN-603 ST: Receiving interval over" "$OUT/standin.txt" || break
  echo "attempt $ATTEMPT: this machine stalled deflex beyond the stand-in's queue (MOTN-603)"
done
python3 - "$OUT/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
assert s["link"] == "fanuc-j519", s
assert s["counters"]["replies"] > 300, s["counters"]
assert s["counters"]["guard_trips"] == 0, s["counters"]
assert s["exit_code"] == 0, (s["exit_code"], s["stop_reason"])
print("deflex: %d commands, exit %d (%s)" % (s["counters"]["replies"], s["exit_code"], s["stop_reason"]))
PY
# deflex read the stand-in's threshold tables (6 joints x velocity, acceleration, jerk) before starting.
grep -q "the controller's 18 threshold tables were read" "$OUT/online.log"
exit "$STATUS"
