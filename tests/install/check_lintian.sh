#!/bin/bash
# lintian on the Debian package that install.installs_and_packages built (BUILD/canemu_*.deb):
# every tag of every level it shows (errors, warnings, information) fails the test, except
# those the package itself overrides with a reason (packaging/debian/lintian-overrides, shipped
# as /usr/share/lintian/overrides/canemu; an override that no longer matches is reported as
# unused-override and fails too) and one accepted here: the default maintainer address
# canemu@localhost, which is no address (bogus-mail-host): a distributor sets their own with
# -DCANEMU_PACKAGE_CONTACT="Name <address>", and then lintian checks it like any other.
# Usage: check_lintian.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
build=$(cd "$2" && pwd)
fail() { echo "FAIL: $*" >&2; exit 1; }
command -v lintian >/dev/null || fail "lintian is missing (scripts/apt-packages.txt; make deps)"
debs=("$build"/canemu_*_amd64.deb)
[ ${#debs[@]} -eq 1 ] && [ -e "${debs[0]}" ] || fail "no single package in $build (make package)"
deb=${debs[0]}

out=$(lintian --display-info --fail-on none --tag-display-limit 0 "$deb" 2>&1) ||
  fail "lintian did not run: $out"
tags=$(grep -E '^[EWIPX]: ' <<<"$out" || true)
accepted=""
if [ "$(dpkg-deb -f "$deb" Maintainer)" = "canemu maintainers <canemu@localhost>" ]; then
  accepted='^E: canemu: bogus-mail-host(-in-debian-changelog)? (Maintainer )?canemu@localhost( |$)'
fi
unexpected=$(grep -Ev "${accepted:-^$}" <<<"$tags" | grep -v '^$' || true)
if [ -n "$unexpected" ]; then
  echo "lintian $(lintian --version | cut -d' ' -f2) on $(basename "$deb"):" >&2
  echo "$unexpected" >&2
  fail "lintian reports $(wc -l <<<"$unexpected") unexpected tag(s): fix them, or override one" \
       "with its reason in packaging/debian/lintian-overrides"
fi
overridden=$(lintian --show-overrides --display-info --fail-on none --tag-display-limit 0 "$deb" 2>&1 |
  grep -c '^O: ' || true)
echo "lintian: no unexpected tag ($overridden overridden with a reason$([ -n "$accepted" ] &&
  echo ", the placeholder maintainer address accepted"))"
