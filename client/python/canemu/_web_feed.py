"""What canemu web shows, gathered from canemud through the canemu command line: `canemu status
--json` every interval (canemud offers no status subscription: its SubscribeRequest announces
devices coming and going), `canemu dump --listen-only --sim-time -- BUS...` for the ID tables (one
for the CAN buses of the first look, one more for those a later look finds), and `canemu lin
list` while there are LIN buses. Every look becomes one update pushed to the pages
(web.py); a short history lets a page that opens late draw the last minute."""

from __future__ import annotations

import asyncio
import collections
import ctypes
import json
import signal
import sys
import time
from typing import Any, Deque, Dict, List, Optional, Set, Tuple

from .dbc_decode import frame_signals, parse_frame

HISTORY_NS = 60_000_000_000  # the graphs show the last minute of simulated time
HISTORY_POINTS = 2400  # at most this many looks are kept (a minute at 25 ms)
FAULT_EVENTS = 200  # the newest fault firings kept
# Effects that hit frames (docs/faults.md), CAN and LIN: their hits have no instant of their own.
FRAME_EFFECTS = {"bit_error", "stuff_error", "form_error", "crc_error", "ack_error",
                 "random_errors", "babble", "lin_checksum_error", "lin_parity_error",
                 "lin_sync_error", "lin_short_break", "lin_bit_error", "lin_no_response",
                 "lin_responder_off"}


class SignalDecoder:
    """The ID tables' decoding through DBC files (`canemu web --dbc [BUS=]FILE`): a file given
    with a bus decodes that bus's frames, one without decodes every bus's; a frame is decoded by
    the first file that knows its identifier, its bus's files before the others, each group in
    the order given (docs/web.md)."""

    def __init__(self, files: List[Tuple[Optional[str], str, Any]]) -> None:
        self.files = files  # (bus or None, the file's path, its cantools database)

    def buses(self) -> Dict[str, str]:
        """The buses files were given for, each with the first such file's path."""
        named: Dict[str, str] = {}
        for bus, path, _ in self.files:
            if bus is not None:
                named.setdefault(bus, path)
        return named

    def decode(self, bus: str, text_id: str, data: str) -> Optional[Dict[str, Any]]:
        """What the ID table shows of a frame (candump's identifier and data text, "R" for a
        remote frame): {"message": NAME, "signals": [(signal, value text), ...]}, or with
        "signals" None and "note" saying why; None when no file knows the identifier."""
        frame = parse_frame(f"{text_id}#{data}")
        if frame is None:
            return None
        for only in (bus, None):
            for file_bus, path, db in self.files:
                if file_bus != only:
                    continue
                try:
                    parts = frame_signals(db, *frame)
                except Exception as e:  # whatever cantools does, the page goes on
                    return {"message": None, "signals": None,
                            "note": f"{path}: not decoded: {str(e) or type(e).__name__}"}
                if parts is not None:
                    name, texts, why = parts
                    return {"message": name, "signals": texts, "note": why}
        return None


def valid_bus_name(text: str) -> bool:
    """canemud's rule for bus names (docs/configuration.md): 1 to 28 of a-z, 0-9, "_", "-"."""
    return 1 <= len(text) <= 28 and all(c in "abcdefghijklmnopqrstuvwxyz0123456789_-"
                                        for c in text)


def parse_dbc_option(text: str) -> Tuple[Optional[str], str]:
    """--dbc's value as (bus or None, file): BUS=FILE when the part before the first "=" is a
    bus name by canemud's rule, otherwise the whole text is the file (./v=2.dbc is a file)."""
    bus, sep, path = text.partition("=")
    if sep and valid_bus_name(bus):
        return bus, path
    return None, text


