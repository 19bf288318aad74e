"""`canemu web` against a running canemud: the page in Debian's headless chromium (through
Playwright) shows the buses and nodes, a node's state at the step that changed it (stepped time)
or within a second (real time), the TEC line up to the value `canemu status` shows, ID tables
that count every frame sent; /metrics parsed by the Prometheus client's parser equals `canemu
metrics`; bad requests get a clear HTTP error and change nothing. The test run leaves the
page's picture in docs/web.png (docs/web.md)."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import can
import pytest

from conftest import CANEMU_CLI, REPO, Canemud
from web_support import Web, browser, cli, frame_times, status

pytest.importorskip("aiohttp", reason="canemu web needs aiohttp (python3-aiohttp)")

MS = 1_000_000
# The page as the test leaves it, outside the source tree; docs/web.png is refreshed with
# CANEMU_WEB_SCREENSHOT=docs/web.png when the page changes.
SCREENSHOT = Path(os.environ.get("CANEMU_WEB_SCREENSHOT",
                                 Path(tempfile.gettempdir()) / "canemu-web.png"))
DBC = REPO / "tests" / "data" / "dbc" / "socialledge.dbc"

SCENARIO = """
[scenario]
name = "web-demo"

[[fault]]
at = "1s"
effect = "error_counters"
node = "{node}"
tec = 130
rec = 0

