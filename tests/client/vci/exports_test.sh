#!/bin/sh
# Checks a VCI C library against its header and the vendor's function list:
#   - every function the header declares (following its #include "vcinpl_*.h") is exported;
#   - every vendor function is declared and exported;
#   - every export is declared by the header or by canemu_vci.h (the extensions).
# Usage: exports_test.sh NM LIBRARY HEADER VENDOR_LIST EXTENSION_HEADER
set -eu
nm=$1 lib=$2 header=$3 vendor=$4 extensions=$5
dir=$(dirname "$header")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# The header and the vcinpl_*.h headers it includes.
headers=$header
for inc in $(sed -n 's/^#include "\(vcinpl_[a-z0-9_]*\.h\)".*/\1/p' "$header"); do
  headers="$headers $dir/$inc"
done

# Function names: the identifier after VCIAPI, before its "(" (VCIAPI *PF_x typedefs excluded).
names() {
  grep -ohE 'VCIAPI[[:space:]]+[A-Za-z_][A-Za-z0-9_]*[[:space:]]*\(' "$@" |
    sed -E 's/VCIAPI[[:space:]]+//; s/[[:space:]]*\($//' | sort -u
}
# shellcheck disable=SC2086
names $headers >"$tmp/declared"
names "$extensions" >"$tmp/extensions"
"$nm" -D --defined-only "$lib" | awk '$2 == "T" || $2 == "W" {print $3}' | sort -u >"$tmp/exported"
grep -vE '^[[:space:]]*(#|$)' "$vendor" | sort -u >"$tmp/vendor"

status=0
report() {  # report FILE MESSAGE
  if [ -s "$1" ]; then
    echo "$2:"
    sed 's/^/  /' "$1"
    status=1
  fi
}
comm -23 "$tmp/declared" "$tmp/exported" >"$tmp/not_exported"
report "$tmp/not_exported" "declared in $(basename "$header") but not exported by $(basename "$lib")"
comm -23 "$tmp/vendor" "$tmp/declared" >"$tmp/not_declared"
report "$tmp/not_declared" "vendor functions missing from $(basename "$header")"
comm -23 "$tmp/vendor" "$tmp/exported" >"$tmp/vendor_not_exported"
report "$tmp/vendor_not_exported" "vendor functions not exported by $(basename "$lib")"
sort -u "$tmp/declared" "$tmp/extensions" >"$tmp/known"
comm -23 "$tmp/exported" "$tmp/known" >"$tmp/unknown"
report "$tmp/unknown" "exported by $(basename "$lib") but declared nowhere"

if [ "$status" -eq 0 ]; then
  echo "$(basename "$lib"): $(wc -l <"$tmp/declared") declared functions exported," \
    "$(wc -l <"$tmp/vendor") vendor functions present"
fi
exit "$status"
