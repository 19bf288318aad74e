"""What watching costs canemud: 16 buses at full load in real time (a babbling node and an
acknowledging one on each, both python-can nodes of this process; the babble runs inside
canemud), and canemud's CPU time (utime + stime of /proc/PID/stat) over equal windows without
the page, with `canemu web` serving it to headless chromium (the page open, ID tables on), and
without it again, all in one run. The figure is the difference in % of one core between the
window with the page and the mean of the two without (target: under 2), with the ratio.

    python bench/python/web_bench.py --seconds 10 --out build/bench-results/web.json
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Dict, List

import can

from canemu.testing import Daemon, find_canemud

TICK = os.sysconf("SC_CLK_TCK")


def config(buses: int, bitrate: int) -> str:
    text = '[simulation]\ntime = "realtime"\n'
    for i in range(buses):
        text += f'[[bus]]\nname = "can{i}"\nkind = "can"\nbitrate = {bitrate}\n'
    return text


def cpu_seconds(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK  # utime, stime


def tree_cpu_seconds(pid: int) -> float:
    """A process and its children still running (canemu web: python, its dump)."""
    total = 0.0
    pids = [pid]
    while pids:
        p = pids.pop()
        try:
            total += cpu_seconds(p)
            with open(f"/proc/{p}/task/{p}/children") as f:
                pids += [int(x) for x in f.read().split()]
        except OSError:
            pass
    return total


def window(pid: int, seconds: float, extra=None) -> Dict[str, float]:
    t0, c0 = time.monotonic(), cpu_seconds(pid)
    e0 = extra() if extra else 0.0
    time.sleep(seconds)
    t1, c1 = time.monotonic(), cpu_seconds(pid)
    out = {"canemud_core_percent": 100.0 * (c1 - c0) / (t1 - t0)}
    if extra:
        out["web_core_percent"] = 100.0 * (extra() - e0) / (t1 - t0)
    return out


def status(cli: str, socket: str) -> dict:
    return json.loads(subprocess.run([cli, "--socket", socket, "status", "--json"], check=True,
                                     capture_output=True, text=True).stdout)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--buses", type=int, default=16)
    p.add_argument("--bitrate", type=int, default=500000)
    p.add_argument("--seconds", type=float, default=10.0, help="each window")
    p.add_argument("--out", help="the JSON file (default: standard output only)")
    args = p.parse_args()
    cli = str(Path(find_canemud()).with_name("canemu"))
    with Daemon(config(args.buses, args.bitrate)) as daemon:
        nodes: List[can.BusABC] = []
        for i in range(args.buses):
            nodes.append(can.Bus(interface="canemu", channel=f"can{i}"))
            nodes.append(can.Bus(interface="canemu", channel=f"can{i}"))
        names: Dict[str, List[str]] = {}
        for n in status(cli, daemon.socket)["nodes"]:
            names.setdefault(n["bus"], []).append(n["name"])
        scenario = '[scenario]\nname = "busy"\n'
        for i in range(args.buses):
            scenario += (f'[[fault]]\neffect = "babble"\nnode = "{names[f"can{i}"][0]}"\n'
                         f'id = {0x100 + i}\ndata = [1, 2, 3, 4, 5, 6, 7, 8]\n'
                         'duration = "3600s"\n')
        path = Path(daemon.dir, "busy.toml")
        path.write_text(scenario)
        subprocess.run([cli, "--socket", daemon.socket, "fault", "load", str(path)], check=True,
                       capture_output=True)
        time.sleep(2.0)  # warming up
        pid = daemon.proc.pid
        without_1 = window(pid, args.seconds)
        env = {**os.environ, "CANEMU_PYTHON": sys.executable}
        web = subprocess.Popen([cli, "--socket", daemon.socket, "web", "--listen",
                                "127.0.0.1:0"], stderr=subprocess.PIPE, env=env, text=True)
        line = web.stderr.readline()
        url = re.search(r"(http://\S+/)", line).group(1)
        threading.Thread(target=web.stderr.read, daemon=True).start()
        page_info: Dict[str, float] = {}
        stop = threading.Event()
        opened = threading.Event()

        def browse() -> None:
            from playwright.sync_api import sync_playwright

            with sync_playwright() as pw:
                ctx = pw.chromium.launch_persistent_context(
                    tempfile.mkdtemp(prefix="canemu-web-bench-"),
                    executable_path="/usr/bin/chromium", headless=True,
                    args=["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                          "--disable-background-networking", "--disable-component-update",
                          "--disable-sync"])
                page = ctx.new_page()
                page.goto(url)
                page.wait_for_function("window.canemuView && window.canemuView.updates > 2")
                opened.set()
                stop.wait()
                handled = page.evaluate("window.canemuView.handleMs")
                page_info["updates"] = page.evaluate("window.canemuView.updates")
                page_info["update_handled_max_ms"] = max(handled)
                page_info["update_handled_median_ms"] = sorted(handled)[len(handled) // 2]
                ctx.close()

        browser = threading.Thread(target=browse, daemon=True)
        browser.start()
        if not opened.wait(60):
            raise RuntimeError("the page did not open")
        time.sleep(2.0)
        with_page = window(pid, args.seconds, lambda: tree_cpu_seconds(web.pid))
        stop.set()
        browser.join(60)
        web.terminate()
        web.wait(10)
        time.sleep(2.0)
        without_2 = window(pid, args.seconds)
        s = status(cli, daemon.socket)
        for n in nodes:
            n.shutdown()
    base = (without_1["canemud_core_percent"] + without_2["canemud_core_percent"]) / 2
    figures = {
        "machine": platform.node(), "cpus": os.cpu_count(), "buses": args.buses,
        "bitrate": args.bitrate, "window_s": args.seconds,
        "bus_load_percent": [b["load_percent"] for b in s["buses"]],
        "canemud_core_percent_without_page": [round(without_1["canemud_core_percent"], 2),
                                              round(without_2["canemud_core_percent"], 2)],
        "canemud_core_percent_with_page": round(with_page["canemud_core_percent"], 2),
        "page_cost_core_percent": round(with_page["canemud_core_percent"] - base, 2),
        "page_cost_ratio": round(with_page["canemud_core_percent"] / base, 3) if base else None,
        "canemu_web_core_percent": round(with_page["web_core_percent"], 1),
        "page": page_info,
        "target_core_percent": 2.0,
    }
    text = json.dumps(figures, indent=2)
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
