#!/bin/sh
# Run inside the systemd guest by canemu-guest-tests.service (tests/guest/run-systemd-tests.sh),
# as root, from the unpacked second disk: this build's Debian package installed with dpkg and
# run by systemd as on a test rig, then the SocketCAN scenarios that need Debian's userland
# (python-can, tshark, ip netns, canbusload) against the service with the SocketCAN drop-in,
# then what upgrades, removal and purge do to the units. GUEST-PASS / GUEST-FAIL lines
# (guest-lib.sh) and a count the host reads.
. ./guest-lib.sh
echo "GUEST: systemd $(systemctl --version | head -1 | cut -d' ' -f2), tests start at $(cut -d' ' -f1 /proc/uptime) s of uptime"

show() {  # UNIT PROPERTY: the property's value
  systemctl show -p "$2" --value "$1"
}
journal_has() {  # TEXT: canemud's journal holds TEXT
  journalctl -q -o cat -u canemud.service | grep -q "$1"
}

status() {  # the package's state as dpkg-query abbreviates it ("ii": installed), or "none"
  st=$(dpkg-query -W -f='${db:Status-Abbrev}' canemu 2>/dev/null | tr -d ' ')
  [ -n "$st" ] && [ "$st" != un ] && echo "$st" || echo none
}
allow_and_add() {  # DROP-IN: the package's DROP-IN.conf linked for the service, stdin added to
  # its configuration (docs/security.md); both count from the service's next start
  mkdir -p /etc/systemd/system/canemud.service.d
  ln -s "/usr/share/canemu/systemd/$1.conf" /etc/systemd/system/canemud.service.d/
  systemctl daemon-reload
  cat >>/etc/canemu/canemud.toml
}
enabled() {  # UNIT...: what systemctl is-enabled says of each
  for u in "$@"; do
    systemctl is-enabled "$u" 2>/dev/null || true
  done | paste -sd' ' -
}

# 1. A failing systemd-sysusers fails the package's configuration, with a message, and nothing
# starts (here a broken line in an /etc/sysusers.d/canemu.conf that overrides the package's).
mkdir -p /etc/sysusers.d
echo "x this-is-no-sysusers-line" >/etc/sysusers.d/canemu.conf
dpkg -i ./canemu.deb >/tmp/dpkg0.log 2>&1
rc=$?
grep -q "canemu: systemd-sysusers could not create the user and group canemu" /tmp/dpkg0.log &&
  said=said || said=silent
result a_failing_sysusers_fails_the_configuration "1 said iF inactive inactive" \
  "$rc $said $(status) $(show canemud.socket ActiveState) $(show canemud.service ActiveState)"
[ $rc -ne 0 ] || cat /tmp/dpkg0.log
rm /etc/sysusers.d/canemu.conf

# 2. Configured again, the package creates the user and group, enables and starts the socket and
# the service: the socket listens with the documented owner and mode, and the service reaches
# "active (running)" only after READY=1 (Type=notify), confined to AF_UNIX without a network.
dpkg --configure canemu >/tmp/dpkg.log 2>&1
rc=$?
[ $rc -eq 0 ] || cat /tmp/dpkg.log
wait_for [ "$(show canemud.service SubState)" = running ]
result the_package_installs_and_the_service_is_ready "0 ii enabled enabled active running root:canemu 660 socket" \
  "$rc $(status) $(enabled canemud.socket canemud.service) $(show canemud.service ActiveState) $(show canemud.service SubState) $(stat -c '%U:%G %a %F' /run/canemu/canemud.sock)"
canemu status >/tmp/t-default 2>&1
result the_default_configuration_runs_with_af_unix_only "AF_UNIX yes yes can0" \
  "$(show canemud.service RestrictAddressFamilies) $(show canemud.service PrivateNetwork) $(show canemud.service PrivateMounts) $(grep -o '^can0' /tmp/t-default | head -1)"

# 3. Socket activation: with the service stopped, a client's connection starts it again.
systemctl stop canemud.service
before=$(show canemud.service ActiveState)
canemu --wait 30 status >/tmp/t2 2>&1
rc=$?
result socket_activation_starts_the_service "inactive 0 active can0" \
  "$before $rc $(show canemud.service ActiveState) $(grep -o '^can0' /tmp/t2 | head -1)"

