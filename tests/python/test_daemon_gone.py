"""A bus notices that canemud went away: recv and send raise CanOperationError with the reason
instead of returning nothing and queueing frames nobody takes. A client canemud refuses hears
canemud's reason; one that finds no daemon is told how to start it (docs/python.md)."""

from __future__ import annotations

import socket
import subprocess
import sys
import time

import can
import pytest

import canemu

from conftest import Canemud
from tools_support import TIMEOUT, tool_env


@pytest.fixture
def daemon():
    d = Canemud("stepped")
    yield d
    d.stop()


def test_recv_raises_when_canemud_stops(daemon):
    bus = can.Bus(interface="canemu", channel="can0")
    where = daemon.socket
    daemon.stop()
    start = time.monotonic()
    with pytest.raises(can.CanOperationError, match="canemud went away") as raised:
        bus.recv(TIMEOUT)
    assert where in str(raised.value)
    assert time.monotonic() - start < TIMEOUT / 2  # told, not timed out
    with pytest.raises(can.CanOperationError, match="canemud went away"):
        bus.recv(0)  # and again on every later call
    bus.shutdown()


def test_send_raises_when_canemud_stops(daemon):
    bus = can.Bus(interface="canemu", channel="can0")
    bus.send(can.Message(arbitration_id=0x100, data=[1], is_extended_id=False))
    where = daemon.socket
    daemon.stop()
    msg = can.Message(arbitration_id=0x123, data=[1, 2], is_extended_id=False)
    deadline = time.monotonic() + TIMEOUT
    # The transmit FIFO takes frames while it has room; the daemon's absence is noticed within
    # 10 ms of sending, and whenever the FIFO is full.
    with pytest.raises(can.CanOperationError, match="canemud went away") as raised:
        while time.monotonic() < deadline:
            bus.send(msg, timeout=0.1)
    assert where in str(raised.value)
    bus.shutdown()


def test_the_client_beyond_canemuds_limit_hears_why(daemon):
    # This process holds one connection (canemu.connect); 255 more fill canemud's 256 slots.
    held = []
    try:
        for _ in range(255):
            s = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
            s.connect(daemon.socket)
            held.append(s)
        program = "import can\ncan.Bus(interface='canemu', channel='can0')\n"
        done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                              timeout=60, env=tool_env(daemon))
    finally:
        for s in held:
            s.close()
    assert done.returncode != 0
    assert "can.exceptions.CanInitializationError" in done.stderr, done.stderr
    assert "canemud serves at most 256 clients" in done.stderr, done.stderr
    assert "not running" not in done.stderr, done.stderr


def test_no_daemon_names_the_unit_to_start(daemon):
    try:
        with pytest.raises(can.CanInitializationError,
                           match="canemud is not running at .*'systemctl start canemud'"):
            can.Bus(interface="canemu", channel="can0", socket=daemon.dir + "/nobody.sock")
    finally:
        canemu.connect(daemon.socket)
