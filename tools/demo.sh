#!/usr/bin/env bash
# The demo command: installs what is missing, builds, and runs `rslam demo` (a simulated robot
# explores a real room with the seven services as separate processes). Extra arguments go to
# `rslam demo` (e.g. --out DIR, --dds fastdds, --max-seconds N).
set -euo pipefail
cd "$(dirname "$0")/.."

bash tools/install-deps.sh
cmake --preset default >/dev/null
cmake --build --preset default -j"$(nproc)"
exec build/bin/rslam demo "$@"
