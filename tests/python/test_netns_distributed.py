"""A bus across hosts (docs/distributed.md): three hosts a, b and c, each a network namespace with
its own link and address (netns.Hosts), a canemud in each with Cyclone DDS on that link (unicast
peers; the realtime test by SPDP multicast on the link). Daemon a simulates can0; b and c declare
can0 with owner "a". python-can programs (distributed_peer.py, a process of their own inside each
host, talking to that host's canemud) exchange frames over a's bus. In stepped time, every time
stamp exact: arbitration across hosts, the follower's status, a fault scenario loaded on the
owner taking b's node bus-off (and python-can's recovery), c's daemon killed with SIGKILL in the
middle of a stream (the owner's barrier lets it go after timeout_ms; a and b go on), b cut off
from the hub and back. In realtime: 100 frames each way between b and c, then a partition that
heals. Needs root (netns.netns_available); reported as skipped with the reason otherwise."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from conftest import CANEMUD
from distributed_support import attached_step, cli, frame_ns, nodes, step, wait_until
from distributed_support import config as support_config
from netns import HostProgram, Hosts, netns_available

from canemu.bus import CAN_ERR_BUSOFF, CAN_ERR_CNT, CAN_ERR_CRTL, CAN_ERR_RESTARTED

US = 1_000
MS = 1_000_000
BIT = 2_000  # at 500 kbit/s
TIMEOUT = 20.0
DOMAIN = 1 + (os.getpid() + 103) % 200
PEER = Path(__file__).with_name("distributed_peer.py")
HEARTBEAT_MS = 50
GONE_MS = 1000  # [distributed] timeout_ms


def config(name: str, time_mode: str, owner: str | None = None) -> str:
    return support_config(name, time_mode, owner, domain=DOMAIN,
                          partition=f"canemu-netns-{os.getpid()}", heartbeat_ms=HEARTBEAT_MS,
                          timeout_ms=GONE_MS)


def remote_nodes(daemon) -> dict:
    """The owner's nodes of other daemons ("DAEMON/DEVICE:N"): name -> (sent, received)."""
    return {k: (v["frames_sent"], v["frames_received"]) for k, v in nodes(daemon).items()
            if "/" in k}


def state(node: dict) -> tuple:
    return node["state"], node["tec"], node["rec"]


def collect(fetch, count: int, what: str) -> list:
    """What `fetch` (a peer's frames or errors, each call the new ones) gives until `count` came.
    A step asked of the owner is answered once the owner ran it: a follower runs it to its end
    when the owner's message of it arrives, so its programs get the step's events a little later."""
    got: list = []

    def enough() -> bool:
        got.extend(fetch())
        return len(got) >= count

    wait_until(enough, what)
    return got


class Peer(HostProgram):
    """distributed_peer.py inside `host`, on that host's canemud; its answers read by a thread of
    its own, so every wait has a deadline."""

    def __init__(self, hosts: Hosts, host: str, daemon) -> None:
        super().__init__(hosts, host, [sys.executable, str(PEER), daemon.socket], stdin=True)
        assert self.line(TIMEOUT).strip() == "ready"
        self.name = self.ask("name")

    def ask(self, line: str) -> str:
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        return self.line(TIMEOUT).strip()

    def send(self, ident: int, data: str) -> None:
        assert self.ask(f"send {ident:x} {data}") == "sent"

    def frames(self) -> list:
        return [tuple(f) for f in json.loads(self.ask("recv"))]

    def errors(self) -> list:
        return [tuple(f) for f in json.loads(self.ask("errors"))]


@pytest.fixture()
def hosts():
    available, why = netns_available()
    if not available:
        pytest.skip(why)
    with Hosts(("a", "b", "c")) as h:
        yield h


