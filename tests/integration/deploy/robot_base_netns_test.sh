#!/usr/bin/env bash
# The robot/base-station DDS configurations of deploy/dds/ work between two hosts: two network
# namespaces made here, joined by a veth pair (no other interface, no multicast), one running
# `rslam ping` as a robot, the other `rslam status` as the base station.
#   robot_base_netns_test.sh RSLAM_BIN DEPLOY_DIR ROBOT_VENDOR BASE_VENDOR
# Exits 77 (skipped) without root or network namespaces.
set -euo pipefail
rslam=$1 deploy=$2 robot_vendor=$3 base_vendor=$4

id=$$
ns_robot=rslam-robot-$id ns_base=rslam-base-$id
if [ "$(id -u)" -ne 0 ] || ! command -v ip >/dev/null || ! ip netns add "$ns_robot" 2>/dev/null; then
  echo "SKIP: needs root and network namespaces (ip netns)"
  exit 77
fi
tmp=$(mktemp -d)
cleanup() {
  ip netns pids "$ns_robot" 2>/dev/null | xargs -r kill 2>/dev/null || true
  ip netns del "$ns_robot" 2>/dev/null || true
  ip netns del "$ns_base" 2>/dev/null || true
  rm -rf "$tmp"
}
trap cleanup EXIT
ip netns add "$ns_base"
# Addresses exist only inside the two namespaces.
subnet=10.231.$((id % 250))
robot_ip=$subnet.1 base_ip=$subnet.2
ip link add "vr$id" type veth peer name "vb$id"
ip link set "vr$id" netns "$ns_robot"
ip link set "vb$id" netns "$ns_base"
ip -n "$ns_robot" addr add "$robot_ip/24" dev "vr$id"
ip -n "$ns_base" addr add "$base_ip/24" dev "vb$id"
for ns in "$ns_robot" "$ns_base"; do
  ip -n "$ns" link set lo up
done
ip -n "$ns_robot" link set "vr$id" up
ip -n "$ns_base" link set "vb$id" up

# The shipped files with their placeholder addresses (192.0.2.10 robot, 192.0.2.20 base) replaced.
config() {  # vendor side robot_id -> writes $tmp/side.yaml
  local vendor=$1 side=$2 robot=$3 prefix key
  if [ "$vendor" = cyclone ]; then prefix=cyclonedds key=cyclone_xml; else prefix=fastdds key=fastdds_xml; fi
  sed -e "s/192\.0\.2\.10/$robot_ip/g" -e "s/192\.0\.2\.20/$base_ip/g" "$deploy/dds/$prefix-$side.xml" >"$tmp/$side.xml"
  printf 'bus: {dds: %s, domain_id: 5, robot_id: %s, %s: %s}\n' "$vendor" "$robot" "$key" "$tmp/$side.xml" >"$tmp/$side.yaml"
}
config "$robot_vendor" robot robotA
config "$base_vendor" base base

ip netns exec "$ns_robot" "$rslam" ping --config "$tmp/robot.yaml" --seconds 20 >"$tmp/ping.log" 2>&1 &
ping_pid=$!
for attempt in 1 2 3 4 5 6; do
  ip netns exec "$ns_base" "$rslam" status --config "$tmp/base.yaml" --wait 2 --json >"$tmp/status.json" 2>"$tmp/status.err" || true
  if grep -q '"robot": "robotA"' "$tmp/status.json" && grep -q '"service": "ping"' "$tmp/status.json"; then
    echo "base station ($base_vendor) sees robotA's ping ($robot_vendor) across the namespaces"
    kill "$ping_pid" 2>/dev/null || true
    exit 0
  fi
done
echo "FAIL: the base station never saw the robot"; cat "$tmp/status.json" "$tmp/status.err" "$tmp/ping.log"
exit 1