def _end_with_parent() -> None:
    """In a child before it runs: SIGTERM when canemu web ends, however it ends (a dump waiting
    on a quiet bus would otherwise stay)."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGTERM))  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


# Seconds after a dump ended before its buses get another (canemud restarted).
RETRY_S = 5.0
# How often the dumps summarise their buses' identifiers (canemu dump --summary): an ID table is
# at most this much older than the look that shows it.
SUMMARY_MS = 100
# A page's queue holds at most this many updates; then they give way to one RESYNC.
RESYNC_AFTER = 8
RESYNC = ""  # in a page's queue: send it a snapshot

class IdRow:
    """One identifier on one bus, as cansniffer shows it: count, period, last data, and which
    bytes changed since the previous update; decoded through the DBC files when there are some
    (kept until the data changes). Fed by `canemu dump --summary`'s lines (SUMMARY_MS)."""

    __slots__ = ("count", "first_ns", "last_ns", "data", "changed", "text_id", "decoded",
                 "decoded_data")

    def __init__(self, text_id: str, first_ns: int) -> None:
        self.text_id = text_id
        self.count = 0
        self.first_ns = first_ns
        self.last_ns = first_ns
        self.data = ""
        self.changed = 0  # bit i: byte i differed between two frames in a row
        self.decoded: Optional[Dict[str, Any]] = None
        self.decoded_data: Optional[str] = None  # the data `decoded` is of

    def add(self, line: Dict[str, Any]) -> None:
        """One summary line of this identifier: its frames since the line before."""
        self.count += line["count"]
        self.last_ns = line["last_ns"]
        self.data = line["data"]
        self.changed |= line["changed"]

    def row(self, bus: str, decoder: Optional[SignalDecoder] = None) -> Dict[str, Any]:
        period = (self.last_ns - self.first_ns) / (self.count - 1) / 1e6 if self.count > 1 else None
        if decoder is not None and self.decoded_data != self.data:
            self.decoded = decoder.decode(bus, self.text_id, self.data)
            self.decoded_data = self.data
        decoded = self.decoded or {}
        return {"id": self.text_id, "count": self.count, "period_ms": period, "data": self.data,
                "changed": self.changed, "message": decoded.get("message"),
                "signals": decoded.get("signals"), "note": decoded.get("note") or None}


