"""python-can on the interfaces of an emulated SORCUS X-CAN-2i (channel "xcan0:N"), beside
IXXAT adapters on the same buses, in stepped time: exact instants, both directions, the
82527's limits (one identifier format and one frame kind received, no listen-only, no FD),
errors, bus-off and restart."""

from __future__ import annotations

import ctypes
import logging
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
    CAN_ERR_CRTL_RX_WARNING,
    CAN_ERR_CRTL_TX_WARNING,
)

from conftest import CANEMU_CLI, Canemud, drain, ns

US = 1_000
MS = 1_000_000
XCAN = """
[[device]]
name = "xcan0"
model = "sorcus-x-can-2i"
controllers = ["can0", "can1"]
"""


@pytest.fixture(scope="module")
def daemon():
    d = Canemud("stepped", extra=XCAN)
    yield d
    d.stop()


def frame_ns(frame: str, bitrate: int, intermission: bool = True) -> int:
    """The frame's duration from the wire model (`canemu calc frame`)."""
    text = subprocess.run([str(CANEMU_CLI), "calc", "frame", frame, "--bitrate", str(bitrate)],
                          capture_output=True, text=True, check=True).stdout
    pattern = r"(\d+) ns with intermission" if intermission else r": (\d+) ns \("
    return int(re.search(pattern, text).group(1))


def receive(bus, count: int, timeout: float = 5.0) -> list:
    """`count` messages from `bus`: an X-CAN bus's frames come through libxcan's callback
    thread, a moment after the step that made them."""
    out = []
    while len(out) < count:
        msg = bus.recv(timeout)
        assert msg is not None, f"only {out} of {count} messages came"
        out.append(msg)
    return out


@pytest.fixture
def pair(daemon):
    """xcan0:0 (with its own frames back) and a node of its own on can0, both at 500 kbit/s."""
    x = can.Bus(interface="canemu", channel="xcan0:0", receive_own_messages=True)
    v = can.Bus(interface="canemu", channel="can0")
    drain(v)
    yield x, v
    x.shutdown()
    v.shutdown()


def test_an_xcan_channel_is_an_xcan_bus(daemon):
    with can.Bus(interface="canemu", channel="xcan0:1") as x:
        assert isinstance(x, canemu.XcanBus)
        assert x.node_name == "xcan0:1"
        assert x.channel_info == "canemu xcan0:1 (X-CAN-2i) on can1"
        assert x.state == can.BusState.ACTIVE
        assert x.controller_state == canemu.ControllerState.ERROR_ACTIVE
        # On the bus, no error: the state word's low word is XCAN_BUS_ON.
        assert x.bus_status() == 0x0001


def test_frames_sent_arrive_whole_at_their_exact_instants(pair):
    x, v = pair
    t0 = canemu.sim_time()[0]
    sent = [
        can.Message(arbitration_id=0x123, data=[1, 2, 3], is_extended_id=False),
        can.Message(arbitration_id=0x1ABCDEF0, is_remote_frame=True, dlc=3, is_extended_id=True),
        can.Message(arbitration_id=0x7EF, data=[0xFF] * 8, is_extended_id=False),
        can.Message(arbitration_id=0x1FFFFFEF, data=[], is_extended_id=True),
    ]
    texts = ["123#010203", "1ABCDEF0#R3", "7EF#FFFFFFFFFFFFFFFF", "1FFFFFEF#"]
    for m in sent:
        x.send(m)
    canemu.step(2 * MS)
    got = drain(v)
    own = receive(x, 4)
    assert [(m.arbitration_id, m.is_extended_id, m.is_remote_frame, m.dlc, bytes(m.data))
            for m in got] == [(m.arbitration_id, m.is_extended_id, m.is_remote_frame, m.dlc,
                               bytes(m.data)) for m in sent]
    # The general-ID channel's buffer takes the next message in the instant the frame before
    # ends: back to back, each frame's end at the sum of the durations before it.
    end = t0
    for k, text in enumerate(texts):
        # (SOF to the end of EOF, and for the frames after the first the intermission before)
        end += frame_ns(text, 500_000, intermission=k > 0)
        assert ns(got[k].timestamp) == end, text
        # The acknowledgement the driver reports is the same instant, as a frame sent.
        assert ns(own[k].timestamp) == end and not own[k].is_rx, text
        assert own[k].arbitration_id == sent[k].arbitration_id


