"""canemu's pytest plugin (canemu.pytest_plugin, canemu.bench), run the way a user runs it: test
files written into a fresh folder and run by pytest in a process of their own (pytester), which
loads the plugin through its entry point."""

from __future__ import annotations

import os
import re
import sys

import pytest

from canemu.bench import duration_ns, parse_candump_line

from conftest import BUILD

pytest_plugins = ["pytester"]


@pytest.fixture
def run(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch):
    """Runs pytest on the files written so far, in a subprocess, with this build's canemud."""
    monkeypatch.setenv("CANEMUD", str(BUILD / "bin" / "canemud"))
    monkeypatch.setenv("CANEMU", str(BUILD / "bin" / "canemu"))
    monkeypatch.delenv("CANEMU_SOCKET", raising=False)

    def go(*args: str) -> pytest.RunResult:
        return pytester.runpytest_subprocess("-p", "no:cacheprovider", *args, timeout=300)

    return go


def test_durations_and_candump_lines():
    assert duration_ns(10) == 10_000_000
    assert duration_ns(0.25) == 250_000
    assert duration_ns("150us") == 150_000
    assert duration_ns("2s") == 2_000_000_000
    with pytest.raises(ValueError, match="'10 parsecs'"):
        duration_ns("10 parsecs")
    f = parse_candump_line("(0000000000.000106) can0 124#11AA")
    assert (f.timestamp, f.bus, f.id, f.data, f.is_extended_id) == (0.000106, "can0", 0x124,
                                                                     b"\x11\xaa", False)
    f = parse_candump_line("(1.5) can1 1ABCDEF0#R")
    assert (f.id, f.is_extended_id, f.is_remote_frame, f.data) == (0x1ABCDEF0, True, True, b"")
    f = parse_candump_line("(2.0) fd0 123##1" + "00" * 12)
    assert (f.is_fd, f.bitrate_switch, len(f.data)) == (True, True, 12)
    f = parse_candump_line("(3.0) can0 20000080#0000000000000000")
    assert f.is_error_frame and f.id == 0x80
    f = parse_candump_line("(4.0) can0 123#1122334455667788_C")  # classic DLC 12
    assert f.data == bytes.fromhex("1122334455667788")
    assert parse_candump_line("not a frame") is None


def test_fixtures_and_helpers_in_stepped_time(pytester, run):
    pytester.makepyfile(
        """
        import os
        import can
        import pytest

        pytestmark = pytest.mark.canemu(time="stepped")

        def test_time_buses_and_frames(canemu):
            assert canemu.stepped and canemu.now() == 0.0
            assert canemu.step(2) == 0.002
            assert canemu.step("500us") == 0.0025
            a = canemu.bus("can0")
            b = canemu.bus("can0")
            a.send(can.Message(arbitration_id=0x123, data=b"\\x11\\x22", is_extended_id=False))
            f = canemu.expect_frame("can0", id=0x123, data=b"\\x11\\x22", within=1)
            assert f.timestamp == 0.002624  # the frame's end: 124 us after it started at 2.5 ms
            assert canemu.now() == 0.0035  # stepped 1 ms at a time until it was there
            assert (f.bus, f.is_extended_id, f.is_error_frame) == ("can0", False, False)
            assert b.recv(0).arbitration_id == 0x123
            assert os.environ["CANEMU_SOCKET"] == canemu.socket

        def test_status_and_nodes(canemu):
            bus = canemu.bus("can0")
            status = canemu.status()
            assert [b["name"] for b in status["buses"]] == ["can0", "can1", "lin0"]
            node = canemu.node(bus.node_name)
            assert (node.bus, node.state, node.tec, node.rec) == ("can0", "error-active", 0, 0)
            assert canemu.node("ixxat0:0").state == "init"  # configured, not started
            with pytest.raises(KeyError, match="no node 'nope'; there are: ixxat0:0"):
                canemu.node("nope")

        def test_inject_and_expect_state(canemu):
            a = canemu.bus("can0")
            canemu.bus("can0")
            name = canemu.inject("bit_error", bus="can0", match={"id": 0x123}, count=32)
            assert name == "inject-1"
            a.send(can.Message(arbitration_id=0x123, is_extended_id=False))
            node = canemu.expect_state(a.node_name, "error-passive", within=10, resolution="20us")
            assert 128 <= node.tec <= 136  # 16 x 8 at the 16th bit error, seen within 20 us
            node = canemu.expect_state(a.node_name, "bus-off", within=10)
            assert node.tec > 255 or node.state == "bus-off"
            with pytest.raises(RuntimeError, match="no bus named \\"nope\\""):
                canemu.inject("ack_error", bus="nope")
            text = '[scenario]\\nname = "whole"\\n[[fault]]\\nat = "1ms"\\neffect = "node_off"\\n'
            assert canemu.inject(scenario=text + 'node = "ixxat0:1"\\n') == "whole"
            assert [f["scenario"] for f in canemu.status()["faults"]][-1] == "whole"

        def test_programs(canemu):
            import sys
            done = canemu.run([sys.executable, "-c",
                               "import os; print(os.environ['CANEMU_SOCKET'])"])
            assert done.returncode == 0 and done.stdout.strip() == canemu.socket
            slow = canemu.start([sys.executable, "-c", "import time; print('up', flush=True); "
                                 "time.sleep(60)"])
            assert slow.expect_output("up") == "up"
        """
    )
    result = run("-v")
    result.assert_outcomes(passed=4)