# 4. Access by group: a member of group canemu connects, another user is refused by the
# socket's mode (0660 root:canemu).
useradd --no-create-home --groups canemu alice
useradd --no-create-home bob
setpriv --reuid=alice --regid=alice --init-groups canemu status >/tmp/t3a 2>&1
alice=$?
setpriv --reuid=bob --regid=bob --init-groups canemu status >/tmp/t3b 2>&1
bob=$?
result a_member_of_canemu_connects_and_another_user_is_refused \
  "0 can0 1 Permission denied" \
  "$alice $(grep -o '^can0' /tmp/t3a | head -1) $bob $(grep -o 'Permission denied' /tmp/t3b | head -1)"

# 5. systemctl reload with a broken configuration keeps the running one (same process, same buses).
pid=$(show canemud.service MainPID)
cp /etc/canemu/canemud.toml /tmp/canemud.toml.good
printf '[[bus]]\nname = \n' >>/etc/canemu/canemud.toml
systemctl reload canemud.service
WAIT_SECONDS=10 wait_for journal_has "configuration rejected"
rejected=$?
canemu status >/tmp/t4 2>&1
result a_reload_with_a_bad_file_keeps_the_configuration "0 $pid active 0 can0" \
  "$rejected $(show canemud.service MainPID) $(show canemud.service ActiveState) $(show canemud.service NRestarts) $(grep -o '^can0' /tmp/t4 | head -1)"
cp /tmp/canemud.toml.good /etc/canemu/canemud.toml

# 6. The watchdog: a loop stalled by the test hook (CANEMU_TEST_HOOKS, a drop-in with a 2 s
# watchdog) gets canemud killed and restarted by systemd.
mkdir -p /run/systemd/system/canemud.service.d
printf '[Service]\nEnvironment=CANEMU_TEST_HOOKS=stall-on-sigusr2\nWatchdogSec=2s\n' \
  >/run/systemd/system/canemud.service.d/stall.conf
systemctl daemon-reload
systemctl restart canemud.service
old=$(show canemud.service MainPID)
systemctl kill --kill-whom=main --signal=SIGUSR2 canemud.service
restarted() {
  [ "$(show canemud.service NRestarts)" -ge 1 ] && [ "$(show canemud.service SubState)" = running ] &&
    [ "$(show canemud.service MainPID)" != "$old" ]
}
WAIT_SECONDS=30 wait_for restarted
journal_has "Watchdog timeout" && watchdog=watchdog || watchdog=none
result the_watchdog_restarts_a_stalled_loop "1 running watchdog" \
  "$(show canemud.service NRestarts) $(show canemud.service SubState) $watchdog"
rm -r /run/systemd/system/canemud.service.d
systemctl daemon-reload

# 7. systemctl stop is clean: exit status 0, the socket stays with canemud.socket.
systemctl restart canemud.service
systemctl stop canemud.service
result systemctl_stop_is_clean "inactive success 0 active socket" \
  "$(show canemud.service ActiveState) $(show canemud.service Result) $(show canemud.service ExecMainStatus) $(show canemud.socket ActiveState) $(stat -c %F /run/canemu/canemud.sock)"

modprobe vcan
modprobe vxcan
modprobe can-raw
ip link add dev vcan0 type vcan && ip link set vcan0 up

# 8. As shipped, the service may not open CAN sockets: a SocketCAN bridge is refused, and the
# refusal names the drop-in that allows it.
canemu --wait 30 bridge add can0 vcan0 >/tmp/t-refused 2>&1
rc=$?
grep -q "vcan0: AF_CAN refused (no CAN in the kernel, or no drop-in socketcan.conf)" /tmp/t-refused &&
  said=said || said=silent
result a_socketcan_bridge_needs_the_drop_in "1 said" "$rc $said"
[ "$said" = said ] || cat /tmp/t-refused

# The SocketCAN scenarios run against the service with the drop-in that allows them, installed
# as docs/security.md says, and a bridge from can0 to vcan0 in the configuration.
systemctl stop canemud.service
allow_and_add socketcan <<'TOML'

[[bridge]]
kind = "socketcan"
bus = "can0"
interface = "vcan0"
TOML
systemctl start canemud.service
canemu --wait 30 status >/dev/null || journalctl -u canemud.service | tail -20

