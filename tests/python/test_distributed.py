"""A bus across daemons (docs/distributed.md) on one machine: daemon "a" simulates can0, daemon
"b" declares can0 with owner "a"; both announce themselves over the loopback interface by unicast
in a DDS domain of this run's own (CYCLONEDDS_URI), so no root is needed. Every test runs twice:
with the same-host link that two daemons on one host use (`link`), and with `local_link = false`,
all over DDS (`dds`). python-can programs on both
daemons exchange frames; arbitration, time stamps and error counters are the owner's, exact in
stepped time. tests/python/test_netns_distributed.py runs daemons in network namespaces."""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import time

import can
import pytest

from conftest import BUILD, CANEMU_CLI
from distributed_support import (LOOPBACK_URI, TIMEOUT, attached_step, cli, frame_ns, nodes, step,
                                 wait_until)
from distributed_support import config as support_config

from canemu.testing import Daemon  # noqa: E402

DOMAIN = 1 + (os.getpid() + 97) % 200
URI = LOOPBACK_URI


TRANSPORT = "link"  # the env fixture's parameter


def config(name: str, time_mode: str, owner: str | None = None) -> str:
    return support_config(name, time_mode, owner, domain=DOMAIN,
                          partition=f"canemu-test-{os.getpid()}",
                          local_link=TRANSPORT == "link")


@contextlib.contextmanager
def owner_and_follower(time_mode: str, follower_time: str | None = None, follower_extra: str = ""):
    """Daemon "a" in `time_mode`, owner of can0, and daemon "b" (in `follower_time`, else the
    same), whose can0 has owner "a", with `follower_extra` added to b's configuration."""
    canemud = str(BUILD / "bin" / "canemud")
    with Daemon(config("a", time_mode), canemud=canemud) as a, \
            Daemon(config("b", follower_time or time_mode, owner="a") + follower_extra,
                   canemud=canemud) as b:
        yield a, b


def frames(bus) -> list:
    out = []
    while (m := bus.recv(0)) is not None:
        if not m.is_error_frame:
            out.append((m.arbitration_id, bytes(m.data).hex(), round(m.timestamp * 1e9)))
    return out


def errors(bus) -> list:
    out = []
    while (m := bus.recv(0)) is not None:
        if m.is_error_frame:
            out.append((m.arbitration_id, bytes(m.data).hex()))
    return out


