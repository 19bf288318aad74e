#!/usr/bin/env bash
# The installed package under a real systemd: builds this build tree's Debian package (CPack),
# boots Debian's linux-image-amd64 under qemu-system-x86_64 (TCG, or KVM with
# CANEMU_GUEST_ACCEL=kvm) with a Debian 12 root made by mmdebstrap (systemd, can-utils,
# python3-can, tshark, iproute2 and the package's dependencies; cached in BUILD/guest by the
# hash of what goes into it), and runs tests/guest/systemd-tests.sh in it as a systemd unit:
# the package installed with dpkg, the service and its socket, access by group, reload,
# watchdog and stop, and the SocketCAN scenarios that need a full Debian userland. Results on
# the serial console. Exit 0 when every guest test passed; 77 (ctest: skipped, never passed)
# only when a tool the guest needs is not installed.
# Usage: run-systemd-tests.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$(cd "${1:?usage: run-systemd-tests.sh SOURCE_DIR BUILD_DIR}" && pwd)
build=$(cd "${2:?usage: run-systemd-tests.sh SOURCE_DIR BUILD_DIR}" && pwd)
guest=$build/guest
start=$(date +%s.%N)
stamp() {
  awk "BEGIN {printf \"%.1f\", $(date +%s.%N) - $start}"
}

for tool in qemu-system-x86_64 cpio mmdebstrap mkfs.ext4 cpack; do
  if ! command -v $tool >/dev/null; then
    echo "guest: SKIPPED: $tool is not installed (make deps installs the guest's tools from" \
         "scripts/apt-packages-guest.txt)"
    exit 77
  fi
done

# The kernel and busybox (Debian packages, downloaded once into the build tree).
source "$src/tests/guest/guest-kernel.sh"

# 1. This build as a Debian package, as `make package` makes it.
pkg=$guest/package
rm -rf "$pkg"
mkdir -p "$pkg"
(cd "$build" && cpack -G DEB -B "$pkg" >"$pkg.log" 2>&1) || {
  cat "$pkg.log"
  echo "guest: FAILED: cpack could not build the package"
  exit 1
}
deb=$(ls "$pkg"/canemu_*.deb)
echo "guest: $(basename "$deb") built at $(stamp) s"

# 2. The Debian root: what scripts/guest-debian-packages.txt lists plus the package's own
# dependencies, so that dpkg -i works offline in the guest. Made once per content.
wanted=$(sed 's/#.*//' "$src/scripts/guest-debian-packages.txt" | tr -s ' \n' '\n' | grep -v '^$')
depends=$(dpkg-deb -f "$deb" Depends | tr ',' '\n' | sed 's/|.*//; s/(.*)//' | tr -d ' ')
packages=$(printf '%s\n%s\n' "$wanted" "$depends" | sort -u | paste -sd, -)
key=$( (echo "$packages" "$(basename "$kernel")"; cat "$src/tests/guest/debian-root.sh") |
  sha256sum | cut -c1-16)
image=$guest/debian-$key.img
if [ ! -e "$image" ]; then
  rm -f "$guest"/debian-*.img
  dir=$guest/debian-root
  rm -rf "$dir"
  echo "guest: making the Debian root with mmdebstrap ($packages)"
  mmdebstrap --quiet --variant=apt --include="$packages" bookworm "$dir" >"$guest/mmdebstrap.log" 2>&1 || {
    tail -20 "$guest/mmdebstrap.log"
    echo "guest: FAILED: mmdebstrap (is a Debian mirror reachable?)"
    exit 1
  }
  bash "$src/tests/guest/debian-root.sh" "$dir" "$modules"
  mkfs.ext4 -q -F -L canemu-guest -d "$dir" "$image.part" 1536M
  mv "$image.part" "$image"
  rm -rf "$dir"
  echo "guest: Debian root ready at $(stamp) s"
fi

# 3. The tests and the package on a second disk, as a tar archive the guest unpacks.
disk=$guest/systemd-tests
rm -rf "$disk"
mkdir -p "$disk"
cp "$deb" "$disk/canemu.deb"
cp "$src/tests/guest/systemd-tests.sh" "$src/tests/guest/guest-lib.sh" "$disk/"
tar -C "$disk" -cf "$guest/systemd-tests.tar" .

# 4. A tiny initramfs: busybox mounts the root disk and hands over to systemd.
initrd=$guest/debian-initrd
rm -rf "$initrd"
mkdir -p "$initrd"/{bin,dev,proc,sys,newroot,lib/modules}
cp "$guest/unpacked/bin/busybox" "$initrd/bin/"
for applet in sh mount umount insmod sleep switch_root poweroff echo; do
  ln -s busybox "$initrd/bin/$applet"
done
root_modules="crc32c_generic crc16 mbcache jbd2 ext4 virtio_ring virtio virtio_pci_legacy_dev
  virtio_pci_modern_dev virtio_pci virtio_blk"
for m in $root_modules; do
  cp "$(find "$modules" -name "$m.ko")" "$initrd/lib/modules/"
done
cat >"$initrd/init" <<INIT
#!/bin/sh
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
for m in $(echo $root_modules); do insmod /lib/modules/\$m.ko; done
i=0
while [ ! -b /dev/vda ] && [ \$i -lt 200 ]; do sleep 0.05; i=\$((i + 1)); done
if ! mount -t ext4 /dev/vda /newroot; then
  echo "GUEST-RESULT: the root disk did not mount, 1 failed"
  poweroff -f
fi
umount /proc /sys /dev
exec switch_root /newroot /lib/systemd/systemd
INIT
chmod +x "$initrd/init"
(cd "$initrd" && find . | cpio -o -H newc --quiet) >"$guest/debian-initrd.cpio"

accel=${CANEMU_GUEST_ACCEL:-tcg}
echo "guest: booting $(basename "$kernel") with systemd under qemu ($accel) at $(stamp) s"
console=$guest/systemd-console.log
set +e
timeout 420 qemu-system-x86_64 -accel "$accel" -cpu max -m 1024 -smp 2 -nographic -no-reboot -nic none \
  -kernel "$kernel" -initrd "$guest/debian-initrd.cpio" \
  -drive "file=$image,format=raw,if=virtio,snapshot=on" \
  -drive "file=$guest/systemd-tests.tar,format=raw,if=virtio,readonly=on" \
  -append "console=ttyS0 loglevel=3 panic=-1 rdinit=/init systemd.show_status=0 net.ifnames=0" \
  </dev/null | tr -d '\r' | tee "$console"
status=${PIPESTATUS[0]}
set -e
echo "guest: qemu exited with $status after $(stamp) s in all"
guest_result "$console"