class Feed:
    """canemud's state as the pages see it. `canemu` is the command line's path, `base` its
    global options (--socket)."""

    def __init__(self, canemu: str, base: List[str], interval: float, frames: bool,
                 decoder: Optional[SignalDecoder] = None) -> None:
        self.canemu = canemu
        self.base = base
        self.interval = interval
        self.frames = frames
        self.decoder = decoder
        self.subscribers: Set[asyncio.Queue] = set()
        # Pages that fell behind by more than RESYNC_AFTER updates: their queued updates were
        # replaced by a fresh snapshot (RESYNC), so that they lose nothing; counted here.
        self.resyncs = 0
        self.status: Optional[Dict[str, Any]] = None
        self.error: Optional[str] = None  # why the last look failed
        self.history: Deque[Dict[str, Any]] = collections.deque(maxlen=HISTORY_POINTS)
        self.fault_events: Deque[Dict[str, Any]] = collections.deque(maxlen=FAULT_EVENTS)
        self.id_tables: Dict[str, Dict[str, IdRow]] = {}
        self.error_frames_seen: Dict[str, int] = {}
        self.listening: List[str] = []  # the buses whose frames the ID tables count
        self.capture_note = "" if frames else "ID tables off (--no-frames)"
        self.lin_text = ""
        self.looks = 0
        self._fault_hits: Dict[Tuple[str, int], Tuple[int, str]] = {}
        self._previous: Optional[Tuple[int, Dict[str, Tuple[int, int]]]] = None
        # The dumps that feed the ID tables: one for the CAN buses of the first look, one more
        # for each look that finds new ones (a reload adds buses); the buses asked for so far.
        self._dumps: List[asyncio.subprocess.Process] = []
        self._captures: List[asyncio.Future] = []
        self._asked: Set[str] = set()
        self._ended: Dict[str, float] = {}  # bus -> when its dump ended (time.monotonic)
        self._wake = asyncio.Event()
        self._last_pid = 0
        self._rates: Dict[str, Tuple[float, float]] = {}

    def _hide_own(self, status: Dict[str, Any], status_pid: int) -> None:
        """Leaves out this tool's own clients: the listen-only nodes of its dump (and their
        device) and the `canemu status` that answered; `clients` counts them still."""
        own = {status_pid}
        own.update(dump.pid for dump in self._dumps)
        hidden = set()
        devices = []
        for d in status.get("devices", []):
            if d.get("ephemeral") and d.get("owner_pid") in own:
                hidden.update(d.get("nodes", []))
            else:
                devices.append(d)
        status["devices"] = devices
        status["nodes"] = [n for n in status["nodes"] if n["name"] not in hidden]
        status["client_list"] = [c for c in status.get("client_list", []) if c["pid"] not in own]

    # ---- the command line ----
    async def run_canemu(self, *args: str, timeout: float = 10.0) -> Tuple[int, str, str]:
        proc = await asyncio.create_subprocess_exec(
            self.canemu, *self.base, *args, stdin=asyncio.subprocess.DEVNULL,
            stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE)
        self._last_pid = proc.pid
        try:
            out, err = await asyncio.wait_for(proc.communicate(), timeout)
        except asyncio.TimeoutError:
            proc.kill()
            await proc.wait()
            return 1, "", f"canemu {' '.join(args)} did not answer within {timeout:g} s"
        return proc.returncode, out.decode(errors="replace"), err.decode(errors="replace")

    def look_now(self) -> None:
        """Takes the next look at once (after an action changed something)."""
        self._wake.set()

    # ---- the loops ----
    async def run(self) -> None:
        try:
            await self._poll()
        finally:
            for task in self._captures:
                task.cancel()
            for dump in self._dumps:
                if dump.returncode is None:
                    dump.kill()
                    await dump.wait()

    async def _poll(self) -> None:
        while True:
            await self.look()
            try:
                await asyncio.wait_for(self._wake.wait(), self.interval)
            except asyncio.TimeoutError:
                pass
            self._wake.clear()

    async def look(self) -> None:
        code, out, err = await self.run_canemu("status", "--json")
        status_pid = self._last_pid
        if code != 0:
            self.error = err.strip() or f"canemu status ended with status {code}"
            self.publish({"type": "error", "error": self.error})
            return
        self.error = None
        status = json.loads(out)
        if any(b["kind"] == "lin" for b in status["buses"]) and self.looks % 8 == 0:
            code, out, err = await self.run_canemu("lin", "list")
            self.lin_text = out if code == 0 else err
        self.looks += 1
        if self.looks == 1 and self.decoder is not None:
            self._check_dbc_buses(status)
        if self.frames:
            self._capture_new_buses(status)
        self._hide_own(status, status_pid)
        self.status = status
        self.publish(self.update(status))

    def update(self, status: Dict[str, Any]) -> Dict[str, Any]:
        """One look as the pages get it: the status, rates since the previous look, the point
        added to the graphs, fault firings, the ID tables."""
        now = status["sim_time_ns"]
        counts = {b["name"]: (b["frames"], b["error_frames"]) for b in status["buses"]}
        if self._previous is not None and now > self._previous[0]:
            seconds = (now - self._previous[0]) / 1e9
            rates = {}
            for bus, (frames, errors) in counts.items():
                before = self._previous[1].get(bus, (frames, errors))
                rates[bus] = ((frames - before[0]) / seconds, (errors - before[1]) / seconds)
            self._rates = rates
        if self._previous is None or now != self._previous[0]:
            self._previous = (now, counts)
        rates = self._rates  # stepped time: the last step's, until time moves again
        point = {"t": now,
                 "load": {b["name"]: b["load_percent"] for b in status["buses"]},
                 "tec": {n["name"]: n["tec"] for n in status["nodes"]},
                 "rec": {n["name"]: n["rec"] for n in status["nodes"]},
                 "state": {n["name"]: n["state"] for n in status["nodes"]}}
        if not self.history or self.history[-1] != point:
            self.history.append(point)
        while self.history and self.history[0]["t"] < now - HISTORY_NS:
            self.history.popleft()
        fired = self._fault_firings(status, now)
        return {"type": "update", "status": status, "rates": rates, "point": point,
                "fired": fired, "ids": self.id_rows(), "lin": self.lin_text,
                "listening": self.listening, "capture_note": self.capture_note,
                "error_frames_seen": self.error_frames_seen, "real_time": time.time()}

    def _fault_firings(self, status: Dict[str, Any], now: int) -> List[Dict[str, Any]]:
        """Faults whose hits grew or whose state changed since the previous look."""
        fired = []
        for f in status.get("faults", []):
            key = (f["scenario"], f["line"])
            before = self._fault_hits.get(key, (0, "pending"))
            if f["hits"] > before[0] or (f["state"] != before[1] and f["state"] == "done"):
                # A timed effect fired at its instant; a frame effect's hits came at frames
                # between the previous look and this one: marked at this look.
                timed = f["effect"] not in FRAME_EFFECTS and f.get("at_ns", now) <= now
                event = {"t": f["at_ns"] if timed else now, "scenario": f["scenario"],
                         "line": f["line"], "effect": f["effect"], "target": f["target"],
                         "hits": f["hits"], "state": f["state"]}
                fired.append(event)
                self.fault_events.append(event)
            self._fault_hits[key] = (f["hits"], f["state"])
        return fired

    def id_rows(self) -> Dict[str, List[Dict[str, Any]]]:
        out = {}
        for bus, table in self.id_tables.items():
            out[bus] = [row.row(bus, self.decoder) for _, row in sorted(table.items())]
            for row in table.values():
                row.changed = 0
        return out

    def snapshot(self) -> Dict[str, Any]:
        """What a page that just opened gets: the newest update's parts and the history."""
        status = self.status
        ids = {bus: [row.row(bus, self.decoder) for _, row in sorted(table.items())]
               for bus, table in self.id_tables.items()}
        return {"type": "snapshot", "status": status, "history": list(self.history),
                "faults_fired": list(self.fault_events), "ids": ids, "lin": self.lin_text,
                "listening": self.listening, "capture_note": self.capture_note,
                "error": self.error, "error_frames_seen": self.error_frames_seen,
                "resyncs": self.resyncs,
                "real_time": time.time()}

    def publish(self, message: Dict[str, Any]) -> None:
        text = json.dumps(message, separators=(",", ":"))
        for queue in list(self.subscribers):
            if queue.qsize() < RESYNC_AFTER:
                queue.put_nowait(text)
            elif queue.qsize() == RESYNC_AFTER:
                # A page that does not keep up gets the whole state again once it reads, instead
                # of the updates it missed (memory stays bounded, nothing is lost).
                while not queue.empty():
                    queue.get_nowait()
                queue.put_nowait(RESYNC)
                self.resyncs += 1

    # ---- the ID tables ----
    def _check_dbc_buses(self, status: Dict[str, Any]) -> None:
        """Says once which --dbc BUS=FILE names a bus canemud does not have (a typo decodes
        nothing)."""
        have = [b["name"] for b in status["buses"]]
        for bus, path in self.decoder.buses().items():
            if bus not in have:
                print(f"canemu: web: --dbc {bus}={path}: canemud has no bus {bus} (buses: "
                      f"{', '.join(have) or 'none'}); the file decodes nothing", file=sys.stderr,
                      flush=True)

    def _capture_new_buses(self, status: Dict[str, Any]) -> None:
        """A dump of the CAN buses no dump listens on yet: those of the first look, then those
        a reload added, or whose dump ended RETRY_S ago (canemud restarted)."""
        now = time.monotonic()
        for bus, since in list(self._ended.items()):
            if now - since >= RETRY_S:
                del self._ended[bus]
                self._asked.discard(bus)
        self._captures = [task for task in self._captures if not task.done()]
        new = [b["name"] for b in status["buses"]
               if b["kind"] != "lin" and b["name"] not in self._asked]
        if "any" in new:
            # `canemu dump any` means every CAN bus: a bus of that name has no dump of its own.
            new.remove("any")
            self._asked.add("any")
            self.capture_note = "bus any has no ID table: canemu dump takes the name for every bus"
        if new:
            self._asked.update(new)
            self._captures.append(asyncio.ensure_future(self._capture(new)))

    async def _capture(self, buses: List[str]) -> None:
        """The frames of `buses` into the ID tables, through a listen-only dump of them; when
        it ends (or cannot start), the capture note says why and the buses may be dumped again
        after RETRY_S."""
        stopped = f"the ID tables of {', '.join(buses)} stopped"
        try:
            dump = await asyncio.create_subprocess_exec(
                self.canemu, *self.base, "dump", "--listen-only", "--sim-time", "--summary",
                str(SUMMARY_MS), "--", *buses,
                stdin=asyncio.subprocess.DEVNULL, stdout=asyncio.subprocess.PIPE,
                stderr=asyncio.subprocess.PIPE, limit=1 << 20, preexec_fn=_end_with_parent)
        except OSError as e:
            self.capture_note = f"{stopped}: {e}"
        else:
            self._dumps.append(dump)
            try:
                code = await self._read_dump(dump)
                self.capture_note = f"{stopped}: canemu dump ended with status {code}"
            except Exception as e:  # the page goes on, and says why the tables stopped
                self.capture_note = f"{stopped}: {e}"
                if dump.returncode is None:
                    dump.kill()
                    await dump.wait()
            self._dumps.remove(dump)  # (a cancelled task leaves it to run() to end)
        now = time.monotonic()
        for bus in buses:
            self._ended[bus] = now
            if bus in self.listening:
                self.listening.remove(bus)

    async def _read_dump(self, dump: asyncio.subprocess.Process) -> int:
        """`dump`'s summary lines into the ID tables until it ends; its exit status."""
        errors = asyncio.ensure_future(self._dump_stderr(dump.stderr))
        tables = self.id_tables
        seen = self.error_frames_seen
        async for raw in dump.stdout:
            line = json.loads(raw)
            bus = line["bus"]
            if "error_frames" in line:
                seen[bus] = seen.get(bus, 0) + line["error_frames"]
                continue
            table = tables.get(bus)
            if table is None:
                table = tables[bus] = {}
            ident = line["id"]
            row = table.get(ident)
            if row is None:
                row = table[ident] = IdRow(ident, line["first_ns"])
            row.add(line)
        await errors
        return await dump.wait()

    async def _dump_stderr(self, stream) -> None:
        async for raw in stream:
            line = raw.decode(errors="replace").strip()
            # "canemu: listening on can0 as eph1 (listen-only, ...)"
            if line.startswith("canemu: listening on "):
                self.listening.append(line.split()[3])
            elif line:
                self.capture_note = line

