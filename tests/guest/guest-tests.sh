#!/bin/sh
# The SocketCAN scenarios, run inside the guest by its /init (tests/guest/run-guest-tests.sh):
# can-utils on vcan interfaces bridged to canemud's emulated buses. Each test prints
# GUEST-PASS or GUEST-FAIL with what it expected and got; the last line is the count.
. /guest-lib.sh

for m in can can-raw can-bcm can-gw can-dev vcan vxcan; do
  insmod "/lib/modules/$m.ko" || echo "GUEST-FAIL insmod $m"
done
ip link add dev vcan0 type vcan && ip link set vcan0 up
ip link add dev vcan1 type vcan && ip link set vcan1 mtu 72 up
ip link add dev vcan2 type vcan && ip link set vcan2 up
ip link add dev vcan3 type vcan && ip link set vcan3 up
ip link add dev vcan4 type vcan && ip link set vcan4 mtu 72 up
ip link add dev vcan5 type vcan && ip link set vcan5 mtu 16 up
echo "GUEST: a new vcan's MTU: $(cat /sys/class/net/vcan0/mtu) (vcan0 as created)"

cat > /tmp/canemu.toml <<'TOML'
[[bus]]
name = "can0"
[[bus]]
name = "fd0"
kind = "can-fd"
bitrate = 500000
data_bitrate = 2000000
[[bus]]
name = "can1"
[[device]]
name = "ixxat0"
model = "ixxat-usb-to-can"
controllers = ["can0"]
[[bridge]]
kind = "socketcan"
bus = "can0"
interface = "vcan0"
[[bridge]]
kind = "socketcan"
bus = "fd0"
interface = "vcan1"
[[bridge]]
kind = "socketcan"
bus = "can1"
interface = "vcan2"
error_frames = true
TOML
canemud --config /tmp/canemu.toml --socket /tmp/canemud.sock 2>/tmp/canemud.log &
export CANEMU_SOCKET=/tmp/canemud.sock
if ! canemu --wait 10 status >/dev/null; then
  echo "GUEST-FAIL canemud did not start:"
  cat /tmp/canemud.log
fi

# 1. candump on the interface shows what emulated nodes send.
n=$(receivers vcan0)
candump -L -n 2 vcan0 >/tmp/t1 &
pid=$!
wait_for more_receivers vcan0 "$n"
canemu send can0 123#1122 12345678#R4 >/dev/null
wait_pid $pid
result candump_shows_the_emulated_bus "vcan0 123#1122
vcan0 12345678#R4" "$(cut -d' ' -f2- /tmp/t1)"

# 2. cansend with an extended identifier reaches the emulated bus.
canemu dump can0 -n 1 >/tmp/t2 2>/tmp/t2.err &
pid=$!
wait_for listening /tmp/t2.err
cansend vcan0 1ABCDEF0#AABB
wait_pid $pid
result cansend_extended_id_reaches_the_bus "can0 1ABCDEF0#AABB" "$(cut -d' ' -f2- /tmp/t2)"

# 3. CAN FD both ways on an FD bus (vcan1 at MTU 72).
canemu dump fd0 -n 1 >/tmp/t3 2>/tmp/t3.err &
pid=$!
wait_for listening /tmp/t3.err
cansend vcan1 123##1112233445566778899AABBCC
wait_pid $pid
n=$(receivers vcan1)
candump -L -n 1 vcan1 >/tmp/t3b &
pid=$!
wait_for more_receivers vcan1 "$n"
canemu send fd0 456##1AABBCCDDEEFF001122334455 >/dev/null
wait_pid $pid
# candump prints the whole flags byte: BRS and CANFD_FDF, which the kernel sets on FD frames.
result can_fd_both_ways "fd0 123##1112233445566778899AABBCC
vcan1 456##5AABBCCDDEEFF001122334455" "$(cut -d' ' -f2- /tmp/t3)
$(cut -d' ' -f2- /tmp/t3b)"

