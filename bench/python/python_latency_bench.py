"""python-can latency in real time: one canemu bus sends a frame, another waits for it in
`recv(timeout)`; the figure is the time from `send` until `recv` returns with the frame, minus
the frame's own time on the wire at 1 Mbit/s (p50, p99, max in microseconds). The interface
blocks on the receive ring's eventfd at once (it does not spin), so this is the python-can
counterpart of daemon_bench's spin sweep (BM_ClientDaemonClientLatencyRealtime) and vci_bench.
`recv(0)` polling in a loop (a spinning application) is measured beside it.

    python bench/python/python_latency_bench.py --samples 2000 --out build/bench-results/python_latency.json
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import subprocess
import time
from typing import Dict, List

import can

from canemu.testing import Daemon, find_canemud

CONFIG = """
[simulation]
time = "realtime"

[[bus]]
name = "can0"
kind = "can"
bitrate = 1000000
"""

# 0x123 with 8 bytes 11 22 .. 88, received at the end of its end of frame.
MESSAGE = can.Message(arbitration_id=0x123, data=bytes(0x11 * (k + 1) for k in range(8)),
                      is_extended_id=False)
GAP_S = 0.0005  # the bus is idle again long before the next frame


def percentile(samples: List[int], p: float) -> float:
    ordered = sorted(samples)
    return ordered[min(len(ordered) - 1, int(p * (len(ordered) - 1) + 0.5))] / 1000.0


def wire_ns() -> int:
    """The frame's length on the wire, from canemu's own calculator (one bit is 1 us)."""
    canemu_cli = os.path.join(os.path.dirname(find_canemud()), "canemu")
    out = subprocess.run([canemu_cli, "calc", "frame", "123#1122334455667788"], check=True,
                         capture_output=True, text=True).stdout
    bits = re.search(r"^bits: (\d+)", out, re.MULTILINE)
    if bits is None:
        raise RuntimeError(f"no bit count in: {out}")
    return int(bits.group(1)) * 1000


def measure(samples: int, spin: bool) -> List[int]:
    beyond: List[int] = []
    with Daemon(CONFIG):
        a = can.Bus(interface="canemu", channel="can0")
        b = can.Bus(interface="canemu", channel="can0")
        wire = wire_ns()
        try:
            for _ in range(samples):
                time.sleep(GAP_S)
                t0 = time.perf_counter_ns()
                a.send(MESSAGE)
                if spin:
                    got = None
                    deadline = t0 + 1_000_000_000
                    while got is None and time.perf_counter_ns() < deadline:
                        got = b.recv(0)
                else:
                    got = b.recv(1.0)
                t1 = time.perf_counter_ns()
                if got is None:
                    raise RuntimeError("the frame did not arrive")
                beyond.append(t1 - t0 - wire)
        finally:
            a.shutdown()
            b.shutdown()
    return beyond


def figures(name: str, beyond: List[int]) -> Dict[str, object]:
    return {
        "name": name,
        "beyond_frame_p50_us": percentile(beyond, 0.50),
        "beyond_frame_p99_us": percentile(beyond, 0.99),
        "beyond_frame_max_us": max(beyond) / 1000.0,
        "samples": len(beyond),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=2000)
    parser.add_argument("--out", help="JSON file to write")
    args = parser.parse_args()
    result = {
        "context": {"python": platform.python_version(), "python_can": can.__version__},
        "benchmarks": [
            figures("python_can_recv_blocking", measure(args.samples, spin=False)),
            figures("python_can_recv_polling", measure(args.samples, spin=True)),
        ],
    }
    for b in result["benchmarks"]:
        print(f"{b['name']:28} beyond the frame: p50 {b['beyond_frame_p50_us']:.1f} us, "
              f"p99 {b['beyond_frame_p99_us']:.1f} us, max {b['beyond_frame_max_us']:.1f} us")
    if args.out:
        with open(args.out, "w") as f:
            json.dump(result, f, indent=2)


if __name__ == "__main__":
    main()
