#!/usr/bin/env bash
# Configures and builds the fuzz configuration (preset fuzz's settings: clang, AGVSLAM_FUZZ=ON) into BUILD_DIR
# (default build/fuzz), with ccache when it is installed. Only the fuzz targets and the parsers' sources build.
set -euo pipefail
src="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${1:-$src/build/fuzz}"
launcher=()
if command -v ccache > /dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache); fi
for tool in clang clang++; do
  command -v "$tool" > /dev/null || { echo "fuzz build: $tool not found (bash deploy/install-deps.sh installs it)" >&2; exit 1; }
done
cmake -S "$src" -B "$build" -G "Unix Makefiles" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DAGVSLAM_FUZZ=ON -DAGVSLAM_BUILD_TESTS=OFF -DAGVSLAM_BUILD_BENCH=OFF "${launcher[@]}" > /dev/null
cmake --build "$build" -j "${AGVSLAM_FUZZ_JOBS:-2}" --target fuzz_targets