# 4. Error frames: a sender at 250 kbit/s on the 500 kbit/s bus can1; the bridge's node
# detects the errors and writes them to vcan2 as CAN_ERR_PROT | BUSERROR | CNT frames.
n=$(receivers vcan2)
candump -L -n 1 vcan2,#1FFFFFFF >/tmp/t4 &
pid=$!
wait_for more_receivers vcan2 "$n"
canemu send can1 100#11 --bitrate 250000 --timeout 200 >/dev/null 2>&1
wait_pid $pid
result error_frames_as_candump_reads_them "vcan2 20000288" "$(cut -d' ' -f2- /tmp/t4 | cut -d'#' -f1)"

# 5. cangen at full speed: every frame arrives, at the emulated bus's rate (1000 frames of 8
# bytes take at least 999 x 111 bits x 2 us = 0.221778 s of simulated time).
canemu dump can0 -n 1000 --sim-time >/tmp/t5 2>/tmp/t5.err &
pid=$!
wait_for listening /tmp/t5.err
cangen vcan0 -g 0 -p 10 -n 1000 -I 100 -L 8 -D i
wait_pid $pid 30
span=$(awk '{t = substr($1, 2, length($1) - 2); if (NR == 1) f = t; l = t}
            END {print (l - f >= 0.221778) ? "at or below the bus rate" : "faster than the bus: " l - f}' /tmp/t5)
result cangen_arrives_whole_at_the_bus_rate "1000 at or below the bus rate" "$(wc -l </tmp/t5) $span"

# 6. More than the bus can take: what the bridge could not send is counted, nothing vanishes
# (sent on the bus, dropped at the full queue, or dropped by the kernel before it was read).
# `canemu bridge list --json` one bridge per line (its nested "rejected_by" table flattened,
# so that a line holds the whole entry).
bridge_entries() {
  canemu bridge list --json | sed 's/"rejected_by" *: *{[^}]*}/"rejected_by": 0/g' | tr '}' '\n'
}
accounted() {
  bridge_entries | grep '"vcan0"' | awk -F'[:,]' '{
    for (i = 1; i < NF; i++) if ($i ~ /"(from_interface|queue_dropped|rejected|kernel_dropped)"/) s += $(i + 1)
  } END {print s + 0}'
}
reached() {
  [ "$(accounted)" -eq "$1" ]
}
# An acknowledging node on can0 (alone, the bridge's node would get no ACK and retry forever).
canemu dump can0 --no-errors >/dev/null 2>/tmp/t6.err &
ack=$!
wait_for listening /tmp/t6.err
before=$(accounted)
cangen vcan0 -g 0 -p 10 -n 3000 -I 200 -L 8  # -p: cangen itself waits rather than drop
wait_for reached $((before + 3000))
result every_frame_sent_or_counted "3000" "$(($(accounted) - before))"
kill $ack
canemu bridge list

# 7. A VCI program (the VCI C API's example, on the emulated adapter ixxat0 of can0) and
# can-utils on vcan0 see each other's frames.
n=$(receivers vcan0)
candump -L -n 1 vcan0 >/tmp/t7 &
pid=$!
wait_for more_receivers vcan0 "$n"
vci_c_talk send ixxat0 321 5A
wait_pid $pid
vci_c_talk receive ixxat0 >/tmp/t7b 2>&1 &
pid=$!
wait_for grep -q ready /tmp/t7b
cansend vcan0 1A0#7E
wait_pid $pid
result a_vci_program_and_can_utils_see_each_other "vcan0 321#5A
ready
1A0#7E" "$(cut -d' ' -f2- /tmp/t7)
$(cat /tmp/t7b)"

