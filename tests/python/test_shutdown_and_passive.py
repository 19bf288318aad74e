"""shutdown() drains the transmit FIFO (or says what it leaves), flush_tx_buffer() gives the
queued frames up, and `state = BusState.PASSIVE` makes a node listen only."""

from __future__ import annotations

import logging
import subprocess
import sys

import can
import pytest
from can import BusState

import canemu
from canemu.bus import CAN_ERR_ACK, CAN_ERR_BUSERROR

from conftest import Canemud, drain, frames
from tools_support import numbered, receive_frames, same_frames, tool_env


@pytest.fixture
def realtime():
    d = Canemud("realtime")
    yield d
    d.stop()


def warnings_of(caplog) -> list:
    return [r.getMessage() for r in caplog.records
            if r.name == "can.canemu" and r.levelno == logging.WARNING]


def test_shutdown_waits_for_the_queued_frames_in_real_time(realtime, caplog):
    receiver = can.Bus(interface="canemu", channel="can0")
    sender = can.Bus(interface="canemu", channel="can0")
    sent = numbered(1000)
    for msg in sent:
        sender.send(msg)  # the FIFO (304 messages) fills: send waits, the rest stays queued
    with caplog.at_level(logging.WARNING, logger="can.canemu"):
        sender.shutdown()
    got = receive_frames(receiver, 1000)
    receiver.shutdown()
    assert len(got) == 1000
    assert same_frames(got, sent)
    assert warnings_of(caplog) == []


def test_a_send_then_exit_program_loses_nothing(realtime):
    program = (
        "import can\n"
        "with can.Bus(interface='canemu', channel='can0') as bus:\n"
        "    for k in range(1000):\n"
        "        tail = bytes([0xA5, 0x5A, k & 0xFF, 0x3C])\n"
        "        bus.send(can.Message(arbitration_id=0x123, is_extended_id=False,\n"
        "                             data=k.to_bytes(4, 'big') + tail))\n"
    )
    receiver = can.Bus(interface="canemu", channel="can0")
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                          timeout=60, env=tool_env(realtime))
    got = receive_frames(receiver, 1000)
    receiver.shutdown()
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    assert len(got) == 1000
    assert same_frames(got, numbered(1000))


def test_a_lone_sender_waits_no_longer_than_its_frames_need_and_says_what_it_leaves(realtime,
                                                                                   caplog):
    lone = can.Bus(interface="canemu", channel="can0")
    lone.send(can.Message(arbitration_id=0x100, data=[1], is_extended_id=False))
    lone.send(can.Message(arbitration_id=0x101, data=[2], is_extended_id=False))
    start, _ = canemu.sim_time()
    with caplog.at_level(logging.WARNING, logger="can.canemu"):
        lone.shutdown()
    end, _ = canemu.sim_time()
    # Bound: at most 4 frames by the FIFO's 1 % (3 of 304, and the controller's) of 160 bits
    # at 500 kbit/s, times 1.5, plus 50 ms of margin: 51.92 ms of bus time.
    assert 0.051_920 <= (end - start) / 1e9 < 0.5
    assert warnings_of(caplog) == [
        "canemu vci1:0 on can0: shutdown discards 2 frame(s) not sent: they did not get "
        "through within 0.052 s of bus time (is a node acknowledging?)"]


def test_in_stepped_time_shutdown_waits_for_nothing_and_counts_what_it_leaves(daemon, caplog):
    a = can.Bus(interface="canemu", channel="can0")
    b = can.Bus(interface="canemu", channel="can0")
    for k in range(3):
        a.send(can.Message(arbitration_id=0x10 + k, data=[k], is_extended_id=False))
    canemu.step(1_000)  # 1 us: the first frame is on the wire, not through
    with caplog.at_level(logging.WARNING, logger="can.canemu"):
        a.shutdown()
    assert warnings_of(caplog) == [
        "canemu vci1:0 on can0: shutdown discards 3 frame(s) not sent: in stepped time nothing "
        "moves at shutdown"]
    b.shutdown()


def test_flush_tx_buffer_gives_the_queued_frames_up(daemon, caplog):
    a = can.Bus(interface="canemu", channel="can0")
    a.send(can.Message(arbitration_id=0x10, data=[1], is_extended_id=False))
    a.flush_tx_buffer()
    with caplog.at_level(logging.WARNING, logger="can.canemu"):
        a.shutdown()
    assert warnings_of(caplog) == []


def test_a_passive_bus_neither_acknowledges_nor_sends_and_active_restores_it(nodes):
    a, b = nodes
    b.state = BusState.PASSIVE
    assert b.state == BusState.PASSIVE
    b.send(can.Message(arbitration_id=0x7, data=[7], is_extended_id=False))
    b.send(can.Message(arbitration_id=0x8, data=[8], is_extended_id=False))
    a.send(can.Message(arbitration_id=0x55, data=[1], is_extended_id=False))
    canemu.step(1_000_000)
    # a is alone: nobody acknowledges, it repeats its frame after each ACK error; b's frame
    # never goes out.
    got_a = drain(a)
    assert frames(got_a) == []
    acks = [m for m in got_a if m.is_error_frame and m.arbitration_id & CAN_ERR_BUSERROR]
    assert len(acks) == 7  # in 1 ms at 500 kbit/s
    assert all(m.arbitration_id == CAN_ERR_ACK | CAN_ERR_BUSERROR for m in acks)
    assert [m.arbitration_id for m in frames(drain(b))] == []

    b.state = BusState.ACTIVE
    assert b.state == BusState.ACTIVE
    assert b.error_counters() == (0, 0)
    canemu.step(10_000_000)
    got_b = frames(drain(b))
    got_a = frames(drain(a))
    # b acknowledges a's frame now and sends the two frames its transmit FIFO kept while it
    # listened (0x7 and 0x8 win the arbitration against a's 0x55).
    assert [m.arbitration_id for m in got_b] == [0x55]
    assert [m.arbitration_id for m in got_a] == [0x7, 0x8]


def test_state_error_cannot_be_set(nodes):
    with pytest.raises(ValueError):
        nodes[0].state = BusState.ERROR


def test_a_bus_without_the_control_unit_cannot_change_the_mode(daemon):
    owner = can.Bus(interface="canemu", channel="ixxat0:0")
    guest = can.Bus(interface="canemu", channel="ixxat0:0")
    with pytest.raises(can.CanOperationError, match="another program controls the line"):
        guest.state = BusState.PASSIVE
    guest.shutdown()
    owner.shutdown()
