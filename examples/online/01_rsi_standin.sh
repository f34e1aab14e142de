#!/bin/sh
# deflex online --link rsi against the Python stand-in of a KUKA controller (4 ms cycle, IPOC, late answers
# counted up to the ETHERNET Timeout), over loopback UDP, both sides set up from the files
# `deflex controller-setup --link rsi` writes. Passes when the stand-in ran to the end without RSI
# stopping and deflex answered.
#   sh examples/online/01_rsi_standin.sh build/bin/deflex /tmp/rsi-example
set -eu
DEFLEX=$1
OUT=$2
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT/setup"
# A free UDP port for this run.
PORT=$(python3 -c 'import socket; s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"$DEFLEX" controller-setup --link rsi --sensor-ip 127.0.0.1 --rsi-port "$PORT" --max-joint-correction-deg 0.5 \
    -o "$OUT/setup"
"$DEFLEX" online --link rsi --rsi-port "$PORT" --max-joint-correction-deg 0.5 \
    --force-source "csv:$HERE/force_replay.csv" --loop --duration-s 4 --log "$OUT/cycles.csv" \
    --log-file "$OUT/online.log" --json > "$OUT/summary.json" &
ONLINE=$!
sleep 0.5
python3 "$HERE/rsi_standin.py" --setup "$OUT/setup" --seconds 2.5 --log "$OUT/standin.csv"
wait "$ONLINE"
# deflex answered, never exceeded AXISCORR's limit (the stand-in clamps and counts), and logged it all.
python3 - "$OUT/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
assert s["link"] == "rsi", s
assert s["counters"]["replies"] > 100, s["counters"]
assert s["counters"]["guard_trips"] == 0, s["counters"]
print("deflex: %d answers, compute p99 %.0f us" % (s["counters"]["replies"], s["timing"]["compute_us"]["p99"]))
PY
