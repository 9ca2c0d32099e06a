#!/usr/bin/env bash
# The test command: installs what is missing, builds everything once, runs every test.
#   bash tools/test.sh            all tests (unit, integration, system) + a short fuzz run
#   bash tools/test.sh -L unit    only tests with that ctest label (extra args go to ctest)
set -euo pipefail
cd "$(dirname "$0")/.."

bash tools/install-deps.sh
jobs=$(nproc)
cmake --preset default >/dev/null
cmake --build --preset default -j"$jobs"
ctest --preset default -j"$jobs" "$@"
if [ $# -eq 0 ] && [ -x tests/fuzz/run.sh ]; then
  bash tests/fuzz/run.sh 30
fi