def test_a_failing_expectation_says_what_came_and_the_report_carries_the_trace(pytester, run):
    pytester.makepyfile(
        """
        import can
        import pytest

        @pytest.mark.canemu(time="stepped")
        def test_wrong_frame(canemu):
            a = canemu.bus("can0")
            canemu.bus("can0")
            a.send(can.Message(arbitration_id=0x124, data=b"\\x11", is_extended_id=False))
            canemu.expect_frame("can0", id=0x123, within=3)

        @pytest.mark.canemu(time="stepped")
        def test_state_not_reached(canemu):
            a = canemu.bus("can0")
            canemu.expect_state(a.node_name, "bus-off", within="2ms")
        """
    )
    result = run("--basetemp", str(pytester.path / "tmp"))
    result.assert_outcomes(failed=2)
    out = result.stdout.str()
    assert "no frame with id 0x123 on can0 within 3 ms; 1 frame(s) came instead, the last 1:" in out
    assert re.search(r"\(0000000000\.\d{6}\) can0 124#11", out)
    assert re.search(r"vci\d+:0 not bus-off within 2ms: vci\d+:0 on can0: error-active, TEC 0, "
                     r"REC 0", out)
    for section in ("canemu status", "canemu trace can0", "canemu trace lin0", "canemu files"):
        assert section in out, section
    folder = pytester.path / "tmp" / "test_wrong_frame0" / "canemu"
    assert "can0 124#11" in (folder / "can0.log").read_text()
    assert (folder / "can0.pcap").stat().st_size > 24  # the pcap header and a record
    assert "listening on" in (folder / "canemud.log").read_text()
    assert f"traces, canemud's log and programs' output: {folder}" in out


def test_a_passing_test_gets_no_trace_sections(pytester, run):
    pytester.makepyfile(
        """
        def test_nothing(canemu):
            assert canemu.status()["buses"]
        """
    )
    result = run("-rA")
    result.assert_outcomes(passed=1)
    assert "canemu trace" not in result.stdout.str()


def test_real_time_waits_on_the_recorders(pytester, run):
    pytester.makepyfile(
        """
        import can
        import pytest

        @pytest.mark.canemu(time="realtime")
        def test_frame(canemu):
            assert not canemu.stepped
            a = canemu.bus("can0")
            canemu.bus("can0")
            a.send(can.Message(arbitration_id=0x1ABCDEF, data=b"\\x01", is_extended_id=True))
            f = canemu.expect_frame("can0", id=0x1ABCDEF, extended=True, within=5000)
            assert f.data == b"\\x01"
            with pytest.raises(AssertionError, match="nothing came on can1"):
                canemu.expect_frame("can1", within=20)
        """
    )
    run().assert_outcomes(passed=1)


