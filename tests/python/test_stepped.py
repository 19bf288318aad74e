"""The python-can interface in stepped time: exact instants, error confinement, bus-off and
recovery, the adapter's cyclic list, and a full transmit FIFO. Time moves only by
canemu.step(), so every figure here is exact."""

from __future__ import annotations

import re
import select
import subprocess
import threading
import time

import can
import pytest

import canemu
from canemu.bus import (
    CAN_ERR_ACK,
    CAN_ERR_BUSERROR,
    CAN_ERR_BUSOFF,
    CAN_ERR_CNT,
    CAN_ERR_CRTL,
    CAN_ERR_CRTL_ACTIVE,
    CAN_ERR_CRTL_RX_PASSIVE,
    CAN_ERR_CRTL_RX_WARNING,
    CAN_ERR_CRTL_TX_PASSIVE,
    CAN_ERR_CRTL_TX_WARNING,
    CAN_ERR_PROT,
    CAN_ERR_PROT_BIT,
    CAN_ERR_RESTARTED,
)
from canemu._receive import _RX_BATCH

from conftest import CANEMU_CLI, Canemud, bus_pair, drain, frames, ns

US = 1_000
MS = 1_000_000
PASSIVE_BITS = CAN_ERR_CRTL_TX_PASSIVE | CAN_ERR_CRTL_RX_PASSIVE
WARNING_BITS = CAN_ERR_CRTL_TX_WARNING | CAN_ERR_CRTL_RX_WARNING
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
    yield from bus_pair("can0", drained=False)


def frame_ns(frame: str, bitrate: int, data_bitrate: int | None = None,
             intermission: bool = True) -> int:
    """The frame's duration, with its intermission or from SOF to the end of EOF, from the wire
    model (`canemu calc frame`; CAN FD frames in cansend's syntax, 123##<flags><data>, flags 1
    for bit-rate switch)."""
    command = [str(CANEMU_CLI), "calc", "frame", frame, "--bitrate", str(bitrate)]
    if data_bitrate is not None:
        command += ["--data-bitrate", str(data_bitrate)]
    text = subprocess.run(command, capture_output=True, text=True, check=True).stdout
    pattern = r"(\d+) ns with intermission" if intermission else r": (\d+) ns \("
    return int(re.search(pattern, text).group(1))


def data_frames(msgs) -> list:
    return [m for m in msgs if not m.is_error_frame]


def state_frames(msgs) -> list:
    """The controller-state error frames (CAN_ERR_CRTL) among `msgs`."""
    return [m for m in msgs if m.is_error_frame and m.arbitration_id & CAN_ERR_CRTL]


