"""The DDS bridge across hosts: canemud (stepped time) with a DDS bridge on can0 in host a, a DDS
peer (netns_dds_peer.py, PyPI cyclonedds) in host b, each host a network namespace with its own
link and address (netns.Hosts), Cyclone DDS on that link by unicast discovery (every host's
address a peer, multicast off) and once more by SPDP multicast on the link. A third host, c,
taken off the hub, runs the same peer and must find no one. Every time stamp is simulated time,
exact. Needs root (netns.netns_available); reported as skipped otherwise."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import can
import pytest

from conftest import CAN0, CANEMU_CLI, CANEMUD, table, toml
from distributed_support import TIMEOUT, frame_ns, wait_until

pytest.importorskip(
    "cyclonedds", reason="PyPI's cyclonedds is not in this Python environment (requirements.txt, "
    ".venv)")

import canemu  # noqa: E402
from netns import HostProgram, Hosts, netns_available  # noqa: E402

MS = 1_000_000
ALONE = 1.0  # seconds host c's peer looks for the bridge (discovery on a link takes ~50 ms)
DOMAIN = 1 + (os.getpid() + 101) % 200
PEER = Path(__file__).with_name("netns_dds_peer.py")

CONFIG = toml(table("[simulation]", time="stepped"), CAN0,
              table("[[bridge]]", kind="dds", bus="can0", domain=DOMAIN))


class Peer(HostProgram):
    """netns_dds_peer.py inside a host: one JSON line an event."""

    def __init__(self, hosts: Hosts, host: str, *args: str) -> None:
        super().__init__(hosts, host, [sys.executable, str(PEER), "--domain", str(DOMAIN), *args])

    def next(self, timeout: float = TIMEOUT) -> dict:
        """The peer's next event, waited for at most `timeout` seconds."""
        return json.loads(self.line(timeout))


def bridges(daemon) -> list:
    done = subprocess.run([str(CANEMU_CLI), "--socket", daemon.socket, "bridge", "list", "--json"],
                          capture_output=True, text=True, timeout=TIMEOUT, check=True)
    return json.loads(done.stdout)


def namespace_of(pid: int) -> str:
    return subprocess.run(["ip", "netns", "identify", str(pid)], capture_output=True, text=True,
                          check=True).stdout.strip()


@pytest.fixture(params=["unicast", "multicast"])
def hosts(request):
    """Hosts a, b, c; Cyclone's discovery by unicast peers or by SPDP multicast on the link."""
    available, why = netns_available()
    if not available:
        pytest.skip(why)
    with Hosts(("a", "b", "c"), multicast=request.param == "multicast") as h:
        yield h


def test_dds_bridge_to_a_peer_on_another_host(hosts):
    started = time.monotonic()
    hosts.disconnect("c")
    assert not hosts.reachable("c", "a", 0.3) and hosts.reachable("b", "a")
    daemon = hosts.daemon("a", CONFIG, canemud=str(CANEMUD))
    assert namespace_of(daemon.proc.pid) == hosts.namespace["a"]
    ecu = can.Bus(interface="canemu", channel="can0")
    try:
        assert canemu.sim_time()[0] == 0
        peer = Peer(hosts, "b", "--write", "123#1122", "--write", "12345678#R4", "--take", "3")
        alone = Peer(hosts, "c", "--expect-alone", "--timeout", str(ALONE))
        assert namespace_of(peer.proc.pid) == hosts.namespace["b"]
        matched = peer.next()
        assert matched["event"] == "matched"
        assert peer.next() == {"event": "written", "count": 2}
        wait_until(lambda: bridges(daemon)[0]["received"] == 2, "the bridge received 2 samples")
        # Both frames were taken at t = 0 and go out one after the other in the first step.
        canemu.step(MS)
        first, first_gap = frame_ns("123#1122")
        second, _ = frame_ns("12345678#R4")
        got = [(m.arbitration_id, m.is_extended_id, m.is_remote_frame, bytes(m.data).hex(),
                round(m.timestamp * 1e9)) for m in iter(lambda: ecu.recv(0), None)
               if not m.is_error_frame]
        assert got == [(0x123, False, False, "1122", first),
                       (0x12345678, True, True, "", first_gap + second)]
        # A frame of the node on can0 from t = 1 ms reaches host b too.
        ecu.send(can.Message(arbitration_id=0x321, is_extended_id=False, data=[1, 2, 3]))
        canemu.step(MS)
        own, _ = frame_ns("321#010203")
        assert peer.next() == {"event": "frames", "frames": [
            [first, 0x123, False, False, 2, 2, "1122", True],
            [first_gap + second, 0x12345678, True, True, 4, 0, "", True],
            [MS + own, 0x321, False, False, 3, 3, "010203", False],
        ]}
        assert peer.proc.wait(TIMEOUT) == 0
        (entry,) = bridges(daemon)
        assert (entry["received"], entry["sent"], entry["published"]) == (2, 2, 3)
        # Host c, off the hub, never found canemud's bridge.
        assert alone.next(ALONE + TIMEOUT) == {"event": "alone", "tx": 0, "frames": 0}
        assert alone.proc.wait(TIMEOUT) == 0
    finally:
        ecu.shutdown()
    print(f"\nhosts made in {hosts.setup_seconds:.3f} s; discovery across hosts took "
          f"{matched['seconds']} s; the test {time.monotonic() - started:.2f} s")
