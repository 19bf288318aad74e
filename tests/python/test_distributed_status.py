"""canemu status and canemu metrics with buses across hosts: two canemud processes "a" and "b" in
a DDS domain of this run's own over the loopback interface (CYCLONEDDS_URI, unicast), b using a's
bus can0 with an IXXAT adapter on it. The tests wait for what the daemons say (a
answered b, a knows b's version) and then read b's and a's status as tables, as JSON and as metrics."""

from __future__ import annotations

import json
import os
import re
import subprocess
import time

import pytest

from conftest import CANEMU_CLI, CANEMUD
from canemu.testing import Daemon

# Another domain than test_dds_bridge.py's in the same process, and a partition of this file's.
DOMAIN = 1 + (os.getpid() + 100) % 200
PARTITION = f"status-{os.getpid()}"
URI = ("<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface name=\"lo\"/>"
       "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
       "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>30"
       "</MaxAutoParticipantIndex><Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery>"
       "</Domain></CycloneDDS>")

DISTRIBUTED = """
[distributed]
name = "{name}"
domain = {domain}
partition = "{partition}"
heartbeat_ms = 50
timeout_ms = 5000
"""

CONFIG_A = DISTRIBUTED.format(name="a", domain=DOMAIN, partition=PARTITION) + """
[[bus]]
name = "can0"
bitrate = 500000

[[bus]]
name = "can1"
bitrate = 125000
"""

CONFIG_B = DISTRIBUTED.format(name="b", domain=DOMAIN, partition=PARTITION) + """
[[bus]]
name = "can0"
bitrate = 500000
owner = "a"

[[bus]]
name = "local"
bitrate = 250000

[[device]]
name = "ixxat0"
model = "ixxat-usb-to-can"
controllers = ["can0"]
"""


def canemu(daemon: Daemon, *args: str) -> str:
    return subprocess.run([str(CANEMU_CLI), "--socket", daemon.socket, *args],
                          capture_output=True, text=True, check=True).stdout


@pytest.fixture(scope="module")
def pair():
    saved = os.environ.get("CYCLONEDDS_URI")
    os.environ["CYCLONEDDS_URI"] = URI  # the daemons inherit it
    a = b = None
    try:
        try:
            a = Daemon(CONFIG_A, canemud=str(CANEMUD))
        except RuntimeError as e:
            if "built without DDS" in str(e):
                pytest.skip("canemud was built without Cyclone DDS")
            raise
        b = Daemon(CONFIG_B, canemud=str(CANEMUD))
        b.wait_log("daemon a answers: its buses are attached", 20)
        # b's hello may reach a before b's announcement does (a then knows b by name only, and
        # does not log it as joined): wait for a's status to show b's version.
        deadline = time.monotonic() + 20
        while not any(p["name"] == "b" and p["version"]
                      for p in json.loads(canemu(a, "status", "--json"))["distributed"]["peers"]):
            assert time.monotonic() < deadline, "a never heard b's announcement"
            time.sleep(0.01)  # polling a condition with a deadline, not waiting for time to pass
        yield a, b
    finally:
        for d in (b, a):
            if d is not None:
                d.stop()
        if saved is None:
            os.environ.pop("CYCLONEDDS_URI", None)
        else:
            os.environ["CYCLONEDDS_URI"] = saved


