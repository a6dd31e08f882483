#!/usr/bin/env bash
# The operating-point controller on a real cluster over loopback: `rtwall run --target-fps`
# with external local clients that are killed and started mid-run, and the loopback link
# throttled with tc's token-bucket filter (this kernel has no sch_netem). Run inside a private
# network namespace so that the throttle touches nothing else:
#
#   unshare -rn tools/controller_trace.sh RTWALL FRONT TARGET_FPS OUT_DIR [RATE]
#
# Writes OUT_DIR/trace.csv (rtwall run --trace: one line per frame) and OUT_DIR/events.csv
# (what happened at which frame). Called by tools/speed_accuracy.py, which charts the two.
set -euo pipefail
RTWALL=$1 FRONT=$2 TARGET=$3 OUT=$4 RATE=${5:-8mbit} PHASE=${PHASE:-25}
PORT=7791
ENDPOINT=tcp://127.0.0.1:$PORT
mkdir -p "$OUT"
ip link set lo up
# tbf drops every packet larger than its bucket (burst), and loopback's 64 KiB MTU makes most TCP
# segments larger than that: with the default MTU a throttled loopback carries almost nothing
# (0 bytes of a 2 MB transfer in 20 s at 8mbit, burst 32kb; 7.65 Mbit/s with MTU 1500). An
# Ethernet MTU, as between real machines, makes the throttle a rate limit. Private namespace only.
ip link set lo mtu 1500
tc qdisc del dev lo root 2>/dev/null || true

CLIENTS=()
start_client() { "$RTWALL" client --connect "$ENDPOINT" --threads 1 --exit-after-idle 5000 >/dev/null 2>&1 & CLIENTS+=($!); }
frames() { [ -f "$OUT/trace.csv" ] && echo $(( $(wc -l < "$OUT/trace.csv") - 1 )) || echo 0; }
event() { echo "$(frames),$1" >> "$OUT/events.csv"; echo "[trace] frame $(frames): $1" >&2; }

echo "frame,event" > "$OUT/events.csv"
"$RTWALL" run configs/run/demo.toml --clients 0 --bind "$ENDPOINT" --headless --write-every 0 --frames 0 \
  --target-fps "$TARGET" --front "$FRONT" --trace "$OUT/trace.csv" > "$OUT/run.log" 2>&1 &
MASTER=$!
trap 'kill $MASTER ${CLIENTS[@]} 2>/dev/null || true' EXIT
start_client
start_client
echo "0,start: 2 clients" >> "$OUT/events.csv"
sleep $PHASE
kill -KILL "${CLIENTS[0]}"
event "one client killed (1 left)"
sleep $PHASE
start_client
start_client
event "two clients started (3)"
sleep $PHASE
tc qdisc add dev lo root tbf rate "$RATE" burst 32kb latency 200ms
event "link throttled to $RATE"
sleep $PHASE
tc qdisc del dev lo root
event "throttle removed"
sleep $PHASE
event "end"
kill -INT $MASTER
wait $MASTER || true