def test_configuration_from_marker_file_ini_and_text(pytester, run):
    pytester.makefile(".toml", bench='[[bus]]\nname = "body"\n[[device]]\nname = "ecu"\n'
                      'model = "ixxat-usb-to-can"\ncontrollers = ["body"]\n')
    pytester.makefile(".toml", other='[[bus]]\nname = "chassis"\n')
    pytester.makeini("[pytest]\ncanemu_config = other.toml\ncanemu_time = stepped\n")
    pytester.makepyfile(
        """
        import pytest

        @pytest.mark.canemu(config="bench.toml")
        def test_marker_file(canemu):
            assert list(canemu.buses) == ["body"] and canemu.stepped
            assert canemu.node("ecu:0").bus == "body"

        def test_ini(canemu):
            assert list(canemu.buses) == ["chassis"]

        @pytest.mark.canemu(config_text='[[bus]]\\nname = "x"\\nkind = "can-fd"\\n', time="realtime")
        def test_text(canemu):
            assert canemu.buses == {"x": "can-fd"} and not canemu.stepped

        @pytest.mark.canemu(config="missing.toml")
        def test_missing(canemu):
            pass

        @pytest.mark.canemu(cofig="bench.toml")
        def test_typo(canemu):
            pass
        """
    )
    result = run()
    result.assert_outcomes(passed=3, errors=2)
    out = result.stdout.str()
    assert re.search(r"canemu configuration \S*missing\.toml: no such file", out)
    assert "@pytest.mark.canemu takes config=, config_text=, time= and files= (got cofig)" in out


def test_parallel_workers_run_two_daemons_at_once(pytester, run):
    pytester.makepyfile(
        """
        import os
        import time
        from pathlib import Path

        import pytest

        @pytest.mark.parametrize("me", ["a", "b"])
        def test_side_by_side(canemu, me, tmp_path_factory):
            meet = tmp_path_factory.getbasetemp().parent
            pid = canemu.daemon.proc.pid
            (meet / f"{me}.pid").write_text(f"{pid} {canemu.socket} {os.getpid()}")
            other = meet / ("b.pid" if me == "a" else "a.pid")
            deadline = time.monotonic() + 60
            while not other.exists():  # both daemons must run at the same time
                assert time.monotonic() < deadline, "the other worker never came"
                time.sleep(0.01)
            assert canemu.status()["buses"]
        """
    )
    result = run("-n", "2", "-p", "xdist", "--basetemp", str(pytester.path / "tmp"))
    result.assert_outcomes(passed=2)
    a = (pytester.path / "tmp" / "a.pid").read_text().split()
    b = (pytester.path / "tmp" / "b.pid").read_text().split()
    assert a[0] != b[0] and a[1] != b[1] and a[2] != b[2]  # daemons, sockets, workers


def test_canemud_dying_mid_test_is_reported_with_its_log(pytester, run):
    pytester.makepyfile(
        """
        import os
        import signal

        import pytest

        @pytest.mark.canemu(time="stepped")
        def test_dies(canemu):
            canemu.step(1)
            os.kill(canemu.daemon.proc.pid, signal.SIGKILL)
            canemu.daemon.proc.wait()
            canemu.step(1)

        @pytest.mark.canemu(time="stepped")
        def test_dies_unnoticed(canemu):
            os.kill(canemu.daemon.proc.pid, signal.SIGKILL)
            canemu.daemon.proc.wait()
        """
    )
    result = run("--basetemp", str(pytester.path / "tmp"))
    result.assert_outcomes(failed=1, passed=1, errors=1)
    out = result.stdout.str()
    log = pytester.path / "tmp" / "test_dies0" / "canemu" / "canemud.log"
    assert f"CanemudDied: canemud exited with status -9 during the test; its log: {log}" in out
    assert "listening on" in log.read_text()
    unnoticed = pytester.path / "tmp" / "test_dies_unnoticed0" / "canemu" / "canemud.log"
    assert f"canemud exited with status -9 during the test; its log: {unnoticed}" in out
    assert "ERROR at teardown of test_dies_unnoticed" in out
    assert "ERROR at teardown of test_dies " not in out  # told once, in the test
