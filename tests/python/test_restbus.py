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

from conftest import Canemud, cli, drain, frames, ns
from restbus_support import (CYCLE_NS, DBC, INTERMISSION_NS, MS, REFUSALS, SET_VALUES,
                             SIMULATED, START_VALUES, expected_frames, wire_ns)


@pytest.fixture(scope="module")
def db():
    return cantools.database.load_file(str(DBC))


@pytest.fixture(scope="module")
def daemon_and_bus():
    """canemud in stepped time and a python-can bus on can0 (the DRIVER's place), for the
    module."""
    d = Canemud("stepped")
    bus = can.Bus(interface="canemu", channel="can0")
    yield d, bus
    bus.shutdown()
    d.stop()


@pytest.fixture
def restbus(daemon_and_bus):
    """Every socialledge node but the DRIVER loaded now on can0 (a load replaces the previous
    test's nodes: start values, schedules from now), the bus drained: (daemon, bus, the load's
    simulated instant)."""
    d, bus = daemon_and_bus
    drain(bus)
    loaded = cli(d, "restbus", "load", str(DBC), "--bus", "can0", "--real", "DRIVER",
                 env=dict(os.environ, CANEMU_PYTHON=sys.executable))
    assert loaded.stdout.split("\n")[0].split() == ["NODE", "BUS", "POWER", "MESSAGES", "FRAMES"]
    return d, bus, canemu.sim_time()[0]


def test_every_simulated_message_comes_at_its_cycle_with_the_start_values(restbus, db):
    daemon, bus, loaded = restbus
    canemu.step(350 * MS)
    got = frames(drain(bus))
    names = [db.get_message_by_frame_id(m.arbitration_id).name for m in got]
    # Every 100 ms from the load the three queue together and go in the
    # order of their identifiers: four cycles in 350 ms, none of the DRIVER's messages.
    assert names == SIMULATED * 4
    first = got[:3]
    # The first frame starts at once on the idle bus and is stamped at its end; each next one
    # starts after the intermission.
    end = loaded
    for m in first:
        end += wire_ns(daemon, m)
        assert ns(m.timestamp) == end
        end += INTERMISSION_NS
    for k, m in enumerate(got):
        assert ns(m.timestamp) - ns(got[k % 3].timestamp) == (k // 3) * CYCLE_NS
    for m in got:
        message = db.get_message_by_frame_id(m.arbitration_id)
        assert len(m.data) == message.length
        decoded = message.decode(bytes(m.data), decode_choices=False)
        assert decoded == START_VALUES[message.name]


def test_signal_set_changes_the_next_frame_as_cantools_encodes_it(restbus, db):
    daemon, bus, _ = restbus
    for signal, value in SET_VALUES.items():
        cli(daemon, "signal", "set", "can0", signal, f"{value}")
    read = cli(daemon, "signal", "get", "can0", "MOTOR_STATUS.MOTOR_STATUS_speed_kph")
    assert read.stdout == "12.345\n"
    canemu.step(50 * MS)
    got = {m.arbitration_id: bytes(m.data) for m in frames(drain(bus))}
    for frame_id, data in expected_frames(db).items():
        assert got[frame_id] == data


@pytest.mark.parametrize("signal, value, reason", REFUSALS)
def test_what_cannot_be_set_is_refused_and_nothing_changes(restbus, db, signal, value, reason):
    daemon, bus, _ = restbus
    refused = cli(daemon, "signal", "set", "can0", signal, f"{value}", check=False)
    assert refused.returncode != 0
    assert reason in refused.stderr
    assert "nothing changed" in refused.stderr
    canemu.step(50 * MS)
    for m in frames(drain(bus)):
        message = db.get_message_by_frame_id(m.arbitration_id)
        assert set(message.decode(bytes(m.data), decode_choices=False).values()) == {0}
