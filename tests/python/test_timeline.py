"""`canemu timeline` and `canemu plot` against a running canemud in stepped time: the load of
a bus in 100 ms bins with the exact busy time of its frames, each node's counter changes at
the instants its error frames carry, and the picture drawn from them."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from decimal import Decimal

import can
import pytest

import canemu
from canemu.plot import series

from conftest import (CANEMU_CLI, REPO, bus_errors, drain, fault, frames, load, missing_acks, ns,
                      scenario)

US = 1_000
MS = 1_000_000
BIT = 2 * US  # at 500 kbit/s


def cli(daemon, *args, check=True, env=None) -> subprocess.CompletedProcess:
    done = subprocess.run(
        [str(CANEMU_CLI), "--socket", daemon.socket, *args],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
    )
    if check:
        assert done.returncode == 0, done.stderr
    return done


def timeline(daemon, *args) -> dict:
    return json.loads(cli(daemon, "timeline", *args, "--json").stdout)


def msg(arbitration_id=0x123, data=(1, 2)):
    return can.Message(arbitration_id=arbitration_id, data=list(data), is_extended_id=False)


def test_the_load_history_has_the_exact_busy_time_of_each_bin(daemon, nodes):
    a, _ = nodes
    a.send(msg(0x100))  # 64 bits + 3 of intermission: 134 us (canemu calc frame 100#0102)
    canemu.step(150 * MS)
    a.send(msg(0x100))
    a.send(msg(0x100))
    canemu.step(100 * MS)  # now 250 ms: two bins have ended
    t = timeline(daemon, "can0")
    assert t["bus"] == "can0" and t["now_ns"] == 250 * MS
    assert t["load"] == {"start_ns": 0, "bin_ns": 100 * MS, "busy_ns": [134 * US, 2 * 134 * US]}
    text = cli(daemon, "timeline", "can0").stdout.splitlines()
    assert text[0] == "bus can0: load per 0.1 s of simulated time, up to 0.250000000 s"
    assert text[1].split() == ["0.000", "..", "0.100", "s", "0.13", "%"]
    assert text[2].split() == ["0.100", "..", "0.200", "s", "0.27", "%"]


def test_each_counted_error_is_in_the_senders_timeline_at_its_instant(daemon, nodes):
    a, b = nodes
    load(daemon, missing_acks(3, "three acks missing"))
    a.send(msg(0x123))
    canemu.step(5 * MS)
    errors_a = bus_errors(drain(a))
    received_b = [m for m in drain(b) if not m.is_error_frame]
    assert len(errors_a) == 3 and len(received_b) == 1
    t = timeline(daemon, "can0", a.node_name)
    [node] = t["nodes"]
    assert node["name"] == a.node_name and node["forgotten"] == 0
    samples = node["samples"]
    # +8 per ACK error at the instant its error frame says, then -1 for the frame that went.
    assert [(s["tec"], s["rec"], s["state"], s["cause"]) for s in samples] == [
        (8, 0, "error-active", "error"),
        (16, 0, "error-active", "error"),
        (24, 0, "error-active", "error"),
        (23, 0, "error-active", "success"),
    ]
    assert [s["at_ns"] for s in samples[:3]] == [round(e.timestamp * 1e9) for e in errors_a]
    assert all(s["error"] == "ack" and s["role"] == "transmitter" for s in samples[:3])
    assert samples[3]["at_ns"] == round(received_b[0].timestamp * 1e9)
    # Every node of the bus when none is named; the text form says the same.
    everyone = timeline(daemon, "can0")
    assert a.node_name in [n["name"] for n in everyone["nodes"]]
    assert b.node_name in [n["name"] for n in everyone["nodes"]]
    text = cli(daemon, "timeline", "can0", a.node_name).stdout
    assert f"node {a.node_name}: 4 changes of its error counters" in text
    assert "ack error as transmitter" in text and "good frame" in text


def test_bad_names_are_refused_with_the_reason(daemon):
    assert "no bus named \"nope\"" in cli(daemon, "timeline", "nope", check=False).stderr
    done = cli(daemon, "timeline", "can0", "ghost:0", check=False)
    assert done.returncode == 1 and 'no CAN node named "ghost:0"' in done.stderr
    done = cli(daemon, "timeline", "can1", "ixxat0:0", check=False)
    assert 'node "ixxat0:0" is not on bus "can1"' in done.stderr


def test_plot_draws_the_timeline(daemon, nodes, tmp_path):
    a, _ = nodes
    load(daemon, scenario(
        fault(at="0s", bus="can0", effect="ack_error", count=20),
        name="acks missing"))
    a.send(msg(0x123))
    canemu.step(120 * MS)
    t = timeline(daemon, "can0", a.node_name)
    lines = series(t)
    x, tec = lines["nodes"][a.node_name]["tec"]
    # From 0 at time 0, one step per change, held to the end (error-passive from TEC 128 on:
    # an ACK error of a passive sender does not count, so TEC stays at 128 until it goes).
    assert x[0] == 0.0 and tec[0] == 0 and x[-1] == 0.12
    assert max(tec) == 128 and tec[-1] == 127
    lx, ly = lines["load"]
    assert lx[:2] == [0.0, 0.1] and ly[0] == ly[1] > 0
    env = dict(os.environ, CANEMU_PYTHON=sys.executable)
    for name in ("timeline.png", "timeline.svg"):
        out = tmp_path / name
        cli(daemon, "plot", "can0", a.node_name, "-o", str(out), "--title", "acks missing", env=env)
        data = out.read_bytes()
        if name.endswith(".png"):
            assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000
        else:
            assert b"<svg" in data and b"acks missing" in data


def rows(daemon, bus, node) -> list:
    """`canemu timeline BUS NODE`'s table as (at_ns, tec, rec, state), read from its text."""
    out = []
    for line in cli(daemon, "timeline", bus, node).stdout.splitlines():
        words = line.split()
        if len(words) >= 5 and words[0][0].isdigit() and "." in words[0] and words[1].isdigit():
            out.append((int(Decimal(words[0]) * 10**9), int(words[1]), int(words[2]), words[3]))
    return out


