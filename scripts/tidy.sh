#!/usr/bin/env bash
# clang-tidy over canemud's sources with the checks of .clang-tidy, every finding an error.
# Usage: tidy.sh [BUILD_DIR] (default build; it needs the compile_commands.json CMake writes
# there). Runs on as many cores as there are.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
if [ ! -f "$build/compile_commands.json" ]; then
  echo "tidy: no $build/compile_commands.json: configure the build first (make build)" >&2
  exit 2
fi
log=$(mktemp)
trap 'rm -f "$log"' EXIT
if ! git ls-files -z 'daemon/src/*.cpp' |
  xargs -0 -P "$(nproc)" -n 4 clang-tidy -p "$build" --quiet >"$log" 2>/dev/null; then
  grep -E '(error|warning):' "$log" | sort -u >&2 || cat "$log" >&2
  echo "tidy: findings in the daemon's sources (.clang-tidy)" >&2
  exit 1
fi
echo "tidy: the daemon's sources pass .clang-tidy"
