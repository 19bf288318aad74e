"""What watching costs canemud: 16 buses at full load in real time (on each a babbling node,
python-can's in this process, and an acknowledging configured adapter's in a child; the babble
runs inside canemud), and canemud's CPU time (utime + stime of /proc/PID/stat) over equal
windows, alternately without `canemu web` and with it serving the page to headless chromium
(the page open; with the ID tables, and without them: --no-frames), all in one run. The figure is the difference in % of one core
between the median window with the page and the median without (target: under 2), with the
ratio, and the same per simulated second. As the tool and the browser load the 2-core machine,
which changes canemud's own figure, windows without the page but with one core kept busy by
another process are measured too, and the page compared with them.

    python bench/python/web_bench.py --seconds 10 --out build/bench-results/web.json
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import statistics
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
ACKERS = """
import sys
import can
buses = [can.Bus(interface="canemu", channel=f"ack{i // 2}:{i % 2}") for i in range(int(sys.argv[1]))]
print("ready", flush=True)
sys.stdin.read()
for b in buses:
    b.shutdown()
"""


def config(buses: int, bitrate: int, spin_us: int) -> str:
    """The buses, and IXXAT adapters of two controllers each whose nodes acknowledge (a process
    makes at most 16 adapters of its own: those babble)."""
    text = f'[simulation]\ntime = "realtime"\nspin_us = {spin_us}\n'
    for i in range(buses):
        text += f'[[bus]]\nname = "can{i}"\nkind = "can"\nbitrate = {bitrate}\n'
    for k in range((buses + 1) // 2):
        pair = [f'"can{i}"' for i in (2 * k, 2 * k + 1) if i < buses]
        text += (f'[[device]]\nname = "ack{k}"\nmodel = "ixxat-usb-to-can"\n'
                 f'controllers = [{", ".join(pair)}]\n')
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


def window(pid: int, seconds: float, cli: str, socket: str, extra=None) -> Dict[str, float]:
    """canemud's share of a core over `seconds`, its CPU per simulated second, and `extra`'s."""
    sim0 = status(cli, socket)["sim_time_ns"]
    t0, c0 = time.monotonic(), cpu_seconds(pid)
    e0 = extra() if extra else 0.0
    time.sleep(seconds)
    t1, c1 = time.monotonic(), cpu_seconds(pid)
    e1 = extra() if extra else 0.0
    sim1 = status(cli, socket)["sim_time_ns"]
    sim_s = (sim1 - sim0) / 1e9
    out = {"canemud_core_percent": 100.0 * (c1 - c0) / (t1 - t0),
           "canemud_cpu_per_sim_s": (c1 - c0) / sim_s, "sim_per_wall": sim_s / (t1 - t0)}
    if extra:
        out["web_core_percent"] = 100.0 * (e1 - e0) / (t1 - t0)
    return out


def status(cli: str, socket: str) -> dict:
    return json.loads(subprocess.run([cli, "--socket", socket, "status", "--json"], check=True,
                                     capture_output=True, text=True).stdout)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--buses", type=int, default=16)
    p.add_argument("--bitrate", type=int, default=500000)
    p.add_argument("--seconds", type=float, default=10.0, help="each window")
    p.add_argument("--rounds", type=int, default=3, help="windows with the page")
    p.add_argument("--spin-us", type=int, default=0,
                   help="[simulation] spin_us (default 0: no spinning, whose CPU time moves "
                        "with the machine's other load; canemud's default is 20)")
    p.add_argument("--out", help="the JSON file (default: standard output only)")
    args = p.parse_args()
    cli = str(Path(find_canemud()).with_name("canemu"))
    with Daemon(config(args.buses, args.bitrate, args.spin_us)) as daemon:
        nodes: List[can.BusABC] = []
        # A connection has at most 16 channels: the acknowledging nodes in a child process.
        ackers = subprocess.Popen(
            [sys.executable, "-c", ACKERS, str(args.buses)], stdin=subprocess.PIPE,
            stdout=subprocess.PIPE, text=True,
            env={**os.environ, "CANEMU_SOCKET": daemon.socket})
        if ackers.stdout.readline().strip() != "ready":
            raise RuntimeError("the acknowledging nodes did not start")
        babblers = {}
        for i in range(args.buses):
            nodes.append(can.Bus(interface="canemu", channel=f"can{i}"))
        for n in status(cli, daemon.socket)["nodes"]:
            if not n["name"].startswith("ack"):
                babblers[n["bus"]] = n["name"]
        scenario = '[scenario]\nname = "busy"\n'
        for i in range(args.buses):
            scenario += (f'[[fault]]\nat = "0s"\neffect = "babble"\nnode = "{babblers[f"can{i}"]}"\n'
                         f'id = {0x100 + i}\ndata = [1, 2, 3, 4, 5, 6, 7, 8]\n'
                         'duration = "3600s"\n')
        path = Path(daemon.dir, "busy.toml")
        path.write_text(scenario)
        done = subprocess.run([cli, "--socket", daemon.socket, "fault", "load", str(path)],
                              capture_output=True, text=True)
        if done.returncode != 0:
            raise RuntimeError(f"the babble scenario: {done.stderr}")
        time.sleep(2.0)  # warming up
        pid = daemon.proc.pid
        without: List[Dict[str, float]] = [window(pid, args.seconds, cli, daemon.socket)]
        with_page: List[Dict[str, float]] = []
        pages: List[Dict[str, float]] = []
        burning: List[Dict[str, float]] = []
        no_frames: List[Dict[str, float]] = []
        for _ in range(args.rounds):
            with Page(cli, daemon.socket) as page:
                with_page.append(window(pid, args.seconds, cli, daemon.socket,
                                        lambda: tree_cpu_seconds(page.web.pid)))
            pages.append(page.info)
            time.sleep(1.0)
            with Page(cli, daemon.socket, "--no-frames") as page:  # what the ID tables cost
                no_frames.append(window(pid, args.seconds, cli, daemon.socket,
                                        lambda: tree_cpu_seconds(page.web.pid)))
            time.sleep(1.0)
            without.append(window(pid, args.seconds, cli, daemon.socket))
            # The control: no page, but a process keeping one core busy, as the tool and the
            # browser keep the machine busy (canemud's own figure moves with such load).
            burner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
            burning.append(window(pid, args.seconds, cli, daemon.socket))
            burner.kill()
            burner.wait()
            time.sleep(1.0)
        s = status(cli, daemon.socket)
        for n in nodes:
            n.shutdown()
        ackers.stdin.close()
        ackers.wait(30)
    median = statistics.median
    base = median(w["canemud_core_percent"] for w in without)
    shown = median(w["canemud_core_percent"] for w in with_page)
    base_per_sim = median(w["canemud_cpu_per_sim_s"] for w in without)
    shown_per_sim = median(w["canemud_cpu_per_sim_s"] for w in with_page)
    figures = {
        "machine": platform.node(), "cpus": os.cpu_count(), "buses": args.buses,
        "bitrate": args.bitrate, "window_s": args.seconds, "rounds": args.rounds,
        "spin_us": args.spin_us,
        "bus_load_percent_min": min(b["load_percent"] for b in s["buses"]),
        "canemud_core_percent_without_page": [round(w["canemud_core_percent"], 2)
                                              for w in without],
        "canemud_core_percent_with_page": [round(w["canemud_core_percent"], 2)
                                           for w in with_page],
        "page_cost_core_percent": round(shown - base, 2),
        "page_cost_ratio": round(shown / base, 3) if base else None,
        "canemud_core_percent_with_page_no_frames": [
            round(w["canemud_core_percent"], 2) for w in no_frames],
        "page_no_frames_cost_core_percent": round(
            median(w["canemud_core_percent"] for w in no_frames) - base, 2),
        "canemu_web_no_frames_core_percent": [round(w["web_core_percent"], 1)
                                              for w in no_frames],
        "canemud_core_percent_without_page_one_core_busy": [
            round(w["canemud_core_percent"], 2) for w in burning],
        "page_cost_core_percent_against_busy_core": round(
            shown - median(w["canemud_core_percent"] for w in burning), 2),
        "page_cost_core_percent_per_simulated_second": round(
            100.0 * (shown_per_sim - base_per_sim), 2),
        "sim_seconds_per_second_with_page": [round(w["sim_per_wall"], 3) for w in with_page],
        "canemu_web_core_percent": [round(w["web_core_percent"], 1) for w in with_page],
        "page": pages,
        "target_core_percent": 2.0,
    }
    text = json.dumps(figures, indent=2)
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")
    return 0


class Page:
    """canemu web with its page open in headless chromium, for as long as the `with`."""

    def __init__(self, cli: str, socket: str, *options: str) -> None:
        env = {**os.environ, "CANEMU_PYTHON": sys.executable}
        self.web = subprocess.Popen([cli, "--socket", socket, "web", "--listen", "127.0.0.1:0",
                                     *options], stderr=subprocess.PIPE, env=env, text=True)
        self.url = re.search(r"(http://\S+/)", self.web.stderr.readline()).group(1)
        threading.Thread(target=self.web.stderr.read, daemon=True).start()
        self.info: Dict[str, float] = {}
        self._stop = threading.Event()
        self._opened = threading.Event()
        self._browser = threading.Thread(target=self._browse, daemon=True)

    def _browse(self) -> None:
        from playwright.sync_api import sync_playwright

        with sync_playwright() as pw:
            ctx = pw.chromium.launch_persistent_context(
                tempfile.mkdtemp(prefix="canemu-web-bench-"),
                executable_path="/usr/bin/chromium", headless=True,
                args=["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                      "--disable-background-networking", "--disable-component-update",
                      "--disable-sync"])
            page = ctx.new_page()
            page.goto(self.url)
            page.wait_for_function("window.canemuView && window.canemuView.updates > 2")
            self._opened.set()
            self._stop.wait()
            handled = page.evaluate("window.canemuView.handleMs")[1:]  # after the snapshot
            self.info = {"updates": page.evaluate("window.canemuView.updates"),
                         "update_handled_median_ms": round(statistics.median(handled), 1),
                         "update_handled_max_ms": round(max(handled), 1)}
            ctx.close()

    def __enter__(self) -> "Page":
        self._browser.start()
        if not self._opened.wait(60):
            raise RuntimeError("the page did not open")
        time.sleep(2.0)  # the ID tables' nodes are on the buses, the page drawing
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._browser.join(60)
        self.web.terminate()
        self.web.wait(10)


if __name__ == "__main__":
    sys.exit(main())
