"""canemu.restbus: the restbus of test_restbus.py from Python, in stepped time, with a python-can
bus in the DRIVER's place on can0. socialledge.dbc loads through the module (the DBC import in
this process), nodes() lists the nodes, set_signal changes the next frame exactly as cantools
encodes the value and get_signal reads it back, each refusal raises canemud's reason and changes
no frame, power stops a node and restarts its schedule from that instant, remove takes it off,
and the Decoder gives what cantools gives. One canemud for the module: each test loads the DBC
again, which replaces the nodes (fresh values, schedules from the load instant)."""

from __future__ import annotations

import can
import cantools
import pytest

import canemu
from canemu import dbc_decode, restbus
from canemu.restbus import CanNode, RestbusError

from conftest import Canemud, drain, frames, ns
from restbus_support import (CYCLE_NS, DBC, MS, NODES, REFUSALS, SET_VALUES, SIMULATED,
                             START_VALUES, expected_frames, wire_ns)

# A node on can1 whose message carries an XOR checksum (a signal that cannot be set).
CHECKSUM_NODE = """
[[can_node]]
name = "CHK"
bus = "can1"

[[can_node.message]]
name = "CHK_STATUS"
id = 0x123
length = 2
send = "cyclic"
cycle = "100ms"

[[can_node.message.signal]]
name = "CHK_value"
start = 0
length = 8

[[can_node.message.signal]]
name = "CHK_xor"
start = 8
length = 8
checksum = "xor8"
"""


@pytest.fixture(scope="module")
def daemon():
    d = Canemud("stepped")
    yield d
    d.stop()


@pytest.fixture(scope="module")
def db():
    return cantools.database.load_file(str(DBC))


@pytest.fixture(scope="module")
def bus(daemon):
    b = can.Bus(interface="canemu", channel="can0")
    yield b
    b.shutdown()


@pytest.fixture
def loaded(daemon, bus):
    """socialledge.dbc (all but the DRIVER) loaded now on can0, the bus drained: the load's
    simulated instant."""
    drain(bus)
    assert restbus.load(DBC, bus="can0", real=["DRIVER"]) == NODES
    return canemu.sim_time()[0]


def by_name(db, msgs) -> dict:
    """Message name -> its frames among `msgs`."""
    out: dict = {}
    for m in frames(msgs):
        out.setdefault(db.get_message_by_frame_id(m.arbitration_id).name, []).append(m)
    return out


def test_load_starts_the_nodes_and_nodes_lists_them(daemon, loaded, bus, db):
    listed = [n for n in restbus.nodes() if n.bus == "can0"]
    assert listed == [CanNode(name, "can0", True, 0 if name == "DBG" else 1, 0) for name in NODES]
    canemu.step(350 * MS)
    got = frames(drain(bus))
    assert [db.get_message_by_frame_id(m.arbitration_id).name for m in got] == SIMULATED * 4
    assert ns(got[0].timestamp) - loaded == wire_ns(daemon, got[0])  # queued at the load
    frames_sent = {n.name: n.frames for n in restbus.nodes() if n.bus == "can0"}
    assert frames_sent == {"DBG": 0, "IO": 4, "MOTOR": 4, "SENSOR": 4}


def test_set_signal_changes_the_next_frame_as_cantools_encodes_it(loaded, bus, db):
    canemu.step(150 * MS)  # the frames at 0 and 100 ms carry the start values
    drain(bus)
    for signal, value in SET_VALUES.items():
        restbus.set_signal("can0", signal, value)
    for signal, value in SET_VALUES.items():
        assert restbus.get_signal("can0", signal) == value
    canemu.step(100 * MS)
    got = {m.arbitration_id: bytes(m.data) for m in frames(drain(bus))}
    assert len(got) == 3
    for frame_id, data in expected_frames(db).items():
        assert got[frame_id] == data


@pytest.mark.parametrize("signal, value, reason", REFUSALS + [
    ("MOTOR_STATUS", 1, '"MOTOR_STATUS" is not MESSAGE.SIGNAL'),
])
def test_what_cannot_be_set_raises_the_reason_and_nothing_changes(loaded, bus, db, signal,
                                                                   value, reason):
    with pytest.raises(RestbusError) as refused:
        restbus.set_signal("can0", signal, value)
    assert str(refused.value) == reason
    assert refused.value.call == "canemuSetSignal"
    canemu.step(150 * MS)
    got = frames(drain(bus))
    assert len(got) == 6
    for m in got:
        message = db.get_message_by_frame_id(m.arbitration_id)
        assert message.decode(bytes(m.data), decode_choices=False) == START_VALUES[message.name]


def test_a_checksum_signal_cannot_be_set(daemon):
    assert restbus.load(CHECKSUM_NODE) == ["CHK"]
    restbus.set_signal("can1", "CHK_STATUS.CHK_value", 0x5A)
    with pytest.raises(RestbusError) as refused:
        restbus.set_signal("can1", "CHK_STATUS.CHK_xor", 1)
    assert str(refused.value) == "CHK_STATUS.CHK_xor is a checksum: it is computed as each " \
                                 "frame goes out"
    assert restbus.get_signal("can1", "CHK_STATUS.CHK_value") == 0x5A
    assert restbus.get_signal("can1", "CHK_STATUS.CHK_xor") == 0x5A  # XOR of the other byte
    restbus.remove("CHK")


