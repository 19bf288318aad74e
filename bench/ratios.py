"""Issue 41's figures from one `make bench` run: each a ratio (or a count) whose both sides were
measured in the same run, beside its goal. `make bench` prints them last.

    python bench/ratios.py build/bench-results

Reads instructions.json, daemon.json, python.json and busy_receivers.json; a figure whose file
or benchmark is missing is shown as such.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple

SPINS = (0, 50, 200, 1000)


def load(folder: Path, name: str) -> Optional[Dict[str, Any]]:
    try:
        return json.loads((folder / name).read_text())
    except (OSError, ValueError):
        return None


def counter(data: Optional[Dict[str, Any]], benchmark: str, key: str) -> Optional[float]:
    """A figure of the Google Benchmark entry whose name starts with `benchmark`."""
    for entry in (data or {}).get("benchmarks", []):
        if str(entry.get("name", "")).startswith(benchmark) and key in entry:
            return float(entry[key])
    return None


def rows(folder: Path) -> List[Tuple[str, List[Optional[float]], str, Callable[[float], bool]]]:
    instructions = load(folder, "instructions.json")
    daemon = load(folder, "daemon.json")
    python = load(folder, "python.json")
    busy = load(folder, "busy_receivers.json")

    def latency(spin: int, idle_poll: int, key: str) -> Optional[float]:
        return counter(daemon, f"BM_ClientDaemonClientLatencyRealtime/spin_us:{spin}/"
                       f"idle_poll:{idle_poll}/", key)

    def hop(spin: int, local_link: int, key: str) -> Optional[float]:
        return counter(daemon, f"BM_DdsHopLatencyRealtime/spin_us:{spin}/local_link:{local_link}/",
                       key)

    held = all(latency(s, 1, "idle_poll_held") in (1, None) for s in SPINS)
    out = [
        ("engine, 4 nodes at full load: instructions per frame (callgrind)",
         [counter(instructions, "BM_EngineInstructionsPerFrame/nodes:4", "instructions_per_frame")],
         "<= 1000", lambda v: v <= 1000),
        ("canemud CPU per bus frame / engine's, 64 busy buses, real time",
         [counter(daemon, "BM_BusyBusesRealtime/buses:64/batch_us:50/batch_max_us:1000/",
                  "canemud_over_engine_cpu")],
         "<= 2", lambda v: v <= 2),
        ("client -> canemud -> client p50 / Unix socket p50, spin 0 50 200 1000",
         [latency(s, 0, "beyond_frame_over_unix_socket_p50") for s in SPINS],
         "<= 1.5", lambda v: v <= 1.5),
        ("  the same, canemud with cpu_latency_us = 0 (idle CPUs poll)" +
         ("" if held else "\n    canemud could not make the request (not root?): as without it"),
         [latency(s, 1, "beyond_frame_over_unix_socket_p50") for s in SPINS],
         "<= 1.5", lambda v: v <= 1.5),
        ("two daemons b to b / one canemud, p50, spin 0 200 (same-host link)",
         [hop(s, 1, "b_to_b_over_one_daemon_p50") for s in (0, 200)],
         "<= 2", lambda v: v <= 2),
        ("  the same, p99",
         [hop(s, 1, "b_to_b_over_one_daemon_p99") for s in (0, 200)],
         "<= 3", lambda v: v <= 3),
        ("  the same over DDS (local_link = false, as between hosts), p50",
         [hop(s, 0, "b_to_b_over_one_daemon_p50") for s in (0, 200)],
         "<= 2", lambda v: v <= 2),
        ("  the same over DDS, p99",
         [hop(s, 0, "b_to_b_over_one_daemon_p99") for s in (0, 200)],
         "<= 3", lambda v: v <= 3),
        ("python-can round trip, canemu / virtual bus",
         [float(python["canemu_over_virtual"]) if python else None],
         ">= 3", lambda v: v >= 3),
    ]
    for n in (64, 256):
        lost: Optional[float] = None
        why = ""
        for entry in (busy or {}).get("benchmarks", []):
            if entry.get("buses") == n:
                lost = float(entry["frames_lost"]) if "frames_lost" in entry else None
                why = f"\n    {entry['error']}" if "error" in entry else ""
        out.append((f"{n} busy buses + {n} python-can receivers: frames lost{why}", [lost], "0",
                    lambda v: v == 0))
    return out


def main() -> None:
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "build/bench-results")
    print("issue 41's figures (both sides measured in this run):")
    for what, values, goal, met in rows(folder):
        shown = " ".join("missing" if v is None else f"{v:.3g}" if v < 1000 else f"{v:.0f}"
                         for v in values)
        known = [v for v in values if v is not None]
        verdict = "met" if known and len(known) == len(values) and all(map(met, known)) else \
            "NOT met" if known else "not measured"
        what, _, note = what.partition("\n")
        print(f"  {what:72} {shown:24} goal {goal:8} {verdict}")
        if note:
            print(note)


if __name__ == "__main__":
    main()
