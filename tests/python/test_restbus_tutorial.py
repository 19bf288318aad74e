"""docs/restbus.md's tutorial in stepped time: socialledge.dbc loaded with its DRIVER left to
client/examples/restbus_watch.py, then the tutorial's signal change, ramp and message timeout
as its commands give them; the example prints what the tutorial shows."""

from __future__ import annotations

import importlib.util
import os
import sys

import can
import cantools

import canemu

from conftest import REPO, Canemud, cli, drain

DBC = REPO / "tests" / "data" / "dbc" / "socialledge.dbc"
SPEED = "MOTOR_STATUS.MOTOR_STATUS_speed_kph"
MS = 1_000_000


def example():
    spec = importlib.util.spec_from_file_location(
        "restbus_watch", REPO / "client" / "examples" / "restbus_watch.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_tutorial_shows_what_it_says():
    d = Canemud("stepped")
    try:
        cli(d, "restbus", "load", str(DBC), "--bus", "can0", "--real", "DRIVER",
            env=dict(os.environ, CANEMU_PYTHON=sys.executable))
        with can.Bus(interface="canemu", channel="can0") as bus:
            drain(bus)
            canemu.step(250 * MS)
            cli(d, "signal", "set", "can0", SPEED, "12.5")
            canemu.step(100 * MS)
            cli(d, "fault", "inject", "--effect", "signal_ramp", "--bus", "can0", "--signal",
                SPEED, "--to", "30", "--until", "1s")
            cli(d, "fault", "inject", "--effect", "message_timeout", "--bus", "can0",
                "--message", "MOTOR_STATUS", "--at", "1.5s", "--until", "2.5s")
            canemu.step(2700 * MS)
            said = []
            example().watch(bus, cantools.database.load_file(str(DBC)), 3.0, said.append)
    finally:
        d.stop()
    # MOTOR_STATUS every 100 ms from 0 (each frame stamped at its end, a fraction of a
    # millisecond after its instant); the value set at 250 ms in the frame of 300 ms.
    assert said[:2] == ["  0.000 s  speed 0 kph", "  0.300 s  speed 12.5 kph"]
    # The ramp from 350 ms to 1.35 s, 12.5 to 30 kph: 1.75 kph per 100 ms, the frame of 400 ms
    # 50 ms into it; 30 from 1.4 s on.
    ramp = [f"{0.4 + 0.1 * k:7.3f} s  speed {13.375 + 1.75 * k:g} kph" for k in range(10)]
    assert said[2:12] == ramp
    assert said[12] == "  1.400 s  speed 30 kph"
    # No MOTOR_STATUS from 1.85 to 2.85 s: the frames of 1.9 ... 2.8 s are missing.
    assert said[13:] == ["  2.900 s  MOTOR_STATUS back after 1.100 s without it"]
