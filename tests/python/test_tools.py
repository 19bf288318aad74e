"""python-can's own command-line tools on canemu buses, as a user runs them: can.player,
can.logger (with its options), can.viewer (in a pseudo-terminal) and can.bridge. Each tool is a
child process against this module's canemud in real time; the tests wait for what the tools
print and for frames, with timeouts."""

from __future__ import annotations

import glob
import importlib.util
import inspect
import os

import can
import pytest

from tools_support import (
    TIMEOUT,
    Tool,
    candump_log,
    numbered,
    receive_frames,
    same_frames,
    screen,
)

# python-can's shared command-line module (can.cli) brought --timing, --bus-kwargs and the
# spelling --data-bitrate; can.bridge came later. Debian's 4.1 has neither.
NEW_CLI = importlib.util.find_spec("can.cli") is not None
HAS_BRIDGE = importlib.util.find_spec("can.bridge") is not None
DATA_BITRATE = "--data-bitrate" if NEW_CLI else "--data_bitrate"


@pytest.fixture(autouse=True)
def no_tool_left():
    """A test that fails midway leaves no tool on the module's buses for the next one."""
    yield
    Tool.kill_all()


def writes(suffix: str) -> bool:
    """Whether python-can's can.logger can write `suffix` files: 4.1's passes `append` to
    every writer, and its TRCWriter does not take it."""
    writers = getattr(can.Logger, "message_writers", None)  # a class in python-can 4.1
    if writers is None:
        return True
    writer = writers[suffix]
    return "append" in inspect.signature(writer.__init__).parameters or any(
        p.kind == p.VAR_KEYWORD for p in inspect.signature(writer.__init__).parameters.values())


@pytest.fixture
def receiver(realtime_daemon):
    bus = can.Bus(interface="canemu", channel="can0")
    yield bus
    bus.shutdown()


@pytest.fixture
def sender(realtime_daemon):
    bus = can.Bus(interface="canemu", channel="can0")
    yield bus
    bus.shutdown()


# ---- can.player ----

def test_the_player_replays_a_log_of_1000_frames_completely(realtime_daemon, receiver, tmp_path):
    sent = numbered(1000)
    log = tmp_path / "file.log"
    candump_log(log, sent)  # 0.5 ms apart: the player replays it in 0.5 s
    player = Tool(realtime_daemon, "can.player", ["-i", "canemu", "-c", "can0", str(log)])
    got = receive_frames(receiver, 1000)
    assert player.finish() == 0, player.output
    assert len(got) == 1000
    assert same_frames(got, sent)
    assert "shutdown discards" not in player.output


def test_the_player_without_time_stamps_fills_the_fifo_and_still_sends_everything(
        realtime_daemon, receiver, tmp_path):
    sent = numbered(1000)
    log = tmp_path / "file.log"
    candump_log(log, sent)
    player = Tool(realtime_daemon, "can.player",
                  ["-i", "canemu", "-c", "can0", "--ignore-timestamps", "-g", "0", str(log)])
    got = receive_frames(receiver, 1000)
    assert player.finish() == 0, player.output
    assert len(got) == 1000
    assert same_frames(got, sent)


# ---- can.logger ----

def start_logger(daemon, args, channel="can0") -> Tool:
    logger = Tool(daemon, "can.logger", ["-i", "canemu", "-c", channel, *args])
    logger.wait_for(r"Connected to CanemuBus")
    return logger


def stop_logger(logger: Tool) -> None:
    """Ctrl-C once the logger has read every frame it was sent; it exits 0."""
    logger.wait_idle()
    logger.interrupt()
    assert logger.finish() == 0, logger.output
    assert "Traceback" not in logger.output


def send_through(sender, receiver, msgs) -> None:
    """`msgs` from `sender`, each seen by `receiver`: on the bus, so in every node's FIFO."""
    for msg in msgs:
        sender.send(msg)
    assert same_frames(receive_frames(receiver, len(msgs)), msgs)


