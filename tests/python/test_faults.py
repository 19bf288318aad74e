"""Every fault effect against a running canemud, loaded at run time with `canemu fault load`,
seen through python-can: error frames, counters, states, frames that do or do not arrive.
Stepped time, so every figure is exact; a fresh daemon per test."""

from __future__ import annotations

import subprocess

import can
import pytest

import canemu
from canemu.bus import (
    CAN_ERR_ACK,
    CAN_ERR_BUSERROR,
    CAN_ERR_BUSOFF,
    CAN_ERR_CRTL,
    CAN_ERR_CRTL_TX_WARNING,
    CAN_ERR_PROT,
    CAN_ERR_PROT_BIT,
    CAN_ERR_PROT_FORM,
    CAN_ERR_PROT_LOC_CRC_SEQ,
    CAN_ERR_PROT_STUFF,
    CAN_ERR_TRX,
)

from conftest import (CANEMU_CLI, Canemud, bus_errors, drain, fault, fault_load, frames, load, ns,
                      scenario)

US = 1_000
MS = 1_000_000






def msg(arbitration_id=0x123, data=(1, 2)):
    return can.Message(arbitration_id=arbitration_id, data=list(data), is_extended_id=False)


def one_frame_under(daemon, a, b, **fault_fields):
    """a sends one frame while a fault of `fault_fields` hits every frame on can0 from 0 s;
    what b received in the next 10 ms: its frames, and its bus errors."""
    load(daemon, scenario(fault(at="0s", bus="can0", **fault_fields)))
    a.send(msg())
    canemu.step(10 * MS)
    got_b = drain(b)
    return frames(got_b), bus_errors(got_b)


def now_ns():
    return canemu.sim_time()[0]


def test_bit_errors_take_the_sender_to_bus_off_at_the_32nd(daemon, nodes):
    a, b = nodes
    start = now_ns()
    load(daemon, scenario(
        fault(at="1ms", bus="can0", match={"from": a.node_name}, effect="bit_error", count=32)))
    a.send(msg())  # before the window: acknowledged, untouched
    canemu.step(500 * US)
    assert len(frames(drain(b))) == 1
    canemu.step(600 * US)
    a.send(msg())
    canemu.step(50 * MS)
    seen = drain(a)
    errors = bus_errors(seen)
    assert len(errors) == 32
    assert all(e.arbitration_id == CAN_ERR_PROT | CAN_ERR_BUSERROR for e in errors)
    assert all(e.data[2] == CAN_ERR_PROT_BIT for e in errors)
    assert errors[0].timestamp >= (start + MS) / 1e9
    warning = [m for m in seen if m.arbitration_id == CAN_ERR_CRTL]
    assert len(warning) == 1 and seen.index(warning[0]) == 12  # TEC 96 after the 12th
    assert seen[-1].arbitration_id & CAN_ERR_BUSOFF and seen[-1].data[6] == 255
    assert a.controller_state == canemu.ControllerState.BUS_OFF
    assert a.error_counters()[0] == 256
    assert frames(drain(b)) == []


def test_stuff_errors_are_detected_by_the_receivers(daemon, nodes):
    a, b = nodes
    load(daemon, scenario(
        fault(at="0s", bus="can0", match={"id": 0x123, "mask": 0x7FF}, effect="stuff_error",
              count=3)))
    a.send(msg(0x124))  # does not match
    a.send(msg(0x123))
    canemu.step(10 * MS)
    got_b = drain(b)
    assert [m.arbitration_id for m in frames(got_b)] == [0x124, 0x123]
    errors_b = bus_errors(got_b)
    assert len(errors_b) == 3
    assert all(e.data[2] == CAN_ERR_PROT_STUFF for e in errors_b)
    assert len(bus_errors(drain(a))) == 3
    # Transmitter: +8 per error flag, -1 per success after them. Receiver: +1 for the error it
    # detects, +8 because the transmitter's flag (started when it saw theirs) is still dominant
    # right after its own, -1 for the success.
    assert a.error_counters() == (3 * 8 - 1, 0)
    assert b.error_counters() == (0, 3 * 9 - 1)


