#!/usr/bin/env bash
# Installs every Debian 12 package rslam needs to build, test and run. Idempotent:
# packages already present are skipped, so a second run does no network work.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git python3
  cyclonedds-tools cyclonedds-dev             # Cyclone DDS C API + idlc
  libfastrtps-dev libfastcdr-dev              # Fast DDS 2.9
  libprotobuf-dev protobuf-compiler
  libopencv-dev libeigen3-dev libspdlog-dev libfmt-dev
  libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libzstd-dev liblz4-dev libssl-dev
  clang libclang-rt-14-dev                     # libFuzzer target for the MCAP reader
)

# node + npm run the independent MCAP reader in the tests; a machine that already has
# a Node.js (with its own npm) keeps it, since Debian's npm conflicts with other builds.
command -v npm >/dev/null 2>&1 || packages+=(nodejs npm)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
