"""Two python-can buses on one emulated bus exchange frames (python-can's back-to-back
scenarios), in real time: every wait is a recv with a timeout."""

from __future__ import annotations

import asyncio
import ctypes
import os
import select
import subprocess
import sys
import time

import can
import pytest

import canemu
from canemu import _vci

from conftest import Canemud, bus_pair

TIMEOUT = 2.0
CAN_ACCEPT_FILTER_1 = 0x01  # the channel's acceptance filter let the frame through
CAN_ACCEPT_FILTER_2 = 0x02  # its ID list did


@pytest.fixture
def pair(realtime_daemon):
    """Two nodes of their own on can0 (ephemeral adapters)."""
    yield from bus_pair("can0", drained=False)


@pytest.fixture
def fd_pair(realtime_daemon):
    a = can.Bus(interface="canemu", channel="fd0", fd=True)
    b = can.Bus(interface="canemu", channel="fd0", fd=True)
    yield a, b
    a.shutdown()
    b.shutdown()


def exchange(sender, receiver, msg):
    sender.send(msg)
    got = receiver.recv(TIMEOUT)
    assert got is not None, "nothing received"
    return got


def passes(sender: dict, receiver: dict, msg) -> None:
    """`msg` from a bus opened with `sender`'s options reaches one opened with `receiver`'s,
    unchanged."""
    a = can.Bus(interface="canemu", **sender)
    b = can.Bus(interface="canemu", **receiver)
    try:
        assert_same_frame(msg, exchange(a, b, msg))
    finally:
        a.shutdown()
        b.shutdown()


def garbled(sender: dict, receiver: dict, msg) -> None:
    """`msg` from a bus opened with `sender`'s options gives one opened with `receiver`'s only
    error frames (the two do not talk)."""
    a = can.Bus(interface="canemu", **sender)
    b = can.Bus(interface="canemu", **receiver)
    try:
        a.send(msg)
        only_errors(b)
    finally:
        a.shutdown()
        b.shutdown()


def assert_same_frame(sent, got):
    assert got.arbitration_id == sent.arbitration_id
    assert got.is_extended_id == sent.is_extended_id
    assert got.is_remote_frame == sent.is_remote_frame
    assert got.is_fd == sent.is_fd
    assert got.bitrate_switch == sent.bitrate_switch
    assert got.dlc == sent.dlc
    assert bytes(got.data) == bytes(sent.data)
    assert not got.is_error_frame


def test_the_interface_is_found_through_the_entry_point():
    assert can.interfaces.BACKENDS["canemu"] == ("canemu.bus", "CanemuBus")


def test_a_program_that_never_imports_canemu_talks(realtime_daemon):
    # Another process, as a user's program: python-can finds the interface by its entry point.
    program = (
        "import can, sys\n"
        "a = can.Bus(interface='canemu', channel='can0')\n"
        "b = can.Bus(interface='canemu', channel='can0')\n"
        "a.send(can.Message(arbitration_id=0x321, data=[7], is_extended_id=False))\n"
        "m = b.recv(5.0)\n"
        "print(hex(m.arbitration_id), bytes(m.data).hex(), 'canemu' in sys.modules)\n"
        "a.shutdown(); b.shutdown()\n"
    )
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                          timeout=60, env={**os.environ, "CANEMU_SOCKET": realtime_daemon.socket})
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["0x321", "07", "True"]  # loaded by python-can, not by us


def test_no_message(pair):
    a, _ = pair
    start = time.monotonic()
    assert a.recv(0.1) is None
    assert time.monotonic() - start >= 0.09


def test_timestamps_are_on_the_wall_clock_scale_in_real_time(pair):
    a, b = pair
    got = exchange(a, b, can.Message(arbitration_id=1, is_extended_id=False))
    assert abs(got.timestamp - time.time()) < TIMEOUT


