"""LDF import (canemu.ldf): a realistic LDF (tests/data/lin/doors.ldf) as canemud's simulated
LIN nodes, checked by canemud's own configuration reader."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from canemu import ldf

from conftest import CANEMUD, REPO

DOORS = REPO / "tests" / "data" / "lin" / "doors.ldf"
LIN_BUS = '[[bus]]\nname = "lin0"\nkind = "lin"\nbitrate = 19200\n\n'


def test_every_node_but_the_real_one_with_its_frames_and_the_masters_tables():
    nodes = ldf.lin_nodes(str(DOORS), "lin0", real=["DoorRight"])
    assert [n["name"] for n in nodes] == ["bcm", "doorleft"]
    bcm, left = nodes
    assert bcm["schedule"] == "normal"
    assert [t["name"] for t in bcm["schedules"]] == ["normal", "events", "collisions"]
    assert bcm["schedules"][1]["slots"] == [
        {"frame": 0x10, "delay": "10ms"},
        {"event_triggered": 0x30, "frames": [0x20, 0x21], "delay": "10ms"},
    ]
    assert bcm["response"] == [{"id": 0x10, "data": [0, 0], "checksum": "enhanced"}]
    # LeftStatus: byte 0 reserved (the event-triggered frame's PID), LeftLocked = 1 in bit 8,
    # LeftWindowPos = 100 in byte 2.
    assert left["response"] == [{"id": 0x20, "data": [0x00, 0x01, 0x64], "checksum": "enhanced",
                                 "event_triggered": 0x30}]
    assert left["bitrate"] == 19200 and "schedules" not in left


def test_a_real_master_leaves_the_schedules_to_the_program():
    nodes = ldf.lin_nodes(str(DOORS), "lin0", real=["BCM"], schedule=None)
    assert [n["name"] for n in nodes] == ["doorleft", "doorright"]
    assert all("schedule" not in n for n in nodes)
    assert nodes[1]["response"][0]["data"] == [0x00, 0x01, 50]


def test_the_toml_passes_canemuds_configuration_check(tmp_path):
    out = subprocess.run([sys.executable, "-m", "canemu.ldf", str(DOORS), "--bus", "lin0",
                          "--real", "DoorRight", "--schedule", "Events"],
                         capture_output=True, text=True, check=True).stdout
    assert out.startswith(f"# LIN nodes from {DOORS} (canemu.ldf)\n")
    assert 'schedule = "events"\n' in out
    config = tmp_path / "lin.toml"
    config.write_text(LIN_BUS + out)
    check = subprocess.run([str(CANEMUD), "--check-config", str(config)], capture_output=True,
                           text=True)
    assert check.returncode == 0, check.stderr
    assert "lin node bcm on lin0 (commander, schedule events)" in check.stdout
    assert "lin node doorleft on lin0 (responder)" in check.stdout


def test_mistakes_are_named(tmp_path):
    with pytest.raises(ValueError, match=r"no node is named 'Trunk' \(nodes: BCM, DoorLeft, "
                                         r"DoorRight\)"):
        ldf.lin_nodes(str(DOORS), "lin0", real=["Trunk"])
    with pytest.raises(ValueError, match=r"no schedule table is named 'Fast' \(tables: Normal, "
                                         r"Events, Collisions\)"):
        ldf.lin_nodes(str(DOORS), "lin0", schedule="Fast")
    broken = tmp_path / "broken.ldf"
    broken.write_text("LIN_description_file;\nLIN_speed = fast;\n")
    done = subprocess.run([sys.executable, "-m", "canemu.ldf", str(broken), "--bus", "lin0"],
                          capture_output=True, text=True)
    assert done.returncode == 1
    assert done.stderr.startswith(f"canemu.ldf: {broken}: not a readable LDF: ")
    missing = subprocess.run([sys.executable, "-m", "canemu.ldf", str(tmp_path / "none.ldf"),
                              "--bus", "lin0"], capture_output=True, text=True)
    assert missing.returncode == 1
    assert "none.ldf" in missing.stderr and "Traceback" not in missing.stderr
