# Sourced by the guest runners (run-guest-tests.sh, run-systemd-tests.sh) with $src (the source
# tree) and $guest (BUILD/guest) set: downloads the Debian packages of
# scripts/guest-packages.txt once into $guest/debs, unpacks them (not installed) into
# $guest/unpacked, and sets $kernel (the vmlinuz) and $modules (its /lib/modules/VERSION).
"$src/scripts/fetch-guest-packages.sh" "$guest/debs"
if [ ! -e "$guest/unpacked/.done" ] || [ -n "$(find "$guest/debs" -newer "$guest/unpacked/.done")" ]; then
  rm -rf "$guest/unpacked"
  mkdir -p "$guest/unpacked"
  for deb in "$guest"/debs/linux-image-[0-9]*.deb "$guest"/debs/busybox-static_*.deb \
             "$guest"/debs/can-utils_*.deb; do
    dpkg-deb -x "$deb" "$guest/unpacked"
  done
  touch "$guest/unpacked/.done"
fi
kernel=$(ls "$guest"/unpacked/boot/vmlinuz-* | head -1)
modules=$(ls -d "$guest"/unpacked/lib/modules/* | head -1)

# guest_result CONSOLE_LOG: exit status 0 when the guest's last GUEST-RESULT line counts no
# failure, 1 otherwise (also when the guest printed no result).
guest_result() {
  local result
  result=$(grep -a '^GUEST-RESULT: ' "$1" | tail -1 || true)
  if [ -z "$result" ]; then
    echo "guest: FAILED: no result on the console (see $1)"
    return 1
  fi
  case "$result" in
    *" 0 failed") return 0 ;;
    *) return 1 ;;
  esac
}
