"""A bus across daemons (docs/distributed.md) with a configured IXXAT adapter on the remote side,
driven by a VCI C program (build/bin/vci_c_talk, libvcinpl), in real and stepped time; and two
daemons in scaled time, which join when their factors agree and refuse each other otherwise.
Daemon "a" simulates can0; daemon "b" declares can0 with owner "a" and the adapter "alpha" on it.
Same rig as test_distributed.py: loopback unicast in a DDS domain of this run's own, no root."""

from __future__ import annotations

import contextlib
import json
import os
import subprocess

from conftest import BUILD
from distributed_support import TIMEOUT, attached_step, cli, frame_ns, nodes, step, wait_until
from test_distributed import Peer, env, owner_and_follower

from canemu.testing import Daemon  # noqa: E402

assert env  # the fixture, used by name below
VCI_C_TALK = str(BUILD / "bin" / "vci_c_talk")

ALPHA = """
[[device]]
name = "alpha"
model = "ixxat-usb-to-can"
controllers = ["can0"]
"""


def talk(daemon: Daemon, *args: str) -> subprocess.Popen:
    """vci_c_talk on `daemon` (it finds canemud by CANEMU_SOCKET)."""
    return subprocess.Popen([VCI_C_TALK, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env={**os.environ, "CANEMU_SOCKET": daemon.socket})


def finish(proc: subprocess.Popen) -> str:
    """Its output once it ended; it must end well."""
    out, err = proc.communicate(timeout=TIMEOUT)
    assert proc.returncode == 0, f"vci_c_talk: {err}"
    return out


def distributed(daemon: Daemon) -> dict:
    return json.loads(cli(daemon, "status", "--json"))["distributed"]


def remote_state(daemon: Daemon) -> str:
    return distributed(daemon)["remote_buses"][0]["state"]


def peers_of(daemon: Daemon) -> dict:
    return {p["name"]: p for p in distributed(daemon)["peers"]}


def wait_for_node(owner: Daemon, user: Daemon, name: str) -> None:
    """Waits until the owner lists the user's node `name`; else fails with what the user's log
    says of its nodes (an owner's refusal is logged there)."""
    try:
        wait_until(lambda: name in nodes(owner), f"{owner.socket} lists {name}")
    except AssertionError as e:
        said = [line for line in user.log.splitlines() if "node" in line]
        raise AssertionError(f"{e}; the user's log: {said}") from None


@contextlib.contextmanager
def receiving(owner: Daemon, user: Daemon):
    """vci_c_talk receiving on the user's adapter alpha, ready and listed by the owner as node
    b/alpha:0; killed on the way out if it has not ended."""
    receiver = talk(user, "receive", "alpha")
    try:
        assert receiver.stdout.readline() == "ready\n"
        wait_for_node(owner, user, "b/alpha:0")
        yield receiver
    finally:
        receiver.kill()
        receiver.wait()


def test_realtime_vci_adapter_on_a_remote_bus(env):
    with owner_and_follower("realtime", follower_extra=ALPHA) as (a, b):
        wait_until(lambda: remote_state(b) == "attached", "b's can0 attached to a")
        ecu_a = Peer(a)
        try:
            # b's VCI program waits for a frame; a lists its node as b/alpha:0 (the device's name
            # on b and its controller number), and a's program's frame reaches it.
            with receiving(a, b) as receiver:
                assert [k for k in nodes(a) if k.startswith("b/")] == ["b/alpha:0"]
                ecu_a.send(0x1A5, "7E")
                assert finish(receiver) == "1A5#7E\n"
            # Its node is gone from a with the program (the adapter released it).
            wait_until(lambda: not any(k.startswith("b/") for k in nodes(a)),
                       "b's node leaves a when its program ends")
            assert ecu_a.frames() == []

            # b's VCI program sends 1A5#7E (it waits for its own echo, so it ends once the frame
            # has gone out on a's can0, acknowledged by a's program's controller).
            finish(talk(b, "send", "alpha", "1A5", "7E"))
            assert ecu_a.frames_arriving("b's frame reaches a") == [(0x1A5, "7e")]
        finally:
            ecu_a.close()


def test_stepped_vci_adapter_on_a_remote_bus(env):
    with owner_and_follower("stepped", follower_extra=ALPHA) as (a, b):
        attached_step(b)
        ecu_a = Peer(a)
        try:
            # a's program's frame to b's VCI program: queued before a step of a, it goes out at
            # the step's start; b's program prints it once the step ends on b.
            with receiving(a, b) as receiver:
                t0 = step(a, 1000)
                ecu_a.send(0x1A5, "7E")
                assert step(a, 1_000_000) == t0 + 1_000_000
                assert finish(receiver) == "1A5#7E\n"
            assert ecu_a.frames() == []

            # b's VCI program sends and waits for its echo: the test steps b until it ends.
            # Requests are applied at a step's start: the frame starts at one of them.
            starts = [t0 + 1_000_000]
            sender = talk(b, "send", "alpha", "1A5", "7E")
            try:
                while sender.poll() is None:
                    assert len(starts) < 2000, "the send never ended"
                    starts.append(step(b, 100_000))
                assert sender.returncode == 0, sender.stderr.read()
            finally:
                sender.kill()
                sender.wait()
            [(ident, data, at)] = ecu_a.frames()
            assert (ident, data) == (0x1A5, "7e")
            duration, _ = frame_ns("1A5#7E")
            assert at - duration in starts, (at, starts)
        finally:
            ecu_a.close()


def test_scaled_time_daemons_with_one_factor_exchange_frames(env):
    with owner_and_follower("scaled:2") as (a, b):
        wait_until(lambda: remote_state(b) == "attached", "b's can0 attached to a")
        assert peers_of(a)["b"]["time"] == "scaled:2"
        ecu_a, ecu_b = Peer(a), Peer(b)
        try:
            ecu_b.send(0x222, "02")
            assert ecu_a.frames_arriving("b's frame reaches a") == [(0x222, "02")]
            ecu_a.send(0x111, "01")
            assert ecu_b.frames_arriving("a's frame reaches b") == [(0x111, "01")]
        finally:
            ecu_a.close()
            ecu_b.close()


def test_scaled_time_daemons_with_other_factors_refuse_each_other(env):
    with owner_and_follower("scaled:2", "scaled:3") as (a, b):
        wait_until(lambda: "b" in peers_of(a) and "a" in peers_of(b)
                   and peers_of(a)["b"]["time"] == "scaled:3", "a and b hear each other")
        pb = peers_of(a)["b"]
        assert (pb["state"], pb["reason"]) == ("refused",
                                               "its time is scaled:3, this daemon's scaled:2")
        da = distributed(b)
        [pa] = da["peers"]
        assert (pa["name"], pa["state"], pa["time"], pa["reason"]) == (
            "a", "refused", "scaled:2", "its time is scaled:2, this daemon's scaled:3")
        assert da["remote_buses"] == [{
            "bus": "can0", "owner": "a", "state": "refused",
            "reason": "its time is scaled:2, this daemon's scaled:3", "nodes": 0}]
        assert da["counters"]["requests_sent"] == 0  # not even a hello to a refused daemon
