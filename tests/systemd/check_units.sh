#!/bin/bash
# The units as installed: `systemd-analyze verify` finds nothing, and `systemd-analyze security`
# rates canemud.service at 0.6 or below ("SAFE": AF_UNIX only, no network), and at 1.8 or below
# with the drop-ins that open the bridges' address families (systemd/canemud.service.d/), 0.6
# with the one that lets it hold a CPU latency request; a change that loosens the confinement
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
fail=0

# UNIT_DIR THRESHOLD (tenths) WHAT: verify and rate the service in UNIT_DIR (with the drop-ins
# in its canemud.service.d/, which both read).
check() {
  local unit=$1/canemud.service out report
  out=$(systemd-analyze verify "$1/canemud.socket" "$unit" 2>&1) || true
  if [ -n "$out" ]; then
    echo "systemd-analyze verify ($3):" >&2
    echo "$out" >&2
    fail=1
  fi
  if report=$(systemd-analyze security --offline=yes --threshold="$2" "$unit" 2>&1); then
    echo "$3: $(echo "$report" | tail -1 | sed 's/^→ //')"
  else
    echo "$report" | grep '✗' >&2
    echo "$3: $(echo "$report" | tail -1 | sed 's/^→ //'), beyond $(($2 / 10)).$(($2 % 10))" >&2
    fail=1
  fi
}

# verify wants the programs the units run to exist: point them at this build.
for variant in default socketcan ip socketcan+ip cpu-latency; do
  mkdir -p "$dir/$variant/canemud.service.d"
  sed "s|/usr/bin/canemud|$canemud|g" "$src/systemd/canemud.service" >"$dir/$variant/canemud.service"
  cp "$src/systemd/canemud.socket" "$dir/$variant/"
  for dropin in ${variant//+/ }; do
    [ "$dropin" = default ] || cp "$src/systemd/canemud.service.d/$dropin.conf" "$dir/$variant/canemud.service.d/"
  done
done
check "$dir/default" 6 "canemud.service"
check "$dir/socketcan" 18 "with socketcan.conf"
check "$dir/ip" 18 "with ip.conf"
check "$dir/socketcan+ip" 18 "with socketcan.conf and ip.conf"
check "$dir/cpu-latency" 6 "with cpu-latency.conf"

# Without a drop-in the service may open AF_UNIX sockets only and has no network.
grep -qx "RestrictAddressFamilies=AF_UNIX" "$src/systemd/canemud.service" ||
  { echo "canemud.service allows more address families than AF_UNIX" >&2; fail=1; }
grep -qx "PrivateNetwork=yes" "$src/systemd/canemud.service" ||
  { echo "canemud.service has the host's network" >&2; fail=1; }
exit $fail
