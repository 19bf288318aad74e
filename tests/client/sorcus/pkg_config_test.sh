#!/usr/bin/env bash
# Builds the X-CAN-2i example (client/examples/xcan_talk.c) with nothing but what pkg-config
# says for the build tree (one include directory, one library) and runs it where no canemud
# listens: it must say so with the library's code.
# Usage: pkg_config_test.sh BUILD_DIR PKG_CONFIG C_COMPILER CXX_COMPILER [BUILD_FLAGS]
# (../pkg_config_support.sh; the C++ compiler is not used here).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source_dir=$(cd "$here/../../.." && pwd)
# shellcheck source=../pkg_config_support.sh
source "$here/../pkg_config_support.sh"

flags=$("$pkg_config" --cflags --libs canemu-xcan)
echo "canemu-xcan: $flags"
# shellcheck disable=SC2086 # the flags are words
"$cc" -std=c11 -Wall -Wextra -Werror $build_flags "$source_dir/client/examples/xcan_talk.c" \
  $flags -o "$out/xcan_talk"

status=0
got=$(CANEMU_SOCKET="$out/nobody.sock" LD_LIBRARY_PATH=$build/lib \
  "$out/xcan_talk" xcan0 0 0x100 0x200 2>&1) || status=$?
want="xcan_talk: module: error 0x60"
if [ "$status" != 1 ] || [ "$got" != "$want" ]; then
  printf 'xcan_talk exited %s printing\n  %s\nnot 1 printing\n  %s\n' "$status" "$got" "$want"
  exit 1
fi

# Arguments that are no numbers, or out of range, are named before anything is tried.
for args in "x 0x100 0x200:INTERFACE \"x\": a number from 0 to 1" \
  "2 0x100 0x200:INTERFACE \"2\": a number from 0 to 1" \
  "0 0x1g 0x200:SEND_ID \"0x1g\": a number from 0 to 536870911"; do
  status=0
  # shellcheck disable=SC2086 # the arguments are words
  got=$(CANEMU_SOCKET="$out/nobody.sock" LD_LIBRARY_PATH=$build/lib \
    "$out/xcan_talk" xcan0 ${args%%:*} 2>&1) || status=$?
  want="xcan_talk: ${args#*:}"
  if [ "$status" != 2 ] || [ "$got" != "$want" ]; then
    printf 'xcan_talk exited %s printing\n  %s\nnot 2 printing\n  %s\n' "$status" "$got" "$want"
    exit 1
  fi
done
