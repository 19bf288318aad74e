"""The receive and send hot paths of the python-can interface: the Messages that recv builds
without Message.__init__ (_convert_run) are those __init__ builds, attribute for attribute; the
short path of recv keeps BusABC.recv's behaviour (order, software filters, its log record,
several reading threads); send's short path sends what the general one sends. Run with both
python-can versions (make test)."""

from __future__ import annotations

import ctypes
import sys
import threading
import weakref
from collections import deque
from pathlib import Path

import can
import pytest
from can import Message

import canemu
from canemu import _vci
from canemu._receive import _FLOAT_EXACT, _MSG_SIZE, _RX_BATCH, _ReceiveMixin
from canemu.bus import CAN_ERR_ACK, CAN_ERR_BUSERROR

from conftest import bus_pair, drain, frames, ns

MS = 1_000_000
# Every attribute a Message has: its slots (python-can 4.1 and 4.6 list the same ones).
ATTRIBUTES = [name for name in Message.__slots__ if name != "__weakref__"]


def assert_same_message(got: Message, want: Message) -> None:
    """`got` has every attribute of `want`, equal and of the same type (a bool is no int)."""
    assert type(got) is Message
    for name in ATTRIBUTES:
        value, expected = getattr(got, name), getattr(want, name)
        assert value == expected and type(value) is type(expected), (name, value, expected)
    assert got.equals(want, timestamp_delta=0)


def test_a_message_has_exactly_the_slots_compared():
    """Message.__init__ sets every slot, and nothing lies outside them: comparing the slots
    compares the whole message."""
    msg = Message()
    assert all(hasattr(msg, name) for name in ATTRIBUTES)
    assert not hasattr(msg, "__dict__")
    assert set(ATTRIBUTES) == {
        "timestamp", "arbitration_id", "is_extended_id", "is_remote_frame", "is_error_frame",
        "channel", "dlc", "data", "is_fd", "is_rx", "bitrate_switch", "error_state_indicator"}


# ---- _convert_run against _convert, without canemud ----


class _Receiver(_ReceiveMixin):
    """The receive side's state alone, as a bus has it after opening (no channel)."""

    def __init__(self, epoch_ns: int = 1_700_000_000_123_456_789) -> None:
        self._rx_bytes = bytearray(_RX_BATCH * _MSG_SIZE)
        self._rx_batch = (_vci.CANMSG2 * _RX_BATCH).from_buffer(self._rx_bytes)
        self._rx_batch_view = memoryview(self._rx_bytes)
        self._rx_count = self._rx_next = 0
        self._rx_ready = deque()
        self._pending = deque()
        self._rx_lock = threading.Lock()
        self._closed = False
        self._hw_filtered = True
        self._reported = _vci.CANEMU_STATE_ACTIVE
        self._counters = (0, 0)
        self._wraps = 0
        self._last_ticks = 0
        self._epoch_ns = epoch_ns
        self._time_offset = 0.25
        self._channel_name = "fd0"

    def load(self, messages) -> None:
        """`messages` (ticks, ident, type, flags2, flags, data) as the batch taken from the
        ring."""
        for k, (ticks, ident, kind, flags2, flags, data) in enumerate(messages):
            m = self._rx_batch[k]
            m.dwTime, m.dwMsgId, m.bType, m.bFlags2, m.bFlags = ticks, ident, kind, flags2, flags
            m.bAccept = 0
            ctypes.memmove(m.abData, data, len(data))
        self._rx_count, self._rx_next = len(messages), 0


