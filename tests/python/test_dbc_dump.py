"""`canemu dump BUS --dbc FILE`: socialledge.dbc (cantools' test data, tests/data/dbc/README.md)
simulated on can0 with its DRIVER left to a python-can bus, in stepped time. Every line is the
line `canemu dump` prints; each frame the DBC knows is followed by its decoding, checked against
cantools' own single-line decoding of the same bytes done here; a frame the DBC does not know
stays a raw line; a frame of a wrong length names the reason; a bad --dbc is refused."""

from __future__ import annotations

import os
import subprocess
import sys

import can
import cantools
import pytest
from cantools.subparsers.__utils__ import format_message

import canemu

from conftest import CANEMU_CLI, REPO, Canemud, cli, drain, frames

DBC = REPO / "tests" / "data" / "dbc" / "socialledge.dbc"
MS = 1_000_000


def env() -> dict:
    """The environment with this interpreter as the one canemu runs canemu.dbc_decode with."""
    return dict(os.environ, CANEMU_PYTHON=sys.executable)


def raw_line(m: can.Message) -> str:
    """The candump -L line `canemu dump --sim-time` prints for a frame python-can received."""
    us = round(m.timestamp * 1e6)
    ident = f"{m.arbitration_id:08X}" if m.is_extended_id else f"{m.arbitration_id:03X}"
    data = bytes(m.data).hex().upper()
    return f"({us // 1_000_000:010d}.{us % 1_000_000:06d}) can0 {ident}#{data}"


def test_dump_dbc_decodes_every_known_frame_as_cantools_does():
    db = cantools.database.load_file(str(DBC))
    daemon = Canemud("stepped")
    bus = None
    dump = None
    try:
        cli(daemon, "restbus", "load", str(DBC), "--bus", "can0", "--real", "DRIVER", env=env())
        bus = can.Bus(interface="canemu", channel="can0", receive_own_messages=True)
        drain(bus)
        dump = subprocess.Popen(
            [str(CANEMU_CLI), "--socket", daemon.socket, "dump", "can0", "--dbc", str(DBC),
             "--sim-time", "--no-errors", "-n", "14"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env())
        # Its channel is open once it says it listens.
        assert "canemu: listening on can0" in dump.stderr.readline()
        sonars = db.get_message_by_name("SENSOR_SONARS")
        own = [
            # The DRIVER's heartbeat: a choice by name.
            can.Message(arbitration_id=100, data=[2], is_extended_id=False),
            # Unknown to the DBC: a standard 0x7FF, and an extended 100 (the heartbeat's number).
            can.Message(arbitration_id=0x7FF, data=[1, 2], is_extended_id=False),
            can.Message(arbitration_id=100, data=[1], is_extended_id=True),
            # MOTOR_CMD (1 byte) with no data: cantools cannot decode it.
            can.Message(arbitration_id=101, data=[], is_extended_id=False),
            # SENSOR_SONARS with multiplexor 1: the other group of signals.
            can.Message(arbitration_id=200, is_extended_id=False, data=sonars.encode(
                {"SENSOR_SONARS_mux": 1, "SENSOR_SONARS_err_count": 3,
                 "SENSOR_SONARS_no_filt_left": 1.5, "SENSOR_SONARS_no_filt_middle": 2.0,
                 "SENSOR_SONARS_no_filt_right": 0, "SENSOR_SONARS_no_filt_rear": 409.5})),
        ]
        for m in own:
            bus.send(m)
        cli(daemon, "signal", "set", "can0", "MOTOR_STATUS.MOTOR_STATUS_speed_kph", "12.345")
        cli(daemon, "signal", "set", "can0", "IO_DEBUG.IO_DEBUG_test_enum", "1")
        canemu.step(250 * MS)
        out, err = dump.communicate(timeout=60)
        assert dump.returncode == 0, err
        got = frames(drain(bus))
    finally:
        if dump is not None and dump.poll() is None:
            dump.kill()
            dump.wait()
        if bus is not None:
            bus.shutdown()
        daemon.stop()
    # Five of the DRIVER's place, and the simulated three at 0, 100 and 200 ms.
    assert len(got) == 14
    lines = out.splitlines()
    assert len(lines) == 14
    decoded = []
    for m, line in zip(got, lines):
        raw, sep, text = line.partition(" :: ")
        assert raw == raw_line(m)
        try:
            message = db.get_message_by_frame_id(m.arbitration_id)
        except KeyError:
            message = None
        if message is None or message.is_extended_frame != m.is_extended_id:
            assert sep == "", line  # unknown to the DBC: the raw line alone
            continue
        assert sep == " :: ", line
        try:
            want = format_message(message, message.decode(bytes(m.data), decode_choices=True),
                                  True).strip()
        except cantools.database.DecodeError as e:
            assert text == f"{message.name}: not decoded: {e}"
            continue
        assert text == want
        decoded.append(text)
    assert len(decoded) == 11
    assert "DRIVER_HEARTBEAT(DRIVER_HEARTBEAT_cmd: DRIVER_HEARTBEAT_cmd_REBOOT)" in decoded
    assert ("SENSOR_SONARS(SENSOR_SONARS_mux: 1, SENSOR_SONARS_err_count: 3, "
            "SENSOR_SONARS_no_filt_left: 1.5, SENSOR_SONARS_no_filt_middle: 2.0, "
            "SENSOR_SONARS_no_filt_right: 0.0, SENSOR_SONARS_no_filt_rear: 409.5)") in decoded
    assert "MOTOR_STATUS(MOTOR_STATUS_wheel_error: 0, MOTOR_STATUS_speed_kph: 12.345 kph)" \
        in decoded
    assert any("IO_DEBUG_test_enum: IO_DEBUG_test2_enum_one" in t for t in decoded)
    assert sum(" :: " not in line for line in lines) == 2
    assert sum(line.endswith(" :: MOTOR_CMD: not decoded: Wrong data size: 0 instead of 1 bytes")
               for line in lines) == 1


@pytest.mark.parametrize("make, reason", [
    (lambda d: d / "missing.dbc", "missing.dbc: No such file or directory"),
    (lambda d: d / "not.dbc", "not.dbc: not a DBC cantools"),
])
def test_dump_dbc_refuses_a_file_that_is_not_a_dbc(tmp_path, make, reason):
    (tmp_path / "not.dbc").write_text("this is no CAN database\n")
    # Refused before canemud is asked: no daemon listens on this socket.
    done = subprocess.run(
        [str(CANEMU_CLI), "--socket", str(tmp_path / "none.sock"), "dump", "can0", "--dbc",
         str(make(tmp_path))], capture_output=True, text=True, timeout=60, env=env())
    assert done.returncode == 2
    assert done.stdout == ""
    assert f"canemu: --dbc {tmp_path}/{reason}" in done.stderr
