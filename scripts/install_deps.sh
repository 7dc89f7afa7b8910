#!/usr/bin/env bash
# Installs every Debian 12 package segslam needs to build, test and render off-screen.
# Idempotent: packages already present are skipped by apt; run as root or with sudo.
set -euo pipefail

packages=(
  build-essential cmake pkg-config git
  libmujoco-dev
  libosmesa6-dev libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri
  libeigen3-dev libopencv-dev libopencv-contrib-dev libceres-dev
  libyaml-cpp-dev libcli11-dev nlohmann-json3-dev libspdlog-dev libfmt-dev
  libtbb-dev libpng-dev libssl-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang-14 libclang-rt-14-dev llvm-14  # fuzz targets: clang, libFuzzer, llvm-symbolizer (docs/testing.md)
  chromium  # the HTML report is checked in a headless browser (scripts/check_report.sh)
  slurm-wlm munge  # sweeps as Slurm job arrays, tested on a private single-node Slurm (scripts/slurm/)
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#packages[@]} packages already installed"
  exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
echo "install_deps: installing ${missing[*]}"
"${sudo_cmd[@]}" apt-get update -qq
# Through env: sudo resets the environment, so a variable set before it would be lost.
"${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