def test_the_plot_shows_every_change_of_a_recovery_at_its_instant(daemon, nodes):
    a, b = nodes
    load(daemon, missing_acks(16, "passive"))
    for _ in range(40):
        a.send(msg(0x123))
    canemu.step(50 * MS)
    received = frames(drain(b))
    assert len(received) == 40
    table = rows(daemon, "can0", a.node_name)
    # 16 ACK errors to error-passive (128), then one count-down per frame that went, each at
    # the instant the receiver has for it: 127 .. 96 warning, 95 .. 88 error-active.
    assert [r[1] for r in table[:16]] == [8 * (k + 1) for k in range(16)]
    assert table[15][3] == "error-passive"
    assert table[16:] == [
        (ns(m.timestamp), 127 - k, 0, "warning" if 127 - k >= 96 else "error-active")
        for k, m in enumerate(received)
    ]
    # The picture's TEC and REC lines: a step at each row, at its instant, from 0 at time 0 to
    # the end of the timeline.
    from canemu.plot import figure

    t = timeline(daemon, "can0", a.node_name)
    fig = figure(t)
    lines = {line.get_label(): line for line in fig.axes[1].get_lines()}
    for key, column in (("TEC", 1), ("REC", 2)):
        line = lines[f"{a.node_name} {key}"]
        assert line.get_drawstyle() == "steps-post"
        x, y = list(line.get_xdata()), list(line.get_ydata())
        assert x[0] == 0.0 and y[0] == 0
        assert [round(v * 1e9) for v in x[1:-1]] == [r[0] for r in table]
        assert y[1:-1] == [r[column] for r in table]
        assert x[-1] == t["now_ns"] / 1e9 and y[-1] == table[-1][column]


def plot(daemon, out, env) -> subprocess.CompletedProcess:
    return cli(daemon, "plot", "can0", "-o", str(out), check=False, env=env)