@pytest.mark.parametrize(
    "msg",
    [
        can.Message(arbitration_id=0x123, data=[1, 2, 3, 4, 5, 6, 7, 8], is_extended_id=False),
        can.Message(arbitration_id=0x0, data=[], is_extended_id=False),
        can.Message(arbitration_id=0x7FF, data=[0xFF, 0x00, 0x55], is_extended_id=False),
        can.Message(arbitration_id=0x1ABCDEF0, data=[0xAA] * 8, is_extended_id=True),
        can.Message(arbitration_id=0x123, is_remote_frame=True, dlc=4, is_extended_id=False),
        can.Message(arbitration_id=0x1FFFFFFF, is_remote_frame=True, dlc=0, is_extended_id=True),
    ],
    ids=["standard", "empty", "max-id", "extended", "remote", "remote-extended"],
)
def test_frames_cross_unchanged(pair, msg):
    a, b = pair
    got = exchange(a, b, msg)
    assert_same_frame(msg, got)
    assert got.is_rx
    assert got.channel == "can0"


def test_dlc_less_than_eight(pair):
    a, b = pair
    for n in range(9):
        msg = can.Message(arbitration_id=0x100 + n, data=list(range(n)), is_extended_id=False)
        assert_same_frame(msg, exchange(a, b, msg))


def test_own_messages_come_back_only_when_asked_for(realtime_daemon):
    a = can.Bus(interface="canemu", channel="can0", receive_own_messages=True)
    b = can.Bus(interface="canemu", channel="can0")
    try:
        msg = can.Message(arbitration_id=0x321, data=[9, 8, 7], is_extended_id=False)
        a.send(msg)
        theirs = b.recv(TIMEOUT)
        own = a.recv(TIMEOUT)
        assert theirs is not None and theirs.is_rx
        assert own is not None and not own.is_rx
        assert_same_frame(msg, own)
        # The echo carries the end of transmission; the receiver took it within the same frame.
        assert abs(own.timestamp - theirs.timestamp) < 100e-6
        b.send(msg)
        assert a.recv(TIMEOUT).is_rx
        assert b.recv(0.1) is None  # b did not ask for its own
    finally:
        a.shutdown()
        b.shutdown()


def test_unique_message_instances(pair):
    a, b = pair
    c = can.Bus(interface="canemu", channel="can0")
    try:
        a.send(can.Message(arbitration_id=0x10, data=[1], is_extended_id=False))
        m1 = b.recv(TIMEOUT)
        m2 = c.recv(TIMEOUT)
        assert m1.equals(m2, timestamp_delta=0) and m1 is not m2
        m1.data[0] = 99
        assert m2.data[0] == 1
    finally:
        c.shutdown()


def test_fd_frames(fd_pair):
    a, b = fd_pair
    for length in (0, 8, 12, 20, 48, 64):
        msg = can.Message(arbitration_id=0x42, data=bytes(range(length)), is_fd=True,
                          is_extended_id=False)
        assert_same_frame(msg, exchange(a, b, msg))


def test_fd_frames_with_bit_rate_switch(fd_pair):
    a, b = fd_pair
    msg = can.Message(arbitration_id=0x1234567, data=bytes(range(64)), is_fd=True,
                      bitrate_switch=True, is_extended_id=True)
    assert_same_frame(msg, exchange(a, b, msg))
    # A classic frame on the same FD bus.
    classic = can.Message(arbitration_id=0x43, data=[1, 2], is_extended_id=False)
    assert_same_frame(classic, exchange(b, a, classic))


def test_fd_lengths_are_padded_to_the_next_dlc(fd_pair):
    a, b = fd_pair
    got = exchange(a, b, can.Message(arbitration_id=1, data=bytes(range(9)), is_fd=True,
                                     is_extended_id=False))
    assert got.dlc == 12 and bytes(got.data) == bytes(range(9)) + bytes(3)


def test_protocol(pair, fd_pair):
    if hasattr(can, "CanProtocol"):
        assert pair[0].protocol == can.CanProtocol.CAN_20
        assert fd_pair[0].protocol == can.CanProtocol.CAN_FD
    else:  # python-can before 4.3 has no protocol property
        assert not hasattr(pair[0], "protocol")


