"""A test bench: a private canemud, the buses' traces, fault injection and expectations that wait
for what they expect, in simulated time when time is stepped. The pytest plugin
(canemu.pytest_plugin, docs/testing.md) hands one to every test as the `canemu` fixture; it
works without pytest as well:

    with Bench(config_text, trace_dir="out", time="stepped") as bench:
        bus = bench.bus("can0")
        bus.send(can.Message(arbitration_id=0x123, data=b"\\x01", is_extended_id=False))
        frame = bench.expect_frame("can0", id=0x123, within=10)   # ms of simulated time

Every CAN bus of the configuration is recorded by canemud itself into a candump log and a pcap
file in `trace_dir` (a LIN bus into a pcap file): the expectations read the candump logs, and
a failing test's report shows them.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

try:
    import tomllib
except ImportError:  # pragma: no cover - Python 3.9 and 3.10
    import tomli as tomllib

from . import _daemon, _vci
from ._program import ExpectationFailed, Program
from ._trace import Duration, Frame, Watch, duration_ns, parse_candump_line
from .testing import Daemon, find_canemud

__all__ = ["Bench", "CanemudDied", "Duration", "ExpectationFailed", "Frame", "Node", "Program",
           "duration_ns", "find_canemu", "parse_candump_line"]


def find_canemu() -> str:
    """The canemu command line: $CANEMU, else the one beside find_canemud()'s canemud, else
    canemu on PATH."""
    if os.environ.get("CANEMU"):
        return os.environ["CANEMU"]
    try:
        beside = Path(find_canemud()).with_name("canemu")
        if beside.exists():
            return str(beside)
    except FileNotFoundError:
        pass
    found = shutil.which("canemu")
    if found is None:
        raise FileNotFoundError("canemu not found: build canemu or set CANEMU")
    return found


class CanemudDied(RuntimeError):
    """canemud ended while a test used it."""


@dataclass
class Node:
    """A node as `canemu status --json` lists it."""

    name: str
    bus: str
    state: str  # init, error-active, warning, error-passive, bus-off; LIN: offline, online
    tec: int
    rec: int
    frames_sent: int
    frames_received: int
    errors: int

    def __str__(self) -> str:
        return (f"{self.name} on {self.bus}: {self.state}, TEC {self.tec}, REC {self.rec}, "
                f"{self.frames_sent} sent, {self.frames_received} received, "
                f"{self.errors} errors")

class Bench:
    """A private canemud and what a test does with it.

    :param config: the configuration's text (TOML); None: canemud's embedded default.
    :param trace_dir: where the traces, canemud's log and programs' output go (kept).
    :param time: "realtime", "stepped" or "scaled:F"; None: what the configuration says.
    :param config_dir: a folder whose files the configuration names by relative path (its own
        folder): they are linked into canemud's folder.
    :param files: more files for canemud's folder (name -> text).
    :param canemud: the program; default canemu.testing.find_canemud().
    """

    def __init__(self, config: Optional[str] = None, *, trace_dir: Union[str, Path],
                 time: Optional[str] = None, config_dir: Optional[Union[str, Path]] = None,
                 files: Optional[Mapping[str, str]] = None, canemud: Optional[str] = None,
                 timeout: float = 10.0) -> None:
        self.trace_dir = Path(trace_dir).resolve()
        self.trace_dir.mkdir(parents=True, exist_ok=True)
        self.log_path = self.trace_dir / "canemud.log"
        self._canemud = canemud or find_canemud()
        self._canemu = find_canemu()
        if config is None:
            config = subprocess.run([self._canemud, "--print-default-config"], check=True,
                                    capture_output=True, text=True).stdout
        try:
            parsed = tomllib.loads(config)
        except tomllib.TOMLDecodeError as e:
            raise ValueError(f"the configuration is not TOML: {e}") from None
        self.buses: Dict[str, str] = {
            str(b.get("name")): str(b.get("kind", "can")) for b in parsed.get("bus", [])
        }
        self.traces: Dict[str, Dict[str, Path]] = {}
        extra = []
        for name, kind in self.buses.items():
            pcap = self.trace_dir / f"{name}.pcap"
            self.traces[name] = {"pcap": pcap}
            extra.append(f"\n[[recorder]]\nbus = {_toml(name)}\npath = {_toml(str(pcap))}\n")
            if kind != "lin":
                log = self.trace_dir / f"{name}.log"
                self.traces[name]["candump"] = log
                extra.append(f"\n[[recorder]]\nbus = {_toml(name)}\npath = {_toml(str(log))}\n"
                             'format = "candump"\n')
        links = {}
        if config_dir is not None:
            links = {p.name: p.resolve() for p in Path(config_dir).iterdir()}
        self._offsets: Dict[str, int] = {}
        self._pending: Dict[str, List[Frame]] = {}
        self._buses: List[Any] = []
        self._programs: List[Program] = []
        self._watch: Optional[Watch] = None
        self._scenarios = 0
        self._told_dead = False
        self.time_mode = time
        try:
            self.daemon = Daemon(config + "".join(extra), files=dict(files or {}),
                                 canemud=self._canemud, timeout=timeout,
                                 args=["--time", time] if time else (), links=links)
        except RuntimeError as e:
            self.log_path.write_text(str(e))
            raise
        self.socket = self.daemon.socket
        self._watch = Watch(self.trace_dir)
        _, mode = _daemon.sim_time()
        self.stepped = mode == _vci.CANEMU_TIME_STEPPED
        self.scale = 1.0
        if mode == _vci.CANEMU_TIME_SCALED:
            scaled = [a for a in (time or "", str(parsed.get("simulation", {}).get("time", "")))
                      if a.startswith("scaled:")]
            self.scale = float(scaled[0].split(":", 1)[1]) if scaled else 1.0

    # -- canemud as a whole -------------------------------------------------------------------

    def _alive(self) -> None:
        """CanemudDied, naming its log, when canemud is gone."""
        status = self.daemon.proc.poll()
        if status is not None:
            self.log_path.write_text(self.daemon.log)
            tail = "\n".join(self.daemon.log.splitlines()[-15:])
            self._told_dead = True
            raise CanemudDied(f"canemud exited with status {status} during the test; its log: "
                              f"{self.log_path}\n{tail}")

    def cli(self, *args: str, check: bool = True) -> str:
        """`canemu ARGS` against this canemud; its standard output. RuntimeError with its
        message when it fails (and `check`)."""
        self._alive()
        done = subprocess.run([self._canemu, "--socket", self.socket, *args], text=True,
                              capture_output=True, timeout=60)
        if check and done.returncode != 0:
            self._alive()
            raise RuntimeError(f"canemu {' '.join(args)}: {done.stderr.strip() or done.stdout}")
        return done.stdout

    def status(self) -> Dict[str, Any]:
        """`canemu status --json`: buses, nodes, devices, clients, faults, recorders."""
        return json.loads(self.cli("status", "--json"))

    def node(self, name: str) -> Node:
        """A node's state and counters now. KeyError naming the nodes there are."""
        nodes = self.status()["nodes"]
        for n in nodes:
            if n["name"] == name:
                return Node(name=n["name"], bus=n["bus"], state=n["state"], tec=n["tec"],
                            rec=n["rec"], frames_sent=n["frames_sent"],
                            frames_received=n["frames_received"], errors=n["errors"])
        raise KeyError(f"no node {name!r}; there are: {', '.join(n['name'] for n in nodes)}")

    def now(self) -> float:
        """Simulated time in seconds."""
        self._alive()
        return _daemon.sim_time()[0] / 1e9

    def step(self, ms: Duration) -> float:
        """Stepped time: runs the emulation `ms` further (a number of ms, or "150us"); returns
        the simulated time in seconds after it."""
        self._alive()
        try:
            return _daemon.step(duration_ns(ms)) / 1e9
        except Exception:
            self._alive()
            raise

    def bus(self, channel: str, **kwargs: Any):
        """A python-can bus of interface canemu on `channel` (a bus name or an adapter's
        "DEVICE:N"), shut down when the bench ends."""
        import can

        self._alive()
        b = can.Bus(interface="canemu", channel=channel, **kwargs)
        self._buses.append(b)
        return b

    # -- faults ---------------------------------------------------------------------------------

    def inject(self, effect: Optional[str] = None, *, scenario: Optional[str] = None,
               name: Optional[str] = None, **keys: Any) -> str:
        """Applies a fault scenario from now on (docs/faults.md), checked by canemud as a file
        is: either one fault given by its keys (``inject("bit_error", bus="can0",
        match={"id": 0x123}, count=3)``, ``inject("bus_off", node="ixxat0:0", at="5ms")``), or
        a whole scenario's TOML text (``inject(scenario=text)``). Returns the scenario's name.
        RuntimeError with canemud's reasons when it refuses it."""
        if (effect is None) == (scenario is None):
            raise ValueError("inject: give an effect and its keys, or scenario=TOML text")
        if scenario is not None and (keys or name):
            raise ValueError("inject: scenario=TOML text takes no other keys")
        self._scenarios += 1
        path = self.trace_dir / f"scenario-{self._scenarios}.toml"
        if scenario is None:
            name = name or f"inject-{self._scenarios}"
            lines = ["[scenario]", f"name = {_toml(name)}", "", "[[fault]]",
                     f"effect = {_toml(effect)}"]
            keys.setdefault("at", "0s")  # from now: the scenario starts when it is loaded
            lines += [f"{k} = {_toml(v)}" for k, v in keys.items()]
            scenario = "\n".join(lines) + "\n"
        else:
            declared = tomllib.loads(scenario).get("scenario", {}).get("name")
            name = declared or path.stem  # canemud's default: the file's name
        path.write_text(scenario)
        self.cli("fault", "load", str(path))
        return name

    # -- expectations ---------------------------------------------------------------------------

    def frames(self, bus: str) -> List[Frame]:
        """The frames of `bus` recorded so far that no expectation took yet (and takes them)."""
        self._read(bus)
        out, self._pending[bus] = self._pending.get(bus, []), []
        return out

    def _trace(self, bus: str) -> Path:
        if bus not in self.traces:
            raise KeyError(f"no bus {bus!r}; there are: {', '.join(self.traces)}")
        if "candump" not in self.traces[bus]:
            raise ValueError(f"{bus} is a LIN bus: its trace is {self.traces[bus]['pcap']} "
                             "(pcap); expect_frame reads CAN buses")
        return self.traces[bus]["candump"]

    def _read(self, bus: str) -> None:
        path = self._trace(bus)
        pending = self._pending.setdefault(bus, [])
        try:
            with open(path, "rb") as f:
                f.seek(self._offsets.get(bus, 0))
                chunk = f.read()
        except FileNotFoundError:
            return
        whole = chunk[: chunk.rfind(b"\n") + 1]
        self._offsets[bus] = self._offsets.get(bus, 0) + len(whole)
        for line in whole.decode(errors="replace").splitlines():
            frame = parse_candump_line(line)
            if frame is not None:
                pending.append(frame)

    def _wait(self, within: Duration, resolution: Duration, done, describe) -> Any:
        """Steps (stepped time) or waits (real and scaled time) until done() gives something
        other than None, for `within` of simulated time; ExpectationFailed with describe()."""
        span = duration_ns(within)
        if self.stepped:
            slice_ns = max(duration_ns(resolution), 1)
            waited = 0
            while True:
                got = done()
                if got is not None:
                    return got
                if waited >= span:
                    break
                step = min(slice_ns, span - waited)
                self.step(f"{step}ns")
                waited += step
        else:
            deadline = time.monotonic() + span / 1e9 / self.scale
            poll = max(duration_ns(resolution) / 1e9, 0.001)
            while True:
                self._alive()
                got = done()
                if got is not None:
                    return got
                left = deadline - time.monotonic()
                if left <= 0:
                    break
                assert self._watch is not None
                self._watch.wait(min(left, poll))  # a recorder's write ends the wait early
        self._alive()
        raise ExpectationFailed(describe())

    def expect_frame(self, bus: str, id: Optional[int] = None, data: Optional[bytes] = None, *,
                     within: Duration = 100, extended: Optional[bool] = None,
                     error: bool = False, resolution: Duration = 1) -> Frame:
        """Waits for a frame on `bus` matching `id` (and `data`, `extended`; error frames only
        with `error=True`) among those recorded since the previous expectation on that bus
        took one; returns it, and the frames before it are taken too. `within`: simulated time
        (a number of ms or "2s"); stepped time is stepped `resolution` at a time until then.
        ExpectationFailed lists the frames that came instead."""
        want = bytes(data) if data is not None else None
        seen: List[Frame] = []
        self._trace(bus)

        def match() -> Optional[Frame]:
            self._read(bus)
            pending = self._pending[bus]
            while pending:
                frame = pending.pop(0)
                seen.append(frame)
                if (frame.is_error_frame == error and (id is None or frame.id == id)
                        and (want is None or frame.data == want)
                        and (extended is None or frame.is_extended_id == extended)):
                    return frame
            return None

        def describe() -> str:
            what = [f"id 0x{id:X}" if id is not None else "any id"]
            if want is not None:
                what.append(f"data {want.hex().upper() or '(none)'}")
            text = f"no frame with {', '.join(what)} on {bus} within {_show(within)}"
            trace = self.traces[bus]["candump"]
            if not seen:
                return text + f"; nothing came on {bus} (trace: {trace})"
            last = seen[-10:]
            text += (f"; {len(seen)} frame(s) came instead, the last {len(last)}:\n  "
                     + "\n  ".join(map(str, last)))
            if id is not None:
                near = sorted(seen, key=lambda f: (abs(f.id - id), f.timestamp))[:5]
                text += "\nthe nearest identifiers:\n  " + "\n  ".join(map(str, near))
            return text + f"\ntrace: {trace}"

        return self._wait(within, resolution, match, describe)

    def expect_state(self, node: str, state: str, *, within: Duration = 100,
                     resolution: Duration = 1) -> Node:
        """Waits until `node` is in `state`, as `canemu status` names it: "error-active" (both
        counters below 96), "warning" (one at 96 or above), "error-passive", "bus-off", "init"
        (not started); a LIN node "offline", "online". Returns the node then. `within`,
        `resolution` as for expect_frame. ExpectationFailed gives the node's state and counters
        at the end."""
        states = {"init", "error-active", "warning", "error-passive", "bus-off", "offline",
                  "online"}
        if state not in states:
            raise ValueError(f"state {state!r}: one of {', '.join(sorted(states))}")
        last: List[Node] = []

        def reached() -> Optional[Node]:
            n = self.node(node)
            last[:] = [n]
            return n if n.state == state else None

        def describe() -> str:
            return f"{node} not {state} within {_show(within)}: {last[0] if last else node}"

        return self._wait(within, resolution, reached, describe)

    # -- programs under test --------------------------------------------------------------------

    def start(self, args: Sequence[str], env: Optional[Mapping[str, str]] = None,
              cwd: Optional[Union[str, Path]] = None) -> Program:
        """Starts a program under test with CANEMU_SOCKET naming this canemud; its output goes
        to files in the trace folder. It is killed when the bench ends, if still running."""
        self._alive()
        n = len(self._programs) + 1
        base = Path(args[0]).name
        out = self.trace_dir / f"program-{n}-{base}.out"
        err = self.trace_dir / f"program-{n}-{base}.err"
        environment = {**os.environ, **(env or {}), "CANEMU_SOCKET": self.socket}
        with open(out, "wb") as o, open(err, "wb") as e:
            proc = subprocess.Popen(list(args), stdout=o, stderr=e, env=environment, cwd=cwd)
        program = Program(list(args), proc, out, err, _watch=self._watch)
        self._programs.append(program)
        return program

    def run(self, args: Sequence[str], timeout: float = 30.0,
            env: Optional[Mapping[str, str]] = None,
            cwd: Optional[Union[str, Path]] = None) -> Program:
        """start() and wait() (real or scaled time; in stepped time a program that waits for
        the bus needs start() and steps)."""
        program = self.start(args, env, cwd)
        program.wait(timeout)
        return program

    # -- the end --------------------------------------------------------------------------------

    def report(self, lines: int = 40) -> List[Tuple[str, str]]:
        """(title, text) sections for a failing test: canemud's status and the end of each
        bus's trace, with the files' paths."""
        sections = []
        if self.daemon.proc.poll() is None:
            try:
                sections.append(("canemu status", self.cli("status")))
            except Exception as e:  # the report must not fail the report
                sections.append(("canemu status", f"(not available: {e})"))
        else:
            self.log_path.write_text(self.daemon.log)
            sections.append(("canemud", f"exited with status {self.daemon.proc.returncode}; "
                                        f"its log: {self.log_path}"))
        for bus, files in self.traces.items():
            if "candump" in files and files["candump"].exists():
                text = files["candump"].read_text(errors="replace").splitlines()
                shown = text[-lines:]
                head = (f"{len(text)} record(s) in {files['candump']} (and {files['pcap']})"
                        + (f"; the last {len(shown)}" if len(shown) < len(text) else ""))
                sections.append((f"canemu trace {bus}", "\n".join([head, *shown])))
            else:
                sections.append((f"canemu trace {bus}", f"pcap: {files['pcap']}"))
        for p in self._programs:
            sections.append((f"program {' '.join(p.args)}", p.stdout + p.stderr))
        return sections

    def close(self) -> None:
        """Stops programs, buses and canemud; writes canemud's log into the trace folder.
        CanemudDied, naming the log, when canemud ended during the test (unless the test was
        told so already) or does not end cleanly now."""
        for p in self._programs:
            p.kill()
        for b in self._buses:
            try:
                b.shutdown()
            except Exception:  # canemud gone: reported below
                pass
        if self._watch is not None:
            self._watch.close()
            self._watch = None
        ended = self.daemon.proc.poll()
        why = None
        try:
            self.daemon.stop()
        except RuntimeError as e:
            why = str(e).split(";", 1)[0]
        self.log_path.write_text(self.daemon.log)
        if ended is not None and not self._told_dead:
            why = f"canemud exited with status {ended} during the test"
        if why is not None:
            raise CanemudDied(f"{why}; its log: {self.log_path}")

    def __enter__(self) -> "Bench":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _toml(value: Any) -> str:
    """A value in TOML's notation (scenario keys: strings, numbers, booleans, lists, tables)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (bytes, bytearray)):
        return "[" + ", ".join(f"0x{b:02X}" for b in value) + "]"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"{value!r}: not a scenario value")


def _show(within: Duration) -> str:
    return f"{within} ms" if isinstance(within, (int, float)) else str(within)