def test_frames_of_other_nodes_reach_it_in_one_format(pair):
    x, v = pair
    t0 = canemu.sim_time()[0]
    v.send(can.Message(arbitration_id=0x100, data=[9], is_extended_id=False))
    v.send(can.Message(arbitration_id=0x100, data=[8], is_extended_id=True))
    v.send(can.Message(arbitration_id=0x101, is_remote_frame=True, is_extended_id=False))
    v.send(can.Message(arbitration_id=0x7FF, data=[7, 7], is_extended_id=False))
    canemu.step(2 * MS)
    got = receive(x, 2)
    # Buffer 15 takes 11-bit data frames: not the 29-bit one, not the remote frame.
    assert [(m.arbitration_id, m.is_extended_id, bytes(m.data), m.is_rx) for m in got] == [
        (0x100, False, b"\x09", True), (0x7FF, False, b"\x07\x07", True)]
    assert ns(got[0].timestamp) == t0 + frame_ns("100#09", 500_000, intermission=False)
    assert x.recv(0.2) is None


def test_rx_format_29_and_rx_remote_choose_what_buffer_15_takes(daemon):
    v = can.Bus(interface="canemu", channel="can1")
    try:
        with can.Bus(interface="canemu", channel="xcan0:1", rx_format=29) as x:
            v.send(can.Message(arbitration_id=0x55, data=[1], is_extended_id=False))
            v.send(can.Message(arbitration_id=0x12345, data=[2], is_extended_id=True))
            canemu.step(5 * MS)
            got = receive(x, 1)
            assert [(m.arbitration_id, m.is_extended_id) for m in got] == [(0x12345, True)]
            assert x.recv(0.2) is None
        with can.Bus(interface="canemu", channel="xcan0:1", rx_remote=True) as x:
            v.send(can.Message(arbitration_id=0x55, data=[1], is_extended_id=False))
            v.send(can.Message(arbitration_id=0x56, is_remote_frame=True, dlc=2,
                               is_extended_id=False))
            canemu.step(5 * MS)
            got = receive(x, 1)
            # XCAN_MESSAGE gives a remote frame received no size: its DLC is not known.
            assert [(m.arbitration_id, m.is_remote_frame, m.dlc) for m in got] == [
                (0x56, True, 0)]
            assert x.recv(0.2) is None
    finally:
        v.shutdown()


def test_filters_are_applied_to_what_buffer_15_lets_in(daemon):
    v = can.Bus(interface="canemu", channel="can0")
    try:
        with can.Bus(interface="canemu", channel="xcan0:0",
                     can_filters=[{"can_id": 0x200, "can_mask": 0x7F0}]) as x:
            for ident in (0x1FF, 0x200, 0x20F, 0x210):
                v.send(can.Message(arbitration_id=ident, data=[0], is_extended_id=False))
            canemu.step(2 * MS)
            got = receive(x, 2)
            assert [m.arbitration_id for m in got] == [0x200, 0x20F]
            assert x.recv(0.2) is None
    finally:
        v.shutdown()