def test_each_plot_error_has_its_own_message(daemon, nodes, tmp_path):
    env = dict(os.environ, CANEMU_PYTHON=sys.executable)
    # A format matplotlib is not asked for: which ones work, no word of packages.
    gif = plot(daemon, tmp_path / "run.gif", env)
    assert gif.returncode == 1
    assert "cannot draw a .gif file; the formats are .pdf, .png and .svg" in gif.stderr
    assert "matplotlib" not in gif.stderr and "package" not in gif.stderr
    bare = plot(daemon, tmp_path / "run", env)
    assert bare.returncode == 1 and "needs an extension for the format" in bare.stderr
    # A folder that is not there: named.
    missing = plot(daemon, tmp_path / "nope" / "run.png", env)
    assert missing.returncode == 1
    assert f"no folder {tmp_path / 'nope'}" in missing.stderr
    assert "matplotlib" not in missing.stderr and "package" not in missing.stderr
    # An interpreter without matplotlib: how to install it.
    fake = tmp_path / "no-matplotlib"
    (fake / "matplotlib").mkdir(parents=True)
    (fake / "matplotlib" / "__init__.py").write_text(
        "raise ModuleNotFoundError(\"No module named 'matplotlib'\", name='matplotlib')\n")
    python = tmp_path / "python-without-matplotlib"
    python.write_text(f"#!/bin/sh\nPYTHONPATH={fake} exec {sys.executable} \"$@\"\n")
    python.chmod(0o755)
    bare_python = plot(daemon, tmp_path / "run.png", dict(os.environ, CANEMU_PYTHON=str(python)))
    assert bare_python.returncode == 1
    assert f"matplotlib is not installed for {sys.executable}" in bare_python.stderr
    assert "pip install matplotlib" in bare_python.stderr
    assert "apt install python3-matplotlib" in bare_python.stderr
    assert not (tmp_path / "run.png").exists()
    # An interpreter that cannot be run.
    none = plot(daemon, tmp_path / "run.png", dict(os.environ, CANEMU_PYTHON=str(tmp_path / "nix")))
    assert none.returncode == 1 and f"cannot run {tmp_path / 'nix'}" in none.stderr


@pytest.mark.skipif(not (REPO / ".venv" / "bin" / "python").exists(), reason="no .venv (make deps)")
def test_plot_from_the_build_tree_finds_the_repositorys_venv(daemon, nodes, tmp_path):
    # The python3 on PATH has neither matplotlib nor canemu; CANEMU_PYTHON is not set.
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    (bin_dir / "python3").write_text("#!/bin/sh\necho 'the python3 on PATH' >&2\nexit 1\n")
    (bin_dir / "python3").chmod(0o755)
    env = {k: v for k, v in os.environ.items() if k != "CANEMU_PYTHON"}
    env["PATH"] = f"{bin_dir}:{env.get('PATH', '/usr/bin:/bin')}"
    done = plot(daemon, tmp_path / "run.svg", env)
    assert done.returncode == 0, done.stderr
    assert b"<svg" in (tmp_path / "run.svg").read_bytes()


def test_a_python_can_nodes_history_stays_readable_after_it_closed(daemon):
    a = can.Bus(interface="canemu", channel="can0", auto_restart=False)
    b = can.Bus(interface="canemu", channel="can0", auto_restart=False)
    drain(a)
    drain(b)
    load(daemon, missing_acks(3, "three acks missing"))
    a.send(msg(0x123))
    canemu.step(5 * MS)
    name = a.node_name
    [before] = timeline(daemon, "can0", name)["nodes"]
    assert [s["tec"] for s in before["samples"]] == [8, 16, 24, 23]
    a.shutdown()
    canemu.step(1 * MS)
    # Under the name it had, marked gone at the instant it went, with every change it had.
    [after] = timeline(daemon, "can0", name)["nodes"]
    assert after["samples"] == before["samples"] and after["gone_at_ns"] == 5 * MS
    assert "gone_at_ns" not in timeline(daemon, "can0", b.node_name)["nodes"][0]
    text = cli(daemon, "timeline", "can0", name).stdout
    assert f"node {name} (gone at 0.005000000 s): 4 changes of its error counters" in text
    # Listed with the bus's nodes when none is named, and drawn.
    everyone = {n["name"]: n for n in timeline(daemon, "can0")["nodes"]}
    assert everyone[name]["gone_at_ns"] == 5 * MS and b.node_name in everyone
    from canemu.plot import series

    x, tec = series(timeline(daemon, "can0", name))["nodes"][name]["tec"]
    assert x[-1] == 0.005 and tec[-1] == 23  # held until it went, not to now
    # Offered when a name is not found.
    done = cli(daemon, "timeline", "can0", "vci99:0", check=False)
    assert done.returncode == 1 and 'no CAN node named "vci99:0"' in done.stderr
    assert f"gone from can0, their history kept: {name}" in done.stderr
    # The next device of that name (the next python-can run) replaces it.
    c = can.Bus(interface="canemu", channel="can0", auto_restart=False)
    assert c.node_name == name
    [fresh] = timeline(daemon, "can0", name)["nodes"]
    assert fresh["samples"] == [] and "gone_at_ns" not in fresh
    b.shutdown()
    c.shutdown()
