"""What the restbus tests share (test_restbus.py through `canemu restbus`, test_restbus_api.py
through canemu.restbus): socialledge.dbc of cantools' tests (tests/data/dbc/README.md) with its
DRIVER left to a python-can bus on can0 (500 kbit/s), its timing and its start values."""

from __future__ import annotations

import can

from conftest import REPO, cli

DBC = REPO / "tests" / "data" / "dbc" / "socialledge.dbc"
MS = 1_000_000
CYCLE_NS = 100 * MS  # GenMsgCycleTime of every message the DRIVER does not send
BIT_NS = 2_000  # can0 runs at 500 kbit/s
INTERMISSION_NS = 3 * BIT_NS
# The simulated nodes in the order of the DBC's BU_ line (DBG sends nothing).
NODES = ["DBG", "IO", "MOTOR", "SENSOR"]
# The simulated messages in the order they win arbitration when queued together.
SIMULATED = ["SENSOR_SONARS", "MOTOR_STATUS", "IO_DEBUG"]
# Every simulated signal at its start value (raw 0: the DBC has no GenSigStartValue).
START_VALUES = {
    "SENSOR_SONARS": {"SENSOR_SONARS_mux": 0, "SENSOR_SONARS_err_count": 0,
                      "SENSOR_SONARS_left": 0, "SENSOR_SONARS_middle": 0,
                      "SENSOR_SONARS_right": 0, "SENSOR_SONARS_rear": 0},
    "MOTOR_STATUS": {"MOTOR_STATUS_wheel_error": 0, "MOTOR_STATUS_speed_kph": 0},
    "IO_DEBUG": {"IO_DEBUG_test_unsigned": 0, "IO_DEBUG_test_enum": 0,
                 "IO_DEBUG_test_signed": 0, "IO_DEBUG_test_float": 0},
}
# A scaled, a signed and a scaled (0.5) signal with the values the tests set.
SET_VALUES = {
    "MOTOR_STATUS.MOTOR_STATUS_speed_kph": 12.345,
    "IO_DEBUG.IO_DEBUG_test_signed": -5,
    "IO_DEBUG.IO_DEBUG_test_float": 7.5,
}
# What canemud refuses to set (MESSAGE.SIGNAL, value, its reason).
REFUSALS = [
    ("MOTOR_STATUS.MOTOR_STATUS_speed_kph", 65.536,
     "65.536 cannot be the value of MOTOR_STATUS.MOTOR_STATUS_speed_kph: 65.536 is outside "
     "what 16 unsigned bits hold (0 .. 65.535)"),
    ("MOTOR_STATUS.MOTOR_STATUS_speed", 1,
     'message MOTOR_STATUS has no signal named "MOTOR_STATUS_speed"'),
    ("MOTOR_SPEED.MOTOR_STATUS_speed_kph", 1,
     'no simulated CAN node sends a message named "MOTOR_SPEED" on can0'),
    # The real DRIVER's message: no simulated node sends it.
    ("DRIVER_HEARTBEAT.DRIVER_HEARTBEAT_cmd", 1,
     'no simulated CAN node sends a message named "DRIVER_HEARTBEAT" on can0'),
]


def expected_frames(db) -> dict:
    """Identifier -> the payload cantools encodes for the SET_VALUES (the rest at start)."""
    values = {name: dict(signals) for name, signals in START_VALUES.items()}
    for spec, value in SET_VALUES.items():
        message, signal = spec.split(".")
        values[message][signal] = value
    return {db.get_message_by_name(name).frame_id: db.get_message_by_name(name).encode(signals)
            for name, signals in values.items() if name != "SENSOR_SONARS"}


def wire_ns(daemon, frame: can.Message) -> int:
    """The frame's duration on the wire at 500 kbit/s, as `canemu calc frame` counts its bits."""
    text = f"{frame.arbitration_id:03X}#{bytes(frame.data).hex().upper()}"
    done = cli(daemon, "calc", "frame", text, "--bitrate", "500000")
    last = done.stdout.strip().split("\n")[-1]  # "at 500000 bit/s: N ns (...), M ns with ..."
    return int(last.split(": ")[1].split(" ns")[0])