def test_form_errors_at_the_crc_delimiter(daemon, nodes):
    a, b = nodes
    frames_b, errors_b = one_frame_under(daemon, a, b, effect="form_error", count=2)
    assert len(frames_b) == 1
    assert len(errors_b) == 2 and all(e.data[2] == CAN_ERR_PROT_FORM for e in errors_b)
    # The transmitter only notices at the ACK delimiter (the receivers' flag there), so its
    # flag overruns theirs: receivers +1 +8 per error, as with stuff errors.
    assert a.error_counters() == (2 * 8 - 1, 0)
    assert b.error_counters() == (0, 2 * 9 - 1)


def test_crc_error_leaves_the_frame_unacknowledged(daemon, nodes):
    a, b = nodes
    frames_b, errors_b = one_frame_under(daemon, a, b, effect="crc_error", count=1)
    assert len(frames_b) == 1  # the repetition
    assert len(errors_b) == 1 and errors_b[0].data[3] == CAN_ERR_PROT_LOC_CRC_SEQ
    errors_a = bus_errors(drain(a))
    assert len(errors_a) == 1 and errors_a[0].arbitration_id & CAN_ERR_ACK
    assert a.error_counters() == (8 - 1, 0)
    assert b.error_counters() == (0, 0)


def test_ack_errors_hit_only_the_matching_frames(daemon, nodes):
    a, b = nodes
    load(daemon, scenario(
        fault(at="0s", bus="can0", match={"id": 0x123}, effect="ack_error", count=3)))
    a.send(msg(0x100))
    a.send(msg(0x123))
    canemu.step(10 * MS)
    assert [m.arbitration_id for m in frames(drain(b))] == [0x100, 0x123]
    errors_a = bus_errors(drain(a))
    assert len(errors_a) == 3
    assert all(e.arbitration_id == CAN_ERR_ACK | CAN_ERR_BUSERROR for e in errors_a)
    assert a.error_counters() == (3 * 8 - 1, 0)


def test_ack_suppress_leaves_a_sender_error_passive_at_128(daemon, nodes):
    a, b = nodes
    load(daemon, scenario(fault(at="0s", bus="can0", effect="ack_suppress", duration="1s")))
    a.send(msg())
    canemu.step(500 * MS)
    assert a.state == can.BusState.PASSIVE and a.error_counters() == (128, 0)
    # Once the sender is error-passive its error flag is recessive: nobody else sees the ACK
    # error, and the receivers take every repetition as a valid frame (ISO 11898-1).
    got_b = frames(drain(b))
    assert len(got_b) > 100 and {m.arbitration_id for m in got_b} == {0x123}
    # 16 unacknowledged attempts made it passive; it goes on seeing its ACK errors.
    errors_a = bus_errors(drain(a))
    assert len(errors_a) > 16
    assert all(e.arbitration_id == CAN_ERR_ACK | CAN_ERR_BUSERROR for e in errors_a)
    canemu.step(600 * MS)  # acknowledged after the window: done, one off the TEC
    assert a.error_counters() == (127, 0)
    drain(b)
    canemu.step(10 * MS)
    assert frames(drain(b)) == []


def test_stuck_dominant_bus(daemon, nodes):
    a, b = nodes
    load(daemon, scenario(fault(at="1ms", bus="can0", effect="stuck_dominant", duration="200us")))
    canemu.step(5 * MS)
    # 100 dominant bit times (bits 0..99) on an idle bus. Each node takes bit 0 for a start of
    # frame; bit 5 should have been a stuff bit: stuff error (+1); its error flag is bits 6..11;
    # bit 12, the first after it, is dominant (+8); so are the 14th dominant bit from the flag's
    # start (bit 19, +8) and every 8th after it up to bit 99 (27..99: 10 x 8): REC 97.
    for node in (a, b):
        errors = bus_errors(drain(node))
        assert errors and errors[0].data[2] == CAN_ERR_PROT_STUFF
        assert node.error_counters() == (0, 97)
    a.send(msg())  # the bus works again
    canemu.step(MS)
    assert len(frames(drain(b))) == 1