def test_fd_frame_on_a_classic_bus_is_refused(pair):
    a, _ = pair
    with pytest.raises(can.CanOperationError, match="fd=True"):
        a.send(can.Message(arbitration_id=1, data=bytes(12), is_fd=True))


def test_fd_needs_an_fd_controller(realtime_daemon):
    with pytest.raises(can.CanInitializationError, match="classic CAN controller"):
        can.Bus(interface="canemu", channel="can0", fd=True)


def test_bad_frames_are_refused_with_the_reason(pair):
    a, _ = pair
    with pytest.raises(can.CanOperationError, match="does not fit 11 bits"):
        a.send(can.Message(arbitration_id=0x800, is_extended_id=False))
    with pytest.raises(can.CanOperationError, match="at most 8"):
        a.send(can.Message(arbitration_id=1, data=bytes(9), is_extended_id=False, check=False))


def test_configured_adapter_controller(realtime_daemon):
    a = can.Bus(interface="canemu", channel="ixxat0:1")  # on can1, 125 kbit/s
    b = can.Bus(interface="canemu", channel="can1")
    try:
        assert a.channel_info == "canemu ixxat0:1 on can1"
        msg = can.Message(arbitration_id=0x55, data=[5], is_extended_id=False)
        assert_same_frame(msg, exchange(a, b, msg))
    finally:
        a.shutdown()
        b.shutdown()


def test_timing_argument_sets_the_controller(realtime_daemon):
    # 500 kbit/s from the SJA1000's 8 MHz: 16 quanta, sample point 87.5 %.
    timing = can.BitTiming(f_clock=8_000_000, brp=1, tseg1=13, tseg2=2, sjw=1)
    passes({"channel": "can0", "timing": timing}, {"channel": "can0"},
           can.Message(arbitration_id=0x66, data=[6], is_extended_id=False))


def test_timing_from_another_clock_keeps_rate_and_sample_point(realtime_daemon):
    # 500 kbit/s at 87.5 % described for a 16 MHz clock: made from the SJA1000's own clock.
    timing = can.BitTiming(f_clock=16_000_000, brp=2, tseg1=13, tseg2=2, sjw=1)
    passes({"channel": "can0", "timing": timing}, {"channel": "can0"},
           can.Message(arbitration_id=0x67, data=[7], is_extended_id=False))


def only_errors(receiver, count: int = 20) -> None:
    """The next `count` messages `receiver` gets are all error frames (none is a frame)."""
    for _ in range(count):
        got = receiver.recv(TIMEOUT)
        assert got is not None and got.is_error_frame, got


@pytest.mark.parametrize(
    "timing",
    [
        # 250 kbit/s from the SJA1000's 8 MHz: 2 x 16 quanta, sample point 87.5 %.
        dict(f_clock=8_000_000, brp=2, tseg1=13, tseg2=2, sjw=1),
        # 250 kbit/s described for a 16 MHz clock: made from the SJA1000's own clock.
        dict(f_clock=16_000_000, brp=4, tseg1=13, tseg2=2, sjw=1),
    ],
    ids=["controller-clock", "another-clock"],
)
def test_timing_at_another_rate_cannot_talk(realtime_daemon, timing):
    # The timing wins over the bus's 500 kbit/s: the others see errors, never the frame.
    garbled({"channel": "can0", "timing": can.BitTiming(**timing)}, {"channel": "can0"},
            can.Message(arbitration_id=0x78, data=[8], is_extended_id=False))


# A can.BitTiming on the CAN FD controller (python-can 4.1 has no BitTimingFd): the nominal
# phase; the data phase follows data_bitrate (default: the bus's 2 Mbit/s).
FD = {"channel": "fd0", "fd": True}
FD_NOMINAL_500K = dict(f_clock=80_000_000, brp=10, tseg1=12, tseg2=3, sjw=1)
FD_NOMINAL_250K = dict(f_clock=80_000_000, brp=20, tseg1=12, tseg2=3, sjw=1)


