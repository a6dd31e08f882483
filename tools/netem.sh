#!/usr/bin/env bash
# Emulated cluster network in network namespaces this script creates itself (root needed):
# a switch namespace with a bridge, the master in rtw-m (10.199.0.1) behind a shaped uplink,
# and N clients rtw-c1..rtw-cN (10.199.0.11, ...) with shaped links. Traffic never leaves
# these namespaces.
#
#   tools/netem.sh up N [MASTER_RATE] [CLIENT_RATE]   e.g. up 4 1gbit 100mbit (default 1gbit 1gbit)
#   tools/netem.sh bench N [MASTER_RATE] [CLIENT_RATE] [-- rtwall bench cluster arguments]
#   tools/netem.sh faults N [MASTER_RATE] [CLIENT_RATE] [-- rtwall bench faults arguments]
#   tools/netem.sh nodes K M [RATE] [-- rtwall bench cluster arguments]
#                                                     a master, K display nodes rtw-n1..rtw-nK
#                                                     (10.199.0.101, ...) and M clients, every link
#                                                     at RATE (default 1gbit); runs
#                                                     `rtwall bench cluster --display-nodes K`
#   tools/netem.sh down
#   LOSS=1 tools/netem.sh bench 2 ...                 each client's link loses 1% of packets each way
#   DELAY=5 JITTER=5 tools/netem.sh bench 2 ...       each packet on a client's link is held 5 +- 5 ms
#
# Shaping uses tc's token-bucket filter (tbf) on the switch's ports, i.e. on what each machine
# receives (tiles flow into the master). The kernel here has no sch_netem (nor act_gact), so
# random loss comes from nftables (`numgen random` in each client's namespace, LOSS percent in
# steps of 0.1), and delay and jitter (hence reordering) from build/tools/netjitter, fed by an
# iptables NFQUEUE rule in each client's namespace.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
RTWALL=${RTWALL:-build/tools/rtwall}
LOSS=${LOSS:-0}
DELAY=${DELAY:-0}
JITTER=${JITTER:-0}
NETJITTER=${NETJITTER:-build/tools/netjitter}

shape() {  # namespace device rate
  ip netns exec "$1" tc qdisc replace dev "$2" root tbf rate "$3" burst 512kb latency 100ms
}

lose() {  # namespace percent: drop that share of what the namespace's eth0 sends and receives
  local permille
  permille=$(awk -v p="$2" 'BEGIN { printf "%d", p * 10 + 0.5 }')
  ip netns exec "$1" nft -f - <<EOF
table inet rtw_loss {
  chain in { type filter hook input priority 0; iifname "eth0" numgen random mod 1000 < $permille counter drop; }
  chain out { type filter hook output priority 0; oifname "eth0" numgen random mod 1000 < $permille counter drop; }
}
EOF
}

jitter() {  # namespace: every packet on its eth0 held DELAY +- JITTER ms by netjitter
  ip netns exec "$1" iptables -A INPUT -i eth0 -j NFQUEUE --queue-num 0 --queue-bypass
  ip netns exec "$1" iptables -A OUTPUT -o eth0 -j NFQUEUE --queue-num 0 --queue-bypass
  ip netns exec "$1" "$NETJITTER" --queue 0 --delay "$DELAY" --jitter "$JITTER" >/dev/null &
  echo $! > "/run/rtw-netjitter-$1.pid"
}