def test_what_the_82527_cannot_do_is_refused_by_name(daemon):
    with pytest.raises(can.CanInitializationError, match="classic CAN controller"):
        can.Bus(interface="canemu", channel="xcan0:0", fd=True)
    with pytest.raises(can.CanInitializationError, match="no listen-only mode"):
        can.Bus(interface="canemu", channel="xcan0:0", listen_only=True)
    with pytest.raises(can.CanInitializationError, match="rx_format is 11 or 29"):
        can.Bus(interface="canemu", channel="xcan0:0", rx_format=12)
    with pytest.raises(can.CanInitializationError, match="cannot be made"):
        can.Bus(interface="canemu", channel="xcan0:0", bitrate=333_333)
    with can.Bus(interface="canemu", channel="xcan0:0") as x:
        with pytest.raises(can.CanInitializationError, match="one general-ID send channel"):
            can.Bus(interface="canemu", channel="xcan0:0")
        with pytest.raises(can.CanOperationError, match="beyond 0x7EF"):
            x.send(can.Message(arbitration_id=0x7F0, is_extended_id=False))
        with pytest.raises(can.CanOperationError, match="no CAN FD"):
            x.send(can.Message(arbitration_id=1, is_fd=True, data=[0] * 12))
        with pytest.raises(can.CanOperationError, match="no listen-only"):
            x.state = can.BusState.PASSIVE
    # A channel number the module does not have is no X-CAN channel, and no adapter's either.
    with pytest.raises(can.CanInitializationError,
                       match=r"'xcan0:2' is no interface .* interfaces: xcan0:0, xcan0:1\)"):
        can.Bus(interface="canemu", channel="xcan0:2")


def test_available_configs_list_both_interfaces(daemon):
    configs = canemu.CanemuBus._detect_available_configs()
    xcan = [c for c in configs if c["channel"].startswith("xcan0:")]
    assert xcan == [
        {"interface": "canemu", "channel": "xcan0:0", "fd": False, "bus": "can0",
         "bitrate": 500_000},
        {"interface": "canemu", "channel": "xcan0:1", "fd": False, "bus": "can1",
         "bitrate": 125_000},
    ]


def active_after_the_recovery(x):
    """x, restarted from bus-off, stays off for 128 x 11 recessive bits at 250 kbit/s (5.632
    ms) and is error-active from then on."""
    canemu.step(5632 * US - 1)
    assert x.state == can.BusState.ERROR
    canemu.step(1)
    assert x.state == can.BusState.ACTIVE


def go_bus_off(x, talkers) -> list:
    """Steps 1 ms at a time, the `talkers` sending a frame each, until `x` (at the wrong bit
    rate, with a frame of its own pending) is bus-off; how many steps that took, and the
    error frames `x` reported."""
    x.send(can.Message(arbitration_id=0x123, data=[1, 2], is_extended_id=False))
    for steps in range(1, 100):
        for k, t in enumerate(talkers):
            t.send(can.Message(arbitration_id=0x010 + k, data=[k], is_extended_id=False))
        canemu.step(1 * MS)
        if x.bus_status() & 0x0004:  # XCAN_BUS_OFF
            break
    seen = []
    while (m := x.recv(2.0)) is not None:
        seen.append(m)
        if m.arbitration_id & CAN_ERR_BUSOFF:
            break
    return steps, seen


@pytest.fixture
def talkers(daemon):
    """Two nodes of their own on can0 (500 kbit/s) that acknowledge and talk."""
    nodes = [can.Bus(interface="canemu", channel="can0") for _ in range(2)]
    yield nodes
    for n in nodes:
        n.flush_tx_buffer()
        n.shutdown()