def test_classic_timing_on_an_fd_controller_sets_the_nominal_phase(realtime_daemon):
    passes({**FD, "timing": can.BitTiming(**FD_NOMINAL_500K)}, FD,
           can.Message(arbitration_id=0x6B, data=bytes(range(24)), is_fd=True,
                       bitrate_switch=True, is_extended_id=False))


@pytest.mark.parametrize(
    "timing,data_bitrate,brs",
    [
        (FD_NOMINAL_250K, None, False),  # nominal 250 kbit/s on a 500 kbit/s bus
        (FD_NOMINAL_500K, 1_000_000, True),  # data phase at 1 Mbit/s on a 2 Mbit/s bus
    ],
    ids=["nominal", "data"],
)
def test_classic_timing_on_an_fd_controller_at_another_rate_cannot_talk(
    realtime_daemon, timing, data_bitrate, brs
):
    rates = {} if data_bitrate is None else {"data_bitrate": data_bitrate}  # 4.1 wants no None
    garbled({**FD, "timing": can.BitTiming(**timing), **rates}, FD,
            can.Message(arbitration_id=0x6C, data=bytes(16), is_fd=True, bitrate_switch=brs,
                        is_extended_id=False))


needs_bit_timing_fd = pytest.mark.skipif(
    not hasattr(can, "BitTimingFd"), reason="python-can before 4.2 has no BitTimingFd")


@needs_bit_timing_fd
def test_fd_timing_argument(realtime_daemon):
    # fd0: 500 kbit/s nominal, 2 Mbit/s data, from the FD controller's 80 MHz.
    timing = can.BitTimingFd(f_clock=80_000_000, nom_brp=2, nom_tseg1=63, nom_tseg2=16,
                             nom_sjw=16, data_brp=1, data_tseg1=29, data_tseg2=10, data_sjw=10)
    passes({**FD, "timing": timing}, FD,
           can.Message(arbitration_id=0x68, data=bytes(range(32)), is_fd=True,
                       bitrate_switch=True, is_extended_id=False))
    with pytest.raises(can.CanInitializationError, match="needs a CAN FD controller"):
        can.Bus(interface="canemu", channel="can0", timing=timing)


@needs_bit_timing_fd
@pytest.mark.parametrize(
    "nominal_brp,data_brp,brs",
    [
        (4, 1, False),  # nominal 250 kbit/s on a 500 kbit/s bus
        (2, 2, True),  # data phase at 1 Mbit/s on a 2 Mbit/s bus
    ],
    ids=["nominal", "data"],
)
def test_fd_timing_at_another_rate_cannot_talk(realtime_daemon, nominal_brp, data_brp, brs):
    timing = can.BitTimingFd(f_clock=80_000_000, nom_brp=nominal_brp, nom_tseg1=63,
                             nom_tseg2=16, nom_sjw=16, data_brp=data_brp, data_tseg1=29,
                             data_tseg2=10, data_sjw=10)
    garbled({**FD, "timing": timing}, FD,
            can.Message(arbitration_id=0x6D, data=bytes(16), is_fd=True, bitrate_switch=brs,
                        is_extended_id=False))


def test_listen_only_receives_but_never_acknowledges(realtime_daemon):
    listener = can.Bus(interface="canemu", channel="can0", listen_only=True)
    sender = can.Bus(interface="canemu", channel="can0")
    try:
        sender.send(can.Message(arbitration_id=0x6A, data=[1], is_extended_id=False))
        # Nobody acknowledges: the sender repeats until error-passive.
        got = sender.recv(TIMEOUT)
        assert got is not None and got.is_error_frame
        assert got.arbitration_id & 0x20  # CAN_ERR_ACK
        helper = can.Bus(interface="canemu", channel="can0")  # acknowledges from now on
        try:
            while (m := listener.recv(TIMEOUT)) is not None and m.is_error_frame:
                pass
            assert m is not None and m.arbitration_id == 0x6A
        finally:
            helper.shutdown()
        assert listener.error_counters() == (0, 0)
    finally:
        listener.shutdown()
        sender.shutdown()


