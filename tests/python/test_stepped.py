"""The python-can interface in stepped time: exact instants, error confinement, bus-off and
recovery, the adapter's cyclic list, and a full transmit FIFO. Time moves only by
canemu.step(), so every figure here is exact."""

from __future__ import annotations

import re
import subprocess
import time

import can
import pytest

import canemu
from canemu.bus import (
    CAN_ERR_ACK,
    CAN_ERR_BUSERROR,
    CAN_ERR_BUSOFF,
    CAN_ERR_CRTL,
    CAN_ERR_CRTL_ACTIVE,
    CAN_ERR_CRTL_TX_WARNING,
    CAN_ERR_PROT,
    CAN_ERR_PROT_BIT,
    CAN_ERR_RESTARTED,
)

from conftest import CANEMU_CLI, Canemud, drain, ns

MS = 1_000_000
CanTimeoutError = getattr(can, "CanTimeoutError", can.CanOperationError)

SCENARIO = """
[scenario]
name = "python bus-off"

[[fault]]
at = "0s"
bus = "can0"
match = { from = "ixxat0:0" }
effect = "bit_error"
count = 32

[[fault]]
at = "0s"
bus = "can1"
match = { from = "ixxat0:1" }
effect = "bit_error"
count = 32
"""


@pytest.fixture(scope="module")
def daemon():
    d = Canemud("stepped", extra='\n[[scenario]]\nfile = "busoff.toml"\n',
                files={"busoff.toml": SCENARIO})
    yield d
    d.stop()


@pytest.fixture
def pair(daemon):
    a = can.Bus(interface="canemu", channel="can0")
    b = can.Bus(interface="canemu", channel="can0")
    yield a, b
    a.shutdown()
    b.shutdown()


def frame_ns(frame: str, bitrate: int) -> int:
    """The frame's duration with intermission, from the wire model (`canemu calc frame`)."""
    text = subprocess.run(
        [str(CANEMU_CLI), "calc", "frame", frame, "--bitrate", str(bitrate)],
        capture_output=True, text=True, check=True,
    ).stdout
    return int(re.search(r"(\d+) ns with intermission", text).group(1))


@pytest.mark.parametrize("bus_name,bitrate", [("can0", 500_000), ("can1", 125_000)])
def test_gap_between_received_frames_is_the_exact_frame_duration(daemon, bus_name, bitrate):
    a = can.Bus(interface="canemu", channel=bus_name)
    b = can.Bus(interface="canemu", channel=bus_name)
    try:
        frames = [
            ("123#1122", can.Message(arbitration_id=0x123, data=[0x11, 0x22], is_extended_id=False)),
            ("7FF#FFFFFFFFFFFFFFFF", can.Message(arbitration_id=0x7FF, data=[0xFF] * 8,
                                                 is_extended_id=False)),
            ("00000000#", can.Message(arbitration_id=0, is_extended_id=True)),
            ("1ABCDEF0#R", can.Message(arbitration_id=0x1ABCDEF0, is_remote_frame=True,
                                       is_extended_id=True)),
            ("001#0000000000000000", can.Message(arbitration_id=1, data=[0] * 8,
                                                 is_extended_id=False)),
        ]
        for _, msg in frames:
            a.send(msg)
        canemu.step(20 * MS)
        got = [m for m in drain(b) if not m.is_error_frame]
        assert [m.arbitration_id for m in got] == [m.arbitration_id for _, m in frames]
        for k in range(1, len(frames)):
            expected = frame_ns(frames[k][0], bitrate)
            assert ns(got[k].timestamp - got[k - 1].timestamp) == expected, frames[k][0]
    finally:
        a.shutdown()
        b.shutdown()


def test_stepped_time_stamps_are_simulated_seconds(pair):
    a, b = pair
    before, mode = canemu.sim_time()
    assert mode == 2
    a.send(can.Message(arbitration_id=0x10, is_extended_id=False))
    canemu.step(MS)
    got = [m for m in drain(b) if not m.is_error_frame]
    assert len(got) == 1
    assert before / 1e9 < got[0].timestamp <= (before + MS) / 1e9


def test_lone_node_sees_ack_errors_and_goes_error_passive(daemon):
    a = can.Bus(interface="canemu", channel="can0")  # nobody else on can0 is online
    try:
        drain(a)
        a.send(can.Message(arbitration_id=0x100, data=[1], is_extended_id=False))
        canemu.step(10 * MS)
        errors = [m for m in drain(a) if m.is_error_frame]
        bus_errors = [m for m in errors if m.arbitration_id & CAN_ERR_BUSERROR]
        assert len(bus_errors) > 16
        assert all(m.arbitration_id == CAN_ERR_ACK | CAN_ERR_BUSERROR for m in bus_errors)
        # The warning limit (TEC 96) after the 12th error: one controller-state frame.
        warnings = [m for m in errors if m.arbitration_id & CAN_ERR_CRTL]
        assert len(warnings) == 1
        assert warnings[0].data[1] == CAN_ERR_CRTL_TX_WARNING
        assert errors.index(warnings[0]) == 12
        # An error-passive transmitter's ACK errors do not count: TEC stays at 128.
        assert a.state == can.BusState.PASSIVE
        assert a.controller_state == canemu.ControllerState.ERROR_PASSIVE
        assert a.error_counters() == (128, 0)
        # Error frames at the bus's pace: each attempt plus its error signalling takes the
        # same number of bits.
        gaps = {ns(y.timestamp - x.timestamp) for x, y in zip(bus_errors[1:12], bus_errors[2:12])}
        assert len(gaps) == 1
    finally:
        a.shutdown()


