#!/usr/bin/env bash
# README command 1: install dependencies, build, and run the main job on the default
# scenario (scenarios/city_two_pass.yaml).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
./build/segslam generate scenarios/city_two_pass.yaml --out data/city_two_pass --force