def test_random_errors_are_the_same_for_the_same_seed(nodes, daemon):
    random_errors = scenario(fault(at="0s", until="200ms", bus="can0", effect="random_errors",
                               bit_error_rate=0.002), seed=11)

    def run(a, b, d):
        load(d, random_errors)
        for k in range(200):
            a.send(msg(0x100 + k % 16, [k % 256]))
        canemu.step(100 * MS)
        errors = [(round(e.timestamp * 1e6), bytes(e.data)) for e in bus_errors(drain(a))]
        received = [(round(m.timestamp * 1e6), m.arbitration_id) for m in frames(drain(b))]
        return errors, received

    first = run(*nodes, daemon)
    errors, received = first
    # Every frame arrives; one hit in the last bit of its EOF arrives twice (the receivers had
    # taken it, the transmitter repeats it: ISO 11898-1's known double reception).
    assert {k for _, k in received} == {0x100 + k for k in range(16)}
    assert 200 <= len(received) <= 200 + len(errors)
    # About one 60-bit frame in eight is hit at 0.002 per bit.
    assert 10 <= len(errors) <= 50
    again = Canemud("stepped")
    try:
        a = can.Bus(interface="canemu", channel="can0", auto_restart=False)
        b = can.Bus(interface="canemu", channel="can0", auto_restart=False)
        drain(a)
        drain(b)
        assert run(a, b, again) == first
        a.shutdown()
        b.shutdown()
    finally:
        again.stop()


def test_node_off_leaves_the_other_unacknowledged_until_it_is_back(daemon, nodes):
    a, b = nodes
    load(daemon, scenario(fault(at="0s", until="100ms", node=b.node_name, effect="node_off")))
    a.send(msg())
    canemu.step(50 * MS)
    assert a.error_counters() == (128, 0)
    assert frames(drain(b)) == []
    canemu.step(60 * MS)
    assert len(frames(drain(b))) == 1
    assert a.error_counters() == (127, 0)


def test_node_on_plugs_a_node_in_again(daemon, nodes):
    a, b = nodes
    load(daemon, scenario(
        fault(at="0s", node=b.node_name, effect="node_off"),
        fault(at="30ms", node=b.node_name, effect="node_on")))
    a.send(msg())
    canemu.step(29 * MS)
    assert frames(drain(b)) == []
    canemu.step(10 * MS)
    assert len(frames(drain(b))) == 1


def test_bus_off_is_forced_at_its_instant(daemon, nodes):
    a, _ = nodes
    start = now_ns()
    load(daemon, scenario(fault(at="1ms", node=a.node_name, effect="bus_off")))
    canemu.step(MS - 1)
    assert a.state == can.BusState.ACTIVE
    canemu.step(1)
    assert a.state == can.BusState.ERROR
    seen = drain(a)
    assert seen[-1].arbitration_id & CAN_ERR_BUSOFF
    assert round(seen[-1].timestamp * 1e9) == start + MS - (start + MS) % 1000
    a.restart()
    canemu.step(1408 * 2 * US)  # 128 x 11 recessive bits at 500 kbit/s
    assert a.state == can.BusState.ACTIVE
    assert a.error_counters() == (0, 0)


def test_error_counters_are_set_and_the_state_follows(daemon, nodes):
    a, _ = nodes
    load(daemon, scenario(
        fault(at="0s", node=a.node_name, effect="error_counters", tec=100, rec=5)))
    assert a.error_counters() == (100, 5)
    assert a.controller_state == canemu.ControllerState.ERROR_WARNING
    warning = [m for m in drain(a) if m.arbitration_id == CAN_ERR_CRTL]
    assert len(warning) == 1 and warning[0].data[1] == CAN_ERR_CRTL_TX_WARNING
    load(daemon, scenario(
        fault(at="0s", node=a.node_name, effect="error_counters", tec=130, rec=0)))
    assert a.state == can.BusState.PASSIVE


def test_oscillator_far_off_is_not_understood_until_it_is_back(daemon, nodes):
    a, b = nodes
    load(daemon, scenario(
        fault(at="0s", until="20ms", node=a.node_name, effect="oscillator", ppm=30000)))
    a.send(msg())
    canemu.step(19 * MS)
    got_b = drain(b)
    assert frames(got_b) == []
    assert bus_errors(got_b)
    assert bus_errors(drain(a))
    canemu.step(20 * MS)
    assert len(frames(drain(b))) == 1