class Peer:
    """tests/python/distributed_peer.py on `daemon`: a python-can program in a process of its
    own (a process talks to one canemud)."""

    def __init__(self, daemon: Daemon, channel: str = "can0") -> None:
        import sys
        from pathlib import Path
        self.proc = subprocess.Popen(
            [sys.executable, str(Path(__file__).with_name("distributed_peer.py")), daemon.socket,
             channel],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        assert self.proc.stdout.readline().strip() == "ready"

    def ask(self, line: str) -> str:
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        return self.proc.stdout.readline().strip()

    def send(self, ident: int, data: str) -> None:
        assert self.ask(f"send {ident:x} {data}") == "sent"

    def frames(self) -> list:
        return [tuple(f) for f in json.loads(self.ask("recv"))]

    def frames_arriving(self, what: str) -> list:
        """The frames received, as (can_id, hexdata), waited for until there are some (`what`
        says which in a failure)."""
        return [(i, d) for i, d, _ in self.frames_arriving_with_times(what)]

    def frames_arriving_with_times(self, what: str) -> list:
        """The frames received, as (can_id, hexdata, timestamp_ns), waited for as
        frames_arriving."""
        got: list = []
        wait_until(lambda: got.extend(self.frames()) or got, what)
        return got

    def errors(self) -> list:
        """Error frames received so far, as (can_id, hexdata)."""
        return [(f[0], f[1]) for f in json.loads(self.ask("errors"))]

    def close(self) -> None:
        if self.proc.poll() is None:
            self.ask("quit")
        self.proc.wait(timeout=TIMEOUT)


@contextlib.contextmanager
def transport(kind: str):
    global TRANSPORT
    TRANSPORT = kind
    os.environ["CYCLONEDDS_URI"] = URI  # the daemons inherit it
    try:
        yield kind
    finally:
        del os.environ["CYCLONEDDS_URI"]
        TRANSPORT = "link"


@pytest.fixture(params=["link", "dds"])
def env(request):
    with transport(request.param) as kind:
        yield kind


@pytest.fixture()
def link_env():
    with transport("link") as kind:
        yield kind


def via(daemon, other: str) -> str:
    """How `daemon` speaks to daemon `other` (status: "link" or "dds")."""
    peers = json.loads(cli(daemon, "status", "--json"))["distributed"]["peers"]
    return next(p["via"] for p in peers if p["name"] == other)


def test_stepped_arbitration_and_time_stamps_across_daemons(env):
    with owner_and_follower("stepped") as (a, b):
        t0 = attached_step(b)
        wait_until(lambda: via(a, "b") == env, "a's status shows how b speaks to it")
        assert via(b, "a") == env
        assert step(a, 1000) == t0 + 1000  # one clock, the owner's: a step of a is one of b
        t0 += 1000  # (VCI time stamps tick in microseconds)
        ecu_b = can.Bus(interface="canemu", channel="can0", socket=b.socket)
        ecu_a = Peer(a)
        try:
            # 1. Both queue a frame before the step, asked for on b: the owner's arbitration
            # sends a's 0x100 first, then b's 0x300, exact to the nanosecond on both daemons.
            ecu_b.send(can.Message(arbitration_id=0x300, is_extended_id=False, data=[3]))
            ecu_a.send(0x100, "01")
            assert step(b, 1_000_000) == t0 + 1_000_000
            first, first_gap = frame_ns("100#01")
            second, _ = frame_ns("300#03")
            assert ecu_a.frames() == [(0x300, "03", t0 + first_gap + second)]
            assert frames(ecu_b) == [(0x100, "01", t0 + first)]
            # 2. A step asked for on the owner waits for b's frame queued before it.
            t1 = t0 + 1_000_000
            ecu_b.send(can.Message(arbitration_id=0x050, is_extended_id=False, data=[5, 5]))
            assert step(a, 1_000_000) == t1 + 1_000_000
            third, _ = frame_ns("050#0505")
            assert ecu_a.frames() == [(0x050, "0505", t1 + third)]
            assert frames(ecu_b) == []
            # 3. The owner lists b's node as "b/DEVICE" with its statistics.
            remote = {k: v for k, v in nodes(a).items() if k.startswith("b/")}
            assert len(remote) == 1
            (name, entry), = remote.items()
            assert (entry["frames_sent"], entry["frames_received"]) == (2, 1)
            # 4. A fault on the owner naming b's node: its counters as the owner set them, seen
            # by the program on b (an error frame with the state and counters) and in b's status.
            device = name.split("/", 1)[1].removesuffix(":0")
            cli(a, "fault", "inject", "--effect", "error_counters", "--node", name.removesuffix(":0"),
                "--tec", "200", "--rec", "0")
            step(b, 1_000_000)
            errs = errors(ecu_b)
            assert errs, "b's program saw no state change"
            data = bytes.fromhex(errs[-1][1])
            assert data[1] & 0x20 and (data[6], data[7]) == (200, 0)  # TX passive, TEC 200
            local = nodes(b)
            mine = [v for k, v in local.items() if k.startswith(device)]
            assert [(n["tec"], n["rec"], n["state"]) for n in mine] == [(200, 0, "error-passive")]
        finally:
            ecu_a.close()
            ecu_b.shutdown()


def test_a_follower_with_self_reception_gets_back_every_frame_it_queued(env):
    # Several frames queued at once on b reach the owner together (the node's window); each one
    # sent comes back to b's program as its own, at its instant on the owner's bus.
    with owner_and_follower("stepped") as (a, b):
        t0 = attached_step(b)
        assert step(a, 1000) == t0 + 1000
        t0 += 1000
        ecu_a = Peer(a)  # acknowledges
        ecu_b = can.Bus(interface="canemu", channel="can0", socket=b.socket,
                        receive_own_messages=True)
        try:
            for ident in (0x101, 0x102, 0x103):
                ecu_b.send(can.Message(arbitration_id=ident, is_extended_id=False,
                                       data=[ident & 0xFF]))
            step(b, 1_000_000)
            at, expected = t0, []
            for ident in (0x101, 0x102, 0x103):
                text = f"{ident:03X}#{ident & 0xFF:02X}"
                duration, with_gap = frame_ns(text)
                expected.append((ident, f"{ident & 0xFF:02x}", at + duration))
                at += with_gap
            assert frames(ecu_b) == expected
            assert ecu_a.frames() == expected
        finally:
            ecu_a.close()
            ecu_b.shutdown()


def test_a_follower_bus_closing_normally_drops_nothing(env):
    # A python-can program on b opens can0, sends a frame and closes its bus as programs do:
    # nothing was lost, so neither daemon counts anything dropped (the owner counted one per
    # close, for a request of a node it had closed already).
    with owner_and_follower("stepped") as (a, b):
        attached_step(b)
        ecu_a = Peer(a)
        ecu_b = Peer(b)
        try:
            ecu_b.send(0x123, "01")
            step(b, 1_000_000)
            assert [(i, d) for i, d, _ in ecu_a.frames()] == [(0x123, "01")]
        finally:
            ecu_b.close()
        wait_until(lambda: not any(k.startswith("b/") for k in nodes(a)),
                   "b's node leaves a's can0")
        step(b, 1_000_000)  # anything still on its way has arrived after a step's round trip
        ecu_a.close()
        for daemon in (a, b):
            counters = json.loads(cli(daemon, "status", "--json"))["distributed"]["counters"]
            assert (counters["dropped"], counters["last_reason"]) == (0, ""), daemon.log


def test_a_daemon_using_two_owners_numbers_its_requests_to_each(env):
    # b uses a's can0 and c's can1 in real time, its requests to the two interleaved: each owner
    # sees its own numbers 1, 2, 3, ... from b, so neither counts a request lost on the way
    # (with one sequence for both, each would see the other's numbers as gaps).
    canemud = str(BUILD / "bin" / "canemud")
    partition = f"canemu-test-{os.getpid()}"
    link = "true" if env == "link" else "false"

    def daemon(name: str, buses: str) -> str:
        return (f'[simulation]\ntime = "realtime"\n\n[distributed]\nname = "{name}"\n'
                f'domain = {DOMAIN}\npartition = "{partition}"\nheartbeat_ms = 50\n'
                f"timeout_ms = 1000\nlocal_link = {link}\n\n{buses}")

    bus = '[[bus]]\nname = "{}"\nbitrate = 500000\n{}\n'
    with Daemon(daemon("a", bus.format("can0", "")), canemud=canemud) as a, \
            Daemon(daemon("c", bus.format("can1", "")), canemud=canemud) as c, \
            Daemon(daemon("b", bus.format("can0", 'owner = "a"') + bus.format("can1", 'owner = "c"')),
                   canemud=canemud) as b:
        b.wait_log("daemon a answers")
        b.wait_log("daemon c answers")
        ecus = [Peer(a), Peer(c, "can1")]  # they acknowledge
        try:
            # Each `canemu send` opens a node on its bus, sends, waits for the frame and closes
            # the node: requests to a and c alternate.
            for k in range(3):
                cli(b, "send", "can0", f"1{k:02X}#{k:02X}")
                cli(b, "send", "can1", f"2{k:02X}#{k:02X}")
            assert [(i, d) for i, d, _ in ecus[0].frames()] == [(0x100 + k, f"{k:02x}")
                                                               for k in range(3)]
        finally:
            for e in ecus:
                e.close()
        for owner in (a, c):
            counters = json.loads(cli(owner, "status", "--json"))["distributed"]["counters"]
            assert counters["requests_received"] >= 1 + 3 * 3, owner.log  # hello; open, frame, close
            assert counters["by_reason"]["lost"] == 0, owner.log


def test_late_counts_events_beyond_its_bound_only(env):
    # Real time on an idle link on one host: an event reaches the follower a little after its
    # instant (the link's delay beyond the fastest heartbeat's, tens of microseconds), which is
    # normal; `late` counts events placed more than 1 ms after it (it counted about 9 of 10
    # before). The largest delay seen is shown beside it.
    with owner_and_follower("realtime") as (a, b):
        ecu_b = Peer(b)
        ecu_a = Peer(a)
        try:
            wait_until(lambda: any(k.startswith("b/") for k in nodes(a)), "b's node on a's can0")
            got: list = []
            for i in range(20):
                ecu_a.send(0x100 + i, "01")
                wait_until(lambda: got.extend(ecu_b.frames()) or len(got) > i,
                           f"frame {i} reaches b")
            assert [ident for ident, _, _ in got] == [0x100 + i for i in range(20)]
        finally:
            ecu_a.close()
            ecu_b.close()
        counters = json.loads(cli(b, "status", "--json"))["distributed"]["counters"]
        assert counters["late_bound_ns"] == 1_000_000
        assert counters["events_received"] >= 20
        # 0 on an idle link; a loaded machine may delay events beyond 1 ms now and then, so the
        # count is held to the largest delay, which the daemon measures on the same events: some
        # counted exactly when that delay is beyond the bound.
        assert counters["late"] <= counters["events_received"], counters
        assert (counters["late"] > 0) == (counters["late_max_ns"] > counters["late_bound_ns"]), \
            counters
        assert 0 <= counters["late_max_ns"]


def test_a_follower_that_dies_leaves_the_bus_and_steps_go_on(env):
    with Daemon(config("a", "stepped"), canemud=str(BUILD / "bin" / "canemud")) as a:
        b = Daemon(config("b", "stepped", owner="a"), canemud=str(BUILD / "bin" / "canemud"))
        try:
            attached_step(b)
            ecu_b = can.Bus(interface="canemu", channel="can0", socket=b.socket)
            ecu_b.send(can.Message(arbitration_id=0x123, is_extended_id=False, data=[1]))
            step(b, 1_000_000)
            assert any(k.startswith("b/") for k in nodes(a))
            b.proc.kill()  # mid-stream, without a word to the owner
            b.proc.wait()
        finally:
            b.stop()
        if env == "link":
            # Its link closed with its process: the owner lets it go at once, and the next step
            # has nobody to wait for.
            a.wait_log("daemon b is gone: its same-host link closed (it closed without a bye")
            answer = cli(a, "time", "step", "1ms").splitlines()
            assert len(answer) == 1 and answer[0].startswith("simulated time ")
        else:
            # The owner's next step waits at the barrier for b at most timeout_ms (1 s), then
            # lets it go: its node leaves can0, and the step ends, its answer naming the follower
            # let go.
            started = time.monotonic()
            answer = cli(a, "time", "step", "1ms").splitlines()
            assert time.monotonic() - started < TIMEOUT
            assert answer[0].startswith("simulated time ")
            assert len(answer) == 2 and answer[1].startswith("let go during the step: daemon b (")
            a.wait_log("daemon b is gone")
        assert not any(k.startswith("b/") for k in nodes(a))


def test_realtime_owner_late_stopping_and_back(env):
    # Programs in processes of their own: starting a Daemon connects this process to it, and a
    # process talks to one canemud at a time.
    canemud = str(BUILD / "bin" / "canemud")
    b = Daemon(config("b", "realtime", owner="a"), canemud=canemud)
    ecu_b = Peer(b)
    a = None
    try:
        # The owner is not there yet: b's frame waits in its transmit queue, nothing is lost.
        ecu_b.send(0x222, "02")
        a = Daemon(config("a", "realtime"), canemud=canemud)
        ecu_a = Peer(a)
        # It goes out once a is there (unacknowledged until a's program's controller joins,
        # which may be before that program reads: so it is counted on the owner's nodes).

        def sent_by_b() -> list:
            return [n["frames_sent"] for k, n in nodes(a).items() if k.startswith("b/")]

        wait_until(lambda: sent_by_b() == [1], "b's waiting frame goes out on a's can0")
        ecu_a.send(0x111, "01")
        assert ecu_b.frames_arriving("a's frame reaches b") == [(0x111, "01")]
        ecu_a.close()
        # The owner stops (it says so as it goes): b's node is off the bus, and its program
        # hears bus-off (CAN_ERR_BUSOFF).
        a.stop()
        errs = []
        wait_until(lambda: errs.extend(ecu_b.errors()) or any(e & 0x40 for e, _ in errs),
                   "bus-off on b")
        b.wait_log("daemon a is gone")
        # The owner back (another boot): b's node is opened there again, back to error-active,
        # and frames flow.
        a = Daemon(config("a", "realtime"), canemud=canemud)
        ecu_a = Peer(a)
        wait_until(lambda: errs.extend(ecu_b.errors()) or any(
            bytes.fromhex(d)[1] & 0x40 for _, d in errs[-1:]), "error-active again on b")
        ecu_b.send(0x333, "03")
        assert ecu_a.frames_arriving("b's frame reaches the new a") == [(0x333, "03")]
        ecu_a.close()
        ecu_b.close()
    finally:
        b.stop()
        if a is not None:
            a.stop()


def test_a_step_asked_of_a_follower_whose_owner_dies_is_answered(env):
    canemud = str(BUILD / "bin" / "canemud")
    with Daemon(config("b", "stepped", owner="a"), canemud=canemud) as b:
        a = Daemon(config("a", "stepped"), canemud=canemud)
        try:
            attached_step(b)
            a.proc.kill()  # without a word
            a.proc.wait()
        finally:
            a.stop()
        if env == "link":
            # Its link closed with its process: b lets it go at once and refuses the step.
            b.wait_log("daemon a is gone: its same-host link closed (it closed without a bye")
            done = subprocess.run([str(CANEMU_CLI), "--socket", b.socket, "time", "step", "1ms"],
                                  capture_output=True, text=True, timeout=TIMEOUT)
            assert done.returncode != 0
            assert "steps are daemon a's, which is not attached (daemon a is gone)" in done.stderr
            return
        # b asks the owner, which never answers; once a is let go (timeout_ms) the step is
        # answered with the reason instead of waiting for ever.
        started = time.monotonic()
        done = subprocess.run([str(CANEMU_CLI), "--socket", b.socket, "time", "step", "1ms"],
                              capture_output=True, text=True, timeout=TIMEOUT)
        assert done.returncode != 0
        assert "daemon a, whose steps these are, is gone (not heard from for" in done.stderr
        assert time.monotonic() - started < TIMEOUT


def same_host_address(name: str) -> str:
    """Daemon `name`'s same-host address, from the kernel's list of Unix sockets."""
    for line in open("/proc/net/unix"):
        path = line.split()[-1]
        if path.startswith(f"@canemu-net/{name}/"):
            return "\0" + path[1:]
    raise AssertionError(f"no same-host address of daemon {name}")


def test_a_same_host_link_speaking_nonsense_is_closed_counted_and_nothing_else_changes(link_env):
    import socket
    with owner_and_follower("stepped") as (a, b):
        attached_step(b)
        address = same_host_address("a")
        # A message's head: type, 3 bytes, count, the time written, `to` and a sequence number
        # (56 bytes); a hello (type 1) is 104 bytes after it, beginning with its magic.
        def head(kind: int) -> bytes:
            return bytes([kind, 0, 0, 0]) + (1).to_bytes(4, "little") + bytes(8 + 32 + 8)

        def connect() -> socket.socket:
            s = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
            s.settimeout(TIMEOUT)
            s.connect(address)
            return s

        def counters() -> dict:
            return json.loads(cli(a, "status", "--json"))["distributed"]["counters"]

        for k, (junk, why) in enumerate([
                (b"abc", "a message of 3 bytes"),
                (head(2), "no hello first"),
                (head(1) + b"notcanem" + bytes(96), "no canemu daemon's hello"),
                (bytes(70000), "a message of 70000 bytes, more than any")], start=1):
            s = connect()
            s.send(junk)
            assert s.recv(100) == b""  # closed by a
            s.close()
            c = counters()
            assert c["by_reason"]["malformed"] == k
            assert c["last_reason"] == ("same-host link with a daemon not identified yet closed: "
                                        + why)
        # Connections that say nothing: 16 may wait for their hello at once, a 17th is refused at
        # once, and each of the 16 is closed once timeout_ms (1 s) has passed without one.
        silent = [connect() for _ in range(16)]
        extra = connect()
        assert extra.recv(100) == b""
        extra.close()
        c = counters()
        assert c["by_reason"]["not_accepted"] == 1
        assert c["last_reason"] == ("refused a same-host link: 16 connections have not said hello "
                                    "yet")
        for s in silent:
            assert s.recv(100) == b""
            s.close()
        wait_until(lambda: counters()["by_reason"]["malformed"] == 4 + 16, "16 links timed out")
        assert counters()["last_reason"] == ("same-host link with a daemon not identified yet "
                                             "closed: no hello within 1000 ms")
        # b's own link is untouched: its frames still reach a's bus, step by step.
        ecu_a = Peer(a)
        ecu_b = can.Bus(interface="canemu", channel="can0", socket=b.socket)
        try:
            ecu_b.send(can.Message(arbitration_id=0x321, is_extended_id=False, data=[1]))
            step(b, 1_000_000)
            assert [(i, d) for i, d, _ in ecu_a.frames()] == [(0x321, "01")]
            assert via(a, "b") == "link"
        finally:
            ecu_a.close()
            ecu_b.shutdown()


def test_a_follower_whose_owner_has_no_same_host_link_speaks_dds(link_env):
    # The owner's local_link is off: the follower finds no address to connect to and says its
    # hello over DDS, and everything goes on as between hosts.
    canemud = str(BUILD / "bin" / "canemud")
    owner = support_config("a", "stepped", None, domain=DOMAIN,
                           partition=f"canemu-test-{os.getpid()}", local_link=False)
    with Daemon(owner, canemud=canemud) as a, \
            Daemon(config("b", "stepped", owner="a"), canemud=canemud) as b:
        attached_step(b)
        ecu_a = Peer(a)
        ecu_b = can.Bus(interface="canemu", channel="can0", socket=b.socket)
        try:
            ecu_b.send(can.Message(arbitration_id=0x42, is_extended_id=False, data=[4, 2]))
            step(b, 1_000_000)
            assert [(i, d) for i, d, _ in ecu_a.frames()] == [(0x42, "0402")]
        finally:
            ecu_a.close()
            ecu_b.shutdown()
        assert via(b, "a") == "dds"
        wait_until(lambda: via(a, "b") == "dds", "a's status lists b")
        assert "same-host link" not in b.log


def test_a_follower_that_stops_reading_has_its_link_closed_and_comes_back_over_dds(link_env):
    # The owner's bus at full load (eight messages every 1 ms of a simulated node, about twice what
    # 500 kbit/s carries) and b's program a node on it: the owner writes b's events over the link
    # for every frame. b stopped (SIGSTOP) reads nothing: the socket fills, then the owner's queue
    # of 4096 messages, and the owner closes the link and lets b go, long before timeout_ms (60 s)
    # would. Once b runs again it reads what was left, finds the link closed, lets a go in its
    # turn, says hello over DDS and its program's node is back on the bus.
    import signal
    canemud = str(BUILD / "bin" / "canemud")
    messages = "".join(f"""
[[can_node.message]]
name = "M{k}"
id = {0x100 + k}
cycle = "1ms"
""" for k in range(8))

    def conf(name: str, owner: str | None) -> str:
        return support_config(name, "realtime", owner, domain=DOMAIN,
                              partition=f"canemu-test-{os.getpid()}", timeout_ms=60000)

    with Daemon(conf("a", None) + '\n[[can_node]]\nname = "LOAD"\nbus = "can0"\n' + messages,
                canemud=canemud) as a, Daemon(conf("b", "a"), canemud=canemud) as b:
        ecu_b = Peer(b)
        try:
            assert ecu_b.frames_arriving("the load's frames reach b")
            assert via(a, "b") == "link"
            b.proc.send_signal(signal.SIGSTOP)
            try:
                a.wait_log("same-host link with b closed: daemon b did not read 4096 messages",
                           timeout=60)
                a.wait_log("daemon b is gone: its same-host link closed (daemon b did not read "
                           "4096 messages)")
                assert not any(k.startswith("b/") for k in nodes(a))
            finally:
                b.proc.send_signal(signal.SIGCONT)
            b.wait_log("daemon a is gone: its same-host link closed (it closed without a bye)")
            wait_until(lambda: any(k.startswith("b/") for k in nodes(a)), "b's node back on a")
            assert via(b, "a") == "dds"
            wait_until(lambda: via(a, "b") == "dds", "a lists b over DDS")
            ecu_b.frames()  # what came before
            assert ecu_b.frames_arriving("the load's frames reach b over DDS")
        finally:
            ecu_b.close()
        counters = json.loads(cli(a, "status", "--json"))["distributed"]["counters"]
        assert counters["by_reason"]["malformed"] == 0


def test_out_of_descriptors_the_owner_leaves_connections_queued_and_takes_them_later(link_env):
    # a's limit on open files lowered to what it has open: a connection to its same-host address
    # is queued by the kernel, and a cannot take it (EMFILE). It must not spin on it: it looks again
    # at every heartbeat (50 ms). Its limit back, it takes the connections, which say no hello and
    # are closed after timeout_ms (1 s) as any such.
    import itertools
    import resource
    import socket
    with owner_and_follower("stepped") as (a, b):
        attached_step(b)
        address = same_host_address("a")
        pid = a.proc.pid

        def cpu_seconds() -> float:
            fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
            return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

        limit = resource.prlimit(pid, resource.RLIMIT_NOFILE)
        open_fds = {int(f) for f in os.listdir(f"/proc/{pid}/fd")}
        lowest_free = next(k for k in itertools.count() if k not in open_fds)
        resource.prlimit(pid, resource.RLIMIT_NOFILE, (lowest_free, limit[1]))
        queued = []
        try:
            for _ in range(3):
                s = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
                s.settimeout(TIMEOUT)
                s.connect(address)
                queued.append(s)
            a.wait_log("distributed: a same-host connection not taken: Too many open files; "
                       "tried again at every heartbeat")
            # A window of 1 s in which a would spin if it looked at the queued connections at
            # every turn (a whole core); it looks 20 times. A busy machine only lowers the figure.
            before = cpu_seconds()
            time.sleep(1.0)
            assert cpu_seconds() - before < 0.5
        finally:
            resource.prlimit(pid, resource.RLIMIT_NOFILE, limit)
        a.wait_log("distributed: same-host connections are taken again")
        for s in queued:
            assert s.recv(100) == b""  # no hello within timeout_ms
            s.close()
        assert a.log.count("a same-host connection not taken") == 1
        counters = json.loads(cli(a, "status", "--json"))["distributed"]["counters"]
        assert counters["by_reason"]["malformed"] == 3
        assert counters["last_reason"] == ("same-host link with a daemon not identified yet "
                                           "closed: no hello within 1000 ms")
        assert via(a, "b") == "link"


def test_in_real_time_a_followers_frame_starts_when_its_program_queued_it(link_env):
    # b's program queues a frame while the owner a is stopped (SIGSTOP): b makes the request at
    # once and the link carries the instant it made it, so a, running again, starts the frame
    # there, as one daemon would have (docs/distributed.md, "Daemons on one host"). The same
    # frame three times: their ends of frame on a's bus, apart as their queueing was apart. a
    # stopped 2 ms: the second frame no later than that; stopped 30 ms: more than 10 ms old, the
    # request is applied when a runs again.
    import signal
    with owner_and_follower("realtime") as (a, b):
        ecu_a = Peer(a)
        ecu_b = can.Bus(interface="canemu", channel="can0", socket=b.socket)
        try:
            wait_until(lambda: any(k.startswith("b/") for k in nodes(a)), "b's node on a")

            def stopped() -> bool:
                stat = open(f"/proc/{a.proc.pid}/stat").read()
                return stat.rsplit(")", 1)[1].split()[0] == "T"

            def queued_and_ended(pause_s: float) -> tuple[int, int]:
                if pause_s:
                    a.proc.send_signal(signal.SIGSTOP)
                    wait_until(stopped, "a stopped")
                before = time.monotonic_ns()
                ecu_b.send(can.Message(arbitration_id=0x2A0, is_extended_id=False, data=[7, 7]))
                queued = (before + time.monotonic_ns()) // 2
                if pause_s:
                    time.sleep(pause_s)  # a kept stopped this long
                    a.proc.send_signal(signal.SIGCONT)
                (_, _, end), = ecu_a.frames_arriving_with_times("b's frame on a")
                return queued, end

            q1, e1 = queued_and_ended(0)
            q2, e2 = queued_and_ended(0.002)
            assert (e2 - e1) - (q2 - q1) < 1_500_000
            q3, e3 = queued_and_ended(0.030)
            assert (e3 - e2) - (q3 - q2) > 20_000_000
        finally:
            ecu_a.close()
            ecu_b.shutdown()
