#!/usr/bin/env bash
# The SocketCAN bridge in a real Linux kernel: boots Debian's linux-image-amd64 under
# qemu-system-x86_64 (TCG, or KVM with CANEMU_GUEST_ACCEL=kvm) with an initramfs of busybox, the
# CAN modules (can, can-raw, can-bcm, can-gw, can-dev, vcan, vxcan), can-utils, and this build's
# canemud and canemu with the host's libraries they link; runs tests/guest/guest-tests.sh in it
# (results on the serial console) and powers off. Exit 0 when every guest test passed; 77 (ctest:
# skipped, never passed) only when qemu is not installed.
# Usage: run-guest-tests.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$(cd "${1:?usage: run-guest-tests.sh SOURCE_DIR BUILD_DIR}" && pwd)
build=$(cd "${2:?usage: run-guest-tests.sh SOURCE_DIR BUILD_DIR}" && pwd)
guest=$build/guest
start=$(date +%s.%N)

if ! command -v qemu-system-x86_64 >/dev/null || ! command -v cpio >/dev/null; then
  echo "guest: SKIPPED: qemu-system-x86_64 or cpio is not installed (make deps installs them" \
       "from scripts/apt-packages-guest.txt)"
  exit 77
fi

# The kernel, busybox and can-utils (Debian packages, downloaded once into the build tree).
source "$src/tests/guest/guest-kernel.sh"
x=$guest/unpacked

# The initramfs, made afresh (the binaries change with every build).
root=$guest/root
rm -rf "$root"
mkdir -p "$root"/{bin,sbin,usr/bin,usr/sbin,proc,sys,dev,tmp,run,lib/modules,etc}
cp "$x/bin/busybox" "$root/bin/busybox"
for applet in $("$root/bin/busybox" --list-full); do
  [ -e "$root/$applet" ] || ln -s /bin/busybox "$root/$applet"
done
for m in can can-raw can-bcm can-gw can-dev vcan vxcan; do
  cp "$(find "$modules" -name "$m.ko")" "$root/lib/modules/"
done
for tool in candump cansend cangen cansequence canbusload; do  # libc only
  cp "$x/usr/bin/$tool" "$root/usr/bin/"
done
# canemud, canemu and can-utils with the shared libraries they load (the host's).
# Each library also goes where the guest's loader searches by default: a build tree under /tmp
# (a CI clone) is hidden by the guest's own /tmp, so its RUNPATH finds nothing there.
# Copies without debug information: a RelWithDebInfo build's would fill most of the guest's
# 512 MiB twice over (the initramfs and what the kernel unpacks from it).
copy_with_libs() {
  cp "$1" "$root/usr/bin/"
  strip --strip-debug "$root/usr/bin/$(basename "$1")"
  mkdir -p "$root/lib/x86_64-linux-gnu"
  for lib in $(ldd "$1" | awk '/=> \// {print $3} /^\t\/lib/ {print $1}'); do
    mkdir -p "$root$(dirname "$lib")"
    for to in "$root$lib" "$root/lib/x86_64-linux-gnu/$(basename "$lib")"; do
      cp -L "$lib" "$to"
      strip --strip-debug "$to"
    done
  done
}
copy_with_libs "$build/bin/canemud"
copy_with_libs "$build/bin/canemu"
copy_with_libs "$x/usr/bin/candump"
copy_with_libs "$build/bin/vci_c_talk"
mkdir -p "$root/lib64"
cp -L /lib64/ld-linux-x86-64.so.2 "$root/lib64/"
cp "$src/tests/guest/guest-tests.sh" "$src/tests/guest/guest-lib.sh" "$root/"
cat > "$root/init" <<'INIT'
#!/bin/sh
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mount -t tmpfs tmp /tmp
echo "GUEST: kernel $(uname -r), tests start at $(cut -d' ' -f1 /proc/uptime) s of uptime"
sh /guest-tests.sh
echo "GUEST: done at $(cut -d' ' -f1 /proc/uptime) s of uptime"
poweroff -f
INIT
chmod +x "$root/init" "$root/guest-tests.sh"
(cd "$root" && find . | cpio -o -H newc --quiet) > "$guest/initramfs.cpio"

# TCG by default: it runs everywhere (nested KVM on a VM can be slower than TCG);
# CANEMU_GUEST_ACCEL=kvm asks for KVM.
accel=${CANEMU_GUEST_ACCEL:-tcg}
echo "guest: booting $(basename "$kernel") under qemu ($accel)"
console=$guest/console.log
set +e
timeout 180 qemu-system-x86_64 -accel "$accel" -cpu max -m 512 -smp 1 -nographic -no-reboot \
  -kernel "$kernel" -initrd "$guest/initramfs.cpio" \
  -append "console=ttyS0 loglevel=4 panic=-1 rdinit=/init" </dev/null | tr -d '\r' | tee "$console"
status=${PIPESTATUS[0]}
set -e
end=$(date +%s.%N)
echo "guest: qemu exited with $status after $(awk "BEGIN {printf \"%.1f\", $end - $start}") s in all"
guest_result "$console"
