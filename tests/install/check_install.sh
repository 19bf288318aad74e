#!/bin/bash
# `make install` into a scratch DESTDIR, then use what it installed as a user would: the
# programs run, the configuration in /etc/canemu loads, a C program builds against the installed
# headers and libraries through pkg-config, the libraries carry sonames, python-can finds the
# canemu interface, the installed units verify. Then `make package` (CPack) and the package's
# contents and control data, leaving the package in BUILD_DIR for check_lintian.sh.
# Usage: check_install.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$1
build=$(cd "$2" && pwd)
dest=$(mktemp -d)
trap 'rm -rf "$dest"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

DESTDIR=$dest cmake --install "$build" --prefix /usr >/dev/null
libdir=$(ls -d "$dest"/usr/lib/x86_64-linux-gnu 2>/dev/null || echo "$dest/usr/lib")
for f in usr/bin/canemud usr/bin/canemu etc/canemu/canemud.toml \
         usr/lib/systemd/system/canemud.service usr/lib/systemd/system/canemud.socket \
         usr/lib/sysusers.d/canemu.conf usr/lib/tmpfiles.d/canemu.conf \
         usr/include/vci/vcinpl.h usr/include/vci/vcisdk.h usr/include/vci/cantype.h \
         usr/include/sorcus/xcan.h usr/include/sorcus/xcan_types.h \
         usr/include/sorcus/sl64lib.h usr/include/sorcus/sl64_types.h \
         usr/share/doc/canemu/security.md usr/share/canemu/examples/two-adapters.toml \
         usr/lib/python3/dist-packages/canemu/bus.py \
         usr/lib/cli/canemu/vcinet2.dll usr/lib/cli/canemu/vcinet2.dll.config; do
  [ -e "$dest/$f" ] || fail "$f was not installed"
done
for lib in vcinpl vcinpl2 vciapi xcan sl64; do
  soname=$(readelf -d "$libdir/lib$lib.so" | sed -n 's/.*SONAME.*\[\(.*\)\]/\1/p')
  [ "$soname" = "lib$lib.so.0" ] || fail "lib$lib.so has soname '$soname', not lib$lib.so.0"
done
# (grep reads what each command printed whole: with pipefail, `cmd | grep -q` fails whenever grep
# stops reading before cmd has written everything)
grep -q "configuration OK" <<<"$("$dest/usr/bin/canemud" --check-config "$dest/etc/canemu/canemud.toml")" ||
  fail "the installed configuration does not load"
grep -q "bits:" <<<"$("$dest/usr/bin/canemu" calc frame 123#11)" || fail "canemu calc does not run"
# A second install keeps the administrator's configuration.
echo "# edited by the administrator" >>"$dest/etc/canemu/canemud.toml"
DESTDIR=$dest cmake --install "$build" --prefix /usr >/dev/null
grep -qx "# edited by the administrator" "$dest/etc/canemu/canemud.toml" ||
  fail "a second install overwrote /etc/canemu/canemud.toml"

# A program of the user's own, built only from what was installed.
export PKG_CONFIG_PATH=$libdir/pkgconfig
cc -std=c99 -Wall -Werror -o "$dest/talk" "$src/client/examples/vci_c_talk.c" \
  $(pkg-config --cflags --libs canemu-vcinpl) || fail "vci_c_talk.c does not build against the install"
cc -std=c11 -Wall -Werror -o "$dest/xtalk" "$src/client/examples/xcan_talk.c" \
  $(pkg-config --cflags --libs canemu-xcan) || fail "xcan_talk.c does not build against the install"
cc -std=c11 -Wall -Werror -o "$dest/stalk" "$src/client/examples/sl64_talk.c" \
  $(pkg-config --cflags --libs canemu-sl64) || fail "sl64_talk.c does not build against the install"
grep -q "libvcinpl.so.0 => $libdir" <<<"$(LD_LIBRARY_PATH=$libdir ldd "$dest/talk")" ||
  fail "the program does not load the installed libvcinpl.so.0"
# A C# program against the installed VCI .NET assembly (docs/dotnet.md), when Mono is there;
# its dllmap names the installed soname.
if command -v mcs >/dev/null; then
  mcs -out:"$dest/dotnet_talk.exe" "$src/client/examples/dotnet/dotnet_talk.cs" \
    $(pkg-config --libs canemu-vcinet2) >/dev/null ||
    fail "dotnet_talk.cs does not build against the installed vcinet2.dll"
  grep -q 'target="libvcinpl2.so.0"' "$dest/usr/lib/cli/canemu/vcinet2.dll.config" ||
    fail "vcinet2.dll.config does not map libvcinpl2.so to libvcinpl2.so.0"
fi

PYTHONPATH=$dest/usr/lib/python3/dist-packages python3 - <<'PY' || fail "python-can or pytest does not find canemu"
from importlib.metadata import entry_points
names = [e.value for e in entry_points().select(group="can.interface") if e.name == "canemu"]
assert names == ["canemu.bus:CanemuBus"], names
plugins = [e.value for e in entry_points().select(group="pytest11") if e.name == "canemu"]
assert plugins == ["canemu.pytest_plugin"], plugins
# send's hot path in C is installed beside the package, where import finds it.
import canemu_speedups
assert canemu_speedups.__file__.endswith("/dist-packages/canemu_speedups.abi3.so"), canemu_speedups.__file__
PY

unit=$dest/usr/lib/systemd/system
sed -i "s|/usr/bin/canemud|$dest/usr/bin/canemud|g" "$unit/canemud.service"
out=$(systemd-analyze verify "$unit/canemud.socket" "$unit/canemud.service" 2>&1)
[ -z "$out" ] || fail "installed units: $out"

# The Debian package.
(cd "$build" && cpack -G DEB >/dev/null) || fail "cpack"
deb=$(ls "$build"/canemu_*_amd64.deb)
contents=$(dpkg-deb -c "$deb")
for f in ./usr/bin/canemud ./etc/canemu/canemud.toml ./usr/lib/systemd/system/canemud.socket \
         ./usr/lib/sysusers.d/canemu.conf ./usr/share/canemu/systemd/socketcan.conf \
         ./usr/share/canemu/systemd/ip.conf ./usr/share/canemu/systemd/cpu-latency.conf \
         ./usr/share/lintian/overrides/canemu \
         ./usr/lib/cli/canemu/vcinet2.dll; do
  grep -q " $f\$" <<<"$contents" || fail "the package lacks $f"
done
grep -q "systemd" <<<"$(dpkg-deb -f "$deb" Depends)" || fail "the package does not depend on systemd"
dpkg-deb -e "$deb" "$dest/control"
grep -qx /etc/canemu/canemud.toml "$dest/control/conffiles" || fail "canemud.toml is no conffile"
grep -q "activate-noawait ldconfig" "$dest/control/triggers" || fail "no ldconfig trigger"
grep -q "^libvcinpl 0 canemu" "$dest/control/shlibs" || fail "no shlibs for libvcinpl.so.0"
# The Description: the summary, then the text's lines each indented by one space (a CMake list
# joined into the text once began them with ";"). lintian runs in install.package_is_lintian_clean.
description=$(dpkg-deb -f "$deb" Description)
expected="emulated IXXAT and SORCUS CAN/LIN adapters
 canemud emulates IXXAT (VCI) and SORCUS CAN and LIN interface adapters
 down to the controller silicon, in real time; programs written for them
 link canemu's client libraries and run without hardware."
[ "$description" = "$expected" ] || fail "the package's Description is
$description"
echo "installed and packaged: $(basename "$deb"), $(wc -l <<<"$contents") entries"
