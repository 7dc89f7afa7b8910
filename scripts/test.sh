#!/usr/bin/env bash
# README command 2: install dependencies, build, and run the whole test suite.
#
#   bash scripts/test.sh [--sanitize] [--fuzz]
#
#   (no option)  the Release build in build/ and its CTest suite
#   --sanitize   then the whole suite again, built with AddressSanitizer, LeakSanitizer and
#                UndefinedBehaviorSanitizer (gcc, -DSEGSLAM_SANITIZE=ON) in build-asan/
#   --fuzz       then the libFuzzer targets of the file readers (clang, build-fuzz/), each
#                run for SEGSLAM_FUZZ_SECONDS (default 20) from its committed seed corpus
#
# CI (.ci/run) runs `bash scripts/test.sh --sanitize --fuzz`. docs/testing.md says what
# each pass checks and how long it takes.
set -euo pipefail
cd "$(dirname "$0")/.."

sanitize=0
fuzz=0
for arg in "$@"; do
  case "$arg" in
    --sanitize) sanitize=1 ;;
    --fuzz) fuzz=1 ;;
    -h|--help) sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "scripts/test.sh: unknown option '$arg' (allowed: --sanitize, --fuzz)" >&2; exit 2 ;;
  esac
done

jobs=$(nproc 2>/dev/null || echo 2)
# Prints how long each pass took, so CI's log shows where its time goes.
phase_start=$SECONDS
phase_done() {
  echo "scripts/test.sh: $1 took $((SECONDS - phase_start)) s"
  phase_start=$SECONDS
}

# The builds take about 1.5 GiB (build/), 3.5 GiB more with --sanitize (build-asan/), and
# the compiler's temporary files go to TMPDIR: a full disk otherwise shows up only as a
# compiler's "No space left on device" deep in the log.
need_gib=$((2 + 4 * sanitize))
free_gib=$(df -P -BG . "${TMPDIR:-/tmp}" 2>/dev/null | awk 'NR > 1 { gsub("G", "", $4); print $4 }' | sort -n | head -1)
if [ -n "$free_gib" ] && [ "$free_gib" -lt "$need_gib" ]; then
  echo "scripts/test.sh: warning: only ${free_gib} GiB free on the disk of $(pwd) or ${TMPDIR:-/tmp};" \
       "these builds need about ${need_gib} GiB" >&2
fi

bash scripts/install_deps.sh
bash scripts/build.sh
phase_done "the Release build"
ctest --test-dir build --output-on-failure -j"$jobs" --timeout 900
phase_done "the Release suite"

if [ "$fuzz" = 1 ]; then
  # Only the readers' libraries and the fuzz targets (tests/fuzz/CMakeLists.txt).
  CC=clang-14 CXX=clang++-14 cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only" \
    -DSEGSLAM_BUILD_FUZZERS=ON -DSEGSLAM_BUILD_BENCHMARKS=OFF \
    -DSEGSLAM_FUZZ_SECONDS="${SEGSLAM_FUZZ_SECONDS:-20}"
  cmake --build build-fuzz -j"$jobs"
  phase_done "the fuzz build"
  ctest --test-dir build-fuzz --output-on-failure -j"$jobs" -L fuzz
  phase_done "the fuzz targets"
fi

if [ "$sanitize" = 1 ]; then
  # -O2 keeps the suite's run time near the Release build's times two; -g1 gives stack
  # traces with file and line; assertions stay on (no NDEBUG). No benchmarks.
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1" \
    -DSEGSLAM_SANITIZE=ON -DSEGSLAM_BUILD_BENCHMARKS=OFF
  cmake --build build-asan -j"$jobs"
  phase_done "the sanitized build"
  ctest --test-dir build-asan --output-on-failure -j"$jobs" --timeout 1800
  phase_done "the sanitized suite"
fi
