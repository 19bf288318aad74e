"""canemu.lin, the Python LIN API, against canemud in stepped time: a commander and a responder
exchange frames at their exact instants (from bit times computed here, not by canemu), headers
nobody answers, the go-to-sleep command, wake-up pulses, errors a fault scenario causes, a
configured adapter's LIN controller, and names that are not LIN controllers."""

from __future__ import annotations

import pytest

import canemu
from canemu.lin import Commander, LinMessage, Responder, protected_id

from conftest import LIN0, LIN_ADAPTER, fault, load, scenario, toml

EXTRA = toml(LIN0, LIN_ADAPTER)

RATE = 19200


def bits(start_ns: int, n: int) -> float:
    """Simulated seconds at bit n of a frame starting at start_ns (bit k at floor(k e9 / rate)),
    as a VCI time stamp gives it: in whole microseconds since the adapter's power-on (simulated
    time 0 for the adapters of these tests)."""
    return (start_ns + n * 1_000_000_000 // RATE) // 1000 * 1000 / 1e9


def checksum(data: bytes, pid: int = 0) -> int:
    total = pid
    for b in data:
        total += b
        if total > 0xFF:
            total -= 0xFF
    return ~total & 0xFF


def now_ns() -> int:
    return canemu.sim_time()[0]


def drain(node) -> list[LinMessage]:
    out = []
    while (m := node.recv(0)) is not None:
        out.append(m)
    return out


def test_a_commander_asks_and_a_responder_answers_at_the_exact_instants(daemon):
    with Responder("lin0") as door, Commander("lin0") as master:
        assert [m.kind for m in drain(door)] == ["info"]  # its start
        drain(master)
        door.set_response(0x20, b"\x11\x22")
        t0 = now_ns()
        master.send_header(0x20)
        canemu.step(10_000_000)
        # Break 13 + delimiter 1 + sync 10 + PID 10, two data bytes and the checksum: 64 bits.
        frame = LinMessage("frame", bits(t0, 64), id=0x20, data=b"\x11\x22", enhanced=True)
        assert drain(master) == [frame]
        assert drain(door) == [LinMessage("frame", bits(t0, 64), id=0x20, data=b"\x11\x22",
                                          enhanced=True, own=True)]
        # The commander's own response, classic checksum; a header nobody answers.
        t1 = now_ns()
        master.send_frame(0x10, b"\x01", enhanced=False)
        canemu.step(10_000_000)
        t2 = now_ns()
        master.send_header(0x11)
        canemu.step(20_000_000)
        assert drain(master) == [
            LinMessage("frame", bits(t1, 54), id=0x10, data=b"\x01", enhanced=False, own=True),
            LinMessage("error", bits(t2, 34 + 126), error="no-response"),
        ]
        assert [m.kind for m in drain(door)] == ["frame", "error"]


def test_sleep_and_wakeup(daemon):
    with Responder("lin0") as door, Commander("lin0") as master:
        drain(door)
        drain(master)
        t0 = now_ns()
        master.sleep()
        canemu.step(10_000_000)
        # 3Ch 00 FF FF FF FF FF FF FF with a classic checksum: 34 + 90 bits.
        sleep = LinMessage("frame", bits(t0, 124), id=0x3C, data=b"\x00" + b"\xff" * 7,
                           enhanced=False)
        assert drain(door) == [sleep]
        assert drain(master) == [LinMessage(**{**sleep.__dict__, "own": True})]
        t1 = now_ns()
        door.wakeup()
        canemu.step(1_000_000)
        assert drain(master) == [LinMessage("wakeup", (t1 + 250_000) / 1e9)]
        assert [m.kind for m in drain(door)] == []  # a node does not hear its own pulse


def test_a_fault_scenario_gives_error_messages(daemon):
    with Responder("lin0") as door, Commander("lin0") as master:
        door.set_response(0x21, b"\xAA")
        load(daemon, scenario(
            fault(at="0s", bus="lin0", effect="lin_checksum_error", match={"id": 0x21}, count=1)))
        drain(master)
        t0 = now_ns()
        master.send_header(0x21)
        canemu.step(10_000_000)
        assert drain(master) == [LinMessage("error", bits(t0, 54), error="checksum")]


def test_a_configured_adapters_controller_and_the_values_computed_here(daemon):
    # The independent tables: protected identifiers and checksums as LIN 2.x defines them.
    assert [protected_id(i) for i in (0x00, 0x10, 0x20, 0x3C, 0x3F)] == [0x80, 0x50, 0x20, 0x3C,
                                                                          0xBF]
    assert checksum(b"\x11\x22", protected_id(0x20)) == 0xAC
    with Commander("ixxat1:1") as master, Responder("lin0") as other:
        assert master.name == "ixxat1:1" and master.bus == "lin0"
        other.set_response(0x05, b"\x42")
        drain(master)
        t0 = now_ns()
        master.send_header(0x05)
        canemu.step(10_000_000)
        assert drain(master) == [LinMessage("frame", bits(t0, 54), id=0x05, data=b"\x42",
                                            enhanced=True)]


def test_names_that_are_no_lin_controller_are_refused(daemon):
    with pytest.raises(ValueError, match="ixxat1:0 is not a LIN controller"):
        Commander("ixxat1:0")
    with pytest.raises(ValueError, match="LIN identifiers are 0..3Fh"):
        with Commander("lin0") as master:
            master.send_header(0x40)
    with pytest.raises(canemu._vci.VciError):
        Responder("nosuchbus")


def test_reset_then_start_puts_the_node_back_with_an_empty_table(daemon):
    with Responder("lin0") as door, Commander("lin0") as master:
        door.set_response(0x20, b"\x11")
        drain(door)
        door.reset()
        door.start()  # goes on: initialised again with the mode and bit rate it was opened with
        assert [m.info for m in drain(door)] == ["reset", "start"]
        drain(master)
        t0 = now_ns()
        master.send_header(0x20)  # the table was emptied: nobody answers
        canemu.step(20_000_000)
        assert drain(master) == [LinMessage("error", bits(t0, 34 + 126), error="no-response")]
        door.set_response(0x20, b"\x22")
        t1 = now_ns()
        master.send_header(0x20)
        canemu.step(10_000_000)
        assert drain(master) == [LinMessage("frame", bits(t1, 54), id=0x20, data=b"\x22",
                                            enhanced=True)]
        assert drain(door)[-1] == LinMessage("frame", bits(t1, 54), id=0x20, data=b"\x22",
                                             enhanced=True, own=True)


def test_two_responders_with_the_same_response_both_see_it_as_their_own(daemon):
    with Responder("lin0") as a, Responder("lin0") as b, Commander("lin0") as master:
        a.set_response(0x20, b"\x11\x22")
        b.set_response(0x20, b"\x11\x22")
        for n in (a, b, master):
            drain(n)
        t0 = now_ns()
        master.send_header(0x20)
        canemu.step(10_000_000)
        frame = LinMessage("frame", bits(t0, 64), id=0x20, data=b"\x11\x22", enhanced=True)
        assert drain(master) == [frame]
        # Both sent every bit of it (identical bits collide into no error), as on a real bus.
        assert drain(a) == [LinMessage(**{**frame.__dict__, "own": True})]
        assert drain(b) == [LinMessage(**{**frame.__dict__, "own": True})]