def test_status_json_shows_the_owner_up_and_the_remote_bus_attached(pair):
    a, b = pair
    d = json.loads(canemu(b, "status", "--json"))["distributed"]
    assert (d["name"], d["domain"], d["partition"]) == ("b", DOMAIN, PARTITION)
    assert (d["heartbeat_ms"], d["timeout_ms"]) == (50, 5000)
    assert sorted(d["counters"]) == ["by_reason", "dropped", "events_received", "events_sent",
                                     "last_reason", "late", "late_bound_ns", "late_max_ns",
                                     "rejected", "requests_received", "requests_sent"]
    assert d["counters"]["dropped"] == 0
    assert d["counters"]["requests_received"] == 0  # a has no node on b's buses
    assert d["counters"]["requests_sent"] >= 1  # its hello at least
    [peer] = d["peers"]
    assert peer["name"] == "a"
    assert peer["state"] == "up"
    assert peer["reason"] == ""
    assert peer["time"] == "realtime"
    assert peer["buses"] == ["can0", "can1"]
    assert peer["bus_total"] == 2
    assert peer["hosted_nodes"] == 0
    assert peer["via"] == "link"  # both on this host: b's requests and a's events over its link
    assert 0 <= peer["last_heard_ms"] < 5000
    assert peer["protocol"] >= 1
    # ixxat0's controller sits on can0, but no program has initialized it: no node of b runs on
    # a's bus yet.
    assert d["remote_buses"] == [
        {"bus": "can0", "owner": "a", "state": "attached", "reason": "", "nodes": 0}]

    # a, the owner: b is up and simulates no bus; a has no remote bus.
    da = json.loads(canemu(a, "status", "--json"))["distributed"]
    [pb] = da["peers"]
    assert (pb["name"], pb["state"], pb["buses"], pb["bus_total"]) == ("b", "up", ["local"], 1)
    assert pb["via"] == "link"
    assert da["remote_buses"] == []
    assert da["counters"]["requests_received"] >= 1
    assert da["counters"]["requests_sent"] == 0


def test_status_tables_show_the_daemon_and_remote_bus(pair):
    _, b = pair
    text = canemu(b, "status")
    assert re.search(r"^daemon b, DDS domain %d, partition %s: requests sent \d+, received 0; "
                     r"events sent \d+, received \d+; dropped 0, rejected 0, "
                     r"late \(> 1\.00 ms\) 0, max \d+\.\d+ (us|ms)$" % (DOMAIN, PARTITION),
                     text, re.M), text
    assert re.search(r"^DAEMON\s+STATE\s+VIA\s+VERSION\s+TIME\s+HEARD\s+HOSTED\s+BUSES\s+REASON$",
                     text, re.M), text
    assert re.search(r"^a\s+up\s+link\s+\S+\s+realtime\s+\d+\.\d s\s+0\s+can0,can1\s*$", text,
                     re.M), text
    assert re.search(r"^REMOTE BUS\s+OWNER\s+STATE\s+NODES\s+REASON$", text, re.M), text
    assert re.search(r"^can0\s+a\s+attached\s+0\s*$", text, re.M), text


def test_metrics_count_messages_and_say_who_is_up(pair):
    a, b = pair
    text = canemu(b, "metrics")
    assert 'canemu_peer_up{daemon="a"} 1\n' in text
    assert 'canemu_remote_bus_attached{bus="can0",owner="a"} 1\n' in text
    assert "canemu_distributed_dropped_total 0\n" in text
    assert "canemu_distributed_late_total 0\n" in text
    assert 'canemu_distributed_requests_total{direction="received"} 0\n' in text
    assert re.search(r'^canemu_distributed_requests_total\{direction="sent"\} [1-9]\d*$', text,
                     re.M), text
    assert "# TYPE canemu_distributed_events_total counter\n" in text
    text_a = canemu(a, "metrics")
    assert 'canemu_peer_up{daemon="b"} 1\n' in text_a
    assert "canemu_remote_bus_attached" in text_a  # the family, with no sample
    assert "canemu_remote_bus_attached{" not in text_a


def test_without_distributed_nothing_is_added():
    daemon = Daemon(None, canemud=str(CANEMUD))
    try:
        status = json.loads(canemu(daemon, "status", "--json"))
        assert "distributed" not in status
        text = canemu(daemon, "status")
        assert "DAEMON" not in text and "REMOTE BUS" not in text
        assert "canemu_distributed" not in canemu(daemon, "metrics")
        assert "canemu_peer_up" not in canemu(daemon, "metrics")
    finally:
        daemon.stop()
