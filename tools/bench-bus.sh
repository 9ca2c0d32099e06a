#!/usr/bin/env bash
# The bus benchmark beside Cyclone DDS's own ddsperf, in one run, loopback only.
#   bash tools/bench-bus.sh [OUT_DIR]      (default build/bench; RSLAM_BUILD_DIR=build picks the binary)
#
# Both sides are measured the same way: two processes on this host, ping-pong with one message
# in flight, half the round trip reported (ddsperf's figure), message sizes equal on the wire
# (ddsperf "size S" serializes to S + 4 bytes, so S = bench_bus's cdr_bytes - 4), reliable,
# the same Cyclone configuration (deploy/dds/cyclonedds-loopback.xml, which the bus embeds).
# ddsperf runs twice: its default listener mode answers inside Cyclone's receive thread (no
# thread hand-off), its waitset mode hands each sample to an application thread, as the bus's
# Subscriber does. Throughput: ddsperf pub/sub keep-all beside bench_bus's lossless stream.
#
# Writes OUT_DIR/bench_bus.json, OUT_DIR/ddsperf-*.txt and prints a comparison.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${RSLAM_BUILD_DIR:-build}
out=${1:-$build/bench}
mkdir -p "$out"
export CYCLONEDDS_URI="file://$PWD/deploy/dds/cyclonedds-loopback.xml"
domain=${RSLAM_BENCH_DOMAIN:-97}  # outside the tests' 100-229
seconds=${RSLAM_BENCH_SECONDS:-5}

echo "bench_bus (two processes per benchmark; about 20 s)"
"$build/bin/bench_bus" --benchmark_format=console --benchmark_out="$out/bench_bus.json" \
  --benchmark_out_format=json

cdr_bytes() {  # benchmark name prefix -> serialized size
  python3 -c 'import json,sys
for b in json.load(open(sys.argv[1]))["benchmarks"]:
    if b["name"].startswith(sys.argv[2]) and "cdr_bytes" in b: sys.exit(print(int(b["cdr_bytes"])))
sys.exit(1)' \
    "$out/bench_bus.json" "$1"
}
small=$(( $(cdr_bytes "BM_LatencySmall/cyclone->cyclone" || echo 64) - 4 ))
image=$(( $(cdr_bytes "BM_LatencyImage/cyclone->cyclone" || echo 307264) - 4 ))

ddsperf_pingpong() {  # name size mode
  timeout $((seconds + 10)) ddsperf -i "$domain" -D $((seconds + 3)) pong "$3" >/dev/null 2>&1 &
  local pong=$!
  timeout $((seconds + 10)) ddsperf -i "$domain" -D "$seconds" -Qminmatch:1 -Qinitwait:5 ping size "$2" "$3" \
    >"$out/ddsperf-$1-$3.txt" 2>&1 || true
  wait "$pong" || true
}
ddsperf_throughput() {  # size
  timeout $((seconds + 10)) ddsperf -i "$domain" -D $((seconds + 1)) -k all sub >"$out/ddsperf-throughput.txt" 2>&1 &
  local sub=$!
  timeout $((seconds + 10)) ddsperf -i "$domain" -D "$seconds" -k all -Qminmatch:1 -Qinitwait:5 pub size "$1" \
    >/dev/null 2>&1 || true
  wait "$sub" || true
}
echo "ddsperf ping/pong: size $small and $image (listener and waitset), pub/sub keep-all size $image"
for mode in listener waitset; do
  ddsperf_pingpong small "$small" "$mode"
  ddsperf_pingpong image "$image" "$mode"
done
ddsperf_throughput "$image"

python3 - "$out" <<'EOF'
import json, re, statistics, sys
out = sys.argv[1]
bench = {b["name"].split("/iterations")[0]: b for b in json.load(open(f"{out}/bench_bus.json"))["benchmarks"]}

def ddsperf_latency(path):
    """Median over ddsperf's per-second lines (the first, warm-up, dropped) of its 50% and 99%."""
    rows = [(float(m.group(1)), float(m.group(2))) for line in open(path)
            if (m := re.search(r" 50% ([0-9.]+)us .* 99% ([0-9.]+)us", line))]
    rows = rows[1:] or rows
    if not rows: return None
    return statistics.median(r[0] for r in rows), statistics.median(r[1] for r in rows)

def ddsperf_rate(path):
    rates = [float(m.group(1)) * 1000 for line in open(path) if (m := re.search(r" rate ([0-9.]+) kS/s", line))]
    rates = rates[1:-1] or rates
    return statistics.median(rates) if rates else None

def fmt(x, unit="us"): return "-" if x is None else f"{x:8.1f} {unit}"

print("\nOne-way latency through the bus, between two processes (p50 / p99, microseconds):")
print(f"  {'writer->reader':18} {'small':>17} {'640x480 mono8':>19}   images/s (lossless)")
for pair in ["cyclone->cyclone", "cyclone->fastdds", "fastdds->cyclone", "fastdds->fastdds"]:
    row = f"  {pair:18}"
    for kind in ["Small", "Image"]:
        b = bench.get(f"BM_Latency{kind}/{pair}", {})
        row += f" {b['p50_us']:8.1f} / {b['p99_us']:7.1f}" if "p50_us" in b else f" {b.get('error_message', '-')[:17]:>17}"
    t = bench.get(f"BM_ImageThroughput/{pair}", {})
    row += f"   {t['items_per_second']:8.0f}" if "items_per_second" in t else f"   {t.get('error_message', '-')}"
    print(row)

print("\nCyclone -> Cyclone beside ddsperf (same sizes on the wire; half the round trip, p50 / p99 us):")
for kind, name in [("Small", "small"), ("Image", "image")]:
    b = bench.get(f"BM_Latency{kind}/cyclone->cyclone", {})
    if "half_rtt_p50_us" not in b:
        print(f"  {name}: bench_bus failed: {b.get('error_message', 'missing')}"); continue
    line = f"  {name:5} ({int(b['cdr_bytes'])} B): bus {b['half_rtt_p50_us']:7.1f} / {b['half_rtt_p99_us']:7.1f}"
    for mode in ["listener", "waitset"]:
        d = ddsperf_latency(f"{out}/ddsperf-{name}-{mode}.txt")
        if d is None: line += f" | ddsperf {mode}: no result"; continue
        line += f" | ddsperf {mode} {d[0]:6.1f} / {d[1]:7.1f}, bus {100 * (b['half_rtt_p50_us'] / d[0] - 1):+.0f}%"
    print(line)
t = bench.get("BM_ImageThroughput/cyclone->cyclone", {})
rate = ddsperf_rate(f"{out}/ddsperf-throughput.txt")
print(f"  640x480 throughput: bus {t.get('items_per_second', float('nan')):.0f}/s (stream, lossless)"
      f" | ddsperf pub/sub keep-all {'-' if rate is None else f'{rate:.0f}/s'}")
EOF
