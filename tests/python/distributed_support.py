"""What the tests of buses across daemons share (test_distributed*.py, test_netns_*.py,
test_dds_bridge.py): a daemon's configuration with [distributed], Cyclone DDS on the loopback
interface by unicast, frame durations from `canemu calc frame`, waiting for a condition with a
deadline, and asking a daemon through the `canemu` command (a process of its own: a python
process talks to one canemud at a time)."""

from __future__ import annotations

import json
import re
import subprocess
import time

from conftest import CANEMU_CLI

TIMEOUT = 20.0

# Cyclone DDS on `lo` only, unicast (multicast off), for daemons and peers on one machine.
LOOPBACK_URI = ("<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
                "name=\"lo\"/></Interfaces><AllowMulticast>false</AllowMulticast></General>"
                "<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>30"
                "</MaxAutoParticipantIndex><Peers><Peer address=\"127.0.0.1\"/></Peers>"
                "</Discovery></Domain></CycloneDDS>")


def config(name: str, time_mode: str, owner: str | None, *, domain: int, partition: str,
           heartbeat_ms: int = 50, timeout_ms: int = 1000, local_link: bool = True) -> str:
    """Daemon `name` with one bus can0 at 500 kbit/s, its own or `owner`'s; `local_link` false:
    over DDS even on one host."""
    owner_line = f'owner = "{owner}"' if owner else ""
    return f"""
[simulation]
time = "{time_mode}"

[distributed]
name = "{name}"
domain = {domain}
partition = "{partition}"
heartbeat_ms = {heartbeat_ms}
timeout_ms = {timeout_ms}
local_link = {"true" if local_link else "false"}

[[bus]]
name = "can0"
bitrate = 500000
{owner_line}
"""


_durations: dict = {}


def frame_ns(frame: str, bitrate: int = 500000) -> tuple[int, int]:
    """The frame's duration from SOF to the end of EOF, and with its intermission."""
    if (frame, bitrate) not in _durations:
        text = subprocess.run([str(CANEMU_CLI), "calc", "frame", frame, "--bitrate", str(bitrate)],
                              capture_output=True, text=True, check=True).stdout
        _durations[frame, bitrate] = (int(re.search(r": (\d+) ns \(", text).group(1)),
                                      int(re.search(r"(\d+) ns with intermission", text).group(1)))
    return _durations[frame, bitrate]


def wait_until(done, what: str, timeout: float = TIMEOUT) -> None:
    deadline = time.monotonic() + timeout
    while not done():
        if time.monotonic() > deadline:
            raise AssertionError(f"{what}: not within {timeout} s")
        time.sleep(0.005)  # polling a condition with a deadline, not waiting for time to pass


def cli(daemon, *args: str) -> str:
    """`canemu --socket SOCKET ARGS...` of `daemon` (anything with `.socket`); its output, or
    AssertionError with what it said."""
    done = subprocess.run([str(CANEMU_CLI), "--socket", daemon.socket, *args],
                          capture_output=True, text=True, timeout=TIMEOUT)
    if done.returncode != 0:
        raise AssertionError(f"canemu {' '.join(args)}: {done.stderr}")
    return done.stdout


def nodes(daemon) -> dict:
    """`canemu status --json`'s nodes by name."""
    return {n["name"]: n for n in json.loads(cli(daemon, "status", "--json"))["nodes"]}


def step(daemon, ns: int) -> int:
    """A step asked of `daemon` by `canemu time step`; the simulated time after it."""
    text = cli(daemon, "time", "step", f"{ns}ns")
    whole, frac = re.search(r"simulated time (\d+)\.(\d{9}) s", text).groups()
    return int(whole) * 1_000_000_000 + int(frac)


def attached_step(follower) -> int:
    """Steps `follower` by 1 us as soon as its bus's owner answers (until then its steps are
    refused); the time after it."""
    got: list = []

    def try_step() -> bool:
        try:
            got.append(step(follower, 1000))
            return True
        except AssertionError:
            return False

    wait_until(try_step, "the follower's steps reach the owner")
    return got[0]