def all_data_frames():
    """A data frame of every bFlags (DLC 0-15, RTR, EXT, SRR) with every bFlags2 that matters
    (EDL, FDR, ESI, and SSM/HPM that must not), time stamps that wrap twice."""
    out = []
    ticks = 0xFFFF_F000
    for flags2 in (0, _vci.FLAGS2_SSM, _vci.FLAGS2_HPM, _vci.FLAGS2_EDL,
                   _vci.FLAGS2_EDL | _vci.FLAGS2_FDR, _vci.FLAGS2_EDL | _vci.FLAGS2_ESI,
                   _vci.FLAGS2_EDL | _vci.FLAGS2_FDR | _vci.FLAGS2_ESI, _vci.FLAGS2_FDR,
                   _vci.FLAGS2_ESI):
        for flags in range(256):
            if flags & _vci.FLAGS_OVR:
                continue
            ident = (0x1ABCDE00 | flags) if flags & _vci.FLAGS_EXT else 0x700 | (flags & 0x7F)
            data = bytes((flags + k) & 0xFF for k in range(64))
            out.append((ticks & 0xFFFF_FFFF, ident, _vci.CAN_MSGTYPE_DATA, flags2, flags, data))
            ticks += 0x600000
    return out


# Epochs where _convert_run sums a time stamp in integers, in floats, and in floats until the
# first wrap of the adapter's counter takes it past what a float holds exactly.
@pytest.mark.parametrize("epoch_ns", [1_700_000_000_123_456_789, 123_456_789,
                                      _FLOAT_EXACT - 5_000])
def test_the_batch_path_builds_what_message_init_builds(epoch_ns):
    fast, slow = _Receiver(epoch_ns), _Receiver(epoch_ns)
    messages = all_data_frames()
    assert len(messages) > 1000
    wraps_seen = 0
    for start in range(0, len(messages), _RX_BATCH):
        batch = messages[start : start + _RX_BATCH]
        fast.load(batch)
        fast._convert_run()
        assert fast._rx_next == len(batch) and len(fast._rx_ready) == len(batch)
        slow.load(batch)
        for k in range(len(batch)):
            want, filtered = slow._convert(slow._rx_batch_view, k * _MSG_SIZE)
            assert filtered
            got = fast._rx_ready.popleft()
            assert_same_message(got, want)
            weakref.ref(got)  # python-can 4.6 lists __weakref__ among the slots
        assert (fast._wraps, fast._last_ticks) == (slow._wraps, slow._last_ticks)
        wraps_seen = fast._wraps
    assert wraps_seen == 2


def test_the_batch_path_stops_before_another_kind_of_message():
    r = _Receiver()
    data = bytes(8)
    r.load([
        (10, 0x100, _vci.CAN_MSGTYPE_DATA, 0, 8, data),
        (20, 0x101, _vci.CAN_MSGTYPE_DATA, 0, 8, data),
        (30, 0, _vci.CAN_MSGTYPE_ERROR, 0, 8, bytes([_vci.CAN_ERROR_ACK, 0, 0, 1, 0])),
        (40, 0x102, _vci.CAN_MSGTYPE_DATA, 0, 8, data),
    ])
    r._convert_run()
    assert [m.arbitration_id for m in r._rx_ready] == [0x100, 0x101]
    assert (r._rx_next, r._last_ticks) == (2, 20)
    got = [r._recv_internal(0)[0] for _ in range(4)]
    assert [(m.arbitration_id, m.is_error_frame) for m in got] == [
        (0x100, False), (0x101, False), (CAN_ERR_ACK | CAN_ERR_BUSERROR, True), (0x102, False)]
    assert (r._rx_next, len(r._rx_ready)) == (4, 0)


def test_an_error_passive_node_converts_one_frame_at_a_time():
    """While error-passive a frame may end the crossing (_convert): no batch conversion."""
    r = _Receiver()
    r._reported = _vci.CANEMU_STATE_PASSIVE
    r.load([(k, 0x100 + k, _vci.CAN_MSGTYPE_DATA, 0, 1, bytes([k])) for k in range(3)])
    for k in range(3):
        msg, filtered = r._recv_internal(0)
        assert (msg.arbitration_id, bytes(msg.data), filtered) == (0x100 + k, bytes([k]), True)
        assert not r._rx_ready and r._rx_next == k + 1