def test_bus_off_and_automatic_recovery(daemon):
    a = can.Bus(interface="canemu", channel="ixxat0:0")  # the scenario's victim on can0
    b = can.Bus(interface="canemu", channel="can0")
    try:
        drain(a)
        msg = can.Message(arbitration_id=0x0AB, data=[0xAB], is_extended_id=False)
        a.send(msg)
        canemu.step(20 * MS)
        errors = [m for m in drain(a) if m.is_error_frame]
        bit_errors = [m for m in errors if m.arbitration_id == CAN_ERR_PROT | CAN_ERR_BUSERROR]
        assert len(bit_errors) == 32
        assert all(m.data[2] == CAN_ERR_PROT_BIT for m in bit_errors)
        assert errors[-1].arbitration_id & CAN_ERR_BUSOFF
        assert errors[-1].data[6] == 255  # TEC 256, shown saturated
        # Reading the bus-off restarted the line; the controller waits for 128 x 11 recessive
        # bits (2.816 ms at 500 kbit/s), then sends the frame it held.
        assert [m for m in drain(b) if not m.is_error_frame] == []
        canemu.step(3 * MS)
        received = [m for m in drain(b) if not m.is_error_frame]
        assert len(received) == 1 and received[0].arbitration_id == 0x0AB
        assert ns(received[0].timestamp - errors[-1].timestamp) >= 1408 * 2000
        restarted = [m for m in drain(a) if m.is_error_frame]
        assert restarted[-1].arbitration_id & CAN_ERR_RESTARTED
        assert restarted[-1].data[1] == CAN_ERR_CRTL_ACTIVE
        assert a.state == can.BusState.ACTIVE
        assert a.error_counters() == (0, 0)
    finally:
        a.shutdown()
        b.shutdown()


def test_bus_off_stays_until_restart_without_auto_restart(daemon):
    a = can.Bus(interface="canemu", channel="ixxat0:1", auto_restart=False)  # can1
    b = can.Bus(interface="canemu", channel="can1")
    try:
        a.send(can.Message(arbitration_id=0x0CD, is_extended_id=False))
        canemu.step(50 * MS)
        drain(a)
        canemu.step(50 * MS)
        assert a.state == can.BusState.ERROR
        assert a.controller_state == canemu.ControllerState.BUS_OFF
        assert a.error_counters()[0] > 255
        assert [m for m in drain(b) if not m.is_error_frame] == []
        a.restart()
        canemu.step(1408 * 8000 - 1)  # 128 x 11 bits at 125 kbit/s, less 1 ns
        assert a.state == can.BusState.ERROR
        canemu.step(2 * MS)
        assert a.state == can.BusState.ACTIVE
        assert [m.arbitration_id for m in drain(b) if not m.is_error_frame] == [0x0CD]
    finally:
        a.shutdown()
        b.shutdown()


def test_cyclic_list_sends_with_exact_period_and_count(pair):
    a, b = pair
    msg = can.Message(arbitration_id=0x3C, data=[1, 2, 3], is_extended_id=False)
    task = a.send_periodic(msg, 0.01, duration=0.05)
    assert isinstance(task, canemu.CanemuCyclicTask)
    canemu.step(200 * MS)
    got = [m for m in drain(b) if not m.is_error_frame]
    assert len(got) == 5
    assert {ns(y.timestamp - x.timestamp) for x, y in zip(got, got[1:])} == {10 * MS}
    task.stop()


def test_send_waits_while_the_transmit_fifo_is_full(pair):
    a, b = pair
    sent = 0
    with pytest.raises(CanTimeoutError):
        while sent < 10_000:
            a.send(can.Message(arbitration_id=0x200, is_extended_id=False), timeout=0)
            sent += 1
    assert sent >= 256  # tx_fifo_size, rounded up to whole pages
    start = time.monotonic()
    with pytest.raises(CanTimeoutError):
        a.send(can.Message(arbitration_id=0x201, is_extended_id=False), timeout=0.05)
    assert time.monotonic() - start >= 0.05
    canemu.step(5 * MS)  # frames leave; room again
    a.send(can.Message(arbitration_id=0x202, is_extended_id=False), timeout=0)
    assert len([m for m in drain(b) if not m.is_error_frame]) > 0


def test_step_outside_stepped_time_is_refused(realtime_daemon):
    with pytest.raises(can.CanOperationError):
        canemu.step(MS)
