#!/usr/bin/env bash
# The main job on embedded default data: installs what is missing, builds unseen, renders
# the demo sequence from scenes/demo.yaml (a lettered cube on a zig-zag over clutter under
# a side light), tracks it from the first frame's pose and prints accuracy and speed.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${UNSEEN_BUILD_DIR:-$root/build}"
jobs="${UNSEEN_JOBS:-$(nproc)}"
out="$build/demo"

bash "$root/scripts/install_deps.sh"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build "$build" -j "$jobs" --target unseen
unseen="$build/tools/unseen/unseen"

mkdir -p "$out"
if [ ! -f "$out/sequence/sequence.json" ] || [ "$root/scenes/demo.yaml" -nt "$out/sequence/sequence.json" ]; then
  echo "== Rendering the demo sequence (scenes/demo.yaml)"
  rm -rf "$out/sequence"
  "$unseen" synth "$root/scenes/demo.yaml" "$out/sequence"
fi

echo "== Tracking"
"$unseen" track "$out/sequence" --init gt --out "$out/poses.csv" --stats "$out/stats.json" "$@"

echo "== Accuracy against ground truth"
"$unseen" eval "$out/sequence" "$out/poses.csv"
echo
echo "Poses: $out/poses.csv   Timing: $out/stats.json"
echo "See it: $unseen overlay $out/sequence $out/poses.csv $out/overlay.mp4"
