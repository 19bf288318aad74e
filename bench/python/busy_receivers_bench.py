"""Busy buses with python-can receivers in real time: does every frame reach its receiver?

N buses at 1 Mbit/s in real time, each kept at full load for --seconds of simulated time by a
simulated node ([[can_node]]) that a babble fault makes send 000#0102030405060708 back to back,
and each with a python-can receiver (interface canemu) taking every frame with `recv(0)`. The
receivers live in worker processes of at most 16 buses each (one canemud connection per
process), which poll their buses and sleep 1 ms when all are empty. Once the babbling is over
and the receivers hold nothing more, the frames each bus carried (canemud's status) are
compared with the frames its receiver got: `frames_lost` is the difference summed over the
buses (issue 41's goal: 0, with 64 and with 256 buses). Beside it: simulated seconds per real
second over the babbling (below 1 when canemud cannot keep real time), canemud's share of a core
(/proc/PID/task/*/schedstat) and the workers' summed share. The babble faults come in scenarios
of at most 64 (a scenario's text is at most 12 KiB), loaded one after the other.

    python bench/python/busy_receivers_bench.py --buses 64 256 --out build/bench-results/busy_receivers.json

`--smoke` (CI's bench run) measures 256 buses for 0.2 s of simulated time only: it shows that the
path works, not the figures.
"""

from __future__ import annotations

import argparse
import json
import os
import select
import subprocess
import sys
import time
from pathlib import Path
from typing import Dict, List

PER_WORKER = 16  # buses a worker process receives from
PER_SCENARIO = 64  # babble faults in one scenario


def config(buses: int) -> str:
    lines = ['[simulation]', 'time = "realtime"', '']
    for i in range(buses):
        lines += ['[[bus]]', f'name = "can{i}"', 'bitrate = 1000000', '',
                  '[[can_node]]', f'name = "B{i}"', f'bus = "can{i}"', '',
                  '[[can_node.message]]', 'name = "IDLE"', 'id = 0x7FF', 'length = 8',
                  'send = "on_change"', '']
    return "\n".join(lines)


def scenario(first: int, count: int, seconds: float) -> str:
    """The babble faults of can{first} .. can{first+count-1}."""
    lines = ['[scenario]', f'name = "busy{first}"', '']
    for i in range(first, first + count):
        lines += ['[[fault]]', 'at = "0s"', f'node = "B{i}"', 'effect = "babble"', 'id = 0',
                  'data = [1, 2, 3, 4, 5, 6, 7, 8]', f'duration = "{int(seconds * 1000)}ms"', '']
    return "\n".join(lines)


def schedstat_ns(pid: int) -> int:
    """A process's run time in ns, summed over its threads."""
    total = 0
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            total += int((task / "schedstat").read_text().split()[0])
        except (OSError, ValueError, IndexError):
            pass
    return total


def worker(socket: str, first: int, count: int) -> None:
    """Receives from can{first} .. can{first+count-1}; "ready" once open; on "drain" on its
    standard input, takes what is left and prints each bus's count as JSON."""
    import can

    import canemu

    canemu.connect(socket)
    buses = [can.Bus(interface="canemu", channel=f"can{i}") for i in range(first, first + count)]
    got = [0] * count
    print("ready", flush=True)
    draining = False
    empty_passes = 0
    while True:
        any_frame = False
        for k, bus in enumerate(buses):
            while True:
                msg = bus.recv(0)
                if msg is None:
                    break
                any_frame = True
                if not msg.is_error_frame:
                    got[k] += 1
        if draining:
            empty_passes = 0 if any_frame else empty_passes + 1
            if empty_passes >= 50:  # 50 ms with nothing more
                break
        elif select.select([sys.stdin], [], [], 0)[0] and sys.stdin.readline().strip() == "drain":
            draining = True
        if not any_frame:
            time.sleep(0.001)
    print(json.dumps(got), flush=True)
    for bus in buses:
        bus.shutdown()


