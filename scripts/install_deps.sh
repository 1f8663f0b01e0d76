#!/usr/bin/env bash
# Installs every Debian package unseen needs to build, test and benchmark; with --fuzz also
# what scripts/fuzz.sh needs (clang, libFuzzer and the sanitizer runtimes, llvm-symbolizer).
# Idempotent: returns at once when everything is already present.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config git
  libopencv-dev libeigen3-dev nlohmann-json3-dev libyaml-cpp-dev libpugixml-dev libcli11-dev
  libspdlog-dev libfmt-dev libassimp-dev libmeshoptimizer-dev
  libgtest-dev libgmock-dev libbenchmark-dev libomp-dev
)
FUZZ_PACKAGES=(clang libclang-rt-14-dev llvm-14)

for arg in "$@"; do
  case "$arg" in
    --fuzz) PACKAGES+=("${FUZZ_PACKAGES[@]}") ;;
    *) echo "usage: $0 [--fuzz]" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "unseen: installing missing packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "unseen: need root (or sudo) to install: ${missing[*]}" >&2; exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
