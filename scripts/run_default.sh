#!/usr/bin/env bash
# README command 1: install dependencies, build, and run the main job on the default
# scenario (scenarios/city_two_pass.yaml): generate both passes, then run the paper's
# framework on them (pass 1 builds the long-term map, pass 2 relocalizes on it) with the
# simulated FCIS-like segmenter, and print the table.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
./build/segslam generate scenarios/city_two_pass.yaml --out data/city_two_pass --force
./build/segslam run data/city_two_pass --mode mutual --segmenter fcis-like