def measure(buses: int, seconds: float) -> Dict[str, float]:
    from canemu.bench import find_canemu
    from canemu.testing import Daemon

    with Daemon(config(buses)) as daemon:
        canemu_cli = [find_canemu(), "--socket", daemon.socket]

        def status() -> Dict:
            return json.loads(subprocess.run([*canemu_cli, "status", "--json"], check=True,
                                             capture_output=True, text=True).stdout)

        workers = []
        for first in range(0, buses, PER_WORKER):
            workers.append(subprocess.Popen(
                [sys.executable, __file__, "--worker", daemon.socket, str(first),
                 str(min(PER_WORKER, buses - first))],
                stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True))
        try:
            for w in workers:
                line = w.stdout.readline().strip()
                if line != "ready":
                    raise RuntimeError(f"a receiver did not start: {line!r}")
            paths = []
            for first in range(0, buses, PER_SCENARIO):
                paths.append(Path(daemon.dir, f"busy{first}.toml"))
                paths[-1].write_text(scenario(first, min(PER_SCENARIO, buses - first), seconds))
            before = status()
            cpu0 = schedstat_ns(daemon.proc.pid)
            workers_cpu0 = sum(schedstat_ns(w.pid) for w in workers)
            wall0 = time.monotonic()
            for path in paths:
                subprocess.run([*canemu_cli, "fault", "load", str(path)], check=True,
                               capture_output=True, text=True)
            # The babbling ends `seconds` of simulated time after the last scenario began
            # (status asked after the loads is at least that instant): wait for that.
            end_ns = status()["sim_time_ns"] + int(seconds * 1e9)
            while True:
                time.sleep(0.1)
                now = status()
                if now["sim_time_ns"] > end_ns + 50_000_000 or time.monotonic() - wall0 > 300:
                    break
            wall = time.monotonic() - wall0
            cpu = schedstat_ns(daemon.proc.pid) - cpu0
            workers_cpu = sum(schedstat_ns(w.pid) for w in workers) - workers_cpu0
            for w in workers:
                w.stdin.write("drain\n")
                w.stdin.flush()
            received: List[int] = []
            for w in workers:
                received += json.loads(w.stdout.readline())
                w.wait(timeout=30)
        finally:
            for w in workers:
                if w.poll() is None:
                    w.kill()
                    w.wait()
        after = status()
    carried = {b["name"]: b["frames"] - prev["frames"]
               for b, prev in zip(after["buses"], before["buses"])}
    lost = sum(carried[f"can{i}"] - received[i] for i in range(buses))
    sim = (now["sim_time_ns"] - before["sim_time_ns"]) / 1e9
    return {
        "buses": buses,
        "receiver_processes": len(workers),
        "frames_carried": sum(carried.values()),
        "frames_received": sum(received),
        "frames_lost": lost,
        "carried_per_bus_per_sim_second": round(sum(carried.values()) / buses / seconds),
        "sim_seconds_per_second": round(sim / wall, 4),
        # False when 300 s of waiting did not see the babbling end: the counts are partial.
        "babbling_over": now["sim_time_ns"] > end_ns,
        "canemud_cpu_percent_of_a_core": round(100 * cpu / 1e9 / wall, 1),
        "receivers_cpu_percent_of_a_core": round(100 * workers_cpu / 1e9 / wall, 1),
    }


def main() -> None:
    if len(sys.argv) == 5 and sys.argv[1] == "--worker":
        worker(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--buses", type=int, nargs="+", default=[64, 256])
    parser.add_argument("--seconds", type=float, default=3.0,
                        help="simulated seconds of babbling")
    parser.add_argument("--out", help="JSON file to write")
    parser.add_argument("--smoke", action="store_true",
                        help="256 buses for 0.2 s of simulated time: the path, not the figures")
    args = parser.parse_args()
    if args.smoke:
        args.buses, args.seconds = [256], 0.2
    results = []
    for n in args.buses:
        try:
            r = measure(n, args.seconds)
        except RuntimeError as e:  # canemud refused the configuration: say why
            # The log's first line names the file and the problem: keep the problem.
            reason = "; ".join(line.split(": ", 1)[-1] for line in str(e).splitlines()[1:])
            results.append({"buses": n, "error": f"canemud refused it: {reason}"})
            print(f"{n:4} busy buses, python-can receivers: not measured, canemud refused it: "
                  f"{reason}")
            continue
        results.append(r)
        print(f"{n:4} busy buses, python-can receivers: frames lost {r['frames_lost']} "
              f"of {r['frames_carried']} (goal 0); {r['sim_seconds_per_second']} simulated s "
              f"per s; canemud {r['canemud_cpu_percent_of_a_core']} % of a core, receivers "
              f"{r['receivers_cpu_percent_of_a_core']} %", flush=True)
    if args.out:
        with open(args.out, "w") as f:
            json.dump({"seconds": args.seconds, "benchmarks": results}, f, indent=2)


if __name__ == "__main__":
    main()
