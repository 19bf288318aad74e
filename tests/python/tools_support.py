"""Running python-can's command-line tools (python -m can.logger, can.player, can.viewer,
can.bridge) against a test's canemud: each as a child process whose output is read all the time
by a thread, so that a test waits for what it prints (with a timeout) instead of sleeping."""

from __future__ import annotations

import fcntl
import os
import pty
import re
import signal
import struct
import subprocess
import sys
import termios
import threading
import time
from pathlib import Path
from typing import List

import can

TIMEOUT = 20.0


def tool_env(daemon) -> dict:
    return {**os.environ, "CANEMU_SOCKET": daemon.socket, "PYTHONUNBUFFERED": "1"}


def _ctrl_c_as_at_a_terminal() -> None:
    """In the tool's process before it starts: SIGINT's default action. A test run started in the
    background by a non-interactive shell (`make test &`) has SIGINT ignored, which its children
    inherit, and Python then never raises KeyboardInterrupt: Ctrl-C (interrupt()) would do
    nothing."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


class WatchedText:
    """Text that a reader thread adds to (`add`, then `end` when its source is done) and that a
    test waits in for a pattern (`wait_for`), instead of sleeping."""

    def __init__(self, what: str) -> None:
        self.what = what
        self.text = ""
        self.ended = False
        self._changed = threading.Condition()

    def add(self, chunk: str) -> None:
        with self._changed:
            self.text += chunk
            self._changed.notify_all()

    def end(self) -> None:
        with self._changed:
            self.ended = True
            self._changed.notify_all()

    def wait_for(self, pattern: str, timeout: float = TIMEOUT) -> re.Match:
        """The first match of the regular expression `pattern`, waited for; an AssertionError
        with the whole text once `timeout` seconds have passed or the text has ended."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                found = re.search(pattern, self.text)
                if found:
                    return found
                left = deadline - time.monotonic()
                if left <= 0 or self.ended:
                    raise AssertionError(f"{pattern!r} not in {self.what}:\n{self.text}")
                self._changed.wait(left)


class Tool:
    """`python -m MODULE ARGS` with its standard output and error read into `output` (through
    a pseudo-terminal of `rows` x `cols` when `pty_size` is given, as curses needs one).
    Every tool started is in `Tool.running` until finish(); kill_all() ends those left."""

    running: List["Tool"] = []

    @classmethod
    def kill_all(cls) -> None:
        for tool in list(cls.running):
            tool.proc.kill()
            tool.finish()

    def __init__(self, daemon, module: str, args: List[str], pty_size=None, cwd=None) -> None:
        Tool.running.append(self)
        command = [sys.executable, "-m", module, *args]
        self._output = WatchedText(f"the output of {command}")
        if pty_size is None:
            self.proc = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                         stderr=subprocess.STDOUT, env=tool_env(daemon), cwd=cwd,
                                         preexec_fn=_ctrl_c_as_at_a_terminal)
            self._read_fd = self.proc.stdout.fileno()
            self._write_fd = None
        else:
            master, slave = pty.openpty()
            rows, cols = pty_size
            fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", rows, cols, 0, 0))
            env = {**tool_env(daemon), "TERM": "xterm", "LINES": str(rows), "COLUMNS": str(cols)}
            self.proc = subprocess.Popen(command, stdin=slave, stdout=slave, stderr=slave,
                                         env=env, cwd=cwd, start_new_session=True,
                                         preexec_fn=_ctrl_c_as_at_a_terminal)
            os.close(slave)
            self._read_fd = master
            self._write_fd = master
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        while True:
            try:
                chunk = os.read(self._read_fd, 65536)
            except OSError:  # the pty's other side closed
                chunk = b""
            if not chunk:
                self._output.end()
                return
            self._output.add(chunk.decode(errors="replace"))

    @property
    def output(self) -> str:
        """What the tool wrote so far."""
        return self._output.text

    def wait_for(self, pattern: str, timeout: float = TIMEOUT) -> re.Match:
        """The first match of the regular expression `pattern` in the output, waited for."""
        return self._output.wait_for(pattern, timeout)

    def write(self, data: bytes) -> None:
        os.write(self._write_fd, data)

    def interrupt(self) -> None:
        """Ctrl-C, as a user stops the tool."""
        self.proc.send_signal(signal.SIGINT)

    def finish(self, timeout: float = TIMEOUT) -> int:
        """The exit status, waited for; the whole output read."""
        try:
            rc = self.proc.wait(timeout)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()
        self._reader.join(timeout)
        if self in Tool.running:
            Tool.running.remove(self)
        if self._write_fd is not None:
            os.close(self._write_fd)
        elif self.proc.stdout:
            self.proc.stdout.close()
        return rc

    def wait_idle(self, timeout: float = TIMEOUT) -> None:
        """Until the tool's main thread sleeps twice in a row (blocked waiting for a frame: it
        has read every frame its receive FIFO held). Read from /proc, looked at every 5 ms."""
        stat = Path(f"/proc/{self.proc.pid}/task/{self.proc.pid}/stat")
        deadline = time.monotonic() + timeout
        sleeping = 0
        while sleeping < 2:
            if self.proc.poll() is not None:
                raise AssertionError(f"{self.proc.args} ended:\n{self.output}")
            state = stat.read_text().rsplit(")", 1)[1].split()[0]
            sleeping = sleeping + 1 if state == "S" else 0
            if time.monotonic() > deadline:
                raise AssertionError(f"{self.proc.args} never waited for a frame")
            threading.Event().wait(0.005)