# 8. A bridge added while canemud runs: cansequence from vcan3 through can0 to vcan0 loses
# nothing (1000 frames, within the bridge's queue); then the bridge is removed.
written() {  # frames the bridge of $1 wrote to its interface
  bridge_entries | grep "\"$1\"" | sed 's/.*"to_interface" *: *\([0-9]*\).*/\1/'
}
wrote() {  # INTERFACE COUNT
  [ "$(written "$1")" -ge "$2" ]
}
canemu bridge add can0 vcan3 >/tmp/t8
n=$(receivers vcan0)
cansequence -r --quit=1 vcan0 >/tmp/t8.rx 2>&1 &
rx=$!
wait_for more_receivers vcan0 "$n"
start=$(written vcan0)
cansequence -p --loop=1000 vcan3
wait_for wrote vcan0 $((start + 1000))
alive=lost
kill -0 $rx 2>/dev/null && alive="nothing lost"
kill $rx
[ "$alive" = lost ] && cat /tmp/t8.rx
canemu bridge remove vcan3 >>/tmp/t8
result cansequence_through_a_bridge_added_at_run_time "can0 bridged to vcan3
$((start + 1000)) nothing lost
bridge on vcan3 removed
0" "$(head -1 /tmp/t8)
$(written vcan0) $alive
$(tail -1 /tmp/t8)
$(canemu bridge list --json | grep -c vcan3)"

# 9. A SocketCAN program and an emulated adapter at the wrong bit rate on one bus: the adapter
# (a dump at 250 kbit/s on the 500 kbit/s bus can1) cannot decode the frame cansend puts on
# vcan2 and reports errors; its error flags destroy the frame, the bridge's node retransmits,
# and with error_frames the bridge shows its own errors on vcan2 (docs/concepts.md: nodes whose
# timing disagrees cannot decode each other).
canemu dump can1 --bitrate 250000 -n 1 >/tmp/t9 2>/tmp/t9.err &
pid=$!
wait_for listening /tmp/t9.err
n=$(receivers vcan2)
candump -L -n 2 vcan2,#1FFFFFFF >/tmp/t9b &  # cansend's frame (the kernel's local echo), then
cd=$!                                        # the bridge's first error frame
wait_for more_receivers vcan2 "$n"
cansend vcan2 123#1122
wait_pid $pid
wait_pid $cd
result a_socketcan_program_and_an_adapter_at_the_wrong_rate "can1 200002 vcan2 123#1122 vcan2 200002" \
  "$(cut -d' ' -f2- /tmp/t9 | cut -c1-11) $(head -1 /tmp/t9b | cut -d' ' -f2-) $(tail -1 /tmp/t9b | cut -d' ' -f2- | cut -c1-12)"
canemu bridge remove vcan2 >/dev/null

# 10. Bus-off and restart: a fault rule gives the bridge's frame 321 32 bit errors, which take
# its node bus-off (TEC 256); 100 ms later (restart_ms) it restarts, as `ip link set ... type can
# restart-ms 100` makes a kernel driver do, writes CAN_ERR_RESTARTED, recovers, and sends the
# frame its transmit buffer kept to the emulated node that listens.
canemu bridge add can1 vcan3 --error-frames --restart-ms 100 >/dev/null
canemu fault inject --effect bit_error --bus can1 --id 0x321 --count 32 >/dev/null
canemu dump can1 -n 1 --no-errors >/tmp/t10 2>/tmp/t10.err &
pid=$!
wait_for listening /tmp/t10.err
n=$(receivers vcan3)
candump -L vcan3,#1FFFFFFF >/tmp/t10b &
cd=$!
wait_for more_receivers vcan3 "$n"
cansend vcan3 321#AB
wait_pid $pid 20
kill $cd
restarts=$(bridge_entries | grep '"vcan3"' | sed 's/.*"restarts" *: *\([0-9]*\).*/\1/')
result a_bridge_restarts_after_bus_off "can1 321#AB
bus-off 1, restarted 1, restarts 1" "$(cut -d' ' -f2- /tmp/t10)
bus-off $(grep -c ' 20000240#' /tmp/t10b), restarted $(grep -c ' 20000100#' /tmp/t10b), restarts $restarts"
canemu bridge remove vcan3 >/dev/null