# ---- through canemud ----


@pytest.fixture
def fd_nodes(daemon):
    """Two CAN FD nodes on fd0; the sender also receives its own frames."""
    yield from bus_pair("fd0", drained=True, own={"receive_own_messages": True}, fd=True)


def sent_frames():
    out = []
    for ext in (False, True):
        ident = 0x1234567 if ext else 0x123
        for n in range(9):
            out.append(Message(arbitration_id=ident + n, is_extended_id=ext,
                               data=bytes(range(n))))
            out.append(Message(arbitration_id=ident + n, is_extended_id=ext,
                               is_remote_frame=True, dlc=n))
        for n in _vci.DLC_TO_LEN:
            for brs in (False, True):
                out.append(Message(arbitration_id=ident, is_extended_id=ext, is_fd=True,
                                   bitrate_switch=brs, data=bytes(range(n))))
    return out


def expected(sent: Message, got: Message, is_rx: bool) -> Message:
    """What Message.__init__ makes of the frame `sent` as canemu receives it."""
    return Message(timestamp=got.timestamp, arbitration_id=sent.arbitration_id,
                   is_extended_id=sent.is_extended_id, is_remote_frame=sent.is_remote_frame,
                   is_fd=sent.is_fd, bitrate_switch=sent.bitrate_switch,
                   error_state_indicator=False, dlc=sent.dlc, data=sent.data, channel="fd0",
                   is_rx=is_rx)


def test_received_frames_are_the_messages_init_makes(fd_nodes):
    a, b = fd_nodes
    sent = sent_frames()
    for msg in sent:
        a.send(msg)
    canemu.step(100 * MS)
    first = b.recv(0)
    assert len(b._rx_ready) == min(len(sent), _RX_BATCH) - 1  # the batch path made them
    got_b = [first] + drain(b)
    got_a = drain(a)
    assert len(got_b) == len(got_a) == len(sent)
    for want, rx, own in zip(sent, got_b, got_a):
        assert_same_message(rx, expected(want, rx, True))
        assert_same_message(own, expected(want, own, False))
    stamps = [m.timestamp for m in got_b]
    assert stamps == sorted(stamps) and len(set(stamps)) == len(stamps)


def test_error_frames_are_the_messages_init_makes(nodes):
    """A node alone on the bus: its frame is never acknowledged; the error frames between the
    data frames (own ones) come in their order."""
    lone, other = nodes
    other.shutdown()
    lone.send(Message(arbitration_id=0x55, is_extended_id=False, data=[1]))
    canemu.step(5 * MS)
    got = drain(lone)
    errors = [m for m in got if m.is_error_frame]
    assert errors
    for m in errors:
        assert_same_message(m, Message(timestamp=m.timestamp, arbitration_id=m.arbitration_id,
                                       is_error_frame=True, dlc=8, data=bytes(m.data),
                                       channel="can0"))
    assert [m.timestamp for m in got] == sorted(m.timestamp for m in got)


def test_software_filters_keep_busabc_recv(daemon):
    """Filters python-can matches itself: recv(0) that takes a frame the filters drop returns
    None (BusABC.recv's timeout), the next call the frame that matches."""
    a = can.Bus(interface="canemu", channel="can0")
    b = can.Bus(interface="canemu", channel="can0")
    try:
        b.set_filters([
            {"can_id": 0x1200000, "can_mask": 0x1F00000, "extended": True},
            {"can_id": 0x0000000, "can_mask": 0x1F00000, "extended": True},
        ])
        assert not b._hw_filtered
        a.send(Message(arbitration_id=0x1300000, data=[1]))
        a.send(Message(arbitration_id=0x1234567, data=[2]))
        canemu.step(5 * MS)
        assert b.recv(0) is None
        msg = b.recv(0)
        assert (msg.arbitration_id, bytes(msg.data)) == (0x1234567, b"\x02")
        assert b.recv(0) is None
    finally:
        a.shutdown()
        b.shutdown()