# A node with a wrong bit rate cannot talk: the others see errors, not the frame. "nominal":
# 250 kbit/s on a 500 kbit/s bus; "data": a wrong data bit rate breaks FD frames with bit rate
# switch.
WRONG_BITRATES = {
    "nominal": ("can0", dict(bitrate=250_000), {},
                can.Message(arbitration_id=0x77, data=[7], is_extended_id=False)),
    "data": ("fd0", dict(fd=True, data_bitrate=4_000_000), dict(fd=True),
             can.Message(arbitration_id=0x69, data=bytes(16), is_fd=True, bitrate_switch=True,
                         is_extended_id=False)),
}


@pytest.mark.parametrize("case", WRONG_BITRATES)
def test_a_wrong_bitrate_cannot_talk(realtime_daemon, case):
    channel, wrong, right, message = WRONG_BITRATES[case]
    a = can.Bus(interface="canemu", channel=channel, **wrong)
    b = can.Bus(interface="canemu", channel=channel, **right)
    try:
        a.send(message)
        got = b.recv(TIMEOUT)
        assert got is not None and got.is_error_frame
    finally:
        a.shutdown()
        b.shutdown()


def test_unknown_channel_names_what_exists(realtime_daemon):
    with pytest.raises(can.CanInitializationError, match="buses: can0, can1, fd0"):
        can.Bus(interface="canemu", channel="nosuch")
    with pytest.raises(can.CanInitializationError,
                       match="adapter ixxat0 has 2 CAN controllers, ixxat0:0 on can0 and "
                             "ixxat0:1 on can1$"):
        can.Bus(interface="canemu", channel="ixxat0:2")


def test_no_daemon_says_how_to_start_it(realtime_daemon):
    try:
        with pytest.raises(can.CanInitializationError, match="canemud is not running"):
            can.Bus(interface="canemu", channel="can0",
                    socket=realtime_daemon.dir + "/nobody.sock")
    finally:
        canemu.connect(realtime_daemon.socket)


def test_at_most_16_buses_of_their_own_per_process(realtime_daemon):
    buses = []
    try:
        for _ in range(16):
            buses.append(can.Bus(interface="canemu", channel="can0"))
        with pytest.raises(can.CanInitializationError, match="at most 16 adapters"):
            can.Bus(interface="canemu", channel="can0")
        buses.pop().shutdown()  # its adapter goes: room for one again
        buses.append(can.Bus(interface="canemu", channel="can1"))
    finally:
        for bus in buses:
            bus.shutdown()


def test_failures_are_python_can_errors(realtime_daemon):
    """Every public path maps the VCI's failures to python-can's exceptions (canemud gone
    here): CanOperationError, CanInitializationError for a new bus; never the VciError."""
    private = Canemud("realtime")  # the process talks to this one now
    try:
        bus = can.Bus(interface="canemu", channel="can0")
        private.proc.kill()
        private.proc.wait()
        calls = {
            "sim_time": canemu.sim_time,
            "step": lambda: canemu.step(1000),
            "buses": canemu.buses,
            "state": lambda: bus.state,
            "error_counters": bus.error_counters,
            "restart": bus.restart,
            "set_filters": lambda: bus.set_filters([{"can_id": 1, "can_mask": 0x7FF}]),
            "send_periodic": lambda: bus.send_periodic(
                can.Message(arbitration_id=1, is_extended_id=False), 0.01),
        }
        for name, call in calls.items():
            try:
                call()  # a VciError would leave the test here
            except can.CanOperationError as e:
                assert "disconnected" in str(e), name
            else:
                pytest.fail(f"{name} did not fail")
        with pytest.raises(can.CanInitializationError, match="canemud is not running"):
            can.Bus(interface="canemu", channel="can0")
        assert can.detect_available_configs(["canemu"]) == []
        bus.shutdown()
    finally:
        private.stop()
        canemu.connect(realtime_daemon.socket)


