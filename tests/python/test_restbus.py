"""The rest of a vehicle's bus from a public DBC file: socialledge.dbc of cantools' tests
(tests/data/dbc/README.md) loaded with `canemu restbus load` and its DRIVER left to a real
program, in stepped time. Every simulated message appears at its exact instants, cantools run
here decodes every frame to the DBC's start values, `canemu signal set` changes the next frame
exactly as cantools encodes the value, and what is refused changes nothing."""

from __future__ import annotations

import os
import sys

import can
import cantools
import pytest

import canemu

from conftest import REPO, Canemud, cli, drain, frames, ns

DBC = REPO / "tests" / "data" / "dbc" / "socialledge.dbc"
MS = 1_000_000
CYCLE_NS = 100 * MS  # GenMsgCycleTime of every message the DRIVER does not send
BIT_NS = 2_000  # can0 runs at 500 kbit/s
INTERMISSION_NS = 3 * BIT_NS
# The simulated messages in the order they win arbitration when queued together.
SIMULATED = ["SENSOR_SONARS", "MOTOR_STATUS", "IO_DEBUG"]


@pytest.fixture
def db():
    return cantools.database.load_file(str(DBC))


@pytest.fixture
def restbus():
    """canemud in stepped time with every socialledge node but the DRIVER simulated on can0, and
    a python-can bus on can0 (the DRIVER's place) that has taken its line start messages."""
    d = Canemud("stepped")
    loaded = cli(d, "restbus", "load", str(DBC), "--bus", "can0", "--real", "DRIVER",
                 env=dict(os.environ, CANEMU_PYTHON=sys.executable))
    assert loaded.stdout.split("\n")[0].split() == ["NODE", "BUS", "POWER", "MESSAGES", "FRAMES"]
    bus = can.Bus(interface="canemu", channel="can0")
    drain(bus)
    yield d, bus
    bus.shutdown()
    d.stop()


def wire_ns(daemon, frame: can.Message) -> int:
    """The frame's duration on the wire at 500 kbit/s, as `canemu calc frame` counts its bits."""
    text = f"{frame.arbitration_id:03X}#{bytes(frame.data).hex().upper()}"
    done = cli(daemon, "calc", "frame", text, "--bitrate", "500000")
    last = done.stdout.strip().split("\n")[-1]  # "at 500000 bit/s: N ns (...), M ns with ..."
    return int(last.split(": ")[1].split(" ns")[0])


def test_every_simulated_message_comes_at_its_cycle_with_the_start_values(restbus, db):
    daemon, bus = restbus
    canemu.step(350 * MS)
    got = frames(drain(bus))
    names = [db.get_message_by_frame_id(m.arbitration_id).name for m in got]
    # Every 100 ms from the load (simulated time 0) the three queue together and go in the
    # order of their identifiers: four cycles in 350 ms, none of the DRIVER's messages.
    assert names == SIMULATED * 4
    first = got[:3]
    # The first frame starts at once on the idle bus and is stamped at its end; each next one
    # starts after the intermission.
    end = 0
    for m in first:
        end += wire_ns(daemon, m)
        assert ns(m.timestamp) == end
        end += INTERMISSION_NS
    for k, m in enumerate(got):
        assert ns(m.timestamp) - ns(got[k % 3].timestamp) == (k // 3) * CYCLE_NS
    expected = {
        "SENSOR_SONARS": {"SENSOR_SONARS_mux": 0, "SENSOR_SONARS_err_count": 0,
                          "SENSOR_SONARS_left": 0, "SENSOR_SONARS_middle": 0,
                          "SENSOR_SONARS_right": 0, "SENSOR_SONARS_rear": 0},
        "MOTOR_STATUS": {"MOTOR_STATUS_wheel_error": 0, "MOTOR_STATUS_speed_kph": 0},
        "IO_DEBUG": {"IO_DEBUG_test_unsigned": 0, "IO_DEBUG_test_enum": 0,
                     "IO_DEBUG_test_signed": 0, "IO_DEBUG_test_float": 0},
    }
    for m in got:
        message = db.get_message_by_frame_id(m.arbitration_id)
        assert len(m.data) == message.length
        decoded = message.decode(bytes(m.data), decode_choices=False)
        assert decoded == expected[message.name]


def test_signal_set_changes_the_next_frame_as_cantools_encodes_it(restbus, db):
    daemon, bus = restbus
    cli(daemon, "signal", "set", "can0", "MOTOR_STATUS.MOTOR_STATUS_speed_kph", "12.345")
    cli(daemon, "signal", "set", "can0", "IO_DEBUG.IO_DEBUG_test_signed", "-5")
    cli(daemon, "signal", "set", "can0", "IO_DEBUG.IO_DEBUG_test_float", "7.5")
    read = cli(daemon, "signal", "get", "can0", "MOTOR_STATUS.MOTOR_STATUS_speed_kph")
    assert read.stdout == "12.345\n"
    canemu.step(50 * MS)
    got = {m.arbitration_id: bytes(m.data) for m in frames(drain(bus))}
    motor = db.get_message_by_name("MOTOR_STATUS")
    io = db.get_message_by_name("IO_DEBUG")
    assert got[motor.frame_id] == motor.encode(
        {"MOTOR_STATUS_wheel_error": 0, "MOTOR_STATUS_speed_kph": 12.345})
    assert got[io.frame_id] == io.encode(
        {"IO_DEBUG_test_unsigned": 0, "IO_DEBUG_test_enum": 0, "IO_DEBUG_test_signed": -5,
         "IO_DEBUG_test_float": 7.5})


@pytest.mark.parametrize("signal, value, reason", [
    ("MOTOR_STATUS.MOTOR_STATUS_speed_kph", "65.536",
     "65.536 is outside what 16 unsigned bits hold (0 .. 65.535)"),
    ("MOTOR_STATUS.MOTOR_STATUS_speed", "1",
     'message MOTOR_STATUS has no signal named "MOTOR_STATUS_speed"'),
    ("MOTOR_SPEED.MOTOR_STATUS_speed_kph", "1",
     'no simulated CAN node sends a message named "MOTOR_SPEED" on can0'),
    # The real DRIVER's message: no simulated node sends it.
    ("DRIVER_HEARTBEAT.DRIVER_HEARTBEAT_cmd", "1",
     'no simulated CAN node sends a message named "DRIVER_HEARTBEAT" on can0'),
])
def test_what_cannot_be_set_is_refused_and_nothing_changes(restbus, db, signal, value, reason):
    daemon, bus = restbus
    refused = cli(daemon, "signal", "set", "can0", signal, value, check=False)
    assert refused.returncode != 0
    assert reason in refused.stderr
    assert "nothing changed" in refused.stderr
    canemu.step(50 * MS)
    for m in frames(drain(bus)):
        message = db.get_message_by_frame_id(m.arbitration_id)
        assert set(message.decode(bytes(m.data), decode_choices=False).values()) == {0}