def test_recv_writes_busabc_log_record(nodes, caplog):
    a, b = nodes
    for k in range(3):
        a.send(Message(arbitration_id=0x10 + k, is_extended_id=False, data=[k]))
    canemu.step(5 * MS)
    with caplog.at_level(b.RECV_LOGGING_LEVEL, logger="can.bus"):
        got = frames(drain(b))
    records = [r for r in caplog.records if r.name == "can.bus" and r.msg == "Received: %s"]
    assert [r.args[0] if isinstance(r.args, tuple) else r.args for r in records] == got
    assert all(r.levelno == b.RECV_LOGGING_LEVEL for r in records) and len(got) == 3


def test_threads_reading_one_bus_share_its_frames(nodes):
    """Two threads calling recv at once: every frame once, each thread's in order."""
    a, b = nodes
    total = 600
    for start in range(0, total, 200):
        for k in range(start, start + 200):
            a.send(Message(arbitration_id=k & 0x7FF, is_extended_id=False,
                           data=k.to_bytes(2, "little")))
        canemu.step(40 * MS)
    got = [[], []]
    barrier = threading.Barrier(2)

    def read(out):
        barrier.wait()
        while (msg := b.recv(0)) is not None:
            out.append(int.from_bytes(msg.data, "little"))

    threads = [threading.Thread(target=read, args=(out,)) for out in got]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(got[0] + got[1]) == list(range(total))
    assert all(out == sorted(out) for out in got)


@pytest.mark.parametrize("data", [b"\x01\x02\x03", bytearray(b"\x01\x02\x03"), [1, 2, 3],
                                  memoryview(b"\x01\x02\x03"), b""])
def test_send_takes_any_data_python_can_does(nodes, data):
    a, b = nodes
    msg = Message(arbitration_id=0x7FF, is_extended_id=False)
    msg.data = data  # as a program may set it after making the message
    a.send(msg)
    a.send(Message(arbitration_id=0x1FFFFFFF, is_extended_id=True, data=bytes(8)))
    canemu.step(5 * MS)
    got = frames(drain(b))
    assert [(m.arbitration_id, bytes(m.data), m.dlc) for m in got] == [
        (0x7FF, bytes(data), len(bytes(data))), (0x1FFFFFFF, bytes(8), 8)]


@pytest.mark.parametrize("msg, reason", [
    (Message(arbitration_id=0x800, is_extended_id=False), "does not fit 11 bits"),
    (Message(arbitration_id=0x20000000, is_extended_id=True), "does not fit 29 bits"),
    (Message(arbitration_id=-1, is_extended_id=False), "does not fit 11 bits"),
    (Message(arbitration_id=1, data=bytes(9)), "at most 8 data bytes"),
])
def test_send_refuses_what_the_general_path_refuses(nodes, msg, reason):
    a, _ = nodes
    with pytest.raises(can.CanOperationError, match=reason):
        a.send(msg)


def test_send_after_shutdown_is_a_python_can_error(daemon):
    bus = can.Bus(interface="canemu", channel="can0")
    bus.shutdown()
    with pytest.raises(can.CanOperationError):
        bus.send(Message(arbitration_id=1, is_extended_id=False))


# ---- send's hot path in C (canemu_speedups) ----
# Every classic data frame the C path takes: both formats at their extremes, 0 to 8 bytes, the
# data as bytes and as bytearray.
C_FRAMES = [Message(arbitration_id=i, is_extended_id=ext, data=d)
            for i, ext, d in [(0, False, b""), (0x7FF, False, bytearray(b"\x01")),
                              (0x123, False, bytes(range(8))), (0, True, b"\xff" * 5),
                              (0x1FFFFFFF, True, bytearray(range(1, 9)))]]