up() {
  local n=$1 mrate=${2:-1gbit} crate=${3:-1gbit}
  down >/dev/null 2>&1 || true
  ip netns add rtw-sw
  ip -n rtw-sw link add br0 type bridge
  ip -n rtw-sw link set br0 up
  attach() {  # namespace address rate-into-it
    local ns=$1 addr=$2 rate=$3 port="p-$1"
    ip netns add "$ns"
    ip link add "$port" type veth peer name eth0 netns "$ns"
    ip link set "$port" netns rtw-sw
    ip -n rtw-sw link set "$port" master br0 up
    ip -n "$ns" addr add "$addr/24" dev eth0
    ip -n "$ns" link set eth0 up
    ip -n "$ns" link set lo up
    shape rtw-sw "$port" "$rate"    # the switch's port towards this machine: what it receives
    shape "$ns" eth0 "$rate"        # and what it sends
  }
  attach rtw-m 10.199.0.1 "$mrate"
  for i in $(seq 1 "${NODES:-0}"); do
    attach "rtw-n$i" "10.199.0.$((100 + i))" "$mrate"
  done
  for i in $(seq 1 "$n"); do
    attach "rtw-c$i" "10.199.0.$((10 + i))" "$crate"
    if [ "$LOSS" != 0 ]; then lose "rtw-c$i" "$LOSS"; fi
    if [ "$DELAY" != 0 ] || [ "$JITTER" != 0 ]; then jitter "rtw-c$i"; fi
  done
  if [ "${NODES:-0}" != 0 ]; then echo "netem: ${NODES} display nodes 10.199.0.101.. at $mrate" >&2; fi
  echo "netem: master 10.199.0.1 at $mrate, $n clients at $crate, loss $LOSS% each way," \
       "delay $DELAY +- $JITTER ms each way on client links" >&2
}

down() {
  for f in /run/rtw-netjitter-rtw-*.pid; do
    [ -e "$f" ] || continue
    kill "$(cat "$f")" 2>/dev/null || true
    rm -f "$f"
  done
  for ns in $(ip netns list | awk '{print $1}' | grep -E '^rtw-(m|sw|c[0-9]+|n[0-9]+)$' || true); do ip netns del "$ns"; done
}

case "${1:-}" in
  up) shift; up "$@" ;;
  down) down ;;
  bench|faults)
    what=$1
    shift
    n=$1; shift
    mrate=1gbit crate=1gbit
    if [ $# -gt 0 ] && [ "$1" != "--" ]; then mrate=$1; shift; fi
    if [ $# -gt 0 ] && [ "$1" != "--" ]; then crate=$1; shift; fi
    [ "${1:-}" = "--" ] && shift
    up "$n" "$mrate" "$crate"
    trap down EXIT
    link="master $mrate, clients $crate"
    if [ "$LOSS" != 0 ]; then link="$link, loss $LOSS% each way"; fi
    if [ "$DELAY" != 0 ] || [ "$JITTER" != 0 ]; then link="$link, delay $DELAY +- $JITTER ms each way"; fi
    if [ "$what" = bench ]; then
      # --insecure: these namespaces are the script's own and reach nothing else.
      ip netns exec rtw-m "$RTWALL" bench cluster --bind tcp://10.199.0.1:7700 --client-netns rtw-c --insecure \
        --max-clients "$n" --link "$link" "$@"
    else
      ip netns exec rtw-m "$RTWALL" bench faults --bind tcp://10.199.0.1:7700 --client-netns rtw-c \
        --link "$link" "$@"
    fi
    ;;
  nodes)
    # Display nodes (issue 19): every machine's link, master's, nodes' and clients', at one rate.
    shift
    k=$1 m=$2
    shift 2
    rate=1gbit
    if [ $# -gt 0 ] && [ "$1" != "--" ]; then rate=$1; shift; fi
    [ "${1:-}" = "--" ] && shift
    NODES=$k up "$m" "$rate" "$rate"
    trap down EXIT
    addresses=$(seq -s, 101 $((100 + k)) | sed 's/\([0-9]*\)/10.199.0.\1/g')
    mbit=$(awk -v r="$rate" 'BEGIN { v = r + 0; if (r ~ /gbit$/) v *= 1000; else if (r ~ /kbit$/) v /= 1000; print v }')
    # --insecure: these namespaces are the script's own and reach nothing else.
    ip netns exec rtw-m "$RTWALL" bench cluster --bind tcp://10.199.0.1:7700 --client-netns rtw-c --insecure \
      --max-clients "$m" --display-nodes "$k" --node-netns rtw-n --node-addresses "$addresses" \
      --node-link-mbit "$mbit" --link "master, $k nodes and $m clients at $rate each" "$@"
    ;;
  *) echo "usage: tools/netem.sh up N [MASTER_RATE] [CLIENT_RATE] | bench|faults N [RATES] [-- ARGS] | nodes K M [RATE] [-- ARGS] | down" >&2; exit 2 ;;
esac