def stepped(hosts: Hosts):
    """canemud in a (owner of can0), b and c (can0 owned by a), stepped time; returns the daemons
    once b's and c's steps reach a, and the simulated time then (a multiple of 1 us)."""
    a = hosts.daemon("a", config("a", "stepped"), canemud=str(CANEMUD))
    b = hosts.daemon("b", config("b", "stepped", owner="a"), canemud=str(CANEMUD))
    c = hosts.daemon("c", config("c", "stepped", owner="a"), canemud=str(CANEMUD))
    attached_step(b)
    t0 = attached_step(c)
    assert t0 == 2 * US  # one clock, the owner's: each follower's step was one of a
    return a, b, c, t0


def test_arbitration_across_hosts(hosts):
    started = time.monotonic()
    a, b, c, t0 = stepped(hosts)
    pa, pb, pc = Peer(hosts, "a", a), Peer(hosts, "b", b), Peer(hosts, "c", c)
    # Three hosts queue a frame each before one step asked on c: a's bus arbitrates 0x100, then
    # c's 0x200, then b's 0x300, back to back, exact to the nanosecond on every host.
    pb.send(0x300, "03")
    pc.send(0x200, "02")
    pa.send(0x100, "01")
    assert step(c, MS) == t0 + MS
    d1, g1 = frame_ns("100#01")
    d2, g2 = frame_ns("200#02")
    d3, _ = frame_ns("300#03")
    f1, f2, f3 = ((0x100, "01", t0 + d1), (0x200, "02", t0 + g1 + d2),
                  (0x300, "03", t0 + g1 + g2 + d3))
    assert pa.frames() == [f2, f3]
    assert pb.frames() == [f1, f2]
    assert pc.frames() == [f1, f3]
    # The owner lists the remote nodes as "DAEMON/DEVICE:N" with the owner's statistics.
    assert remote_nodes(a) == {f"b/{pb.name}": (1, 2), f"c/{pc.name}": (1, 2)}
    assert (nodes(a)[pa.name]["frames_sent"], nodes(a)[pa.name]["frames_received"]) == (1, 2)
    # A second step asked on the owner: b answers c, exact again.
    pc.send(0x010, "1010")
    pb.send(0x011, "1111")
    assert step(a, MS) == t0 + 2 * MS
    d4, g4 = frame_ns("010#1010")
    d5, _ = frame_ns("011#1111")
    f4, f5 = (0x010, "1010", t0 + MS + d4), (0x011, "1111", t0 + MS + g4 + d5)
    assert pa.frames() == [f4, f5]
    assert collect(pb.frames, 1, "b's program gets c's frame") == [f4]
    assert collect(pc.frames, 1, "c's program gets b's frame") == [f5]
    assert remote_nodes(a) == {f"b/{pb.name}": (2, 3), f"c/{pc.name}": (2, 3)}
    assert (pa.errors(), pb.errors(), pc.errors()) == ([], [], [])
    print(f"\nhosts made in {hosts.setup_seconds:.2f} s; the test "
          f"{time.monotonic() - started:.2f} s")


def test_a_followers_status_counts_the_frames_of_its_nodes(hosts):
    """`canemu status` on b shows its node on a's bus with the frames it sent and received, as
    the owner counts them (and as a node of a local bus would be shown)."""
    a, b, c, t0 = stepped(hosts)
    pa, pb = Peer(hosts, "a", a), Peer(hosts, "b", b)
    pb.send(0x300, "03")
    pa.send(0x100, "01")
    assert step(b, MS) == t0 + MS
    assert (len(pa.frames()), len(pb.frames())) == (1, 1)
    assert remote_nodes(a) == {f"b/{pb.name}": (1, 1)}
    mine = nodes(b)[pb.name]
    assert (mine["frames_sent"], mine["frames_received"]) == (1, 1)
    # Each host is a network namespace of its own, where the owner's same-host address (in the
    # abstract namespace) cannot be reached: b speaks to a over DDS, local_link on as it is.
    peers = json.loads(cli(b, "status", "--json"))["distributed"]["peers"]
    assert [p["via"] for p in peers if p["name"] == "a"] == ["dds"]


