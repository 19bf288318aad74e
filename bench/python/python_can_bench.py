"""python-can throughput: frames per second sent by one bus and received by another, through
canemu's interface and through python-can's own virtual bus, measured in the same run.

Each figure is taken apart: frames/s SENT (the frames over the time spent in `send`), frames/s
RECEIVED (over the time spent in `recv`, the empty reads that end a batch included) and the
round trip (over the whole run, stepping the emulation included), each beside the virtual bus's
with the ratio canemu / virtual. The two alternate for --rounds rounds and each figure is the
median of its rounds.

canemu runs in stepped time here, so that the figures are the interface's own cost (a real-time
bus at 1 Mbit/s carries at most about 8,000 such frames per second, whoever sends them); the
real-time round trip at 1 Mbit/s is reported beside it. Writes JSON (--out) and prints a
summary.

    python bench/python/python_can_bench.py --frames 20000 --out build/bench-results/python.json
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from typing import Callable, Dict, List, Optional

import can

import canemu
from canemu import _vci
from canemu.testing import Daemon

BATCH = 200  # frames per round: within the transmit and receive FIFOs

CONFIG = """
[simulation]
time = "{time}"

[[bus]]
name = "can0"
kind = "can"
bitrate = 1000000
"""


def frame(i: int) -> can.Message:
    return can.Message(arbitration_id=i & 0x7FF, data=i.to_bytes(8, "little"), is_extended_id=False)


def round_trip(sender, receiver, total: int,
               advance: Optional[Callable[[], object]] = None) -> Dict[str, float]:
    """`total` frames sent in batches by `sender`, all received by `receiver`; `advance()` moves
    stepped time when given. Frames per second sent (time in `send`), received (time in
    `recv`) and round trip (wall time of the whole), and the seconds spent in `advance`."""
    send_s = recv_s = advance_s = 0.0
    start = time.perf_counter()
    sent = 0
    while sent < total:
        n = min(BATCH, total - sent)
        batch = [frame(sent + k) for k in range(n)]
        t = time.perf_counter()
        for msg in batch:
            sender.send(msg)
        send_s += time.perf_counter() - t
        got = 0
        while got < n:
            if advance is not None:
                t = time.perf_counter()
                advance()
                advance_s += time.perf_counter() - t
                timeout = 0.0
            else:
                timeout = 1.0
            while got < n:
                t = time.perf_counter()
                msg = receiver.recv(timeout)
                recv_s += time.perf_counter() - t
                if msg is None:
                    if advance is None:
                        raise RuntimeError(f"received {got} of {n}")
                    break
                if not msg.is_error_frame:
                    got += 1
        sent += n
    whole = time.perf_counter() - start
    return {
        "sent_per_second": total / send_s,
        "received_per_second": total / recv_s,
        "round_trip_per_second": total / whole,
        "step_seconds": advance_s,
    }


def measure_canemu(time_mode: str, total: int) -> Dict[str, float]:
    with Daemon(CONFIG.format(time=time_mode)):
        a = can.Bus(interface="canemu", channel="can0")
        b = can.Bus(interface="canemu", channel="can0")
        try:
            # 200 frames of at most 135 bits at 1 Mbit/s take under 30 ms.
            advance = (lambda: canemu.step(30_000_000)) if time_mode == "stepped" else None
            round_trip(a, b, min(total, 1000), advance)  # warm-up
            return round_trip(a, b, total, advance)
        finally:
            a.shutdown()
            b.shutdown()


def measure_virtual(total: int) -> Dict[str, float]:
    a = can.Bus(interface="virtual", channel="bench", receive_own_messages=False)
    b = can.Bus(interface="virtual", channel="bench", receive_own_messages=False)
    try:
        round_trip(a, b, min(total, 1000))
        return round_trip(a, b, total)
    finally:
        a.shutdown()
        b.shutdown()


def median_figures(runs: List[Dict[str, float]]) -> Dict[str, float]:
    """Each figure's median over the runs."""
    return {key: statistics.median(run[key] for run in runs) for key in runs[0]}


def entry(name: str, figures: Dict[str, float]) -> Dict[str, object]:
    return {
        "name": name,
        "frames_per_second": round(figures["round_trip_per_second"]),  # the round trip
        "sent_frames_per_second": round(figures["sent_per_second"]),
        "received_frames_per_second": round(figures["received_per_second"]),
        "step_seconds": round(figures["step_seconds"], 3),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20000)
    parser.add_argument("--realtime-frames", type=int, default=4000)
    parser.add_argument("--rounds", type=int, default=7, help="alternating runs of each")
    parser.add_argument("--out", help="JSON file to write")
    args = parser.parse_args()

    # The two alternate, round after round, and each figure is the median of its rounds: a
    # spell of a busy machine then hits both alike instead of deciding the ratio.
    virtual_runs, stepped_runs = [], []
    for _ in range(args.rounds):
        virtual_runs.append(measure_virtual(args.frames))
        stepped_runs.append(measure_canemu("stepped", args.frames))
    virtual = median_figures(virtual_runs)
    stepped = median_figures(stepped_runs)
    realtime = measure_canemu("realtime", args.realtime_frames)
    ratios = {
        what: round(stepped[f"{what}_per_second"] / virtual[f"{what}_per_second"], 3)
        for what in ("sent", "received", "round_trip")
    }
    result = {
        "context": {
            "python": platform.python_version(),
            "python_can": can.__version__,
            "frames": args.frames,
            "rounds": args.rounds,
            "batch": BATCH,
            # send's hot path in C (canemu_speedups; CANEMU_SPEEDUPS=0 measures without it)
            "speedups": _vci.speedups() is not None,
        },
        "benchmarks": [
            entry("python_can_virtual_bus", virtual),
            entry("canemu_plugin_stepped", stepped),
            entry("canemu_plugin_realtime_1mbit", realtime),
        ],
        "canemu_over_virtual": ratios["round_trip"],
        "canemu_over_virtual_sent": ratios["sent"],
        "canemu_over_virtual_received": ratios["received"],
    }
    print(f"{'frames/s':32} {'sent':>10} {'received':>10} {'round trip':>11}")
    for b in result["benchmarks"]:
        print(f"{b['name']:32} {b['sent_frames_per_second']:>10} "
              f"{b['received_frames_per_second']:>10} {b['frames_per_second']:>11}")
    print(f"{'canemu (stepped) / virtual bus':32} {ratios['sent']:>10} {ratios['received']:>10} "
          f"{ratios['round_trip']:>11}")
    print(f"python-can round trip through canemu (stepped) / python-can's virtual bus: "
          f"{ratios['round_trip']} (median of {args.rounds} alternating rounds each; "
          f"issue 41's goal: >= 3)")
    if args.out:
        with open(args.out, "w") as f:
            json.dump(result, f, indent=2)


if __name__ == "__main__":
    main()
