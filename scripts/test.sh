#!/usr/bin/env bash
# Installs what is missing, builds unseen (Release, with tests) and runs the whole test suite.
#   UNSEEN_BUILD_DIR  build folder (default build)
#   UNSEEN_ARCH       instruction set of every target, -march= (default x86-64-v2, portable)
#   UNSEEN_JOBS       build and test jobs (default: nproc)
# Extra arguments go to ctest (e.g. -R tracker).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${UNSEEN_BUILD_DIR:-$root/build}"
jobs="${UNSEEN_JOBS:-$(nproc)}"

bash "$root/scripts/install_deps.sh"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DUNSEEN_BUILD_TESTS=ON \
  -DUNSEEN_BUILD_BENCHMARKS=ON -DUNSEEN_ARCH="${UNSEEN_ARCH:-x86-64-v2}"
cmake --build "$build" -j "$jobs"
cd "$build"
ctest --output-on-failure -j "$jobs" "$@"