def test_a_fault_scenario_on_the_owner_hits_a_remote_node(hosts):
    a, b, c, t0 = stepped(hosts)
    pa, pb, pc = Peer(hosts, "a", a), Peer(hosts, "b", b), Peer(hosts, "c", c)
    remote = f"b/{pb.name}"
    pb.send(0x300, "03")
    assert step(b, MS) == t0 + MS
    assert remote_nodes(a)[remote] == (1, 0)
    f1 = (0x300, "03", t0 + frame_ns("300#03")[0])
    assert (pa.frames(), pc.frames()) == ([f1], [f1])
    # The scenario, a file on the owner's side, takes b's node off the bus 200 us into the
    # next step; c's frame at the step's start is on the wire before it.
    with tempfile.NamedTemporaryFile("w", suffix=".toml") as f:
        f.write(f'[scenario]\nname = "remote bus-off"\n\n[[fault]]\nat = "200us"\n'
                f'node = "{remote}"\neffect = "bus_off"\n')
        f.flush()
        cli(a, "fault", "load", f.name)
    t1 = t0 + MS
    pc.send(0x200, "02")
    assert step(c, MS) == t1 + MS
    f2 = (0x200, "02", t1 + frame_ns("200#02")[0])
    assert pa.frames() == [f2] and pb.frames() == [f2]
    # b's program hears bus-off (python-can: an error frame with CAN_ERR_BUSOFF and the counters,
    # TEC shown as 255) at the fault's instant; b's status and the owner's show the node's state.
    busoff = t1 + 200 * US
    assert pb.errors() == [(CAN_ERR_BUSOFF | CAN_ERR_CNT, "000000000000ff00", busoff)]
    assert state(nodes(b)[pb.name]) == ("bus-off", 256, 0)
    assert state(nodes(a)[remote]) == ("bus-off", 256, 0)
    assert [(f["scenario"], f["effect"], f["target"], f["state"])
            for f in json.loads(cli(a, "status", "--json"))["faults"]] == [
        ("remote bus-off", "bus_off", remote, "done")]
    # c is unaffected: no error, error-active, counters 0.
    assert pc.errors() == []
    assert state(nodes(c)[pc.name]) == ("error-active", 0, 0)
    # python-can restarts the controller when it hears bus-off (at the step's end); the owner
    # then counts 128 x 11 recessive bits before b's node is error-active again, and b talks.
    t2 = t1 + MS
    assert step(a, 5 * MS) == t2 + 5 * MS
    assert collect(pb.errors, 1, "b's program hears the restart") == [
        (CAN_ERR_RESTARTED | CAN_ERR_CRTL, "0040000000000000", t2 + 128 * 11 * BIT)]
    assert state(nodes(b)[pb.name]) == state(nodes(a)[remote]) == ("error-active", 0, 0)
    t3 = t2 + 5 * MS
    pb.send(0x301, "01")
    assert step(c, MS) == t3 + MS
    f4 = (0x301, "01", t3 + frame_ns("301#01")[0])
    assert (pa.frames(), pc.frames()) == ([f4], [f4])
    assert remote_nodes(a) == {remote: (2, 1), f"c/{pc.name}": (1, 2)}


