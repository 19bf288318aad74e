"""LDF import (canemu.ldf): a realistic LDF (tests/data/lin/doors.ldf) as canemud's simulated
LIN nodes, checked by canemud's own configuration reader."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

import canemu
from canemu import ldf

from canemu.testing import Daemon
from conftest import BUILD, CANEMUD, REPO

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


def test_an_ldf_cluster_runs_with_a_real_program_as_one_responder():
    """doors.ldf imported: canemud plays the BCM (its Normal schedule: 0x10, 0x20, 0x21, 10 ms
    each) and DoorLeft; a VCI program on the adapter's LIN controller plays DoorRight (0x21)."""
    nodes = subprocess.run([sys.executable, "-m", "canemu.ldf", str(DOORS), "--bus", "lin0",
                            "--real", "DoorRight"], capture_output=True, text=True,
                           check=True).stdout
    adapter = ('[[bus]]\nname = "can0"\nkind = "can"\n\n[[device]]\nname = "ixxat0"\n'
               'model = "ixxat-usb-to-can"\ncontrollers = ["can0"]\nlin = ["lin0"]\n\n')
    daemon = Daemon('[simulation]\ntime = "stepped"\n\n' + LIN_BUS + adapter + nodes,
                    canemud=str(CANEMUD))
    program = None
    try:
        env = dict(os.environ, CANEMU_SOCKET=daemon.socket)
        program = subprocess.Popen([str(BUILD / "bin" / "vci_c_talk"), "lin", "ixxat0", "21", "32"],
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                   env=env)
        assert program.stdout.readline() == "ready\n"
        assert canemu.step(30_000_000) == 30_000_000
        out, _ = program.communicate(timeout=10)
        # Each frame's time stamp is the end of its checksum: 34 + 10 x (bytes + 1) bits from
        # its slot's start at 19200 bit/s (BodyCommand 2 bytes, LeftStatus 3, the program's 1).
        assert out.splitlines() == ["3333 us: 10#00", "13854 us: 20#00",
                                    "22812 us: 21#32 (mine)"]
        assert program.returncode == 0
    finally:
        if program is not None and program.poll() is None:
            program.kill()
        daemon.stop()


SEATS = REPO / "tests" / "data" / "lin" / "seats_iso17987.ldf"
WIPERS = REPO / "tests" / "data" / "lin" / "wipers_j2602.ldf"


def test_an_iso17987_ldf_imports_with_each_publishers_checksum(tmp_path):
    nodes = ldf.lin_nodes(str(SEATS), "lin0")
    assert [n["name"] for n in nodes] == ["seatctrl", "seatmodule", "lumbar"]
    ctrl, seat, lumbar = nodes
    assert ctrl["schedules"] == [{"name": "seats", "slots": [
        {"frame": 0x08, "delay": "10ms"}, {"frame": 0x18, "delay": "10ms"},
        {"frame": 0x19, "delay": "10ms"}]}]
    assert ctrl["response"] == [{"id": 0x08, "data": [0x00], "checksum": "enhanced"}]
    assert seat["response"] == [{"id": 0x18, "data": [42, 0x00], "checksum": "enhanced"}]
    # A LIN 1.3 slave in the ISO 17987 cluster: classic, as on its wire.
    assert lumbar["response"] == [{"id": 0x19, "data": [7, 0x00], "checksum": "classic"}]
    out = subprocess.run([sys.executable, "-m", "canemu.ldf", str(SEATS), "--bus", "lin0"],
                         capture_output=True, text=True)
    assert out.returncode == 0 and out.stderr == ""
    config = tmp_path / "lin.toml"
    config.write_text(LIN_BUS + out.stdout)
    check = subprocess.run([str(CANEMUD), "--check-config", str(config)], capture_output=True,
                           text=True)
    assert check.returncode == 0, check.stderr
    assert "lin node seatctrl on lin0 (commander, schedule seats)" in check.stdout


def test_a_j2602_ldf_imports_at_10417_bits_with_enhanced_checksums(tmp_path):
    warnings = []
    nodes = ldf.lin_nodes(str(WIPERS), "lin0", warn=warnings.append)
    assert warnings == []
    assert [(n["name"], n["bitrate"]) for n in nodes] == [("body", 10417), ("wiper", 10417)]
    body, wiper = nodes
    assert body["schedule"] == "wiping"
    assert body["response"] == [{"id": 0x01, "data": [0x00], "checksum": "enhanced"}]
    # J2602's status byte (APINFO 0, ERR 0), park 1, speed 3.
    assert wiper["response"] == [{"id": 0x02, "data": [0x00, 0x01, 0x03],
                                  "checksum": "enhanced"}]
    out = subprocess.run([sys.executable, "-m", "canemu.ldf", str(WIPERS), "--bus", "lin0"],
                         capture_output=True, text=True)
    assert out.returncode == 0 and out.stderr == ""
    config = tmp_path / "lin.toml"
    config.write_text(LIN_BUS.replace("19200", "10417") + out.stdout)
    check = subprocess.run([str(CANEMUD), "--check-config", str(config)], capture_output=True,
                           text=True)
    assert check.returncode == 0, check.stderr
    assert "lin node wiper on lin0 (responder)" in check.stdout


def test_a_j2602_ldf_at_another_rate_is_taken_with_a_warning_and_2021_is_named(tmp_path):
    fast = tmp_path / "fast.ldf"
    fast.write_text(WIPERS.read_text().replace("10.417 kbps", "19.2 kbps"))
    warnings = []
    nodes = ldf.lin_nodes(str(fast), "lin0", warn=warnings.append)
    assert nodes[0]["bitrate"] == 19200
    assert warnings == [f"{fast}: an SAE J2602 cluster at 19200 bit/s (J2602-1 names 10417 "
                        f"bit/s); taken as written"]
    done = subprocess.run([sys.executable, "-m", "canemu.ldf", str(fast), "--bus", "lin0"],
                          capture_output=True, text=True)
    assert done.returncode == 0
    assert done.stderr == f"canemu.ldf: warning: {warnings[0]}\n"
    later = tmp_path / "j2602_2021.ldf"
    later.write_text(WIPERS.read_text().replace('"J2602_1_1.0"', '"J2602_1_2.0"'))
    done = subprocess.run([sys.executable, "-m", "canemu.ldf", str(later), "--bus", "lin0"],
                          capture_output=True, text=True)
    assert done.returncode == 1
    assert done.stderr.startswith(f"canemu.ldf: {later}: ldfparser ")
    assert "does not take it: J2602_1_2.0" in done.stderr and "Traceback" not in done.stderr
