#!/bin/bash
# The units as installed: `systemd-analyze verify` finds nothing, and `systemd-analyze security`
# rates canemud.service at 2.0 or below ("OK" or better); a change that loosens the confinement
# fails here. Usage: check_units.sh SOURCE_DIR CANEMUD
set -euo pipefail
src=$1
canemud=$2
if ! command -v systemd-analyze >/dev/null; then
  echo "systemd-analyze is missing (apt package systemd)" >&2
  exit 1
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
# verify wants the programs the units run to exist: point them at this build.
sed "s|/usr/bin/canemud|$canemud|g" "$src/systemd/canemud.service" >"$dir/canemud.service"
cp "$src/systemd/canemud.socket" "$dir/"
out=$(systemd-analyze verify "$dir/canemud.socket" "$dir/canemud.service" 2>&1)
if [ -n "$out" ]; then
  echo "systemd-analyze verify:" >&2
  echo "$out" >&2
  exit 1
fi
report=$(systemd-analyze security --offline=yes --threshold=20 "$dir/canemud.service" 2>&1) || {
  echo "$report" | tail -3 >&2
  echo "canemud.service is exposed beyond 2.0" >&2
  exit 1
}
echo "$report" | tail -1
echo "$report" | tail -1 | grep -Eq ' (PERFECT|SAFE|OK) '