def test_killing_a_remote_daemon_mid_stream(hosts):
    a, b, c, t0 = stepped(hosts)
    pa, pb, pc = Peer(hosts, "a", a), Peer(hosts, "b", b), Peer(hosts, "c", c)
    # c's program streams 50 frames, one a step, the steps asked on b; c's daemon is killed
    # after the 25th step.
    expected = []
    t = t0
    for i in range(25):
        pc.send(0x200, f"{i:02x}")
        assert step(b, MS) == t + MS
        expected.append((0x200, f"{i:02x}", t + frame_ns(f"200#{i:02x}")[0]))
        t += MS
    assert (pa.frames(), pb.frames()) == (expected, expected)
    assert remote_nodes(a) == {f"b/{pb.name}": (0, 25), f"c/{pc.name}": (25, 0)}
    c.proc.kill()  # without a word to the owner
    c.proc.wait(TIMEOUT)
    killed = time.monotonic()
    # The stream goes on (c's program may or may not notice: nothing of it arrives anywhere),
    # and so do a and b. The first step after the kill, asked on the owner, waits at the barrier
    # for c at most timeout_ms, then lets it go: c's node leaves can0, and the step ends.
    for i in range(25, 50):
        answer = pc.ask(f"send 200 {i:02x}")
        assert answer == "sent" or answer.startswith("error:"), answer
        pb.send(0x300, f"{i:02x}")
        pa.send(0x100, f"{i:02x}")
        assert step(a if i == 25 else b, MS) == t + MS
        if i == 25:
            waited = time.monotonic() - killed
            assert waited < 3 * GONE_MS / 1000, waited
            a.wait_log("daemon c is gone")
            assert remote_nodes(a) == {f"b/{pb.name}": (1, 26)}  # c's 25, a's 1
        da, ga = frame_ns(f"100#{i:02x}")
        db, _ = frame_ns(f"300#{i:02x}")
        assert pa.frames() == [(0x300, f"{i:02x}", t + ga + db)]
        assert pb.frames() == [(0x100, f"{i:02x}", t + da)]
        t += MS
    assert remote_nodes(a) == {f"b/{pb.name}": (25, 50)}
    assert (pa.errors(), pb.errors()) == ([], [])
    print(f"\nthe step after the kill waited {waited:.2f} s for c")


@pytest.fixture()
def multicast_hosts():
    available, why = netns_available()
    if not available:
        pytest.skip(why)
    with Hosts(("a", "b", "c"), multicast=True) as h:
        yield h


def test_realtime_across_hosts_and_a_partition(multicast_hosts):
    hosts = multicast_hosts
    a = hosts.daemon("a", config("a", "realtime"), canemud=str(CANEMUD))
    b = hosts.daemon("b", config("b", "realtime", owner="a"), canemud=str(CANEMUD))
    c = hosts.daemon("c", config("c", "realtime", owner="a"), canemud=str(CANEMUD))
    b.wait_log("daemon a answers")
    c.wait_log("daemon a answers")
    pa, pb, pc = Peer(hosts, "a", a), Peer(hosts, "b", b), Peer(hosts, "c", c)
    # b and c each send 100 frames at once; everyone gets all of them, each sender's in order.
    assert pb.ask("burst 100 300") == "sent"
    assert pc.ask("burst 100 200") == "sent"
    got = {"a": [], "b": [], "c": []}

    def all_arrived() -> bool:
        for name, peer in (("a", pa), ("b", pb), ("c", pc)):
            got[name].extend(peer.frames())
        return len(got["a"]) >= 200 and len(got["b"]) >= 100 and len(got["c"]) >= 100

    wait_until(all_arrived, "200 frames across hosts")
    counting = [f"{i:04x}" for i in range(100)]
    assert [d for i, d, _ in got["b"] if i == 0x200] == counting and len(got["b"]) == 100
    assert [d for i, d, _ in got["c"] if i == 0x300] == counting and len(got["c"]) == 100
    assert [d for i, d, _ in got["a"] if i == 0x200] == counting
    assert [d for i, d, _ in got["a"] if i == 0x300] == counting and len(got["a"]) == 200
    for frames in got.values():
        stamps = [ts for _, _, ts in frames]
        assert stamps == sorted(stamps)
    assert remote_nodes(a) == {f"b/{pb.name}": (100, 100), f"c/{pc.name}": (100, 100)}
    # A partition: b's link leaves the hub. After timeout_ms the owner lets b go (its node
    # leaves can0) and b hears bus-off from its node, whose owner is gone.
    mark_a, mark_b = len(a.log), len(b.log)
    hosts.disconnect("b")
    a.wait_log("daemon b is gone", start=mark_a, timeout=TIMEOUT)
    b.wait_log("daemon a is gone", start=mark_b, timeout=TIMEOUT)
    assert remote_nodes(a) == {f"c/{pc.name}": (100, 100)}
    errs: list = []
    wait_until(lambda: errs.extend(pb.errors()) or any(e[0] & 0x40 for e in errs),
               "bus-off on b's program")
    # c and a go on.
    pc.send(0x201, "01")
    back: list = []
    wait_until(lambda: back.extend(pa.frames()) or back, "c's frame reaches a")
    assert [(i, d) for i, d, _ in back] == [(0x201, "01")]
    # The partition heals: b answers again, its node is opened on a's bus as it was, and b's
    # program talks to c again.
    mark_a, mark_b = len(a.log), len(b.log)
    hosts.connect("b")
    b.wait_log("daemon a answers", start=mark_b, timeout=TIMEOUT)
    wait_until(lambda: f"b/{pb.name}" in remote_nodes(a), "b's node back on a's bus")
    pb.send(0x301, "01")
    again: list = []
    wait_until(lambda: again.extend(pc.frames()) or again, "b's frame reaches c after healing")
    assert [(i, d) for i, d, _ in again] == [(0x301, "01")]