def test_oscillator_talks_within_twice_the_tolerance_and_not_beyond(daemon, nodes):
    # The interface's 500 kbit/s timing: 16 quanta, phase 1 of 13, phase 2 of 2, SJW 2. The
    # receiver's df is the smaller of SJW / (20 x 16) = 0.625 % and 2 / (2 x (13 x 16 - 2)) =
    # 0.485 %, and it decodes a rate off by at most 2 x df = 9709 ppm (docs/wire-model.md).
    a, b = nodes
    load(daemon, scenario(
        fault(at="0s", until="10ms", node=a.node_name, effect="oscillator", ppm=9600),
        fault(at="10ms", node=a.node_name, effect="oscillator", ppm=9800)))
    for k in range(10):
        a.send(msg(0x100 + k, (k,) * 8))
    canemu.step(10 * MS)
    assert [m.arbitration_id for m in frames(drain(b))] == [0x100 + k for k in range(10)]
    assert bus_errors(drain(a)) == [] and a.error_counters() == (0, 0)
    assert b.error_counters() == (0, 0)
    a.send(msg(0x200))
    canemu.step(1 * MS)
    assert frames(drain(b)) == [] and bus_errors(drain(a)) != []


def test_lin_effects_on_a_can_bus_are_refused_whole_with_the_reason(daemon, nodes):
    a, _ = nodes
    done = fault_load(daemon, scenario(
        fault(at="0s", node=a.node_name, effect="error_counters", tec=50, rec=0),
        fault(at="0s", bus="can0", effect="lin_no_response")))
    assert done.returncode != 0
    assert "lin_no_response: bus can0 is a CAN bus; LIN faults need a LIN bus" in done.stderr
    assert a.error_counters() == (0, 0)  # nothing of it applied


def test_babble_floods_the_bus_and_starves_the_others(daemon):
    a = can.Bus(interface="canemu", channel="can0")
    babbler = can.Bus(interface="canemu", channel="can0")
    c = can.Bus(interface="canemu", channel="can0")
    try:
        for bus in (a, babbler, c):
            drain(bus)
        start = now_ns()
        load(daemon, scenario(
            fault(at="0s", node=babbler.node_name, effect="babble", id=0x000,
                  data=[0xDE, 0xAD, 0xBE, 0xEF], duration="1ms")))
        a.send(msg(0x123))  # loses arbitration to every copy
        canemu.step(2 * MS)
        got = frames(drain(c))
        # Copies of 0x000#DEADBEEF (81 bits + 3 of intermission: 168 us) back to back from the
        # scenario's start; every one that starts before 1 ms goes out: 6 (at 0 .. 840 us).
        copies = [m for m in got if m.arbitration_id == 0]
        assert len(copies) == 6
        assert all(bytes(m.data) == b"\xde\xad\xbe\xef" for m in copies)
        assert [ns(m.timestamp) - ns(copies[0].timestamp) for m in copies] == [
            k * 168_000 for k in range(6)]
        assert got[-1].arbitration_id == 0x123  # a's frame once the babbling stopped
        assert ns(got[-1].timestamp) > start + MS
        # The babbler's program sees nothing of it: no frames of its own, no errors.
        assert [(m.arbitration_id, m.timestamp) for m in frames(drain(babbler))] == [
            (m.arbitration_id, m.timestamp) for m in got if m.arbitration_id == 0x123]
        assert babbler.error_counters() == (0, 0)
    finally:
        a.shutdown()
        babbler.shutdown()
        c.shutdown()


def test_babble_needs_the_node_on_the_bus(daemon):
    # ixxat0:0's line has not been started: nothing babbles, and the log says why.
    c = can.Bus(interface="canemu", channel="can0")
    try:
        drain(c)
        load(daemon, scenario(
            fault(at="0s", node="ixxat0:0", effect="babble", id=0x100, duration="1ms")))
        canemu.step(2 * MS)
        assert frames(drain(c)) == []
        daemon.wait_log("babble: the node is not on the bus (its line is not started); nothing "
                        "babbles")
        [row] = [line for line in subprocess.run(
            [str(CANEMU_CLI), "--socket", daemon.socket, "fault", "list"],
            capture_output=True, text=True, timeout=30, check=True).stdout.splitlines()
            if "babble" in line]
        # seen, hits: it did nothing; the frame it would have sent last
        assert row.split()[-5:] == ["0", "0", "done", "sends", "0x100"]
    finally:
        c.shutdown()


def test_babble_parameters_are_checked(daemon):
    done = fault_load(daemon, scenario(
        fault(at="0s", node="ixxat0:0", effect="babble", id=0x800,
              data=[1, 2, 3, 4, 5, 6, 7, 8, 9])))
    assert done.returncode != 0
    assert "id" in done.stderr and "data" in done.stderr and "duration" in done.stderr


