"""Faults on a simulated CAN node's messages and signals (docs/faults.md, "Simulated CAN nodes")
through `canemu fault inject`, against canemud in stepped time, as a python-can program on the
bus receives them: a frozen counter, a wrong checksum, a ramp, a message that stops; each
refusal names its reason. The receiver checks the frames with a CRC-8 of its own."""

from __future__ import annotations

import can
import pytest

import canemu

from conftest import REPO, Canemud, cli, drain, frames, ns

MS = 1_000_000

# ENGINE and BRAKE; the file says what they send.
NODES = REPO / "tests" / "data" / "restbus" / "engine_and_brake.toml"
ENGINE_DATA = 0x100


def crc8_sae_j1850(data: bytes) -> int:
    """CRC-8/SAE-J1850 (poly 0x1D, init 0xFF, xorout 0xFF), bit by bit."""
    crc = 0xFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


def crc_ok(data: bytes) -> bool:
    """What a receiver checks: the data ID 0x12 (low byte, high byte), then bytes 0..6."""
    return crc8_sae_j1850(bytes([0x12, 0x00]) + data[:7]) == data[7]


@pytest.fixture
def engine():
    d = Canemud("stepped")
    cli(d, "restbus", "load", str(NODES))
    bus = can.Bus(interface="canemu", channel="can0")
    drain(bus)
    yield d, bus
    bus.shutdown()
    d.stop()


def inject(daemon, *args: str) -> None:
    cli(daemon, "fault", "inject", "--bus", "can0", *args)


def test_faults_on_a_simulated_nodes_signals_are_what_a_receiver_sees(engine):
    daemon, bus = engine
    inject(daemon, "--effect", "counter_freeze", "--signal", "ENGINE_DATA.alive", "--at", "15ms",
           "--until", "45ms")
    inject(daemon, "--effect", "checksum_error", "--message", "ENGINE_DATA", "--at", "55ms",
           "--count", "1")
    inject(daemon, "--effect", "signal_ramp", "--signal", "ENGINE_DATA.speed", "--to", "2000",
           "--at", "60ms", "--until", "100ms")
    inject(daemon, "--effect", "message_timeout", "--message", "ENGINE_DATA", "--at", "105ms",
           "--until", "125ms")
    canemu.step(135 * MS)
    got = [m for m in frames(drain(bus)) if m.arbitration_id == ENGINE_DATA]
    # Each frame starts at its 10 ms instant (the bus is idle) and is stamped at its end, less
    # than a millisecond later; 110 and 120 ms are missing (the timeout).
    assert [ns(m.timestamp) // (10 * MS) for m in got] == [*range(11), 13]
    assert [m.data[4] & 0x0F for m in got] == [0, 1, 2, 2, 2, 2, 3, 4, 5, 6, 7, 8]
    assert [crc_ok(bytes(m.data)) for m in got] == [True] * 6 + [False] + [True] * 5
    speed = [int.from_bytes(m.data[0:2], "little") * 0.25 for m in got]
    assert speed == [1000] * 7 + [1250, 1500, 1750, 2000, 2000]
    listed = cli(daemon, "fault", "list").stdout
    for target in ("can0/ENGINE_DATA.alive", "can0/ENGINE_DATA.speed", "can0/ENGINE_DATA"):
        assert target in listed
    checksum_row = next(line for line in listed.splitlines() if "checksum_error" in line)
    assert checksum_row.split()[-5:] == ["1", "done", "id", "0x100", "std"]


@pytest.mark.parametrize("args, reason", [
    (["--effect", "signal_step", "--signal", "ENGINE_DATA.speed", "--value", "9000"],
     "signal_step: 9000 is outside the range of ENGINE_DATA.speed: 0..8000 rpm"),
    (["--effect", "counter_freeze", "--signal", "ENGINE_DATA.speed"],
     "counter_freeze: ENGINE_DATA.speed is not a counter"),
    (["--effect", "message_timeout", "--message", "GEARBOX"],
     'message_timeout: no simulated CAN node sends a message named "GEARBOX" on can0'),
    (["--effect", "signal_invalid", "--signal", "ENGINE_DATA.speed", "--raw", "0x10000"],
     "signal_invalid: raw value 65536 does not fit the 16 bits of ENGINE_DATA.speed"),
])
def test_what_a_fault_cannot_do_is_refused_with_the_reason(engine, args, reason):
    daemon, bus = engine
    done = cli(daemon, "fault", "inject", "--bus", "can0", *args, check=False)
    assert done.returncode == 1
    assert done.stderr == f"{reason}\ncanemu: scenario rejected; nothing of it applied\n"
    canemu.step(25 * MS)
    got = [m for m in frames(drain(bus)) if m.arbitration_id == ENGINE_DATA]
    assert [int.from_bytes(m.data[0:2], "little") * 0.25 for m in got] == [1000] * 3
    assert [m.data[4] & 0x0F for m in got] == [0, 1, 2]
