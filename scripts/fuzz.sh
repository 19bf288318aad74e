#!/usr/bin/env bash
# The libFuzzer targets (tests/fuzz), each from its seed corpus and the corpus it grew before.
#   fuzz.sh time SECONDS   each target SECONDS with address and undefined sanitizers
#                          (build-fuzz; `make fuzz`, CI)
#   fuzz.sh runs N         each target for N executions built for speed: coverage only, no
#                          sanitizers (build-fuzz-fast); then every input of the grown corpus
#                          replayed once through the sanitizer build (`make fuzz-long`, by hand).
# Figures (executions, seconds, executions/s, corpus, findings) per target go to
# BUILD/fuzz-figures.json. FUZZ_TARGETS="fuzz_config ..." runs only those. fuzz_server's own log
# lines are hidden (-close_fd_mask=2).
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:?usage: fuzz.sh time SECONDS | runs N}
amount=${2:?usage: fuzz.sh time SECONDS | runs N}
jobs=${JOBS:-$(nproc)}
# One target a line: name, corpus folder, its flags.
targets="fuzz_control_messages control -max_len=20000
fuzz_rings rings -max_len=4096 -timeout=10
fuzz_config config -max_len=4096
fuzz_server server -max_len=4096 -timeout=10 -close_fd_mask=2"

configure() {  # DIR SANITIZE
  CC=clang CXX=clang++ cmake -S . -B "$1" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCANEMU_FUZZ=ON -DCANEMU_FUZZ_SANITIZE="$2" -DCANEMU_WERROR=OFF -DCANEMU_BUILD_TESTS=OFF \
    -DCANEMU_BUILD_BENCH=OFF >/dev/null
  cmake --build "$1" -j "$jobs" --target fuzz_control_messages fuzz_rings fuzz_config fuzz_server
}

case "$mode" in
  time) dir=build-fuzz; configure "$dir" ON; limit=(-max_total_time="$amount") ;;
  runs) dir=build-fuzz-fast; configure "$dir" OFF; configure build-fuzz ON; limit=(-runs="$amount") ;;
  *) echo "fuzz.sh: unknown mode '$mode' (time or runs)" >&2; exit 2 ;;
esac

figures=$dir/fuzz-figures.json
echo "[" >"$figures"
first=1
while read -r target corpus flags; do
  [ -n "$target" ] || continue
  if [ -n "${FUZZ_TARGETS:-}" ] && [[ " $FUZZ_TARGETS " != *" $target "* ]]; then
    continue
  fi
  mkdir -p "$dir/corpus/$corpus"
  log=$dir/$target.log
  start=$(date +%s.%N)
  # shellcheck disable=SC2086
  "$dir/bin/$target" "${limit[@]}" $flags -print_final_stats=1 "$dir/corpus/$corpus" \
    "tests/fuzz/corpus/$corpus" 2>&1 | tee "$log" | grep -E '^(#[0-9]+.*(INITED|DONE)|==|SUMMARY|Done)' || true
  status=${PIPESTATUS[0]}
  seconds=$(awk "BEGIN {printf \"%.1f\", $(date +%s.%N) - $start}")
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  [ $first -eq 1 ] || echo "," >>"$figures"
  first=0
  printf '  {"target": "%s", "executions": %s, "seconds": %s, "per_second": %s, "corpus": %s, "exit": %s}' \
    "$target" "${runs:-0}" "$seconds" "$(awk "BEGIN {printf \"%d\", ${runs:-0} / ($seconds + 0.001)}")" \
    "$(ls "$dir/corpus/$corpus" | wc -l)" "$status" >>"$figures"
  if [ "$status" -ne 0 ]; then
    echo "]" >>"$figures"
    echo "fuzz: $target found something (exit $status); see $log and the crash-* file" >&2
    exit 1
  fi
  if [ "$mode" = runs ]; then  # the grown corpus once through the sanitizers
    # shellcheck disable=SC2086
    build-fuzz/bin/$target -runs=0 $flags "$dir/corpus/$corpus" >"$dir/$target.replay.log" 2>&1 || {
      echo "]" >>"$figures"
      echo "fuzz: $target's corpus fails under the sanitizers; see $dir/$target.replay.log" >&2
      exit 1
    }
  fi
done <<<"$targets"
printf '\n]\n' >>"$figures"
cat "$figures"