def test_a_partition_in_stepped_time(hosts):
    a, b, c, t0 = stepped(hosts)
    pa, pb = Peer(hosts, "a", a), Peer(hosts, "b", b)
    # b's link leaves the hub. The owner's next step waits at the barrier for b at most
    # timeout_ms, then lets it go; a's frame of that step finds nobody to acknowledge it.
    hosts.disconnect("b")
    mark_b = len(b.log)
    pa.send(0x100, "01")
    assert step(a, MS) == t0 + MS
    a.wait_log("daemon b is gone")
    assert remote_nodes(a) == {}
    # Each attempt ends in an ACK error (+8): 8 of them in the step, as an attempt lasts 64 bit
    # times (128 us; the frame up to its ACK slot, error flag, delimiter and intermission).
    mine = nodes(a)[pa.name]
    assert (mine["tec"], mine["state"], mine["frames_sent"]) == (64, "error-active", 0)
    # b, cut off, lost its owner: its steps are refused, and its program heard bus-off at b's
    # last instant.
    b.wait_log("daemon a is gone", start=mark_b)
    with pytest.raises(AssertionError, match="steps are daemon a's, which is not attached"):
        step(b, MS)
    assert pb.frames() == []
    assert [(e[0] & CAN_ERR_BUSOFF, e[2]) for e in pb.errors()] == [(CAN_ERR_BUSOFF, t0)]
    # The partition heals: b follows a's clock again, its node is back on a's bus (fresh
    # statistics), and its program hears it restarted (error-active) at that instant.
    hosts.connect("b")
    t1 = t0 + MS
    assert attached_step(b) == t1 + US
    assert remote_nodes(a) == {f"b/{pb.name}": (0, 0)}
    restarted = pb.errors()
    assert [(e[0] & CAN_ERR_RESTARTED, e[2]) for e in restarted] == [(CAN_ERR_RESTARTED, t1)]
    # a's frame, repeated every 128 us since t0, is acknowledged by b at its first repetition
    # that starts after b's node came back (the ninth, at t0 + 1024 us); b's 0x300, queued now,
    # follows it after the intermission.
    pb.send(0x300, "03")
    assert step(b, MS) == t1 + US + MS
    d1, g1 = frame_ns("100#01")
    d3, _ = frame_ns("300#03")
    attempt = d1 - 8 * BIT + (6 + 8 + 3) * BIT  # up to the ACK slot; flag, delimiter, pause
    assert attempt == 128 * US
    f1 = (0x100, "01", t0 + 8 * attempt + d1)
    assert pb.frames() == [f1]
    assert pa.frames() == [(0x300, "03", f1[2] + (g1 - d1) + d3)]
    assert remote_nodes(a) == {f"b/{pb.name}": (1, 1)}
    mine = nodes(a)[pa.name]
    assert (mine["tec"], mine["state"], mine["frames_sent"]) == (63, "error-active", 1)
