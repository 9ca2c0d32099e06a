#!/usr/bin/env bash
# Bus benchmark beside Cyclone DDS's own ddsperf, in one run, both on loopback only.
#   bash tools/bench-bus.sh [OUT_DIR]   (default build/bench)
# Writes OUT_DIR/bench_bus.json (Google Benchmark) and OUT_DIR/ddsperf-{small,image}.txt
# (ddsperf ping/pong: half the round trip, per second; the last line is the steadiest).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-build/bench}
mkdir -p "$out"
export CYCLONEDDS_URI="file://$PWD/deploy/dds/cyclonedds-loopback.xml"
domain=${RSLAM_BENCH_DOMAIN:-97}

ddsperf_run() {  # name size
  timeout 12 ddsperf -i "$domain" -D 8 pong >/dev/null 2>&1 &
  local pong=$!
  timeout 12 ddsperf -i "$domain" -D 6 -Qminmatch:1 -Qinitwait:5 ping size "$2" >"$out/ddsperf-$1.txt" 2>&1 || true
  wait "$pong" || true
  grep -E "mean" "$out/ddsperf-$1.txt" | tail -1 || true
}
echo "ddsperf small (12 B):"; ddsperf_run small 12
echo "ddsperf image (307200 B):"; ddsperf_run image 307200
build/bin/bench_bus --benchmark_format=console --benchmark_out="$out/bench_bus.json" --benchmark_out_format=json
