#!/bin/sh
# deflex online --link rsi against the Python stand-in of a KUKA controller (4 ms cycle, IPOC, late answers
# counted up to the ETHERNET Timeout), over loopback UDP, both sides set up from the files
# `deflex controller-setup --link rsi` writes. Passes when deflex answered and the stand-in never had to
# clamp an answer to the AXISCORR limits deflex was given.
#   sh examples/online/04_rsi_standin.sh build/bin/deflex /tmp/rsi-example
set -eu
DEFLEX=$1
OUT=$2
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT/setup"
# A free UDP port for this run.
PORT=$(python3 -c 'import socket; s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"$DEFLEX" controller-setup --link rsi --sensor-ip 127.0.0.1 --rsi-port "$PORT" --max-joint-correction-deg 0.5 \
    -o "$OUT/setup"
# The stand-in ends after 2.5 s the way a KRL program's RSI_OFF does (it stops sending): with
# --end-on-silence that silence is the session's planned end (exit 0) unless RSI had stopped on its Timeout.
"$DEFLEX" online --link rsi --rsi-port "$PORT" --max-joint-correction-deg 0.5 --end-on-silence \
    --force-source "csv:$HERE/force_replay.csv" --loop --duration-s 6 --log "$OUT/cycles.csv" \
    --log-file "$OUT/online.log" --json > "$OUT/summary.json" &
ONLINE=$!
sleep 0.5
# The stand-in stops RSI at the Timeout as the controller would; on a busy machine that can happen
# for scheduling reasons, so its exit code is reported, not required.
python3 "$HERE/rsi_standin.py" --setup "$OUT/setup" --seconds 2.5 --log "$OUT/standin.csv" > "$OUT/standin.txt" || true
cat "$OUT/standin.txt"
wait "$ONLINE"
# deflex answered, the stand-in never had to clamp an answer to AXISCORR's limit, and deflex logged it.
python3 - "$OUT/summary.json" "$OUT/standin.txt" <<'PY'
import json, re, sys
s = json.load(open(sys.argv[1]))
standin = open(sys.argv[2]).read()
assert s["link"] == "rsi", s
assert s["counters"]["replies"] > 100, s["counters"]
assert s["counters"]["guard_trips"] == 0, s["counters"]
assert re.search(r"[1-9][0-9]* answers taken in time", standin), standin
assert " 0 clamped" in standin, standin
print("deflex: %d answers, compute p99 %.0f us" % (s["counters"]["replies"], s["timing"]["compute_us"]["p99"]))
PY
