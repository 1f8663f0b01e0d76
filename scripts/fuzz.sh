#!/usr/bin/env bash
# Fuzzes every reader of outside input for a bounded effort (README "Fuzzing"): installs what
# is missing, builds the libFuzzer targets of fuzz/ with clang, AddressSanitizer and UBSan in
# their own build folder, then runs each on a copy of its seed corpus and its regression
# inputs. Prints one line per target; exits non-zero when any target finds a crash, a hang,
# a leak or a sanitizer report (the input is kept in <build>/fuzz-runs/<target>/).
#
#   UNSEEN_FUZZ_RUNS        "budget" (default): each target runs its number of inputs from
#                           fuzz/budgets.txt (about 20 s each on a 2-core machine); with the
#                           fixed seed, runs on any machine explore much the same inputs.
#                           "time": each runs for UNSEEN_FUZZ_SECONDS instead (explore).
#   UNSEEN_FUZZ_SECONDS     fuzzing time per target in "time" mode (default 20); in "budget"
#                           mode a target stops after 3x this time whatever its budget
#   UNSEEN_FUZZ_BUILD_DIR   build folder (default build-fuzz)
#   UNSEEN_FUZZ_TARGETS     space-separated targets to run (default: every fuzz/*_fuzzer.cc)
#   UNSEEN_FUZZ_SEED        libFuzzer's random seed (default 1, so a CI failure can be replayed;
#                           0 draws a new seed each run)
#   UNSEEN_JOBS             build jobs and targets fuzzed at once (default: nproc)
# Extra arguments go to every fuzzer (e.g. -max_len=20000).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${UNSEEN_FUZZ_BUILD_DIR:-$root/build-fuzz}"
seconds="${UNSEEN_FUZZ_SECONDS:-20}"
seed="${UNSEEN_FUZZ_SEED:-1}"
mode="${UNSEEN_FUZZ_RUNS:-budget}"
if [ "$mode" != budget ] && [ "$mode" != time ]; then
  echo "unseen: UNSEEN_FUZZ_RUNS must be 'budget' or 'time', not '$mode'" >&2
  exit 2
fi
jobs="${UNSEEN_JOBS:-$(nproc)}"
timeout=5  # seconds one input may take before libFuzzer reports a hang
start=$SECONDS

bash "$root/scripts/install_deps.sh" --fuzz
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ \
  -DUNSEEN_SANITIZE=ON -DUNSEEN_BUILD_FUZZERS=ON -DUNSEEN_BUILD_TESTS=OFF > /dev/null
cmake --build "$build" -j "$jobs" --target unseen_fuzzers
echo "== Built the fuzz targets in $((SECONDS - start)) s"

if [ -n "${UNSEEN_FUZZ_TARGETS:-}" ]; then
  read -r -a targets <<< "$UNSEEN_FUZZ_TARGETS"