def candump_log(path: Path, messages) -> None:
    """`messages` as a can-utils log (python-can's .log format)."""
    lines = []
    for k, m in enumerate(messages):
        ident = f"{m.arbitration_id:08X}" if m.is_extended_id else f"{m.arbitration_id:03X}"
        lines.append(f"({k * 0.0005:.6f}) can0 {ident}#{bytes(m.data).hex().upper()}")
    path.write_text("\n".join(lines) + "\n")


def numbered(count: int, ident: int = 0x123) -> list:
    """`count` frames whose data is their number (4 bytes, big-endian) and a fixed tail."""
    return [can.Message(arbitration_id=ident, is_extended_id=False,
                        data=k.to_bytes(4, "big") + bytes([0xA5, 0x5A, k & 0xFF, 0x3C]))
            for k in range(count)]


def receive_frames(bus, count: int, timeout: float = TIMEOUT) -> list:
    """`count` data frames from `bus` (error frames are left out), each waited for up to
    `timeout`; fewer when one does not come."""
    out = []
    deadline = time.monotonic() + timeout
    while len(out) < count:
        msg = bus.recv(max(0.0, deadline - time.monotonic()))
        if msg is None:
            break
        if not msg.is_error_frame:
            out.append(msg)
    return out


def same_frames(got, sent) -> bool:
    return [(m.arbitration_id, m.is_extended_id, bytes(m.data)) for m in got] == [
        (m.arbitration_id, m.is_extended_id, bytes(m.data)) for m in sent]


_ESCAPE = re.compile(
    r"\x1b\[([0-9;?]*)([A-Za-z@])|\x1b[()][0-9A-Za-z]|\x1b[=>78]|[\r\n\b]|[^\x1b\r\n\b]")


def screen(output: str, rows: int, cols: int) -> List[str]:
    """The terminal's lines after `output` (what curses drew): cursor addressing (H, f, d, G,
    A-D), clearing (J, K) and text; other control sequences change nothing visible here."""
    cells = [[" "] * cols for _ in range(rows)]
    row = col = 0
    for m in _ESCAPE.finditer(output):
        text = m.group(0)
        if m.group(2):
            params = [int(p) if p.isdigit() else 0 for p in m.group(1).lstrip("?").split(";")]
            n = params[0] or 1
            kind = m.group(2)
            if kind in "Hf":
                row = (params[0] or 1) - 1
                col = ((params[1] if len(params) > 1 else 0) or 1) - 1
            elif kind == "d":
                row = n - 1
            elif kind == "G":
                col = n - 1
            elif kind == "A":
                row -= n
            elif kind == "B":
                row += n
            elif kind == "C":
                col += n
            elif kind == "D":
                col -= n
            elif kind == "J" and params[0] == 2:
                cells = [[" "] * cols for _ in range(rows)]
            elif kind == "K":
                cells[row][col:] = [" "] * (cols - col)
            row, col = max(0, min(row, rows - 1)), max(0, min(col, cols - 1))
        elif text == "\r":
            col = 0
        elif text == "\n":
            row = min(row + 1, rows - 1)
        elif text == "\b":
            col = max(0, col - 1)
        elif not text.startswith("\x1b"):
            cells[row][col] = text
            col = min(col + 1, cols - 1)
    return ["".join(line).rstrip() for line in cells]