@pytest.mark.parametrize("suffix", [".asc", ".blf", ".log", ".csv", ".db", ".trc"])
def test_the_logger_writes_every_format(realtime_daemon, sender, receiver, tmp_path, suffix):
    if not writes(suffix):
        pytest.skip(f"this python-can's can.logger cannot write {suffix} files")
    path = tmp_path / f"out{suffix}"
    logger = start_logger(realtime_daemon, ["-f", str(path)])
    sent = numbered(50) + [can.Message(arbitration_id=0x1ABCDEF0, is_extended_id=True,
                                       data=[1, 2, 3])]
    send_through(sender, receiver, sent)
    stop_logger(logger)
    got = [m for m in can.LogReader(str(path)) if not m.is_error_frame]
    assert same_frames(got, sent)


def test_the_logger_prints_to_standard_output(realtime_daemon, sender, receiver):
    logger = start_logger(realtime_daemon, [])
    send_through(sender, receiver, [can.Message(arbitration_id=0x321, is_extended_id=False,
                                                data=[0xDE, 0xAD])])
    logger.wait_for(r"ID:\s+0?321\s.*DL:\s+2\s+de ad")
    stop_logger(logger)


def test_the_passive_logger_listens_without_acknowledging(realtime_daemon, tmp_path):
    path = tmp_path / "passive.log"
    logger = start_logger(realtime_daemon, ["--passive", "-f", str(path)])
    lone = can.Bus(interface="canemu", channel="can0")
    lone.send(can.Message(arbitration_id=0x100, data=[1], is_extended_id=False))
    first = lone.recv(TIMEOUT)  # nobody acknowledges: an ACK error
    lone.flush_tx_buffer()
    lone.shutdown()
    stop_logger(logger)
    assert first is not None and first.is_error_frame
    assert first.arbitration_id == 0xA0  # CAN_ERR_ACK | CAN_ERR_BUSERROR
    assert [m for m in can.LogReader(str(path)) if not m.is_error_frame] == []


def test_the_passive_logger_logs_what_others_exchange(realtime_daemon, sender, receiver,
                                                      tmp_path):
    path = tmp_path / "passive.log"
    logger = start_logger(realtime_daemon, ["--passive", "-f", str(path)])
    sent = numbered(20)
    send_through(sender, receiver, sent)
    stop_logger(logger)
    assert same_frames([m for m in can.LogReader(str(path)) if not m.is_error_frame], sent)


def test_the_active_logger_acknowledges(realtime_daemon, sender):
    logger = start_logger(realtime_daemon, ["--active"])
    sender.send(can.Message(arbitration_id=0x222, data=[2], is_extended_id=False))
    logger.wait_for(r"ID:\s+0?222\s")
    stop_logger(logger)
    assert sender.error_counters() == (0, 0)


def test_the_logger_filters(realtime_daemon, sender, receiver, tmp_path):
    path = tmp_path / "filtered.log"
    logger = start_logger(realtime_daemon, ["--filter", "100:7FF", "200:7F0", "-f", str(path)])
    msgs = [can.Message(arbitration_id=i, data=[i & 0xFF], is_extended_id=False)
            for i in (0x100, 0x101, 0x205, 0x300, 0x20F)]
    send_through(sender, receiver, msgs)
    stop_logger(logger)
    got = [m.arbitration_id for m in can.LogReader(str(path)) if not m.is_error_frame]
    assert got == [0x100, 0x205, 0x20F]


def test_the_logger_appends(realtime_daemon, sender, receiver, tmp_path):
    path = tmp_path / "appended.log"
    first, second = numbered(3), numbered(2, ident=0x456)
    for batch in (first, second):
        logger = start_logger(realtime_daemon, ["-a", "-f", str(path)])
        send_through(sender, receiver, batch)
        stop_logger(logger)
    assert same_frames([m for m in can.LogReader(str(path)) if not m.is_error_frame],
                       first + second)