def test_detect_available_configs(realtime_daemon):
    configs = can.detect_available_configs(interfaces=["canemu"])
    channels = {c["channel"] for c in configs}
    assert {"ixxat0:0", "ixxat0:1", "ixxatfd:0", "can0", "can1", "fd0"} <= channels
    assert all(c["interface"] == "canemu" for c in configs)
    fd = {c["channel"]: c["fd"] for c in configs}
    assert fd["ixxatfd:0"] and fd["fd0"] and not fd["can0"]


def test_multiple_shutdown(realtime_daemon):
    bus = can.Bus(interface="canemu", channel="can0")
    bus.shutdown()
    bus.shutdown()


def test_ephemeral_adapter_goes_with_its_bus(realtime_daemon):
    bus = can.Bus(interface="canemu", channel="can0")
    name = bus.channel_info.split()[1].split(":")[0]
    assert name in {c["channel"].split(":")[0] for c in can.detect_available_configs(["canemu"])}
    bus.shutdown()
    assert name not in {c["channel"].split(":")[0]
                        for c in can.detect_available_configs(["canemu"])}


# ---- filters ----


def receive_ids(sender, receiver, frames):
    for arbitration_id, extended in frames:
        sender.send(can.Message(arbitration_id=arbitration_id, is_extended_id=extended))
    # A marker frame that every filter below lets through ends the sequence.
    sender.send(can.Message(arbitration_id=0x7E0, is_extended_id=False))
    got = []
    while True:
        msg = receiver.recv(TIMEOUT)
        assert msg is not None, f"the marker did not come; got {got}"
        if msg.arbitration_id == 0x7E0 and not msg.is_extended_id:
            return got
        got.append((msg.arbitration_id, msg.is_extended_id))


FRAMES = [(0x100, False), (0x101, False), (0x200, False), (0x100, True), (0x1234567, True)]


def channel_ids(sender, receiver, frames, marker=(0x7E0, False)):
    """Like receive_ids, but what comes out of the receiver's channel itself (read from its VCI
    channel, before python-can's software filter), each data frame with the VCI's acceptance
    code (bAccept: which stage of the channel's filter let it through). The bus must say the
    channel does the filtering."""
    assert receiver._hw_filtered
    for arbitration_id, extended in frames + [marker]:
        sender.send(can.Message(arbitration_id=arbitration_id, is_extended_id=extended))
    lib = _vci.lib()
    m = _vci.CANMSG2()
    got = []
    while True:
        hr = lib.canChannelReadMessage(receiver._channel, int(TIMEOUT * 1000), ctypes.byref(m))
        assert hr == _vci.VCI_OK, f"the marker did not come; got {got}"
        if m.bType != _vci.CAN_MSGTYPE_DATA:
            continue
        frame = (m.dwMsgId, bool(m.bFlags & _vci.FLAGS_EXT))
        if frame == marker:
            return got
        got.append((*frame, m.bAccept))


def test_one_filter_per_format_is_the_channel_acceptance_filter(pair):
    a, b = pair
    b.set_filters([
        {"can_id": 0x7E0, "can_mask": 0x7F0, "extended": False},
        {"can_id": 0x1234560, "can_mask": 0x1FFFFFF0, "extended": True},
    ])
    frames = [(0x100, False), (0x7E5, False), (0x7F0, False), (0x1234567, True),
              (0x1234570, True), (0x7E5, True)]
    # Only what matches comes out of the channel: the others never reach python-can.
    assert channel_ids(a, b, frames) == [
        (0x7E5, False, CAN_ACCEPT_FILTER_1),
        (0x1234567, True, CAN_ACCEPT_FILTER_1),
    ]