# 9. A python-can program on the emulated bus (interface "canemu") and one on vcan0 (python-can's
# socketcan) see each other's frames; candump on vcan0 shows the first one's.
n=$(receivers vcan0)
candump -L -n 1 vcan0 >/tmp/t7 &
pid=$!
wait_for more_receivers vcan0 "$n"
python3 - >/tmp/t7b 2>&1 <<'PY'
import can
emulated = can.Bus(interface="canemu", channel="can0")
kernel = can.Bus(interface="socketcan", channel="vcan0")
emulated.send(can.Message(arbitration_id=0x123, data=[1, 2], is_extended_id=False))
m = kernel.recv(10)
print("socketcan got", m and f"{m.arbitration_id:X}#{m.data.hex().upper()}")
kernel.send(can.Message(arbitration_id=0x1ABCDE, data=[3, 4, 5], is_extended_id=True))
m = emulated.recv(10)
print("canemu got", m and f"{m.arbitration_id:X}#{m.data.hex().upper()} ext={m.is_extended_id}")
emulated.shutdown()
kernel.shutdown()
PY
wait_pid $pid
result python_can_programs_on_both_sides_of_a_bridge "vcan0 123#0102
socketcan got 123#0102
canemu got 1ABCDE#030405 ext=True" "$(cut -d' ' -f2- /tmp/t7)
$(cat /tmp/t7b)"

# 10. tshark captures the emulated bus live on vcan0 and decodes it as Wireshark does.
tshark -i vcan0 -c 2 -a duration:60 -T fields -e can.id -e can.len -e data.data >/tmp/t8 2>/tmp/t8.err &
pid=$!
# "Capturing on" comes before dumpcap's packet socket runs: wait for that socket on vcan0
# (/proc/net/packet: Iface and R columns), or frames sent at once can be missed.
vcan0=$(cat /sys/class/net/vcan0/ifindex)
WAIT_SECONDS=60 wait_for awk -v i="$vcan0" 'NR > 1 && $5 == i && $6 == 1 {f = 1} END {exit !f}' \
  /proc/net/packet
canemu send can0 123#1122 7FF# >/dev/null
wait_pid $pid 60
result tshark_decodes_the_emulated_bus_on_vcan0 "291 2 1122|2047 0 |" "$(tr '\t\n' ' |' </tmp/t8)"
[ -s /tmp/t8 ] || sed 's/^/  tshark: /' /tmp/t8.err

# 11. vxcan into a network namespace: a program in the namespace (as in a container) and the
# emulated bus see each other's frames through a bridge added at run time.
ip netns add ecu
ip link add vxcan0 type vxcan peer name vxcan1 netns ecu
ip link set vxcan0 up
ip netns exec ecu ip link set vxcan1 up
canemu bridge add can0 vxcan0 >/tmp/t9
ip netns exec ecu candump -L -n 1 vxcan1 >/tmp/t9b &
pid=$!
WAIT_SECONDS=20 wait_for ip netns exec ecu grep -q " vxcan1 " /proc/net/can/rcvlist_all
canemu send can0 321#AB >/dev/null
wait_pid $pid
canemu dump can0 -n 1 >/tmp/t9c 2>/tmp/t9c.err &
pid=$!
wait_for listening /tmp/t9c.err
ip netns exec ecu cansend vxcan1 654#CD
wait_pid $pid
result vxcan_into_a_network_namespace "can0 bridged to vxcan0
vxcan1 321#AB
can0 654#CD" "$(cat /tmp/t9)
$(cut -d' ' -f2- /tmp/t9b)
$(cut -d' ' -f2- /tmp/t9c)"
canemu bridge remove vxcan0 >/dev/null

