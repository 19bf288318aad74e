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
CAN_VERSION = tuple(int(p) for p in re.findall(r"\d+", can.__version__)[:2])


def tool_env(daemon) -> dict:
    return {**os.environ, "CANEMU_SOCKET": daemon.socket, "PYTHONUNBUFFERED": "1"}


class Tool:
    """`python -m MODULE ARGS` with its standard output and error read into `output` (through
    a pseudo-terminal of `rows` x `cols` when `pty` is set, as curses needs one)."""

    def __init__(self, daemon, module: str, args: List[str], pty_size=None, cwd=None) -> None:
        self.output = ""
        self._changed = threading.Condition()
        command = [sys.executable, "-m", module, *args]
        if pty_size is None:
            self.proc = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                         stderr=subprocess.STDOUT, env=tool_env(daemon), cwd=cwd)
            self._read_fd = self.proc.stdout.fileno()
            self._write_fd = None
        else:
            master, slave = pty.openpty()
            rows, cols = pty_size
            fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", rows, cols, 0, 0))
            env = {**tool_env(daemon), "TERM": "xterm", "LINES": str(rows), "COLUMNS": str(cols)}
            self.proc = subprocess.Popen(command, stdin=slave, stdout=slave, stderr=slave,
                                         env=env, cwd=cwd, start_new_session=True)
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
            with self._changed:
                if not chunk:
                    self._eof = True
                    self._changed.notify_all()
                    return
                self.output += chunk.decode(errors="replace")
                self._changed.notify_all()

    def wait_for(self, pattern: str, timeout: float = TIMEOUT) -> re.Match:
        """The first match of the regular expression `pattern` in the output, waited for."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                found = re.search(pattern, self.output)
                if found:
                    return found
                left = deadline - time.monotonic()
                if left <= 0 or getattr(self, "_eof", False):
                    raise AssertionError(f"{pattern!r} not in the output of {self.proc.args}:\n"
                                         f"{self.output}")
                self._changed.wait(left)

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


def python_can_at_least(major: int, minor: int) -> bool:
    return CAN_VERSION >= (major, minor)