def step_until(bus, done, slice_ns: int = 20 * US, limit_ns: int = 50 * MS) -> list:
    """Steps time `slice_ns` at a time, reading `bus` after each step (as a program that keeps
    up with the bus does), until `done(seen)` holds; everything read."""
    seen: list = []
    for _ in range(limit_ns // slice_ns):
        canemu.step(slice_ns)
        seen += drain(bus)
        if done(seen):
            return seen
    raise AssertionError(f"not reached within {limit_ns} ns; read {seen}")


def is_passive_frame(m) -> bool:
    return m.is_error_frame and m.arbitration_id & CAN_ERR_CRTL and m.data[1] & PASSIVE_BITS


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


def test_messages_taken_in_a_batch_come_one_per_recv_in_order(pair):
    """The interface takes up to _RX_BATCH (256) waiting messages from the ring in one call:
    more frames than that waiting come in order, each once, with increasing simulated time
    stamps."""
    a, b = pair
    drain(b)
    total = _RX_BATCH + 44
    for start in range(0, total, 100):
        for i in range(start, min(start + 100, total)):
            a.send(can.Message(arbitration_id=i, data=[i & 0xFF], is_extended_id=False))
        canemu.step(50 * MS)  # 100 frames of 1 byte at 500 kbit/s take about 13 ms
    got = data_frames(drain(b))
    assert [(m.arbitration_id, bytes(m.data)) for m in got] == [
        (i, bytes([i & 0xFF])) for i in range(total)]
    assert all(x.timestamp < y.timestamp for x, y in zip(got, got[1:]))


def test_after_fileno_the_descriptor_is_readable_while_any_message_waits(pair):
    """Once a program asked for the descriptor, recv takes one message at a time from the ring,
    so the descriptor stays readable until the last one is read."""
    a, b = pair
    fd = b.fileno()
    drain(b)
    for i in range(3):
        a.send(can.Message(arbitration_id=0x20 + i, is_extended_id=False))
    canemu.step(5 * MS)
    readable = []
    for _ in range(3):
        readable.append(select.select([fd], [], [], 0)[0] == [fd])
        assert b.recv(0).arbitration_id == 0x20 + len(readable) - 1
    assert readable == [True, True, True]
    assert b.recv(0) is None
    assert select.select([fd], [], [], 0)[0] == []


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
        # The warning limit (TEC 96) after the 12th error: one warning frame, from the status
        # message, exactly there.
        warnings = [m for m in state_frames(errors) if m.data[1] & WARNING_BITS]
        assert len(warnings) == 1
        assert warnings[0].data[1] == CAN_ERR_CRTL_TX_WARNING
        assert errors.index(warnings[0]) == 12
        # Then one error-passive frame with the counters, right after the 16th error and with
        # its time stamp, although the program reads only once the step is over (the ERROR
        # messages carry the counters).
        passive = [m for m in errors if is_passive_frame(m)]
        assert len(passive) == 1
        assert errors.index(passive[0]) == errors.index(bus_errors[15]) + 1
        assert passive[0].timestamp == bus_errors[15].timestamp
        assert passive[0].arbitration_id == CAN_ERR_CRTL | CAN_ERR_CNT
        assert (passive[0].data[6], passive[0].data[7]) == (128, 0)
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


def test_error_passive_frame_comes_with_the_16th_ack_error(daemon):
    a = can.Bus(interface="canemu", channel="can0")  # alone on can0: nobody acknowledges
    try:
        drain(a)
        a.send(can.Message(arbitration_id=0x100, data=[1], is_extended_id=False))
        # One attempt with its ACK error takes 128 us at 500 kbit/s; read every 20 us.
        seen = step_until(a, lambda seen: any(is_passive_frame(m) for m in seen))
        bus_errors = [m for m in seen if m.arbitration_id & CAN_ERR_BUSERROR]
        assert all(m.arbitration_id == CAN_ERR_ACK | CAN_ERR_BUSERROR for m in bus_errors)
        passive = [m for m in seen if is_passive_frame(m)]
        assert len(passive) == 1
        frame = passive[0]
        # TEC 8 x 16 = 128: the 16th ACK error made the node error-passive. SocketCAN's frame:
        # CAN_ERR_CRTL with TX_PASSIVE, and the counters (CAN_ERR_CNT).
        assert len(bus_errors) == 16 and seen[-2] is bus_errors[15] and seen[-1] is frame
        assert frame.arbitration_id == CAN_ERR_CRTL | CAN_ERR_CNT
        assert frame.data[1] == CAN_ERR_CRTL_TX_PASSIVE
        assert (frame.data[6], frame.data[7]) == (128, 0)
        assert frame.timestamp == bus_errors[15].timestamp
        assert a.error_counters() == (128, 0)
        # The warning frame came once, with the 12th error.
        warnings = [m for m in state_frames(seen) if m.data[1] & WARNING_BITS]
        assert len(warnings) == 1 and seen.index(warnings[0]) == seen.index(bus_errors[11]) + 1
        # Further ACK errors leave TEC at 128: no more state frames.
        canemu.step(5 * MS)
        later = drain(a)
        assert len([m for m in later if m.arbitration_id & CAN_ERR_BUSERROR]) > 10
        assert state_frames(later) == []
    finally:
        a.shutdown()


@pytest.mark.parametrize("own", [True, False], ids=["echo", "no-echo"])
def test_leaving_error_passive_gives_warning_then_active_frames(daemon, own):
    a = can.Bus(interface="canemu", channel="can0", receive_own_messages=own)
    b = None
    try:
        drain(a)
        a.send(can.Message(arbitration_id=0x101, data=[1], is_extended_id=False))
        step_until(a, lambda seen: any(is_passive_frame(m) for m in seen))
        # A second node acknowledges from now on: the frame goes through, TEC 128 -> 127.
        b = can.Bus(interface="canemu", channel="can0")
        now = canemu.step(MS)
        seen = drain(a)
        back = state_frames(seen)
        assert len(back) == 1
        assert back[0].arbitration_id == CAN_ERR_CRTL | CAN_ERR_CNT
        assert back[0].data[1] == CAN_ERR_CRTL_TX_WARNING
        assert (back[0].data[6], back[0].data[7]) == (127, 0)
        assert a.controller_state == canemu.ControllerState.ERROR_WARNING
        if own:
            # The echo of the frame that got through marks the instant.
            echo = data_frames(seen)
            assert len(echo) == 1 and not echo[0].is_rx and echo[0].arbitration_id == 0x101
            assert seen.index(back[0]) == seen.index(echo[0]) + 1
            assert back[0].timestamp == echo[0].timestamp
        else:
            # No message marks it: found when the FIFO ran empty, stamped with that instant.
            assert data_frames(seen) == []
            assert ns(back[0].timestamp) == now - now % US
        # 32 more frames through: TEC 95, below the warning limit (the status message says it).
        for k in range(32):
            a.send(can.Message(arbitration_id=0x102, data=[k], is_extended_id=False))
        canemu.step(20 * MS)
        seen = drain(a)
        assert [m.data[1] for m in state_frames(seen)] == [CAN_ERR_CRTL_ACTIVE]
        assert state_frames(seen)[0].arbitration_id == CAN_ERR_CRTL
        assert a.error_counters() == (95, 0)
        assert len(data_frames(drain(b))) == 33
    finally:
        a.shutdown()
        if b is not None:
            b.shutdown()


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


def test_gap_between_fd_frames_is_the_exact_frame_duration(daemon):
    # fd0: 500 kbit/s nominal, 2 Mbit/s data.
    a = can.Bus(interface="canemu", channel="fd0", fd=True)
    b = can.Bus(interface="canemu", channel="fd0", fd=True)
    try:
        sent = [
            ("123##01122", can.Message(arbitration_id=0x123, data=[0x11, 0x22], is_fd=True,
                                        is_extended_id=False)),
            ("123##11122", can.Message(arbitration_id=0x123, data=[0x11, 0x22], is_fd=True,
                                        bitrate_switch=True, is_extended_id=False)),
            ("1ABCDEF0##1" + "AA" * 64, can.Message(arbitration_id=0x1ABCDEF0, data=[0xAA] * 64,
                                                     is_fd=True, bitrate_switch=True,
                                                     is_extended_id=True)),
            ("7FF##0" + "55" * 12, can.Message(arbitration_id=0x7FF, data=[0x55] * 12,
                                                is_fd=True, is_extended_id=False)),
            ("00000000##1", can.Message(arbitration_id=0, is_fd=True, bitrate_switch=True,
                                        is_extended_id=True)),
            ("321#0102", can.Message(arbitration_id=0x321, data=[1, 2], is_extended_id=False)),
            ("0F0##1" + "00" * 20, can.Message(arbitration_id=0x0F0, data=[0] * 20, is_fd=True,
                                               bitrate_switch=True, is_extended_id=False)),
        ]
        now = canemu.step(MS)  # both nodes online, the bus idle
        drain(b)
        for _, msg in sent:
            a.send(msg)
        canemu.step(20 * MS)
        got = data_frames(drain(b))
        assert [(m.arbitration_id, m.is_fd, m.bitrate_switch, len(m.data)) for m in got] == [
            (m.arbitration_id, m.is_fd, m.bitrate_switch, len(m.data)) for _, m in sent]
        # The first frame starts now; each next one a whole frame with intermission later. A
        # data-phase bit is 500 ns, so an end need not fall on a whole microsecond: the time
        # stamp is the adapter's microsecond in which it does.
        end = now + frame_ns(sent[0][0], 500_000, 2_000_000, intermission=False)
        for k, (text, _) in enumerate(sent):
            if k:
                end += frame_ns(text, 500_000, 2_000_000)
            assert ns(got[k].timestamp) == end - end % US, text
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


def test_a_period_the_cyclic_list_has_no_room_for_goes_to_software(pair):
    a, b = pair
    # Two entries of 2 ms take every 1 ms tick of the list: a third is refused there
    # (VCI_E_OUTOFMEMORY) and python-can's software scheduler sends it.
    tasks = [a.send_periodic(can.Message(arbitration_id=0x50 + k, is_extended_id=False), 0.002)
             for k in range(3)]
    try:
        assert [isinstance(t, canemu.CanemuCyclicTask) for t in tasks] == [True, True, False]
    finally:
        for t in tasks:
            t.stop()


def test_send_waits_while_the_transmit_fifo_is_full(pair):
    a, b = pair
    sent = 0
    with pytest.raises(CanTimeoutError):
        while sent < 10_000:
            a.send(can.Message(arbitration_id=0x200, is_extended_id=False), timeout=0)
            sent += 1
    assert sent >= 256  # tx_fifo_size, rounded up to whole pages
    # canemud may still take the frame it puts on the wire at this instant (one slot, once the
    # doorbell it was rung with is served); after that the FIFO stays full while time stands.
    for _ in range(3):
        start = time.monotonic()
        try:
            a.send(can.Message(arbitration_id=0x201, is_extended_id=False), timeout=0.05)
        except CanTimeoutError:
            assert time.monotonic() - start >= 0.05
            break
    else:
        pytest.fail("the transmit FIFO did not stay full while simulated time stood still")
    canemu.step(5 * MS)  # frames leave; room again
    a.send(can.Message(arbitration_id=0x202, is_extended_id=False), timeout=0)
    assert len([m for m in drain(b) if not m.is_error_frame]) > 0


def test_cyclic_list_frames_come_back_as_own_messages(daemon):
    a = can.Bus(interface="canemu", channel="can0", receive_own_messages=True)
    b = can.Bus(interface="canemu", channel="can0")
    try:
        canemu.step(50 * MS)  # what earlier tests left on can0 goes by
        drain(a)
        drain(b)
        msg = can.Message(arbitration_id=0x3D, data=[1, 2, 3], is_extended_id=False)
        task = a.send_periodic(msg, 0.01)
        assert isinstance(task, canemu.CanemuCyclicTask)
        canemu.step(45 * MS)
        theirs = data_frames(drain(b))
        own = data_frames(drain(a))
        assert len(theirs) == 4 and all(m.is_rx for m in theirs)
        assert len(own) == 4 and not any(m.is_rx for m in own)
        assert [m.timestamp for m in own] == [m.timestamp for m in theirs]
        assert all(bytes(m.data) == b"\x01\x02\x03" and m.arbitration_id == 0x3D for m in own)
        # Another node's frame is received as such meanwhile.
        b.send(can.Message(arbitration_id=0x3E, data=[9], is_extended_id=False))
        task.modify_data(can.Message(arbitration_id=0x3D, data=[4, 5, 6], is_extended_id=False))
        canemu.step(25 * MS)
        got = data_frames(drain(a))
        assert [(m.arbitration_id, m.is_rx) for m in got] == [(0x3E, True), (0x3D, False),
                                                             (0x3D, False)]
        assert bytes(got[-1].data) == b"\x04\x05\x06"
        task.stop()
        canemu.step(30 * MS)
        assert data_frames(drain(a)) == []
        drain(b)
        # Long after the list stopped, the same content from another node is received.
        canemu.step(200 * MS)
        b.send(can.Message(arbitration_id=0x3D, data=[4, 5, 6], is_extended_id=False))
        canemu.step(MS)
        got = data_frames(drain(a))
        assert len(got) == 1 and got[0].is_rx
    finally:
        a.shutdown()
        b.shutdown()


def test_send_without_timeout_waits_until_stepped_time_drains_the_fifo(pair):
    a, b = pair
    sent = 0
    with pytest.raises(CanTimeoutError):
        while sent < 10_000:
            a.send(can.Message(arbitration_id=0x200, is_extended_id=False), timeout=0)
            sent += 1
    # canemud takes the first frame into the controller when it sees the doorbell, which may be
    # after the FIFO filled: that frees one place while time stands still. Fill until the FIFO
    # stays full for a while; with a frame in the controller nothing more leaves.
    with pytest.raises(CanTimeoutError):
        while sent < 10_000:
            a.send(can.Message(arbitration_id=0x200, is_extended_id=False), timeout=0.2)
            sent += 1
    outcome: dict = {}

    def blocked_send() -> None:
        try:
            a.send(can.Message(arbitration_id=0x203, is_extended_id=False), timeout=None)
            outcome["sent"] = True
        except Exception as e:  # reported below
            outcome["error"] = e

    thread = threading.Thread(target=blocked_send, daemon=True)
    thread.start()
    thread.join(0.2)
    assert thread.is_alive(), outcome  # time stands still: the FIFO stays full
    canemu.step(MS)  # a few frames leave: room again
    thread.join(10.0)
    assert not thread.is_alive() and outcome == {"sent": True}
    canemu.step(100 * MS)
    got = data_frames(drain(b))
    assert len(got) == sent + 1 and got[-1].arbitration_id == 0x203


def test_time_stamps_stay_exact_past_the_adapters_32_bit_microsecond_counter():
    # The adapter's time stamps are 32-bit microsecond ticks: they wrap after 4294.967296 s
    # (with a TIMEOVR message). Frames before and after the wrap carry the simulated time.
    d = Canemud("stepped")
    a = can.Bus(interface="canemu", channel="can0")
    b = can.Bus(interface="canemu", channel="can0")
    try:
        drain(a)
        drain(b)
        duration = frame_ns("100#00", 500_000, intermission=False)
        for k in range(3):
            canemu.step(2_000 * 10**9)
            sent = canemu.sim_time()[0]
            a.send(can.Message(arbitration_id=0x100, data=[0], is_extended_id=False))
            canemu.step(1_000_000)
            [got] = frames(drain(b))
            assert round(got.timestamp * 1e9) == sent + duration
        assert sent > 2**32 * 1000
    finally:
        a.shutdown()
        b.shutdown()
        d.stop()


def test_step_outside_stepped_time_is_refused(realtime_daemon):
    with pytest.raises(can.CanOperationError):
        canemu.step(MS)