# 12. canbusload on vcan0 and canemu status agree on the load of can0 to 3 points, at a load of
# at least 10 % (so that the agreement means something). The load is the simulation's own, not a
# program's pacing, which a busy machine stretches: python-can's send_periodic puts a frame of 8
# bytes into the emulated adapter's cyclic transmit list, sent by its firmware at each 1 ms tick
# of simulated time, 5000 times (about 25 % of 500 kbit/s). Both figures are over stretches of
# simulated time that hold nothing but that list's frames, never over wall-clock windows:
# canemu status's load over the last simulated second, taken from a snapshot whose frame count
# says the list has run for more than a second and is still running; canbusload's count of the
# exact stuffed bits (intermission included, as canemu counts) of every frame the bridge wrote
# to vcan0, summed over all its lines once it has counted all 5000, over their 5 simulated
# seconds. canbusload's own per-second figures follow wall time and are only printed.
count=5000
can0_now() {  # can0's frame count and load in one snapshot of canemu status
  canemu status --json | python3 -c 'import json, sys
b = [b for b in json.load(sys.stdin)["buses"] if b["name"] == "can0"][0]
print(b["frames"], b["load_percent"])'
}
in_the_list_run() {  # a snapshot taken while the list runs, after its first second: $emulated
  snapshot=$(can0_now) || return 1
  sent=$((${snapshot% *} - before))
  emulated=${snapshot#* }
  if [ "$sent" -gt "$((count - 100))" ]; then
    emulated=missed  # the list had (nearly) ended: too late for a second of it alone
    return 0
  fi
  [ "$sent" -ge 1100 ]
}
counted() {  # the frames on canbusload's lines so far
  awk '/^ *vcan0@/ {n += $2} END {print n + 0}' /tmp/t10
}
all_counted() {
  [ "$(counted)" -ge "$count" ]
}
snapshot=$(can0_now)
before=${snapshot% *}
n=$(receivers vcan0)
canbusload -e vcan0@500000 >/tmp/t10 2>&1 &
cbl=$!
wait_for more_receivers vcan0 "$n"
python3 - "$count" >/tmp/t10py 2>&1 <<'PY' &
import signal, sys
import can
signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})
count = int(sys.argv[1])
bus = can.Bus(interface="canemu", channel="can0")
message = can.Message(arbitration_id=0x100, data=bytes(range(1, 9)), is_extended_id=False)
task = bus.send_periodic(message, 0.001, duration=count * 0.001)
print("sending with", type(task).__name__, flush=True)
signal.sigwait({signal.SIGTERM})
bus.shutdown()
PY
py=$!
emulated=none
if WAIT_SECONDS=60 wait_for grep -q "sending with" /tmp/t10py; then
  WAIT_SECONDS=60 wait_for in_the_list_run
  WAIT_SECONDS=60 wait_for all_counted
fi
kill $cbl
kill -TERM $py
wait_pid $py 30
frames=$(counted)
kernel=$(awk -v n="$count" '/^ *vcan0@/ {b += $3} END {printf "%.1f", b * 100 / (500 * n)}' /tmp/t10)
agree=$(awk -v a="$emulated" -v b="$kernel" 'BEGIN {d = a - b; if (d < 0) d = -d;
  print (a ~ /^[0-9.]+$/ && d <= 3 && a >= 10) ? "within 3 points" : "apart: canemu " a " %, canbusload " b " %"}')
result canbusload_agrees_with_canemu_status \
  "sending with CanemuCyclicTask, $count frames on vcan0, within 3 points" \
  "$(grep -o 'sending with [A-Za-z]*' /tmp/t10py), $frames frames on vcan0, $agree"
grep -q "sending with" /tmp/t10py || sed 's/^/  python: /' /tmp/t10py
echo "  (canemu status $emulated %, canbusload $kernel % over the list's $count ms;" \
  "canbusload per wall-clock second: $(awk '/^ *vcan0@/ {printf "%s ", $5}' /tmp/t10))"

# 13. With the IP drop-in linked too, LCM and DDS bridges open under the service (on lo: the
# guest has no other interface; LCM's UDP multicast needs a multicast route).
ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo
allow_and_add ip <<'TOML'

[[bridge]]
kind = "lcm"
bus = "can1"

[[bridge]]
kind = "dds"
bus = "can1"
TOML
systemctl restart canemud.service
canemu --wait 30 bridge list --json >/tmp/t13 2>&1 || journalctl -u canemud.service | tail -20
kinds=$(python3 -c 'import json, sys; print(" ".join(sorted(b["kind"] for b in json.load(sys.stdin))))' \
  </tmp/t13 2>/dev/null)
result lcm_and_dds_bridges_open_with_the_ip_drop_in "dds lcm socketcan" "$kinds"
[ "$kinds" = "dds lcm socketcan" ] || cat /tmp/t13

# 13a. simulation.cpu_latency_us: the confined service sees no /dev/cpu_dma_latency and says so;
# with cpu-latency.conf linked it holds the request. The key goes again at once: idle CPUs that
# poll would slow the rest of this emulated guest.
sed -i 's/^time = "realtime".*$/&\ncpu_latency_us = 0/' /etc/canemu/canemud.toml
systemctl restart canemud.service
wait_for journal_has "simulation.cpu_latency_us 0: no request made: /dev/cpu_dma_latency"
without=$?
allow_and_add cpu-latency </dev/null
systemctl restart canemud.service
wait_for journal_has "CPUs asked to wake within 0 us"
with=$?
owner=$(stat -c %U /dev/cpu_dma_latency)
result the_cpu_latency_request_needs_its_drop_in "0 0 canemu" "$without $with $owner"
[ "$without $with" = "0 0" ] || journalctl -q -o cat -u canemud.service | grep -i "latency" | tail -5
sed -i '/^cpu_latency_us = 0$/d' /etc/canemu/canemud.toml
systemctl restart canemud.service

