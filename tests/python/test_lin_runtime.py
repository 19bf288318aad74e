"""`canemu lin` against canemud in stepped time: simulated LIN nodes loaded from an LDF file at
run time drive a cluster in which a Python program (canemu.lin) is one responder, at the
schedule's exact slot times; schedules stopped and switched, nodes switched off and removed at
a defined instant; mistakes refused with nothing changed."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

import canemu
from canemu.lin import Responder

import conftest
from conftest import LIN0, REPO, Canemud, toml

DOORS = REPO / "tests" / "data" / "lin" / "doors.ldf"
EXTRA = toml(LIN0)
MS = 1_000_000


def cli(daemon, *args, check=True) -> subprocess.CompletedProcess:
    return conftest.cli(daemon, *args, check=check,
                        env=dict(os.environ, CANEMU_PYTHON=sys.executable))


def frames(node) -> list:
    """(microseconds, id, data, own) of each frame the node's monitor has."""
    out = []
    while (m := node.recv(0)) is not None:
        if m.kind == "frame":
            out.append((round(m.timestamp * 1e6), m.id, m.data, m.own))
    return out


def nodes(daemon) -> dict:
    rows = cli(daemon, "lin", "list").stdout.splitlines()[1:]
    return {r.split()[0]: r.split()[1:4] for r in rows}


def test_an_ldf_loaded_at_run_time_drives_the_cluster(daemon):
    with Responder("lin0") as right:  # the real DoorRight: 21h, one byte
        right.set_response(0x21, b"\x32")
        loaded = cli(daemon, "lin", "load", str(DOORS), "--bus", "lin0", "--real", "DoorRight")
        assert "bcm" in loaded.stdout and "doorleft" in loaded.stdout
        assert nodes(daemon) == {"bcm": ["lin0", "on", "normal"], "doorleft": ["lin0", "on", "-"]}
        canemu.step(30 * MS)
        # The Normal table from the load (t = 0), 10 ms a slot; each frame at the end of its
        # checksum: 34 + 10 x (bytes + 1) bits at 19200 bit/s, rounded down to the microsecond.
        assert frames(right) == [(3333, 0x10, b"\x00\x00", False),
                                 (13854, 0x20, b"\x00\x01\x64", False),
                                 (22812, 0x21, b"\x32", True)]
        # Stopped at 30 ms, just as the fourth slot's header went out (it ran at 30 ms, within
        # the step): that frame completes, no header comes after it. Switched to Events at
        # 100 ms: it starts there.
        cli(daemon, "lin", "schedule", "bcm", "--stop")
        canemu.step(70 * MS)
        assert frames(right) == [(33333, 0x10, b"\x00\x00", False)]
        assert nodes(daemon)["bcm"] == ["lin0", "on", "-"]
        cli(daemon, "lin", "schedule", "bcm", "events")
        canemu.step(5 * MS)
        assert frames(right) == [(103333, 0x10, b"\x00\x00", False)]
        # At 105 ms, the bus idle: DoorLeft switched off, the Normal table again from its first
        # slot: 10h at 105 ms, 20h at 115 ms finds nobody, 21h at 125 ms.
        cli(daemon, "lin", "off", "doorleft")
        cli(daemon, "lin", "schedule", "bcm", "normal")
        canemu.step(30 * MS)
        assert frames(right) == [(108333, 0x10, b"\x00\x00", False),
                                 (127812, 0x21, b"\x32", True)]
        assert nodes(daemon)["doorleft"] == ["lin0", "off", "-"]
        cli(daemon, "lin", "remove", "doorleft")
        assert list(nodes(daemon)) == ["bcm"]