def test_babble_injected_from_the_command_line(daemon):
    babbler = can.Bus(interface="canemu", channel="can0")
    c = can.Bus(interface="canemu", channel="can0")
    try:
        drain(c)
        done = subprocess.run(
            [str(CANEMU_CLI), "--socket", daemon.socket, "fault", "inject", "--effect", "babble",
             "--node", babbler.node_name, "--id", "0x1ABCDEF", "--ext", "--data", "0102",
             "--duration", "300us"],
            capture_output=True, text=True, timeout=30)
        assert done.returncode == 0, done.stderr
        canemu.step(MS)
        copies = frames(drain(c))
        assert copies and all(
            m.arbitration_id == 0x1ABCDEF and m.is_extended_id and bytes(m.data) == b"\x01\x02"
            for m in copies)
    finally:
        babbler.shutdown()
        c.shutdown()


LOW_SPEED_BUS = """
[[bus]]
name = "body"
kind = "can"
bitrate = 125000
transceiver = "low-speed"
"""


@pytest.fixture
def low_speed(request):
    d = Canemud("stepped", extra=LOW_SPEED_BUS)
    a = can.Bus(interface="canemu", channel="body")
    b = can.Bus(interface="canemu", channel="body")
    drain(a)
    drain(b)
    yield d, a, b
    a.shutdown()
    b.shutdown()
    d.stop()


def test_line_error_on_one_wire_is_reported_and_traffic_goes_on(low_speed):
    daemon, a, b = low_speed
    body = [x for x in canemu.buses() if x["name"] == "body"]
    assert body == [{"name": "body", "kind": "can", "transceiver": "low-speed",
                     "bitrate": 125000, "data_bitrate": 0}]
    load(daemon, scenario(fault(at="1ms", until="10ms", node=b.node_name, effect="line_error")))
    canemu.step(2 * MS)
    trx = drain(b)
    assert len(trx) == 1 and trx[0].is_error_frame and trx[0].arbitration_id == CAN_ERR_TRX
    assert round(trx[0].timestamp * 1e9) == MS  # BUSCERR from 1 ms on (a STATUS message)
    a.send(msg())  # single-wire mode: the frame still arrives, acknowledged
    canemu.step(2 * MS)
    assert len(frames(drain(b))) == 1
    assert a.error_counters() == (0, 0)
    canemu.step(10 * MS)  # the wire is back: BUSCERR cleared, nothing more to report
    assert drain(b) == []
    ends = daemon.wait_log("line_error ends")
    assert "fault: t=0.010000000 s: " in ends
    listed = subprocess.run([str(CANEMU_CLI), "--socket", daemon.socket, "fault", "list"],
                            capture_output=True, text=True, timeout=30, check=True).stdout
    [row] = [line for line in listed.splitlines() if "line_error" in line]
    assert row.split()[-3:] == ["2", "done", "-"]  # fired twice: the fault and its end; no match


def test_line_error_on_both_wires_cuts_the_node_off(low_speed):
    daemon, a, b = low_speed
    load(daemon, scenario(
        fault(at="0s", until="50ms", node=b.node_name, effect="line_error", wire="both")))
    a.send(msg())
    canemu.step(40 * MS)
    got_b = drain(b)
    assert [m.arbitration_id for m in got_b] == [CAN_ERR_TRX]  # only its own fault report
    assert a.error_counters() == (128, 0)  # nobody acknowledges
    canemu.step(20 * MS)
    assert len(frames(drain(b))) == 1
    assert a.error_counters() == (127, 0)


def test_line_error_needs_a_low_speed_bus(daemon, nodes):
    a, _ = nodes
    done = fault_load(daemon, scenario(fault(at="0s", node=a.node_name, effect="line_error")))
    assert done.returncode != 0
    assert "high-speed bus" in done.stderr and "low-speed" in done.stderr


def test_canemud_stops_cleanly_while_a_line_error_is_still_to_end(low_speed):
    """The scheduled end of a line error must not keep the adapter's line alive past the
    simulation (canemud used to crash at SIGTERM with such a fault pending)."""
    daemon, a, b = low_speed
    load(daemon, scenario(fault(at="1ms", until="10s", node=b.node_name, effect="line_error")))
    canemu.step(2 * MS)
    assert [m.arbitration_id for m in drain(b)] == [CAN_ERR_TRX]
    a.shutdown()
    b.shutdown()
    assert daemon.stop() == 0
