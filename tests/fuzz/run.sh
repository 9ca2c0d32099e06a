#!/usr/bin/env bash
# Builds the MCAP reader fuzzer with clang (libFuzzer + ASan + UBSan), writes a seed corpus of
# valid files, and fuzzes for N seconds (default 60). Exits non-zero if the fuzzer finds a crash,
# leak, timeout or out-of-memory; the reproducer is left in the build dir (crash-*, leak-*, ...).
# Usage: tests/fuzz/run.sh [seconds] [build dir]
set -euo pipefail
SECONDS_TO_RUN=${1:-60}
HERE=$(cd "$(dirname "$0")" && pwd)
# Default build dir inside this checkout (a shared /tmp dir would tie it to another checkout).
BUILD=${2:-$HERE/../../build/fuzz}
mkdir -p "$BUILD"
BUILD=$(cd "$BUILD" && pwd)
CC=clang CXX=clang++ cmake -S "$HERE" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$BUILD" -j2
CORPUS="$BUILD/corpus"
mkdir -p "$CORPUS"
"$BUILD/make_seed_corpus" "$CORPUS"
cd "$BUILD"
# -rss_limit_mb / -malloc_limit_mb: an absurd allocation is a failure, not a slowdown.
exec ./fuzz_mcap_reader -max_total_time="$SECONDS_TO_RUN" -timeout=10 -rss_limit_mb=1024 \
  -malloc_limit_mb=256 -max_len=65536 -print_final_stats=1 "$CORPUS"