# 14. An upgrade keeps the administrator's choice: units disabled while running stay disabled and
# are restarted (a new process runs the new program; no automatic restart, which a failure would
# cause); dpkg -i of the same version is an upgrade (the postinst gets the old version). dpkg -i
# can return while the restarted service is still starting (seen in start-pre), hence the wait.
systemctl disable --quiet canemud.socket canemud.service
pid=$(show canemud.service MainPID)
dpkg -i ./canemu.deb >/tmp/dpkg14.log 2>&1
rc=$?
[ $rc -eq 0 ] || cat /tmp/dpkg14.log
after=$(show canemud.service SubState)
WAIT_SECONDS=30 wait_for [ "$(show canemud.service SubState)" = running ]
new=$(show canemud.service MainPID)
[ "$new" != 0 ] && [ "$new" != "$pid" ] && restarted=restarted || restarted="not restarted ($pid, $new)"
got="$rc $(enabled canemud.socket canemud.service) $(show canemud.socket ActiveState) $(show canemud.service ActiveState) $restarted $(show canemud.service NRestarts)"
result an_upgrade_keeps_units_disabled_and_restarts_them "0 disabled disabled active active restarted 0" "$got"
echo "  (canemud.service was $after when dpkg -i returned)"
if [ "$got" != "0 disabled disabled active active restarted 0" ]; then
  cat /tmp/dpkg14.log
  systemctl status --no-pager canemud.socket canemud.service | sed 's/^/  /'
  journalctl -q --no-pager -n 30 -u canemud.socket -u canemud.service | sed 's/^/  /'
fi

# 15. An upgrade leaves stopped units stopped, and enabled ones enabled.
systemctl enable --quiet canemud.socket canemud.service
systemctl stop canemud.service canemud.socket
dpkg -i ./canemu.deb >/tmp/dpkg15.log 2>&1
rc=$?
[ $rc -eq 0 ] || cat /tmp/dpkg15.log
result an_upgrade_leaves_stopped_units_stopped "0 enabled enabled inactive inactive" \
  "$rc $(enabled canemud.socket canemud.service) $(show canemud.socket ActiveState) $(show canemud.service ActiveState)"

# 16. Upgraded from a version whose scripts enabled the units with systemctl (deb-systemd-helper
# has no record of them, as here once its records are deleted), disabled units stay disabled.
rm -f /var/lib/systemd/deb-systemd-helper-enabled/canemud.*
systemctl disable --quiet canemud.socket canemud.service
dpkg -i ./canemu.deb >/tmp/dpkg16.log 2>&1
rc=$?
[ $rc -eq 0 ] || cat /tmp/dpkg16.log
result an_upgrade_from_unrecorded_units_keeps_them_disabled "0 disabled disabled" \
  "$rc $(enabled canemud.socket canemud.service)"

# 17. Removal stops the units, masks them while their files are gone and keeps the configuration
# and the enabling, which a reinstallation restores (its units stay stopped until started or the
# next boot); purging forgets the enabling and the masks and removes the configuration.
systemctl enable --quiet canemud.socket canemud.service
systemctl start canemud.socket canemud.service
dpkg -r canemu >/tmp/dpkg17.log 2>&1
rc=$?
removed="$rc $(status) $(show canemud.service ActiveState) $(readlink /etc/systemd/system/canemud.service) $(readlink /etc/systemd/system/canemud.socket)"
[ -e /etc/canemu/canemud.toml ] && removed="$removed config" || removed="$removed no-config"
dpkg -i ./canemu.deb >>/tmp/dpkg17.log 2>&1
rc=$?
reinstalled="$rc $(status) $(enabled canemud.socket canemud.service) $(show canemud.service ActiveState)"
dpkg -P canemu >>/tmp/dpkg17.log 2>&1
rc=$?
left=$(find /etc/systemd/system /var/lib/systemd/deb-systemd-helper-enabled \
  /var/lib/systemd/deb-systemd-helper-masked \( -name canemud.service -o -name canemud.socket \
  -o -name 'canemud.*.dsh-also' \) 2>/dev/null | wc -l)
purged="$rc $(status) $left"
[ -e /etc/canemu/canemud.toml ] && purged="$purged config" || purged="$purged no-config"
result removal_keeps_the_choice_and_purge_forgets_it "0 rc inactive /dev/null /dev/null config
0 ii enabled enabled inactive
0 none 0 no-config" "$removed
$reinstalled
$purged"
[ "$purged" = "0 none 0 no-config" ] || cat /tmp/dpkg17.log

guest_summary
