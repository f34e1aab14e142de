#!/bin/sh
# deflex online --link simple-message against the Python stand-in of ABB's RAPID streaming server
# (simple_message_standin.py), over loopback TCP, for 3 s at the paper's 100 ms cycle: the stand-in must
# have taken the points and the STOP_TRAJECTORY deflex sends when it ends, and every logged command must
# lie within the 0.5 deg bound of the nominal. Usage: 03_simple_message_standin.sh DEFLEX OUTDIR
set -eu
DEFLEX=$1
OUT=$2
HERE=$(cd "$(dirname "$0")" && pwd)
command -v python3 >/dev/null || { echo "needs python3 (scripts/install-deps.sh installs it)" >&2; exit 1; }
mkdir -p "$OUT"
rm -f "$OUT/ports.txt"

"$DEFLEX" offline --circle "centre_mm=1800;0;900,radius_mm=129.9,points=81" --force "ldbb:phi_deg=30,force_N=400" \
  --speed-mm-s 30 --hold-start-s 0.5 --nominal-trajectory "$OUT/nominal.csv" >/dev/null

python3 "$HERE/simple_message_standin.py" --motion-port 0 --state-port 0 --port-file "$OUT/ports.txt" \
  --program "$OUT/nominal.csv" --seconds 6 >"$OUT/standin.txt" 2>&1 &
STANDIN=$!
i=0
while [ ! -s "$OUT/ports.txt" ] && [ $i -lt 100 ]; do sleep 0.05; i=$((i + 1)); done
read -r MOTION STATE <"$OUT/ports.txt"

"$DEFLEX" online --link simple-message --robot-host 127.0.0.1 --motion-port "$MOTION" --state-port "$STATE" \
  --program "$OUT/nominal.csv" --period-ms 100 --force-source "csv:$HERE/force_replay.csv" --loop \
  --duration-s 3 --log "$OUT/log.csv" 2>"$OUT/deflex.txt"
wait $STANDIN
cat "$OUT/standin.txt"

python3 - "$OUT/log.csv" "$OUT/standin.txt" <<'EOF'
import csv, sys
rows = list(csv.DictReader(line for line in open(sys.argv[1]) if not line.startswith("#")))
assert len(rows) >= 25, "only %d cycles logged" % len(rows)
worst = max(abs(float(r["q_command%d_deg" % j]) - float(r["q_nominal%d_deg" % j])) for r in rows for j in range(1, 7))
assert worst <= 0.5, "a command %.4f deg from the nominal" % worst
assert worst > 1e-4, "no correction was made"
standin = open(sys.argv[2]).read()
taken = int(standin.split(" points accepted")[0])
assert taken >= 25, standin
assert "1 STOP_TRAJECTORY" in standin, standin
print("%d cycles, largest |command - nominal| %.4f deg, %d points taken by the stand-in" % (len(rows), worst, taken))
EOF
