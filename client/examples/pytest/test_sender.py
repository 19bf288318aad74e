"""A python-can program when nobody acknowledges, in stepped time: its node goes error-passive
at TEC 128 and comes back (to warning, TEC below 128) once frames are acknowledged again."""

import sys
from pathlib import Path

import can
import pytest

SENDER = Path(__file__).with_name("sender.py")


@pytest.mark.canemu(config="bench.toml", time="stepped")
def test_sender_without_acknowledgement(canemu):
    tester = canemu.bus("can0")
    ecu = canemu.start([sys.executable, str(SENDER), "ecu:0"])
    ecu.expect_output("sending")
    first = canemu.expect_frame("can0", id=0x200, data=b"\x01\x02", within=10)

    canemu.inject("ack_suppress", bus="can0", duration="40ms")
    node = canemu.expect_state("ecu:0", "error-passive", within=40)
    assert node.tec == 128  # 16 ACK errors of 8; an error-passive sender's ACK errors add none

    back = canemu.expect_state("ecu:0", "warning", within=60)  # acknowledged again: TEC < 128
    assert 96 <= back.tec < 128
    later = canemu.expect_frame("can0", id=0x200, within=10)
    assert later.timestamp > first.timestamp

    tester.send(can.Message(arbitration_id=0x7FF, is_extended_id=False))
    canemu.step(1)
    ecu.expect_output("received 7FF")
    assert ecu.wait(timeout=10) == 0
