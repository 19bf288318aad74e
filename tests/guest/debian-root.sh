#!/usr/bin/env bash
# Finishes the Debian root of the systemd guest (run-systemd-tests.sh; its hash is part of the
# cached image's name, so a change here makes a new image): the kernel's modules, a quiet boot
# (no getty on the console, no timers), and the unit that runs the tests and powers off.
# Usage: debian-root.sh ROOT_DIR MODULES_DIR (run as root: depmod runs in a chroot)
set -euo pipefail
dir=${1:?usage: debian-root.sh ROOT_DIR MODULES_DIR}
modules=${2:?usage: debian-root.sh ROOT_DIR MODULES_DIR}
version=$(basename "$modules")
# Only the CAN modules (the rest of the 400 MB stays out): modprobe finds them after depmod.
target=$dir/lib/modules/$version
mkdir -p "$target/kernel/net" "$target/kernel/drivers/net"
cp -a "$modules"/modules.order "$modules"/modules.builtin* "$target/"
cp -a "$modules/kernel/net/can" "$target/kernel/net/"
cp -a "$modules/kernel/drivers/net/can" "$target/kernel/drivers/net/"
chroot "$dir" depmod "$version"

echo canemu-guest >"$dir/etc/hostname"
echo "/dev/vda / ext4 rw 0 0" >"$dir/etc/fstab"
systemd=$dir/etc/systemd/system
for unit in serial-getty@ttyS0.service getty@tty1.service getty.target systemd-timesyncd.service \
            apt-daily.timer apt-daily-upgrade.timer e2scrub_all.timer e2scrub_reap.service \
            fstrim.timer man-db.timer dpkg-db-backup.timer systemd-tmpfiles-clean.timer; do
  ln -sf /dev/null "$systemd/$unit"
done
cat >"$systemd/canemu-guest-tests.service" <<'UNIT'
[Unit]
Description=canemu guest tests (tests/guest/systemd-tests.sh from the second disk)
After=multi-user.target
SuccessAction=poweroff-force
FailureAction=poweroff-force

[Service]
Type=oneshot
StandardOutput=tty
StandardError=tty
TTYPath=/dev/ttyS0
TimeoutStartSec=infinity
ExecStart=/bin/sh -c 'mkdir -p /t && tar -xf /dev/vdb -C /t && cd /t && sh ./systemd-tests.sh'

[Install]
WantedBy=multi-user.target
UNIT
mkdir -p "$systemd/multi-user.target.wants"
ln -sf ../canemu-guest-tests.service "$systemd/multi-user.target.wants/canemu-guest-tests.service"