def test_several_filters_of_a_format_go_into_the_channel_id_list(pair):
    a, b = pair
    b.set_filters([
        {"can_id": 0x100, "can_mask": 0x7FE, "extended": False},
        {"can_id": 0x7E0, "can_mask": 0x7FF, "extended": False},
    ])
    assert channel_ids(a, b, FRAMES) == [(0x100, False, CAN_ACCEPT_FILTER_2),
                                         (0x101, False, CAN_ACCEPT_FILTER_2)]
    assert receive_ids(a, b, FRAMES) == [(0x100, False), (0x101, False)]


def test_setting_filters_again_replaces_the_channel_filters(pair):
    a, b = pair
    marker = {"can_id": 0x7E0, "can_mask": 0x7FF, "extended": False}
    b.set_filters([{"can_id": 0x100, "can_mask": 0x7FF, "extended": False}, marker,
                   {"can_id": 0x1234567, "can_mask": 0x1FFFFFFF, "extended": True},
                   {"can_id": 0x0000100, "can_mask": 0x1FFFFFFF, "extended": True}])
    assert [f[:2] for f in channel_ids(a, b, FRAMES)] == [(0x100, False), (0x100, True),
                                                           (0x1234567, True)]
    # The second set: the IDs of the first no longer pass the channel.
    b.set_filters([{"can_id": 0x200, "can_mask": 0x7FF, "extended": False}, marker,
                   {"can_id": 0x0000100, "can_mask": 0x1FFFFFFF, "extended": True},
                   {"can_id": 0x1ABCDEF, "can_mask": 0x1FFFFFFF, "extended": True}])
    assert b._hw_filtered
    assert [f[:2] for f in channel_ids(a, b, FRAMES)] == [(0x200, False), (0x100, True)]
    # One filter per format now: the acceptance filter alone, the lists empty.
    b.set_filters([marker, {"can_id": 0x1ABCDEF, "can_mask": 0x1FFFFFFF, "extended": True}])
    assert channel_ids(a, b, FRAMES) == []
    # No filters: everything passes again.
    b.set_filters(None)
    assert b._hw_filtered
    assert [f[:2] for f in channel_ids(a, b, FRAMES)] == FRAMES


def test_a_filter_with_identifier_bits_a_format_lacks_matches_none_of_it(pair):
    a, b = pair
    # No "extended": python-can applies it to both formats, but no 11-bit ID has bit 20 set.
    b.set_filters([{"can_id": 0x100100, "can_mask": 0x1FFFFFFF},
                   {"can_id": 0x7E0, "can_mask": 0x7FF, "extended": False}])
    assert channel_ids(a, b, [(0x100, False), (0x100100, True)]) == [
        (0x100100, True, CAN_ACCEPT_FILTER_1)]


def test_filter_without_format_applies_to_both(pair):
    a, b = pair
    b.set_filters([{"can_id": 0x100, "can_mask": 0x7FF}, {"can_id": 0x7E0, "can_mask": 0x7FF}])
    assert receive_ids(a, b, FRAMES) == [(0x100, False), (0x100, True)]


def test_wide_extended_filters_fall_back_to_software(pair):
    a, b = pair
    # Two 29-bit patterns with 20 free bits each: 2 x 2^20 IDs do not fit the channel's list.
    b.set_filters([
        {"can_id": 0x1200000, "can_mask": 0x1F00000, "extended": True},
        {"can_id": 0x0000000, "can_mask": 0x1F00000, "extended": True},
        {"can_id": 0x7E0, "can_mask": 0x7FF, "extended": False},
    ])
    assert not b._hw_filtered
    assert receive_ids(a, b, FRAMES) == [(0x100, True), (0x1234567, True)]
    b.set_filters(None)
    assert b._hw_filtered
    assert receive_ids(a, b, FRAMES) == FRAMES


# ---- waiting on the descriptor ----