def test_the_logger_rotates_files_by_size(realtime_daemon, sender, receiver, tmp_path):
    logger = start_logger(realtime_daemon, ["-s", "2000", "-f", str(tmp_path / "rot.log")])
    sent = numbered(200)
    send_through(sender, receiver, sent)
    stop_logger(logger)
    files = sorted(glob.glob(str(tmp_path / "*.log")), key=os.path.getmtime)
    assert len(files) > 1
    got = [m for f in sorted(files) for m in can.LogReader(f) if not m.is_error_frame]
    assert sorted(bytes(m.data) for m in got) == sorted(bytes(m.data) for m in sent)


def test_the_logger_at_another_bit_rate_and_verbose(realtime_daemon, tmp_path):
    # can1 runs at 125 kbit/s: the logger's node joins it at the rate given.
    path = tmp_path / "can1.log"
    logger = Tool(realtime_daemon, "can.logger",
                  ["-i", "canemu", "-c", "can1", "-b", "125000", "-vvv", "-f", str(path)])
    logger.wait_for(r"Connected to CanemuBus: canemu vci\d+:0 on can1")
    other = can.Bus(interface="canemu", channel="can1")
    echo = can.Bus(interface="canemu", channel="can1")
    other.send(can.Message(arbitration_id=0x125, data=[1, 2, 5], is_extended_id=False))
    try:
        assert same_frames(receive_frames(echo, 1), [can.Message(
            arbitration_id=0x125, data=[1, 2, 5], is_extended_id=False)])
        stop_logger(logger)
        assert other.error_counters() == (0, 0)
    finally:
        other.shutdown()
        echo.shutdown()
    assert [m.arbitration_id for m in can.LogReader(str(path)) if not m.is_error_frame] == [0x125]


def test_the_logger_with_can_fd(realtime_daemon, tmp_path):
    path = tmp_path / "fd.asc"
    logger = start_logger(realtime_daemon, ["--fd", DATA_BITRATE, "2000000", "-f", str(path)],
                          channel="fd0")
    a = can.Bus(interface="canemu", channel="fd0", fd=True)
    b = can.Bus(interface="canemu", channel="fd0", fd=True)
    msg = can.Message(arbitration_id=0x7FF, is_extended_id=False, is_fd=True, bitrate_switch=True,
                      data=bytes(range(64)))
    try:
        send_through(a, b, [msg])
        stop_logger(logger)
    finally:
        a.shutdown()
        b.shutdown()
    got = [m for m in can.LogReader(str(path)) if not m.is_error_frame]
    assert len(got) == 1 and got[0].is_fd and got[0].bitrate_switch
    assert bytes(got[0].data) == bytes(range(64))


@pytest.mark.skipif(not NEW_CLI, reason="this python-can's (4.1) tools have no --timing")
def test_the_logger_with_a_bit_timing(realtime_daemon, sender, receiver, tmp_path):
    # 8 MHz / (1 x 16 quanta) = 500 kbit/s, sample point 87.5 %: the SJA1000's own clock.
    path = tmp_path / "timing.log"
    logger = start_logger(realtime_daemon, ["--timing", "f_clock=8000000", "brp=1", "tseg1=13",
                                            "tseg2=2", "sjw=1", "nof_samples=1",
                                            "-f", str(path)])
    send_through(sender, receiver, numbered(5))
    stop_logger(logger)
    assert same_frames([m for m in can.LogReader(str(path)) if not m.is_error_frame],
                       numbered(5))


@pytest.mark.skipif(not NEW_CLI, reason="this python-can's (4.1) tools have no --bus-kwargs")
def test_the_logger_passes_bus_keyword_arguments(realtime_daemon, sender, receiver, tmp_path):
    # The logger's own bus only listens: listen_only=True through --bus-kwargs.
    logger = start_logger(realtime_daemon, ["--bus-kwargs", "listen_only=True",
                                            "rx_fifo_size=64"])
    assert logger.proc.poll() is None
    lone = sender
    receiver.shutdown()
    lone.send(can.Message(arbitration_id=0x100, data=[1], is_extended_id=False))
    first = lone.recv(TIMEOUT)
    lone.flush_tx_buffer()
    stop_logger(logger)
    assert first is not None and first.arbitration_id == 0xA0