def test_mistakes_change_nothing(daemon, tmp_path):
    cli(daemon, "lin", "load", str(DOORS), "--bus", "lin0", "--real", "DoorRight")
    # A second commander on lin0 while bcm runs its schedule.
    second = tmp_path / "second.toml"
    second.write_text('[[lin_node]]\nname = "gw"\nbus = "lin0"\nschedule = "s"\n\n'
                      '[[lin_node.schedules]]\nname = "s"\nslots = [{ frame = 0x10, delay = "5ms" }]\n')
    done = cli(daemon, "lin", "load", str(second), check=False)
    assert done.returncode == 1
    assert "lin_node gw: bcm is the commander of lin0 already (running normal)" in done.stderr
    bad = tmp_path / "bad.toml"
    bad.write_text('[[lin_node]]\nname = "x"\nbus = "can9"\n')
    done = cli(daemon, "lin", "load", str(bad), check=False)
    assert 'no bus is named "can9"' in done.stderr
    assert "nothing changed" in done.stderr
    done = cli(daemon, "lin", "schedule", "bcm", "fast", check=False)
    assert 'node bcm has no schedule table named "fast"' in done.stderr
    done = cli(daemon, "lin", "off", "ghost", check=False)
    assert 'no simulated LIN node named "ghost"' in done.stderr
    done = cli(daemon, "lin", "load", str(DOORS), check=False)
    assert "an LDF file needs --bus" in done.stderr
    assert set(nodes(daemon)) == {"bcm", "doorleft"}
    assert nodes(daemon)["bcm"] == ["lin0", "on", "normal"]


@pytest.fixture
def two_buses():
    d = Canemud("stepped", extra=EXTRA + EXTRA.replace("lin0", "lin1"))
    yield d
    d.stop()


def rows(daemon) -> list:
    return [r.split()[:4] for r in cli(daemon, "lin", "list").stdout.splitlines()[1:]]


def test_node_names_are_scoped_by_bus(two_buses, tmp_path):
    d = two_buses
    cli(d, "lin", "load", str(DOORS), "--bus", "lin0")
    # The same LDF as a second cluster: its nodes join lin1; lin0's stay as they were.
    cli(d, "lin", "load", str(DOORS), "--bus", "lin1", "--schedule", "Events")
    assert rows(d) == [["bcm", "lin0", "on", "normal"], ["doorleft", "lin0", "on", "-"],
                       ["doorright", "lin0", "on", "-"], ["bcm", "lin1", "on", "events"],
                       ["doorleft", "lin1", "on", "-"], ["doorright", "lin1", "on", "-"]]
    # A bare name that two buses have is refused with the names to use.
    done = cli(d, "lin", "off", "bcm", check=False)
    assert done.returncode == 1
    assert ('LIN nodes named "bcm" are on several buses: name one as lin0/bcm or lin1/bcm'
            in done.stderr)
    cli(d, "lin", "off", "lin1/doorleft")
    cli(d, "lin", "schedule", "lin1/bcm", "--stop")
    assert rows(d)[3:5] == [["bcm", "lin1", "on", "-"], ["doorleft", "lin1", "off", "-"]]
    assert rows(d)[:2] == [["bcm", "lin0", "on", "normal"], ["doorleft", "lin0", "on", "-"]]
    # Loading a node again replaces the one of that name on its own bus only.
    again = tmp_path / "again.toml"
    again.write_text('[[lin_node]]\nname = "doorleft"\nbus = "lin1"\n')
    cli(d, "lin", "load", str(again))
    assert [r[:3] for r in rows(d)] == [["bcm", "lin0", "on"], ["doorleft", "lin0", "on"],
                                        ["doorright", "lin0", "on"], ["bcm", "lin1", "on"],
                                        ["doorright", "lin1", "on"], ["doorleft", "lin1", "on"]]
    # A fault's node: BUS/NAME, or the rule's bus picks it; a bare name two buses have is not
    # guessed.
    bad = cli(d, "fault", "inject", "--effect", "lin_responder_off", "--node", "doorright",
              check=False)
    assert bad.returncode == 1
    assert ('no LIN node named "doorright" (a LIN controller DEVICE:N or a [[lin_node]]; one of '
            'a name several buses have: with the rule\'s bus, or as BUS/NAME)') in bad.stderr
    cli(d, "fault", "inject", "--effect", "lin_responder_off", "--node", "lin0/doorright")
    cli(d, "fault", "inject", "--effect", "lin_checksum_error", "--bus", "lin1", "--from", "bcm")
    bad = cli(d, "fault", "inject", "--effect", "lin_checksum_error", "--bus", "lin1",
              "--from", "lin0/bcm", check=False)
    assert "node lin0/bcm is not on bus lin1" in bad.stderr
    cli(d, "lin", "remove", "lin0/bcm")
    cli(d, "lin", "remove", "bcm")  # only lin1 has one now
    assert [r[:2] for r in rows(d)] == [["doorleft", "lin0"], ["doorright", "lin0"],
                                        ["doorright", "lin1"], ["doorleft", "lin1"]]