def test_a_wrong_bit_rate_takes_it_bus_off_until_restart(talkers):
    x = can.Bus(interface="canemu", channel="xcan0:0", bitrate=250_000, auto_restart=False)
    try:
        steps, seen = go_bus_off(x, talkers)
        # The others' frames are noise to the 82527 at 250 kbit/s, its own frame noise to
        # them: off the bus in the ninth millisecond.
        assert steps == 9
        assert x.state == can.BusState.ERROR
        assert x.controller_state == canemu.ControllerState.BUS_OFF
        # The error callback came at the warning limit and at bus-off: two error frames.
        assert all(m.is_error_frame for m in seen) and len(seen) == 2
        warning, off = seen
        assert warning.arbitration_id & CAN_ERR_CRTL
        assert warning.data[1] == CAN_ERR_CRTL_TX_WARNING | CAN_ERR_CRTL_RX_WARNING
        assert off.arbitration_id & CAN_ERR_BUSOFF
        assert warning.timestamp < off.timestamp <= canemu.sim_time()[0] / 1e9
        # Sending while bus-off is refused by the driver; without auto_restart it stays off.
        with pytest.raises(can.CanOperationError, match="bus-off or stopped"):
            x.send(can.Message(arbitration_id=0x124, is_extended_id=False))
        canemu.step(20 * MS)
        assert x.state == can.BusState.ERROR
        # CMD_STOP, CMD_START: back after 128 x 11 recessive bits at 250 kbit/s (5.632 ms).
        x.restart()
        active_after_the_recovery(x)
    finally:
        x.flush_tx_buffer()
        x.shutdown()


def test_auto_restart_leaves_bus_off_by_itself(talkers):
    x = can.Bus(interface="canemu", channel="xcan0:0", bitrate=250_000)
    try:
        steps, seen = go_bus_off(x, talkers)
        assert seen and seen[-1].arbitration_id & CAN_ERR_BUSOFF
        # The restart was given with the callback, at the end of the step that saw bus-off.
        active_after_the_recovery(x)
    finally:
        x.flush_tx_buffer()
        x.shutdown()


def test_shutdown_names_the_frames_it_leaves(daemon, caplog):
    x = can.Bus(interface="canemu", channel="xcan0:0")
    x.send(can.Message(arbitration_id=0x321, is_extended_id=False))
    x.send(can.Message(arbitration_id=0x322, is_extended_id=False))
    with caplog.at_level(logging.WARNING, logger="can.canemu"):
        x.shutdown()
    assert "shutdown discards 2 frame(s) not acknowledged: in stepped time nothing moves" in \
        caplog.text


def test_libxcan_extensions_answer_outside_their_cases(daemon):
    """canemu_xcan_callback_time outside a callback, canemu_xcan_enum_interfaces past the
    last interface."""
    from canemu import _xcan

    at = ctypes.c_ulonglong(7)
    assert _xcan.lib().canemu_xcan_callback_time(ctypes.byref(at)) == _xcan.ERR_XCAN_NOT_READY
    assert at.value == 7
    info = _xcan.CANEMU_XCAN_INTERFACE()
    assert _xcan.lib().canemu_xcan_enum_interfaces(2, ctypes.byref(info)) == \
        _xcan.ERR_XCAN_NO_MODULE
    assert _xcan.lib().canemu_xcan_enum_interfaces(1, ctypes.byref(info)) == _xcan.ERR_OK
    assert (info.szDevice, info.szBus, info.usChannel, info.usLowSpeed, info.ulBitrate) == (
        b"xcan0", b"can1", 1, 0, 125_000)


def test_in_real_time_stamps_are_wall_clock_seconds():
    with Canemud("realtime", extra=XCAN) as d:
        x = can.Bus(interface="canemu", channel="xcan0:0", receive_own_messages=True,
                    socket=d.socket)
        v = can.Bus(interface="canemu", channel="can0")
        try:
            before = time.time()
            x.send(can.Message(arbitration_id=0x42, data=[4, 2], is_extended_id=False))
            got = v.recv(5.0)
            own = x.recv(5.0)
            after = time.time()
            assert got is not None and own is not None
            assert (got.arbitration_id, bytes(got.data)) == (0x42, b"\x04\x02")
            assert before <= own.timestamp <= after
            # One instant, the frame's end, seen by both libraries: within a microsecond
            # (the VCI's time stamps count whole microseconds).
            assert abs(got.timestamp - own.timestamp) < 1e-6
        finally:
            x.shutdown()
            v.shutdown()
