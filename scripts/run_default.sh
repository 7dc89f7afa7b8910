#!/usr/bin/env bash
# README command 1: install dependencies, build, and run the main job on the default
# scenario (scenarios/city_boulevard.yaml, the paper's AirSim-like setting: a 200 m route
# down avenues lined with parked vehicles, driven twice): generate both passes (cached in
# data/cache/), run plain, mask-moveable, the paper's mutual loop with the simulated
# FCIS-like segmenter and the oracle over them (pass 1 builds the long-term map, pass 2
# relocalizes on it with nine in ten parked vehicles re-parked), print the paper-style
# tables and the scenario's thresholds, and write the report to reports/city_boulevard/
# (report.html, report.md, results.json).
#
# Three repeats of the two segmenter-driven modes (plain and the oracle are deterministic
# and run once), as many runs at a time as there are cores (a run uses about one core),
# take about 13 minutes on two cores once the build is made (measured 2026-12-03: 167 s
# to generate, the eight runs in 651 s); the paper's ten repeats:
# ./build/segslam scenario run scenarios/city_boulevard.yaml --jobs "$(nproc)"
# The street-grid route of scenarios/city_street_grid.yaml, where traffic does not mislead
# plain (docs/results.md), runs the same way.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
status=0
./build/segslam scenario run scenarios/city_boulevard.yaml --repeats 3 --jobs "$(nproc)" || status=$?
# Exit code 2 means the job ran and a threshold of the scenario failed: a result shown
# above, not a broken set-up.
if [ "$status" -eq 2 ]; then
  echo "run_default: the job ran; some of the scenario's thresholds failed (see the table above)"
  exit 0
fi
exit "$status"
