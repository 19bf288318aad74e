#!/usr/bin/env python3
"""Soak: canemud in real time under clients that come and go for a while.

Worker processes open python-can buses on canemud, send and receive frames, load and clear
fault scenarios of their own, close, and start again; every half second or so one of them is
killed (SIGKILL, mid-call) and replaced. Meanwhile this process asks canemud for its buses ten
times a second. At the end every worker is gone, and:

- no request waited 100 ms or more for its answer;
- canemud holds the descriptors it held before the first client (every ring, eventfd and socket
  of the dead and finished clients closed);
- its resident memory grew by less than 16 MiB after the warm-up;
- it lists no client but this one, and `canemu fault clear all` clears what killed workers left;
- no ring memory is held any more (`ring_bytes` 0);
- nothing was lost silently: a listen-only `canemu dump` on each bus, running from before the
  first worker to after the last, printed every frame its node received or reported it lost
  (frames the node received = lines printed + messages reported lost), and that is at least
  every frame the bus carried (a listen-only node also takes the frames whose sender, error
  passive, was left without an acknowledgement: its passive error flag leaves them valid).

Prints the figures as one JSON object; exits 1 with the reasons when a check fails.
Usage: soak.py [--seconds N] [--workers N] [--build DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "client" / "python"))

import canemu  # noqa: E402
from canemu.testing import Daemon  # noqa: E402

CONFIG = """
[simulation]
time = "realtime"

[[bus]]
name = "can0"
bitrate = 500000

[[bus]]
name = "can1"
bitrate = 250000

[[device]]
name = "ixxat0"
model = "ixxat-usb-to-can"
controllers = ["can0", "can1"]
"""

# One worker: a loop of sessions until killed.
WORKER = r"""
import os, random, subprocess, sys, time
import can
cli, seed, folder = sys.argv[1], int(sys.argv[2]), sys.argv[3]
rnd = random.Random(seed)
scenario = f"soak-{os.getpid()}"
text = f'[scenario]\nname = "{scenario}"\n\n[[fault]]\nat = "0s"\nbus = "can1"\nmatch = {{ id = 0x7F0, mask = 0x7FF }}\neffect = "crc_error"\ncount = 1\n'
path = os.path.join(folder, f"{scenario}.toml")
with open(path, "w") as f:
    f.write(text)
