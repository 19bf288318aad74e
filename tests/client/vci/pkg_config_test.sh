#!/usr/bin/env bash
# Builds a VCI C program and a VCI C++ program with nothing but what pkg-config says for the
# build tree (one include directory, one library), runs them and checks what they print.
# Usage: pkg_config_test.sh BUILD_DIR PKG_CONFIG C_COMPILER CXX_COMPILER [BUILD_FLAGS]
# (../pkg_config_support.sh).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# shellcheck source=../pkg_config_support.sh
source "$here/../pkg_config_support.sh"

c_flags=$("$pkg_config" --cflags --libs canemu-vcinpl2)
cxx_flags=$("$pkg_config" --cflags --libs canemu-vciapi)
echo "canemu-vcinpl2: $c_flags"
echo "canemu-vciapi: $cxx_flags"
# shellcheck disable=SC2086 # the flags are words
"$cc" -std=c99 -Wall -Wextra -Werror $build_flags "$here/c_program.c" $c_flags -o "$out/c_program"
# shellcheck disable=SC2086
"$cxx" -std=c++17 -Wall -Wextra -Werror $build_flags "$here/cpp_program.cpp" $cxx_flags \
  -o "$out/cpp_program"

status=0
expect() {  # PROGRAM EXPECTED-OUTPUT
  local got
  got=$(LD_LIBRARY_PATH=$build/lib "$out/$1")
  if [ "$got" != "$2" ]; then
    printf '%s printed\n  %s\nnot\n  %s\n' "$1" "$got" "$2"
    status=1
  fi
}
expect c_program "CANCAPABILITIES2 108 bytes; VCI_E_TIMEOUT: timeout"
expect cpp_program "CANBTP 16 bytes; VCI_E_TIMEOUT: timeout"
exit $status