[[fault]]
at = "0s"
effect = "bit_error"
bus = "can1"
match = {{ id = 0x7A }}
count = 1
"""


def playwright_or_skip():
    """Playwright comes from PyPI (requirements.txt): .venv has it, Debian has no package."""
    return pytest.importorskip("playwright.sync_api", reason="Playwright is not installed for "
                               "this Python (Debian packages none; .venv has it)")


@pytest.fixture(scope="module")
def daemon(stepped_daemon):
    """The module's tests share one canemud in stepped time (conftest's)."""
    return stepped_daemon


@pytest.fixture(scope="module")
def node(daemon):
    """Python-can nodes that send on can0 and can1, and one more on each that acknowledges."""
    buses = [can.Bus(interface="canemu", channel=c) for c in ("can0", "can1", "can0", "can1")]
    yield buses[0], buses[1]
    for bus in buses:
        bus.shutdown()


def node_name(daemon, bus: str) -> str:
    """The first python-can node on `bus` (the one that sends)."""
    configured = {"ixxat0:0", "ixxat0:1", "ixxatfd:0"}
    names = [n["name"] for n in status(daemon)["nodes"]
             if n["bus"] == bus and n["name"] not in configured]
    assert names, f"no python-can node on {bus}"
    return names[0]


def listening_on_every_bus(state) -> bool:
    return sorted(state["listening"]) == ["can0", "can1", "fd0"]


def test_the_page_shows_buses_nodes_state_tec_and_id_counts(daemon, node):
    sync_api = playwright_or_skip()
    a, b = node
    name = node_name(daemon, "can0")
    web = Web(daemon)
    try:
        web.wait_state(listening_on_every_bus, "the ID tables' listen-only nodes")
        with sync_api.sync_playwright() as p:
            context = browser(p)
            page = context.new_page()
            errors = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(web.url)
            page.wait_for_function("window.canemuView && window.canemuView.updates > 0")
            for bus in ("can0", "can1", "fd0"):
                assert page.locator(f'#buses [data-bus="{bus}"]').count() == 1
            for n in ("ixxat0:0", "ixxat0:1", "ixxatfd:0", name):
                assert page.locator(f'#nodes tr[data-node="{n}"]').count() == 1
            assert page.inner_text(f'#nodes tr[data-node="{name}"] .state') == "error-active"

            # Frames: 5 of 0x123 (changing data), 3 of 0x456 on can0, 2 of 0x7A on can1 (the
            # first hit by a bit error and repeated: an error frame, not a frame, on the bus).
            assert cli(daemon, "fault", "load", str(_scenario(daemon, name))).returncode == 0
            for i in range(5):
                a.send(can.Message(arbitration_id=0x123, data=[1, i], is_extended_id=False))
            for _ in range(3):
                a.send(can.Message(arbitration_id=0x456, data=[9], is_extended_id=False))
            for _ in range(2):
                b.send(can.Message(arbitration_id=0x7A, data=[7, 7], is_extended_id=False))
            before = status(daemon)["sim_time_ns"]
            cli(daemon, "time", "step", "100ms")
            page.wait_for_function(
                """() => [["can0", "123", "5"], ["can0", "456", "3"], ["can1", "07A", "2"]]
                    .every(([bus, id, n]) => {
                        const c = document.querySelector(`#ids-${bus} tr[data-id="${id}"] .count`);
                        return c && c.textContent === n; })""")
            s = status(daemon)
            frames = {x["name"]: x["frames"] for x in s["buses"]}
            assert frames["can0"] == 8 and frames["can1"] == 2  # the ID tables counted them all
            assert next(x for x in s["buses"] if x["name"] == "can1")["error_frames"] >= 1
            assert page.inner_text('#ids-can0 tr[data-id="123"] .data') == "01 04"
            assert page.inner_text(f'#nodes tr[data-node="{name}"] .state') == "error-active"
            # The dump's summary lines carry the error frames its node saw, per bus.
            web.wait_state(lambda st: st["error_frames_seen"].get("can1", 0) >= 1,
                           "can1's error frame in the ID tables' counts")

            # The state changes at simulated 1 s after the scenario was applied: the page shows
            # it at the step that crossed that instant, with that step's time, not before.
            cli(daemon, "time", "step", "1s")
            after = status(daemon)["sim_time_ns"]
            assert after == before + 1100 * MS
            page.wait_for_function(
                f"""() => document.querySelector('#nodes tr[data-node="{name}"] .state')
                    .textContent === "error-passive" """)
            log = page.evaluate("window.canemuView.stateLog")
            changes = [entry for entry in log if entry[0] == name]
            assert [c[1] for c in changes] == ["error-active", "error-passive"]
            assert changes[1][2] == after

            # The TEC line ends at the value canemu status shows.
            tec = next(n["tec"] for n in status(daemon)["nodes"] if n["name"] == name)
            assert tec == 130
            line = page.evaluate(f"""() => window.canemuView.charts["can0"].counters.data
                .datasets.find((d) => d.label === "{name} TEC").data.map((p) => [p.x, p.y])""")
            assert line[-1] == [after / 1e9, tec]
            assert line[0][1] == 0  # it climbed from 0
            assert page.locator("#fired li").count() >= 2  # the bit error and the counters

            # Responsiveness: frames while updates come, each update's handling.
            for _ in range(4):
                cli(daemon, "time", "step", "50ms")
            intervals = frame_times(page, 1.0)
            handled = page.evaluate("window.canemuView.handleMs")
            # The first message (the snapshot) also makes the charts.
            print(f"frame time ms: median {statistics.median(intervals):.1f}, "
                  f"max {max(intervals):.1f}; the snapshot handled in {handled[0]:.1f} ms, "
                  f"{len(handled) - 1} updates in at most {max(handled[1:]):.1f} ms "
                  f"(median {statistics.median(handled[1:]):.1f})")
            assert max(handled[1:]) < 250
            assert statistics.median(intervals) < 100
            assert not errors, errors
            page.screenshot(path=str(SCREENSHOT), full_page=True)
            context.close()
    finally:
        web.stop()


def _scenario(daemon, name: str) -> Path:
    path = Path(daemon.dir, "web-demo.toml")
    path.write_text(SCENARIO.format(node=name))
    return path


def test_a_state_change_shows_within_a_second_in_real_time():
    sync_api = playwright_or_skip()
    d = Canemud("realtime")
    try:
        bus = can.Bus(interface="canemu", channel="can0")
        name = node_name(d, "can0")
        web = Web(d, "--no-frames")
        try:
            with sync_api.sync_playwright() as p:
                context = browser(p)
                page = context.new_page()
                page.goto(web.url)
                page.wait_for_function(
                    f"""() => {{ const c = document.querySelector(
                        '#nodes tr[data-node="{name}"] .state');
                        return c && c.textContent === "error-active"; }}""")
                cli(d, "fault", "inject", "--effect", "error_counters", "--node", name,
                    "--tec", "130", "--rec", "0")
                done = time.time()  # canemud has applied it: the node is error-passive now
                node = next(n for n in status(d)["nodes"] if n["name"] == name)
                assert node["state"] == "error-passive"
                page.wait_for_function(
                    f"""() => document.querySelector('#nodes tr[data-node="{name}"] .state')
                        .textContent === "error-passive" """)
                shown = next(e for e in page.evaluate("window.canemuView.stateLog")
                             if e[0] == name and e[1] == "error-passive")[3] / 1000
                print(f"error-passive shown {1000 * (shown - done):.0f} ms after canemud took it")
                assert shown - done < 1.0
                context.close()
        finally:
            web.stop()
            bus.shutdown()
    finally:
        d.stop()


def _families(text: str):
    from prometheus_client.parser import text_string_to_metric_families

    out = {}
    for family in text_string_to_metric_families(text):
        out[family.name] = (family.type, sorted(
            (s.name, tuple(sorted(s.labels.items())), s.value) for s in family.samples
            if s.name != "canemu_clients"))
    return out


def test_metrics_parse_and_equal_canemu_metrics(daemon, node):
    pytest.importorskip("prometheus_client", reason="prometheus_client parses /metrics")
    web = Web(daemon)
    try:
        web.wait_state(listening_on_every_bus, "the ID tables' listen-only nodes")
        code, text = web.get("/metrics")
        assert code == 200
        ours = _families(cli(daemon, "metrics").stdout)
        served = _families(text)
        assert served == ours
        assert served["canemu_bus_frames"][0] == "counter"
        assert served["canemu_node_tec"][0] == "gauge"
        assert served["canemu_pacing_lateness_seconds"][0] == "summary"
        for name, (kind, _) in served.items():
            assert kind in ("counter", "gauge", "summary"), name
    finally:
        web.stop()


def raw_request(web, data: bytes) -> bytes:
    """`data` sent as it is; the answer up to the end of its body (Content-Length)."""
    host, port = web.url.split("//")[1].rstrip("/").split(":")
    with socket.create_connection((host, int(port)), timeout=10) as s:
        s.sendall(data)
        out = b""
        while b"\r\n\r\n" not in out or len(out.split(b"\r\n\r\n", 1)[1]) < int(
                re.search(rb"Content-Length: (\d+)", out).group(1)):
            chunk = s.recv(65536)
            if not chunk:
                break
            out += chunk
    return out


def test_bad_requests_get_a_clear_error_and_change_nothing(daemon, node):
    web = Web(daemon)
    try:
        web.wait_state(listening_on_every_bus, "the ID tables' listen-only nodes")
        before = status(daemon)
        code, text = web.get("/no/such/page")
        assert code == 404 and "no page '/no/such/page'" in text and "/metrics" in text
        # 64 KiB of one header (aiohttp's limit is 8190 bytes), all in the socket's buffers.
        answer = raw_request(web, b"GET / HTTP/1.1\r\nHost: x\r\nX-Big: " + b"a" * 65_536 +
                             b"\r\n\r\n")
        assert re.match(rb"HTTP/1\.[01] 400 Bad Request\r\n", answer), answer[:200]
        assert b"Got more than 8190 bytes" in answer, answer[:300]
        for path, body in (("/api/step", {"duration": "10ms"}),
                           ("/api/fault", {"effect": "bus_off", "node": "ixxat0:0"}),
                           ("/api/unplug", {"node": "ixxat0:0"})):
            code, text = web.post(path, body)
            assert code == 403 and "--allow-control" in text, (path, text)
        code, text = web.get("/api/step")
        assert code == 405 and "POST" in text
        after = status(daemon)
        assert after["sim_time_ns"] == before["sim_time_ns"]
        assert after["faults"] == before["faults"]
        assert [n["state"] for n in after["nodes"]] == [n["state"] for n in before["nodes"]]
    finally:
        web.stop()


def test_actions_with_allow_control(daemon, node):
    web = Web(daemon, "--allow-control")
    try:
        start = status(daemon)
        code, text = web.post("/api/step", {"duration": "10ms"})
        assert code == 200, text
        assert status(daemon)["sim_time_ns"] == start["sim_time_ns"] + 10 * MS
        faults = len(status(daemon)["faults"])
        for body, words in (({"effect": "no_such"}, "\"effect\" must be one of"),
                            ({"effect": "bus_off", "color": "x"}, "unknown key 'color'"),
                            ({"effect": "bus_off", "node": "a b"}, "is not a value"),
                            ({"effect": "bus_off", "node": "--help"}, "is not a value")):
            code, text = web.post("/api/fault", body)
            assert code == 400 and words in text, text
        code, text = web.post("/api/fault", "{not json")
        assert code == 400 and "not JSON" in text
        code, text = web.post("/api/step", {"duration": "10ms"},
                              headers={"Origin": "http://elsewhere.example"})
        assert code == 403 and "elsewhere.example" in text
        code, text = web.post("/api/fault", {"effect": "error_counters", "node": "nobody:0",
                                             "tec": "5", "rec": "0"})
        assert code == 422 and "nobody:0" in text, text
        assert len(status(daemon)["faults"]) == faults
        assert status(daemon)["sim_time_ns"] == start["sim_time_ns"] + 10 * MS
        code, text = web.post("/api/unplug", {"node": "ixxat0:1"})
        assert code == 200, text
        effects = [(f["effect"], f["target"]) for f in status(daemon)["faults"]]
        assert ("node_off", "ixxat0:1") in effects
        code, text = web.post("/api/plug", {"node": "ixxat0:1"})
        assert code == 200, text
    finally:
        web.stop()


def test_the_peer_of_a_loopback_connection_is_known_by_its_uid():
    from canemu._web_control import _uid_of_tcp_peer

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    client = socket.create_connection(server.getsockname())
    conn, peer = server.accept()
    try:
        assert _uid_of_tcp_peer(peer[0], peer[1], server.getsockname()[1]) == os.getuid()
        assert _uid_of_tcp_peer("192.0.2.1", peer[1], server.getsockname()[1]) is None
    finally:
        for s in (conn, client, server):
            s.close()


def _line(ident: str, data: str, count: int = 1, first_ns: int = 0, last_ns: int = 0,
          changed: int = 0) -> dict:
    """A `canemu dump --summary` line of can0."""
    return {"bus": "can0", "id": ident, "count": count, "first_ns": first_ns,
            "last_ns": last_ns, "data": data, "changed": changed}


def test_id_rows_add_up_summary_lines():
    from canemu._web_feed import IdRow

    row = IdRow("123", 0)
    row.add(_line("123", "0102", count=2, first_ns=0, last_ns=10 * MS, changed=0b01))
    row.add(_line("123", "0103", count=1, first_ns=30 * MS, last_ns=30 * MS, changed=0b10))
    r = row.row("can0")
    # Three frames over 30 ms; the bytes changed in either line since the last update.
    assert (r["count"], r["period_ms"], r["data"], r["changed"]) == (3, 15.0, "0103", 0b11)
    assert (r["message"], r["signals"], r["note"]) == (None, None, None)  # no --dbc
    assert json.dumps(r)
    assert row.row("can0")["changed"] == 0b11  # the feed clears it once published (id_rows)


class _NamedDb:
    """A database that knows every standard identifier as one message, named `name`."""

    class _Message:
        is_extended_frame = False
        signals = []

        def __init__(self, name: str) -> None:
            self.name = name

        def decode(self, data, decode_choices):
            return {}

    def __init__(self, name: str) -> None:
        self.message = self._Message(name)

    def get_message_by_frame_id(self, can_id):
        return self.message


def test_the_id_tables_decode_through_dbc_files():
    pytest.importorskip("cantools", reason="--dbc needs cantools (requirements-dbc.txt)")
    from canemu._web_feed import IdRow, SignalDecoder, parse_dbc_option
    from canemu.dbc_decode import load

    assert parse_dbc_option("can1=car.dbc") == ("can1", "car.dbc")
    assert parse_dbc_option("car.dbc") == (None, "car.dbc")
    # No bus name by canemud's rule before "=": the whole text is the file.
    for text in ("dbc/a=b.dbc", "./v=2.dbc", "CAN0=car.dbc", "=car.dbc"):
        assert parse_dbc_option(text) == (None, text)
    db = load(str(DBC))
    everywhere = SignalDecoder([(None, "car.dbc", db)])

    def row(text_id: str, data: str, bus: str = "can0", decoder=everywhere):
        r = IdRow(text_id, 0)
        r.add(_line(text_id, data))
        return r.row(bus, decoder)

    # MOTOR_STATUS (400 = 0x190): wheel_error 1, speed 0x03E8 x 0.001 kph.
    r = row("190", "01E803")
    assert (r["message"], r["signals"], r["note"]) == (
        "MOTOR_STATUS", [("MOTOR_STATUS_wheel_error", "1"), ("MOTOR_STATUS_speed_kph", "1.0 kph")],
        None)
    assert json.loads(json.dumps(r))["signals"][1] == ["MOTOR_STATUS_speed_kph", "1.0 kph"]
    # A choice by its name; a length that is not the message's; a remote frame.
    assert row("064", "01")["signals"] == [("DRIVER_HEARTBEAT_cmd", "DRIVER_HEARTBEAT_cmd_SYNC")]
    short = row("190", "01")
    assert short["message"] == "MOTOR_STATUS" and short["signals"] is None
    assert short["note"].startswith("not decoded: ")
    assert (row("190", "R")["message"], row("190", "R")["note"]) == ("MOTOR_STATUS",
                                                                     "remote frame")
    # Identifiers the file does not know, and 0x190 as an extended identifier.
    assert row("123", "00")["message"] is None
    assert row("00000190", "01E803")["message"] is None
    # A file for one bus decodes that bus only, and comes before the files for every bus.
    only_can1 = SignalDecoder([("can1", "car.dbc", db)])
    assert only_can1.buses() == {"can1": "car.dbc"}
    assert row("190", "01E803", "can0", only_can1)["message"] is None
    assert row("190", "01E803", "can1", only_can1)["message"] == "MOTOR_STATUS"
    both = SignalDecoder([(None, "a.dbc", _NamedDb("FOR_EVERY_BUS")),
                          ("can1", "b.dbc", _NamedDb("FOR_CAN1"))])
    assert row("190", "00", "can1", both)["message"] == "FOR_CAN1"
    assert row("190", "00", "can0", both)["message"] == "FOR_EVERY_BUS"

    # Whatever a database does wrong, the row says so and the tool goes on.
    class Broken(_NamedDb):
        def get_message_by_frame_id(self, can_id):
            raise RuntimeError("broken")

    broken = row("190", "00", "can0", SignalDecoder([(None, "x.dbc", Broken("X"))]))
    assert (broken["message"], broken["signals"], broken["note"]) == (
        None, None, "x.dbc: not decoded: broken")

    # A row is decoded again when its data changes, not at every update.
    class Counting(SignalDecoder):
        calls = 0

        def decode(self, bus, text_id, data):
            Counting.calls += 1
            return super().decode(bus, text_id, data)

    counting = Counting([(None, "car.dbc", db)])
    r = IdRow("190", 0)
    r.add(_line("190", "01E803"))
    r.row("can0", counting)
    r.row("can0", counting)
    assert Counting.calls == 1
    r.add(_line("190", "00D007", first_ns=MS, last_ns=MS))
    assert r.row("can0", counting)["signals"][1] == ("MOTOR_STATUS_speed_kph", "2.0 kph")
    assert Counting.calls == 2


def test_a_dbc_file_that_cannot_be_read_is_named_and_nothing_serves(daemon, tmp_path):
    pytest.importorskip("cantools", reason="--dbc needs cantools (requirements-dbc.txt)")
    bad = tmp_path / "bad.dbc"
    bad.write_text("this is no DBC\n")
    env = {**os.environ, "CANEMU_PYTHON": sys.executable}
    for path in (bad, tmp_path / "missing.dbc"):
        done = subprocess.run([str(CANEMU_CLI), "--socket", daemon.socket, "web", "--listen",
                               "127.0.0.1:0", "--dbc", f"can0={path}"],
                              capture_output=True, text=True, timeout=60, env=env)
        assert done.returncode == 2, done.stderr
        assert f"canemu: web: --dbc {path}: " in done.stderr
        assert "serving" not in done.stderr


def test_a_page_that_falls_behind_gets_a_snapshot_instead_of_losing_updates():
    import asyncio

    from canemu._web_feed import RESYNC, RESYNC_AFTER, Feed

    feed = Feed.__new__(Feed)  # publish needs only the subscribers and the count
    feed.subscribers, feed.resyncs = set(), 0
    slow = asyncio.Queue()
    feed.subscribers.add(slow)
    for n in range(2 * RESYNC_AFTER + 4):
        feed.publish({"n": n})
    queued = [slow.get_nowait() for _ in range(slow.qsize())]
    # Each time the queue is full, what it holds gives way to one RESYNC; the newest updates
    # follow it.
    assert feed.resyncs == 2
    assert queued[0] == RESYNC
    assert [json.loads(t)["n"] for t in queued[1:]] == list(range(2 * RESYNC_AFTER + 1,
                                                                 2 * RESYNC_AFTER + 4))


def test_buses_added_by_a_reload_get_id_tables_decoded_through_the_dbc():
    """A bus that a reload adds after canemu web started gets its ID table too (a dump of its
    own), and its frames are decoded through --dbc's file."""
    pytest.importorskip("cantools", reason="--dbc needs cantools (requirements-dbc.txt)")
    d = Canemud("stepped")
    try:
        web = Web(d, "--dbc", str(DBC), "--dbc", f"can9={DBC}")
        try:
            web.wait_state(listening_on_every_bus, "the ID tables' listen-only nodes")
            # A file for a bus canemud does not have is named once, with the buses it has.
            web.wait_log(rf"--dbc can9={re.escape(str(DBC))}: canemud has no bus can9 \(buses: "
                         r"can0, can1, fd0\); the file decodes nothing")
            with open(d.config, "a") as config:
                config.write('\n[[bus]]\nname = "can2"\nkind = "can"\nbitrate = 500000\n')
            d.proc.send_signal(signal.SIGHUP)
            web.wait_state(lambda s: "can2" in s["listening"], "a listen-only node on can2")
            sender = can.Bus(interface="canemu", channel="can2")
            acker = can.Bus(interface="canemu", channel="can2")
            try:
                sender.send(can.Message(arbitration_id=0x190, data=[1, 0xE8, 3],
                                        is_extended_id=False))
                cli(d, "time", "step", "10ms")
                state = web.wait_state(
                    lambda s: any(r["id"] == "190" and r["count"] == 1
                                  for r in s["ids"].get("can2", [])), "0x190 on can2")
            finally:
                sender.shutdown()
                acker.shutdown()
            row = next(r for r in state["ids"]["can2"] if r["id"] == "190")
            assert row["message"] == "MOTOR_STATUS"
            assert row["signals"] == [["MOTOR_STATUS_wheel_error", "1"],
                                      ["MOTOR_STATUS_speed_kph", "1.0 kph"]]
            assert sorted(state["listening"]) == ["can0", "can1", "can2", "fd0"]
            try:
                import playwright.sync_api as sync_api
            except ImportError:
                return  # the page's column: with Playwright (.venv), not under .venv-debian
            with sync_api.sync_playwright() as p:
                context = browser(p)
                page = context.new_page()
                page.goto(web.url)
                cell = '#ids-can2 tr[data-id="190"] .signals'
                page.wait_for_selector(cell)
                assert page.inner_text(cell) == ("MOTOR_STATUS: MOTOR_STATUS_wheel_error=1 "
                                                 "MOTOR_STATUS_speed_kph=1.0 kph")
                context.close()
        finally:
            web.stop()
    finally:
        d.stop()


def test_a_dump_that_ends_or_cannot_start_is_said_and_its_buses_are_tried_again():
    import asyncio

    from canemu import _web_feed
    from canemu._web_feed import Feed

    status = {"buses": [{"name": "can0", "kind": "can"}, {"name": "lin0", "kind": "lin"}]}

    async def run(canemu: str, note: str):
        feed = Feed(canemu, [], 0.25, True)
        feed._capture_new_buses(status)
        assert len(feed._captures) == 1  # can0's; none for the LIN bus
        await asyncio.gather(*feed._captures)
        assert feed.capture_note.startswith(f"the ID tables of can0 stopped: {note}"), \
            feed.capture_note
        assert feed._dumps == []  # nothing kept of a dump that ended
        feed._capture_new_buses(status)  # not again at once
        assert feed._captures == []
        feed._ended["can0"] -= _web_feed.RETRY_S  # as if RETRY_S had passed
        feed._capture_new_buses(status)
        assert len(feed._captures) == 1
        await asyncio.gather(*feed._captures)

    asyncio.run(run("/bin/false", "canemu dump ended with status 1"))  # it ends at once
    asyncio.run(run("/nonexistent/canemu", ""))  # it cannot start: the reason follows