while True:
    channel = rnd.choice(["can0", "can1"])
    with can.Bus(interface="canemu", channel=channel, receive_own_messages=rnd.random() < 0.5) as bus:
        for _ in range(rnd.randrange(1, 200)):
            msg = can.Message(arbitration_id=rnd.randrange(0x800), data=os.urandom(rnd.randrange(9)),
                              is_extended_id=False)
            try:
                bus.send(msg, timeout=0.2)
            except can.CanError:
                pass
            while bus.recv(0) is not None:
                pass
    if rnd.random() < 0.1:
        subprocess.run([cli, "fault", "load", path], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        subprocess.run([cli, "fault", "clear", scenario], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(rnd.random() * 0.05)
"""


class Observer:
    """`canemu dump BUS --listen-only --no-errors` into a file: every frame the bus carries, or
    a report of how many it could not print."""

    def __init__(self, cli: str, socket: str, bus: str, folder: Path) -> None:
        self.out = folder / f"observed-{bus}.log"
        self.err = folder / f"observed-{bus}.err"
        with open(self.err, "w") as err:
            self.proc = subprocess.Popen([cli, "--socket", socket, "dump", bus, "--listen-only",
                                          "--no-errors", "--sim-time", "-o", str(self.out)],
                                         stdout=subprocess.DEVNULL, stderr=err)
        deadline = time.monotonic() + 10
        while "listening on" not in self.err.read_text():
            if time.monotonic() > deadline or self.proc.poll() is not None:
                raise RuntimeError(f"canemu dump {bus} did not start: {self.err.read_text()}")
            time.sleep(0.01)
        # "canemu: listening on can0 as eph1 (...)": its node is eph1:0
        self.node = self.err.read_text().split(" as ")[1].split()[0] + ":0"

    def stop(self) -> tuple[int, int]:
        """Ends the dump; the lines it printed and the messages it reported lost."""
        self.proc.send_signal(signal.SIGINT)
        self.proc.wait(timeout=10)
        printed = len(self.out.read_text().splitlines())
        lost = sum(int(line.split()[1]) for line in self.err.read_text().splitlines()
                   if line.endswith("lost: the output did not keep up"))
        return printed, lost


def descriptors(pid: int) -> int:
    return len(os.listdir(f"/proc/{pid}/fd"))


def rss_kib(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return 0


def status(cli: str, socket: str) -> dict:
    out = subprocess.run(
        [cli, "--socket", socket, "status", "--json"], capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout)


def main() -> int:
    p = argparse.ArgumentParser()
    p.add_argument("--seconds", type=float, default=60.0)
    p.add_argument("--workers", type=int, default=4)
    p.add_argument("--build", default=str(REPO / "build"))
    args = p.parse_args()
    build = Path(args.build)
    cli = str(build / "bin" / "canemu")
    os.environ["CANEMU_LIBDIR"] = str(build / "lib")
    rnd = random.Random(1)
    failures = []
    with Daemon(CONFIG, canemud=str(build / "bin" / "canemud")) as daemon:
        pid = daemon.proc.pid
        canemu.buses()  # this process's own connection, before counting
        fds_before = descriptors(pid)
        env = dict(os.environ, CANEMU_SOCKET=daemon.socket,
                   PYTHONPATH=str(REPO / "client" / "python"))
        dumps = {bus: Observer(cli, daemon.socket, bus, Path(daemon.dir)) for bus in ("can0", "can1")}

        def start(k: int) -> subprocess.Popen:
            return subprocess.Popen([sys.executable, "-c", WORKER, cli, str(rnd.randrange(1 << 30)),
                                     daemon.dir],
                                    env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)

        workers = [start(k) for k in range(args.workers)]
        begin = time.monotonic()
        warm_rss = None
        slowest = 0.0
        asked = 0
        killed = 0
        next_kill = begin + 0.5
        while time.monotonic() - begin < args.seconds:
            t0 = time.monotonic()
            canemu.buses()  # one status request
            slowest = max(slowest, time.monotonic() - t0)
            asked += 1
            now = time.monotonic()
            if warm_rss is None and now - begin > min(5.0, args.seconds / 4):
                warm_rss = rss_kib(pid)
            for k, w in enumerate(workers):
                if w.poll() is not None:  # a worker must not end by itself
                    failures.append(f"worker {w.pid} ended by itself: {w.stderr.read().decode()[-500:]}")
                    workers[k] = start(k)
            if now >= next_kill:
                k = rnd.randrange(len(workers))
                workers[k].send_signal(signal.SIGKILL)
                workers[k].wait()
                workers[k] = start(k)
                killed += 1
                next_kill = now + rnd.uniform(0.2, 0.8)
            time.sleep(0.1)
        for w in workers:
            w.send_signal(signal.SIGKILL)
            w.wait()
        # canemud notices the dead clients; wait until only this one and the observers are
        # listed and the buses are quiet (the frames of the last workers have gone out).
        deadline = time.monotonic() + 10
        left = status(cli, daemon.socket)
        while time.monotonic() < deadline:
            time.sleep(0.05)
            now_status = status(cli, daemon.socket)
            quiet = [b["frames"] for b in now_status["buses"]] == [b["frames"] for b in left["buses"]]
            left = now_status
            if left["clients"] <= 2 + len(dumps) and quiet:
                break
        received = {bus: next(n["frames_received"] for n in left["nodes"] if n["name"] == d.node)
                    for bus, d in dumps.items()}
        seen = {bus: d.stop() for bus, d in dumps.items()}
        left = status(cli, daemon.socket)
        # This process and the status command are the clients left.
        fds_after = descriptors(pid)
        rss_after = rss_kib(pid)
        cleared = subprocess.run([cli, "--socket", daemon.socket, "fault", "clear", "all"],
                                 capture_output=True, text=True)
        in_force = [f for f in status(cli, daemon.socket)["faults"]
                    if f["state"] in ("pending", "active")]
        figures = {
            "seconds": args.seconds,
            "workers": args.workers,
            "workers_killed": killed,
            "status_requests": asked,
            "slowest_answer_ms": round(slowest * 1000, 2),
            "descriptors_before": fds_before,
            "descriptors_after": fds_after,
            "rss_after_warmup_kib": warm_rss,
            "rss_end_kib": rss_after,
            "frames_can0": left["buses"][0]["frames"],
            "frames_can1": left["buses"][1]["frames"],
            "observed": {bus: {"received": received[bus], "printed": printed, "lost": lost}
                         for bus, (printed, lost) in seen.items()},
            "ring_bytes_end": left["ring_bytes"],
        }
        print(json.dumps(figures))
        if slowest >= 0.1:
            failures.append(f"a status request waited {slowest * 1000:.1f} ms")
        if fds_after != fds_before:
            failures.append(f"canemud holds {fds_after} descriptors, {fds_before} before")
        if warm_rss is not None and rss_after - warm_rss >= 16 * 1024:
            failures.append(f"canemud grew by {rss_after - warm_rss} KiB after the warm-up")
        if left["clients"] > 2:
            failures.append(f"{left['clients']} clients still listed")
        if left["ring_bytes"] != 0:
            failures.append(f"{left['ring_bytes']} bytes of ring memory still held")
        for k, bus in enumerate(("can0", "can1")):
            printed, lost = seen[bus]
            if printed + lost != received[bus]:
                failures.append(f"{bus}: the observer's node received {received[bus]} frames; it "
                                f"printed {printed} and reported {lost} lost")
            if received[bus] < left["buses"][k]["frames"]:
                failures.append(f"{bus} carried {left['buses'][k]['frames']} frames; the observer "
                                f"received only {received[bus]}")
        if cleared.returncode != 0 or in_force:
            failures.append(f"fault clear all: {cleared.stdout}{cleared.stderr}; in force: {in_force}")
    for f in failures:
        print(f"soak: FAIL: {f}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