def test_the_logger_passes_extra_arguments_to_the_writer(realtime_daemon, sender, receiver,
                                                         tmp_path):
    # `--compression-level=9` goes to the BLF writer (python-can's own example).
    path = tmp_path / "compressed.blf"
    logger = start_logger(realtime_daemon, ["-f", str(path), "--compression-level=9"])
    send_through(sender, receiver, numbered(30))
    stop_logger(logger)
    assert same_frames([m for m in can.LogReader(str(path)) if not m.is_error_frame],
                       numbered(30))


# ---- can.viewer ----

def test_the_viewer_shows_the_frames_it_receives(realtime_daemon, sender):
    rows, cols = 30, 120
    viewer = Tool(realtime_daemon, "can.viewer", ["-i", "canemu", "-c", "can0"],
                  pty_size=(rows, cols))
    viewer.wait_for(r"Count")  # its header: it runs and has its bus
    for k in range(3):
        sender.send(can.Message(arbitration_id=0x1A5, data=[0x11, 0x22, 0x30 + k],
                                is_extended_id=False))
    sender.send(can.Message(arbitration_id=0x1B6, data=[0xAB], is_extended_id=False))
    viewer.wait_for(r"0x1B6")  # drawn after the three frames of 0x1A5
    viewer.write(b"q")
    assert viewer.finish() == 0, viewer.output
    lines = screen(viewer.output, rows, cols)
    header = [line.split() for line in lines if line.startswith("Count")]
    assert header == [["Count", "Time", "dt", "ID", "DLC", "Data"]]
    shown = {line.split()[3]: line.split() for line in lines if "0x1" in line}
    # Count, time, dt, ID, DLC, data: the last frame of each identifier, and how many came.
    assert shown["0x1A5"][0] == "3"
    assert shown["0x1A5"][4:] == ["3", "11", "22", "32"]
    assert shown["0x1B6"][0] == "1"
    assert shown["0x1B6"][4:] == ["1", "AB"]
    assert sender.error_counters() == (0, 0)  # the viewer's node acknowledged


# ---- can.bridge ----

@pytest.mark.skipif(not HAS_BRIDGE, reason="this python-can (4.1) has no can.bridge")
def test_the_bridge_carries_frames_between_two_buses(realtime_daemon):
    bridge = Tool(realtime_daemon, "can.bridge",
                  ["--bus1-interface", "canemu", "--bus1-channel", "can0",
                   "--bus2-interface", "canemu", "--bus2-channel", "can1"])
    bridge.wait_for(r"CAN Bridge \(Started on")
    on_can0 = can.Bus(interface="canemu", channel="can0")
    on_can1 = can.Bus(interface="canemu", channel="can1")
    try:
        there = numbered(20)
        for msg in there:
            on_can0.send(msg)
        assert same_frames(receive_frames(on_can1, 20), there)
        back = numbered(5, ident=0x654)
        for msg in back:
            on_can1.send(msg)
        assert same_frames(receive_frames(on_can0, 5), back)
    finally:
        on_can0.shutdown()
        on_can1.shutdown()
    bridge.interrupt()
    assert bridge.finish() == 0, bridge.output
    assert "CAN Bridge (Stopped on" in bridge.output


def test_an_error_frame_handed_to_send_is_not_put_on_the_bus(sender, receiver):
    # can.bridge forwards the error frames it receives; they are no frames to send.
    sender.send(can.Message(arbitration_id=0xA0, is_error_frame=True, dlc=8, data=bytes(8)))
    sender.send(can.Message(arbitration_id=0x42, data=[4, 2], is_extended_id=False))
    got = receiver.recv(TIMEOUT)
    assert (got.arbitration_id, got.is_error_frame, bytes(got.data)) == (0x42, False, b"\x04\x02")