def test_fileno_is_readable_while_messages_wait_and_quiet_after(pair):
    a, b = pair
    fd = b.fileno()
    assert b.recv(0) is None  # takes the line's start message (not a frame)
    assert select.select([fd], [], [], 0)[0] == []
    for i in range(1, 4):
        a.send(can.Message(arbitration_id=i, is_extended_id=False))
    got = []
    deadline = time.monotonic() + TIMEOUT
    while len(got) < 3 and time.monotonic() < deadline:
        if select.select([fd], [], [], deadline - time.monotonic())[0]:
            msg = b.recv(0)  # may find nothing: the descriptor may wake early
            if msg is not None:
                got.append(msg.arbitration_id)
    assert got == [1, 2, 3]
    # Nothing left: one empty read and the descriptor is quiet.
    assert b.recv(0) is None
    assert select.select([fd], [], [], 0)[0] == []
    a.send(can.Message(arbitration_id=4, is_extended_id=False))
    assert select.select([fd], [], [], TIMEOUT)[0] == [fd]


def test_notifier_in_a_thread(pair):
    a, b = pair
    reader = can.BufferedReader()
    notifier = can.Notifier(b, [reader], timeout=0.1)
    try:
        for i in range(20):
            a.send(can.Message(arbitration_id=i, is_extended_id=False))
        got = [reader.get_message(TIMEOUT) for _ in range(20)]
        assert [m.arbitration_id for m in got] == list(range(20))
    finally:
        notifier.stop()


def test_notifier_with_asyncio(pair):
    a, b = pair

    async def main():
        reader = can.AsyncBufferedReader()
        notifier = can.Notifier(b, [reader], loop=asyncio.get_running_loop())
        try:
            for i in range(50):
                a.send(can.Message(arbitration_id=i, data=[i], is_extended_id=False))
            got = [await asyncio.wait_for(reader.get_message(), TIMEOUT) for _ in range(50)]
        finally:
            notifier.stop()
        return got

    got = asyncio.run(main())
    assert [m.arbitration_id for m in got] == list(range(50))


# ---- cyclic transmission ----


def test_send_periodic_uses_the_cyclic_list(pair):
    a, b = pair
    msg = can.Message(arbitration_id=0x99, data=[1, 2], is_extended_id=False)
    task = a.send_periodic(msg, 0.01)
    assert isinstance(task, canemu.CanemuCyclicTask)
    try:
        got = [b.recv(TIMEOUT) for _ in range(5)]
        assert all(m is not None and m.arbitration_id == 0x99 for m in got)
        gaps = [y.timestamp - x.timestamp for x, y in zip(got, got[1:])]
        assert all(abs(g - 0.01) < 1e-3 for g in gaps), gaps
        task.modify_data(can.Message(arbitration_id=0x99, data=[3, 4], is_extended_id=False))
        while (m := b.recv(TIMEOUT)) is not None and bytes(m.data) != b"\x03\x04":
            pass
        assert m is not None
    finally:
        task.stop()


def test_send_periodic_falls_back_to_software(pair):
    a, b = pair
    msgs = [can.Message(arbitration_id=0x98, data=[k], is_extended_id=False) for k in range(3)]
    task = a.send_periodic(msgs, 0.005)  # a sequence: the cyclic list sends one message
    assert not isinstance(task, canemu.CanemuCyclicTask)
    try:
        got = [b.recv(TIMEOUT) for _ in range(6)]
        assert [m.data[0] for m in got] == [0, 1, 2, 0, 1, 2]
    finally:
        task.stop()


def test_shutdown_stops_periodic_tasks(realtime_daemon):
    a = can.Bus(interface="canemu", channel="can0")
    b = can.Bus(interface="canemu", channel="can0")
    try:
        a.send_periodic(can.Message(arbitration_id=0x97, is_extended_id=False), 0.002)
        assert b.recv(TIMEOUT) is not None
        a.shutdown()
        while b.recv(0.05) is not None:  # what was on its way
            pass
        assert b.recv(0.1) is None
    finally:
        a.shutdown()
        b.shutdown()