def test_tables_canemud_refuses_raise_its_reasons_and_nothing_starts(daemon):
    before = restbus.nodes()
    wrong = (CHECKSUM_NODE.replace('"can1"', '"can9"')
             + CHECKSUM_NODE.replace('"CHK"', '"CHK2"').replace("length = 2", "length = 9"))
    with pytest.raises(RestbusError) as refused:
        restbus.load(wrong)
    # One line per mistake, each with its place; the text's source is "can nodes".
    assert str(refused.value) == (
        'can nodes:4:7: can_node[0].bus: no bus is named "can9"\n'
        "can nodes:31:10: can_node[1].message[0].length: 9 bytes: a classic frame has 0 to 8 "
        "(fd = true for more)")
    assert restbus.nodes() == before


def test_power_off_stops_the_frames_and_on_restarts_them_from_that_instant(daemon, loaded, bus,
                                                                           db):
    canemu.step(150 * MS)
    restbus.power("MOTOR", False)
    assert [n.powered for n in restbus.nodes() if n.name == "MOTOR"] == [False]
    canemu.step(300 * MS)  # to 450 ms: the cycles at 200, 300 and 400 ms without MOTOR
    got = by_name(db, drain(bus))
    assert len(got["MOTOR_STATUS"]) == 2  # at 0 and 100 ms
    assert all(ns(m.timestamp) - loaded < 150 * MS for m in got["MOTOR_STATUS"])
    assert len(got["SENSOR_SONARS"]) == len(got["IO_DEBUG"]) == 5
    on = canemu.sim_time()[0]
    restbus.power("MOTOR", True)
    canemu.step(150 * MS)  # its schedule from `on`: frames at on and on + 100 ms
    motor = by_name(db, drain(bus))["MOTOR_STATUS"]
    assert [ns(m.timestamp) - on for m in motor] == [wire_ns(daemon, motor[0]),
                                                     CYCLE_NS + wire_ns(daemon, motor[1])]


def test_remove_takes_a_node_off(loaded, bus, db):
    canemu.step(150 * MS)
    drain(bus)
    restbus.remove("IO")
    assert [n.name for n in restbus.nodes() if n.bus == "can0"] == ["DBG", "MOTOR", "SENSOR"]
    canemu.step(100 * MS)
    assert sorted(by_name(db, drain(bus))) == ["MOTOR_STATUS", "SENSOR_SONARS"]
    with pytest.raises(RestbusError) as refused:
        restbus.get_signal("can0", "IO_DEBUG.IO_DEBUG_test_signed")
    assert str(refused.value) == 'no simulated CAN node sends a message named "IO_DEBUG" on can0'
    with pytest.raises(RestbusError) as refused:
        restbus.remove("IO")
    assert str(refused.value) == 'no simulated CAN node named "IO"'
    with pytest.raises(RestbusError) as refused:
        restbus.power("IO", True)
    assert str(refused.value) == 'no simulated CAN node named "IO"'


def test_the_decoder_gives_what_cantools_gives(loaded, bus, db):
    restbus.set_signal("can0", "IO_DEBUG.IO_DEBUG_test_enum", 2)
    restbus.set_signal("can0", "MOTOR_STATUS.MOTOR_STATUS_speed_kph", 12.345)
    canemu.step(50 * MS)
    decoder = restbus.Decoder(DBC)
    got = frames(drain(bus))
    assert len(got) == 3
    for m in got:
        message = db.get_message_by_frame_id(m.arbitration_id)
        assert decoder.decode(m) == (message.name,
                                     message.decode(bytes(m.data), decode_choices=True))
        assert decoder.text(m) == dbc_decode.decode(db, m.arbitration_id, bytes(m.data), False)
    io = decoder.decode(got[2])
    assert io[1]["IO_DEBUG_test_enum"] == "IO_DEBUG_test2_enum_two"
    assert decoder.text(got[1]) == \
        "MOTOR_STATUS(MOTOR_STATUS_wheel_error: 0, MOTOR_STATUS_speed_kph: 12.345 kph)"
    heartbeat = can.Message(arbitration_id=100, data=[2], is_extended_id=False)
    assert decoder.text(heartbeat) == \
        "DRIVER_HEARTBEAT(DRIVER_HEARTBEAT_cmd: DRIVER_HEARTBEAT_cmd_REBOOT)"
    assert decoder.decode(can.Message(arbitration_id=100, data=[2], is_extended_id=True)) is None
    assert decoder.decode(can.Message(arbitration_id=0x7FF, data=[1], is_extended_id=False)) \
        is None
    assert decoder.decode(can.Message(arbitration_id=101, is_remote_frame=True,
                                      is_extended_id=False)) == ("MOTOR_CMD", {})
    with pytest.raises(ValueError) as short:
        decoder.decode(can.Message(arbitration_id=101, data=[], is_extended_id=False))
    assert str(short.value) == "MOTOR_CMD: not decoded: Wrong data size: 0 instead of 1 bytes"


def test_bad_arguments_are_refused_before_canemud(daemon):
    with pytest.raises(ValueError) as no_bus:
        restbus.load(DBC)
    assert str(no_bus.value) == f"{DBC}: a DBC file needs bus= (the CAN bus its nodes send on)"
    with pytest.raises(ValueError) as toml_options:
        restbus.load(CHECKSUM_NODE, bus="can1")
    assert str(toml_options.value) == "bus, real, counters and checksums belong to a DBC file"
