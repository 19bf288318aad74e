"""python-can throughput: frames per second sent by one bus and received by another, through
canemu's interface and through python-can's own virtual bus, measured in the same run.

canemu runs in stepped time here, so that the figure is the interface's own cost (a real-time
bus at 1 Mbit/s carries at most about 8,000 such frames per second, whoever sends them); the
real-time figure at 1 Mbit/s is reported beside it. Writes JSON (--out) and prints a summary.

    python bench/python/python_can_bench.py --frames 20000 --out build/bench-results/python.json
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import can

import canemu
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


def round_trip(sender, receiver, total: int, advance=None) -> float:
    """Frames per second: `total` frames sent in batches by `sender` and all received by
    `receiver`; `advance()` moves stepped time when given."""
    start = time.perf_counter()
    sent = 0
    while sent < total:
        n = min(BATCH, total - sent)
        for k in range(n):
            sender.send(frame(sent + k))
        got = 0
        while got < n:
            if advance is not None:
                advance()
                timeout = 0
            else:
                timeout = 1.0
            while got < n:
                msg = receiver.recv(timeout)
                if msg is None:
                    if advance is None:
                        raise RuntimeError(f"received {got} of {n}")
                    break
                if not msg.is_error_frame:
                    got += 1
        sent += n
    return total / (time.perf_counter() - start)


def measure_canemu(time_mode: str, total: int) -> float:
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


def measure_virtual(total: int) -> float:
    a = can.Bus(interface="virtual", channel="bench", receive_own_messages=False)
    b = can.Bus(interface="virtual", channel="bench", receive_own_messages=False)
    try:
        round_trip(a, b, min(total, 1000))
        return round_trip(a, b, total)
    finally:
        a.shutdown()
        b.shutdown()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20000)
    parser.add_argument("--realtime-frames", type=int, default=4000)
    parser.add_argument("--out", help="JSON file to write")
    args = parser.parse_args()

    virtual = measure_virtual(args.frames)
    stepped = measure_canemu("stepped", args.frames)
    realtime = measure_canemu("realtime", args.realtime_frames)
    result = {
        "context": {
            "python": platform.python_version(),
            "python_can": can.__version__,
            "frames": args.frames,
            "batch": BATCH,
        },
        "benchmarks": [
            {"name": "python_can_virtual_bus", "frames_per_second": round(virtual)},
            {"name": "canemu_plugin_stepped", "frames_per_second": round(stepped)},
            {"name": "canemu_plugin_realtime_1mbit", "frames_per_second": round(realtime)},
        ],
        "canemu_over_virtual": round(stepped / virtual, 3),
    }
    for b in result["benchmarks"]:
        print(f"{b['name']:32} {b['frames_per_second']:>10} frames/s sent and received")
    print(f"canemu (stepped) / virtual bus: {result['canemu_over_virtual']}")
    if args.out:
        with open(args.out, "w") as f:
            json.dump(result, f, indent=2)


if __name__ == "__main__":
    main()