# 11. What a classic bus cannot carry, written on its interface (vcan4 at MTU 72, so that
# cansend may write CAN FD there): a CAN FD frame and an error frame reach the bridge, are
# counted as rejected and logged with the reason; a frame after them goes out.
rejected() {  # the bridge of $1's rejected count
  bridge_entries | grep "\"$1\"" | sed 's/.*"rejected" *: *\([0-9]*\).*/\1/'
}
rejected_reached() {  # INTERFACE COUNT
  [ "$(rejected "$1")" -ge "$2" ]
}
canemu bridge add can0 vcan4 >/dev/null
canemu dump can0 -n 1 >/tmp/t11 2>/tmp/t11.err &
pid=$!
wait_for listening /tmp/t11.err
cansend vcan4 123##1AABB
cansend vcan4 20000080#0000000000000000
cansend vcan4 321#01
wait_pid $pid
wait_for rejected_reached vcan4 2
result what_a_classic_bus_cannot_carry_is_rejected_with_the_reason "can0 321#01
rejected 2
the CAN FD frame 123##1AABB (the bus is a classic CAN bus)
the error frame 20000080#0000000000000000 (an error frame reports what a controller saw; it is no frame to send on a bus)" \
  "$(cut -d' ' -f2- /tmp/t11)
rejected $(rejected vcan4)
$(grep 'bridge on vcan4: rejected' /tmp/canemud.log | sed 's/.*: rejected //')"
canemu bridge remove vcan4 >/dev/null

# 12. Error frames as Debian 12's candump (can-utils 2020.11) shows them: `candump -e vcan4`
# alone sets no error mask and shows none; with `,#FFFFFFFF` they come, and for a class with
# CAN_ERR_CNT (0x200, newer than this candump) it says "Error class 0x288 is invalid" on stderr
# and prints the frame's line again instead of the words.
canemu bridge add can1 vcan4 --error-frames >/dev/null
n=$(receivers vcan4)
candump -e vcan4 >/tmp/t12a 2>&1 &
plain=$!
candump -e -n 1 vcan4,0:0,#FFFFFFFF >/tmp/t12b 2>/tmp/t12b.err &
pid=$!
wait_for more_receivers vcan4 $((n + 1))
canemu send can1 100#11 --bitrate 250000 --timeout 200 >/dev/null 2>&1
wait_pid $pid
kill $plain
tab=$(printf '\t')
result candump_e_shows_error_frames_with_a_mask_only "0 lines
  vcan4  20000288   [8]  00 00 04 05 00 00 00 01   ERRORFRAME
${tab}20000288   [8]  00 00 04 05 00 00 00 01   ERRORFRAME
Error class 0x288 is invalid" "$(wc -l </tmp/t12a) lines
$(cat /tmp/t12b)
$(cat /tmp/t12b.err)"
canemu bridge remove vcan4 >/dev/null

# 13. A CAN FD bus bridged to an interface at MTU 16 (vcan5): added, with a warning that says
# what will not pass and how to raise the MTU.
canemu bridge add fd0 vcan5 >/tmp/t13 2>/tmp/t13.err
result an_fd_bus_on_a_classic_mtu_interface_is_warned_about "fd0 bridged to vcan5
canemu: warning: vcan5 has MTU 16, not 72 (CAN FD): the CAN FD frames of fd0 cannot be written to it (counted as IF-DROP) and programs cannot send CAN FD frames on it; classic frames pass. For CAN FD: ip link set vcan5 down; ip link set vcan5 mtu 72 up" \
  "$(cat /tmp/t13 /tmp/t13.err)"
canemu bridge remove vcan5 >/dev/null

canemu status
guest_summary
