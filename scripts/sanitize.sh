#!/usr/bin/env bash
# Builds the whole project with AddressSanitizer + UndefinedBehaviorSanitizer (every target,
# see UNSEEN_SANITIZE) and runs the whole test suite under them; any report fails the run.
# The end-to-end tests on the development sequences track each over its first
# UNSEEN_TEST_FRAMES frames (default 40: every code path, a tenth of the time; the other
# builds track them whole).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${UNSEEN_SANITIZE_BUILD_DIR:-$root/build-sanitize}"
jobs="${UNSEEN_JOBS:-$(nproc)}"

bash "$root/scripts/install_deps.sh"
# -O1 keeps instrumented tests quick to build and run; -g1 gives reports file:line.
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE="-O1 -g1" \
  -DUNSEEN_SANITIZE=ON -DUNSEEN_BUILD_TESTS=ON -DUNSEEN_BUILD_BENCHMARKS=OFF
cmake --build "$build" -j "$jobs"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
export UNSEEN_TEST_FRAMES="${UNSEEN_TEST_FRAMES:-40}"
cd "$build"
ctest --output-on-failure -j "$jobs" "$@"
