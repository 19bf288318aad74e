"""netns.Hosts, the harness for tests across hosts: namespaces and links made, reachability and
partitions, Cyclone DDS's configuration, processes and canemud inside a host, and nothing left
behind, also after a failure or a killed run. Needs root (reported as skipped otherwise)."""

from __future__ import annotations

import os
import subprocess

import pytest

import canemu
import netns
from conftest import CANEMU_CLI, CANEMUD
from netns import Hosts, netns_available


@pytest.fixture(autouse=True)
def need_netns():
    available, why = netns_available()
    if not available:
        pytest.skip(why)


def namespaces() -> set:
    out = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True, check=True)
    return {line.split()[0] for line in out.stdout.splitlines() if line.split()}


def alive(pid: int) -> bool:
    """Running (not ended, not a zombie waiting to be reaped)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def test_hosts_linked_configured_and_removed():
    with Hosts(("a", "b", "c")) as h:
        ours = {h.hub, *h.namespace.values()}
        assert ours <= namespaces()
        assert h.run_id.startswith(f"canemu-{os.getpid()}-")
        assert h.namespace["b"] == f"{h.run_id}-b"
        links = h.run("b", ["ip", "-br", "-4", "addr"], capture_output=True, text=True).stdout
        # eth0@ifN: N is the index of its other end, in the hub's namespace.
        assert [(f[0].split("@")[0], f[1], f[2]) for f in map(str.split, links.splitlines())] == [
            ("lo", "UNKNOWN", "127.0.0.1/8"), ("eth0", "UP", "10.77.0.2/24")]
        assert h.cyclone_uri("a") == (
            '<CycloneDDS><Domain Id="any"><General><Interfaces><NetworkInterface name="eth0"/>'
            "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
            "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20"
            '</MaxAutoParticipantIndex><Peers><Peer address="10.77.0.1"/>'
            '<Peer address="10.77.0.2"/><Peer address="10.77.0.3"/></Peers></Discovery>'
            "</Domain></CycloneDDS>")
        assert h.cyclone_uri("c", multicast=True) == (
            '<CycloneDDS><Domain Id="any"><General><Interfaces><NetworkInterface name="eth0"/>'
            "</Interfaces><AllowMulticast>true</AllowMulticast></General></Domain></CycloneDDS>")
        env = h.run("c", ["sh", "-c", 'echo "$CYCLONEDDS_URI|$EXTRA"'], env={"EXTRA": "x"},
                    capture_output=True, text=True).stdout
        assert env == h.cyclone_uri("c") + "|x\n"
        # A partition: c off the hub reaches no one, and back on it, everyone again.
        h.disconnect("c")
        assert h.probe([("c", "a"), ("a", "c"), ("b", "c"), ("a", "b")], 0.3) == {("a", "b")}
        h.check()  # the hosts still on the hub
        h.connect("c")
        h.check()
        # Processes inside, with a child of their own: all gone at the end.
        shell = h.popen("a", ["sh", "-c", "sleep 600 & wait"])
        h.popen("b", ["sleep", "600"])
        h.run("a", ["true"])
        inside = subprocess.run(["ip", "netns", "pids", h.namespace["a"]], capture_output=True,
                                text=True, check=True).stdout.split()
        assert str(shell.pid) in inside
    assert not ours & namespaces()
    assert not any(alive(int(pid)) for pid in inside)


def test_nothing_left_after_a_failure():
    with pytest.raises(ZeroDivisionError):
        with Hosts(("x",)) as h:
            ours = {h.hub, *h.namespace.values()}
            h.popen("x", ["sleep", "600"])
            1 / 0
    assert not ours & namespaces()


def test_namespaces_of_a_killed_run_removed():
    gone = subprocess.Popen(["true"])
    gone.wait()
    stale = f"canemu-{gone.pid}-0-a"
    subprocess.run(["ip", "netns", "add", stale], check=True)
    try:
        with Hosts(("a",)):
            assert stale not in namespaces()
    finally:
        subprocess.run(["ip", "netns", "del", stale], capture_output=True)


def test_canemud_inside_a_host():
    with Hosts(("a", "b")) as h:
        daemon = h.daemon("a", '[simulation]\ntime = "stepped"\n', canemud=str(CANEMUD))
        where = subprocess.run(["ip", "netns", "identify", str(daemon.proc.pid)],
                               capture_output=True, text=True, check=True).stdout.strip()
        assert where == h.namespace["a"]
        # Its AF_UNIX socket is a path: a client in another host reaches it.
        status = h.run("b", [str(CANEMU_CLI), "--socket", daemon.socket, "time", "step", "1ms"],
                       capture_output=True, text=True)
        assert status.returncode == 0, status.stderr
        assert canemu.sim_time()[0] == 1_000_000
    assert daemon.proc.returncode == 0


def test_without_root_a_reason(monkeypatch):
    monkeypatch.setattr(netns.os, "geteuid", lambda: 1000)
    assert netns_available() == (
        False, "network namespaces and links need root (CAP_SYS_ADMIN, CAP_NET_ADMIN)")