# What it leaves to the Python path (which sends or refuses each as it always did).
NOT_C = [Message(arbitration_id=1, is_extended_id=False, is_remote_frame=True, dlc=2),
         Message(arbitration_id=1, is_extended_id=False, is_error_frame=True),
         Message(arbitration_id=0x800, is_extended_id=False),
         Message(arbitration_id=-1, is_extended_id=False),
         Message(arbitration_id=0x20000000, is_extended_id=True),
         Message(arbitration_id=1, is_extended_id=False, data=bytes(9))]


def test_make_test_builds_the_speedups_and_a_bus_uses_them(nodes):
    """python3-dev is one of the dependencies, so the C path is there and send() tries it:
    the other send tests of the suites run through it."""
    a, _ = nodes
    assert _vci.speedups() is not None
    assert a._fast_post is not None


def test_the_c_path_takes_classic_data_frames_and_leaves_the_rest(nodes):
    a, _ = nodes
    assert all(a._fast_post(m) is True for m in C_FRAMES)
    assert not any(a._fast_post(m) for m in NOT_C)
    msg = Message(arbitration_id=1, is_extended_id=False)
    msg.data = [1, 2]  # a list: python-can takes it, the Python path converts it
    assert a._fast_post(msg) is False
    assert a._fast_post("not a message") is False


@pytest.mark.parametrize("own", [False, True])
def test_the_c_path_sends_what_the_python_path_sends(daemon, own):
    """The same frames through each path, as the other node and the sender itself (with
    receive_own_messages: bFlags's SRR) receive them: the same messages, the same times after
    the first."""
    seen = {}
    for path in ("c", "python"):
        a = can.Bus(interface="canemu", channel="can0", receive_own_messages=own)
        b = can.Bus(interface="canemu", channel="can0")
        try:
            canemu.step(10 * MS)
            drain(a)
            drain(b)
            if path == "python":
                a._fast_post = None
            for m in C_FRAMES:
                a.send(m)
            canemu.step(10 * MS)
            got = []
            for node in (a, b):
                msgs = frames(drain(node))
                got.append([(m.arbitration_id, m.is_extended_id, bytes(m.data), m.dlc, m.is_rx,
                             ns(m.timestamp - msgs[0].timestamp)) for m in msgs])
            seen[path] = got
        finally:
            a.shutdown()
            b.shutdown()
    assert seen["c"] == seen["python"]
    theirs = seen["c"][1]
    assert [(i, ext, d) for i, ext, d, *_ in theirs] == [
        (m.arbitration_id, m.is_extended_id, bytes(m.data)) for m in C_FRAMES]
    assert len(seen["c"][0]) == (len(C_FRAMES) if own else 0)


def test_the_c_path_ends_before_the_channel_closes(daemon):
    bus = can.Bus(interface="canemu", channel="can0")
    poster = bus._poster
    bus.shutdown()
    assert bus._fast_post is None
    assert poster.post(C_FRAMES[0]) is False  # closed: nothing reaches the library
    with pytest.raises(can.CanOperationError):
        bus.send(C_FRAMES[0])


def test_the_speedups_are_never_taken_from_the_current_directory(tmp_path, monkeypatch):
    """A libvcinpl2.so the dynamic linker found by its name (an installed canemu) has no folder:
    a canemu_speedups.abi3.so in the current directory is not loaded in its place."""
    planted = tmp_path / "canemu_speedups.abi3.so"
    planted.write_bytes(b"not a module")
    monkeypatch.chdir(tmp_path)

    class ByName:
        _name = "libvcinpl2.so"

    monkeypatch.setattr(_vci, "_lib", ByName())
    monkeypatch.setattr(_vci, "_speedups", None)
    monkeypatch.setattr(_vci, "_speedups_looked", False)
    monkeypatch.delitem(sys.modules, "canemu_speedups", raising=False)
    found = _vci.speedups()  # an installed one, or none; never the planted file
    assert found is None or Path(found.__file__) != planted