else
  targets=()
  for source in "$root"/fuzz/*_fuzzer.cc; do
    name="$(basename "$source" .cc)"
    targets+=("${name%_fuzzer}")
  done
fi

if ! command -v llvm-symbolizer > /dev/null && [ -x /usr/bin/llvm-symbolizer-14 ]; then
  export ASAN_SYMBOLIZER_PATH=/usr/bin/llvm-symbolizer-14
fi
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1}"

# Fuzzes target $1 in <build>/fuzz-runs/$1: corpus/ (a copy of the seeds, grown by the run),
# log, and the input of any failure.
run_target() {
  local name="$1"
  local work="$build/fuzz-runs/$name"
  rm -rf "$work"
  mkdir -p "$work/corpus"
  cp -r "$root/fuzz/corpus/$name/." "$work/corpus/"
  local inputs=("$work/corpus")
  if [ -d "$root/fuzz/regressions/$name" ]; then inputs+=("$root/fuzz/regressions/$name"); fi
  local limits=(-max_total_time="$seconds")
  if [ "$mode" = budget ]; then
    local runs
    runs="$(awk -v t="$name" '$1 == t { print $2 }' "$root/fuzz/budgets.txt")"
    if [ -z "$runs" ]; then
      echo "unseen: fuzz/budgets.txt has no budget for '$name'" > "$work/log"
      echo 2 > "$work/status"
      return
    fi
    limits=(-runs="$runs" -max_total_time="$((3 * seconds))")
  fi
  local fuzzer="$build/fuzz/${name}_fuzzer"
  local status=0
  "$fuzzer" "${inputs[@]}" "${limits[@]}" -timeout="$timeout" -rss_limit_mb=2048 \
    -dict="$root/fuzz/numbers.dict" -artifact_prefix="$work/" -seed="$seed" \
    -print_final_stats=1 "${@:2}" > "$work/log" 2>&1 || status=$?
  # A timeout is a hang only when it recurs: one input over the limit while the machine was
  # busy (another target fuzzing beside it, a stalled disk) is replayed alone with the same
  # limit; when it then finishes, the run is noted in <work>/retry and the target is fuzzed
  # once more from its grown corpus, whose result counts. An input that times out again, or
  # any other failure, fails as before.
  local artifact
  artifact="$(find "$work" -maxdepth 1 -type f -name 'timeout-*' | head -n 1)"
  if [ "$status" -ne 0 ] && [ -n "$artifact" ]; then
    local replay_start=$EPOCHREALTIME
    if "$fuzzer" -timeout="$timeout" -rss_limit_mb=2048 "$artifact" > "$work/replay.log" 2>&1; then
      mkdir -p "$work/first"
      mv "$work/log" "$artifact" "$work/first/"
      awk -v a="$(basename "$artifact")" -v t0="$replay_start" -v t1="$EPOCHREALTIME" \
        'BEGIN { printf "input %s timed out, ran in %.2f s alone\n", a, t1 - t0 }' > "$work/retry"
      status=0
      "$fuzzer" "$work/corpus" "${limits[@]}" -timeout="$timeout" -rss_limit_mb=2048 \
        -dict="$root/fuzz/numbers.dict" -artifact_prefix="$work/" -seed="$seed" \
        -print_final_stats=1 "${@:2}" > "$work/log" 2>&1 || status=$?
    fi
  fi
  echo "$status" > "$work/status"
}

if [ "$mode" = budget ]; then
  echo "== Fuzzing ${#targets[@]} targets, each its budget of inputs (fuzz/budgets.txt), seed $seed, ${jobs} at a time"
else
  echo "== Fuzzing ${#targets[@]} targets for ${seconds} s each, seed $seed, ${jobs} at a time"
fi
running=0
for name in "${targets[@]}"; do
  if [ ! -x "$build/fuzz/${name}_fuzzer" ]; then
    echo "unseen: no fuzz target '$name'" >&2
    exit 2
  fi
  if [ "$running" -ge "$jobs" ]; then
    wait -n || true
    running=$((running - 1))
  fi
  run_target "$name" "$@" &
  running=$((running + 1))
done
wait

failed=0
for name in "${targets[@]}"; do
  work="$build/fuzz-runs/$name"
  status="$(cat "$work/status")"
  runs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/log" | tail -n 1)"
  corpus="$(find "$work/corpus" -type f | wc -l)"
  seeds="$(find "$root/fuzz/corpus/$name" -type f | wc -l)"
  artifacts="$(find "$work" -maxdepth 1 -type f \( -name 'crash-*' -o -name 'timeout-*' \
    -o -name 'leak-*' -o -name 'oom-*' -o -name 'slow-unit-*' \) | sort)"
  if [ "$status" -eq 0 ] && [ -z "$(grep -l -e '==unseen fuzz==' -e 'runtime error:' \
      -e 'ERROR: AddressSanitizer' -e 'ERROR: LeakSanitizer' "$work/log")" ]; then
    result=ok
  else
    result=FAILED
    failed=$((failed + 1))
  fi
  printf 'fuzz %-16s %-6s runs %-8s corpus %4s (%s seeds)' "$name" "$result" "${runs:-?}" \
    "$corpus" "$seeds"
  if [ "$result" = FAILED ]; then
    printf '  exit %s, log %s' "$status" "$work/log"
    for artifact in $artifacts; do printf '  input %s' "$artifact"; done
    grep -m 1 -e '==unseen fuzz==' -e 'runtime error:' -e 'ERROR: [A-Za-z]*Sanitizer' \
      -e 'ERROR: libFuzzer' "$work/log" | sed 's/^/\n    /' | tr -d '\n' || true
  fi
  if [ -e "$work/retry" ]; then printf '  (fuzzed twice: %s, kept in %s)' "$(cat "$work/retry")" \
    "$work/first"; fi
  printf '\n'
done
echo "== ${#targets[@]} targets, $failed failed, $((SECONDS - start)) s in all"
[ "$failed" -eq 0 ]
