"""What the bench's traces hold and how a wait on them wakes up: durations as tests write them,
candump -L lines as Frames, and an inotify watch on the trace folder (canemu.bench)."""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import re
import select
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Union

Duration = Union[int, float, str]

_UNITS_NS = {"ns": 1, "us": 1_000, "ms": 1_000_000, "s": 1_000_000_000}
_DURATION = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*(ns|us|ms|s)\s*$")


def duration_ns(value: Duration) -> int:
    """A duration in ns: a number is milliseconds (as cangen's -g), a string carries its unit
    ("150us", "2.5ms", "1s"). ValueError naming the value otherwise."""
    if isinstance(value, bool):
        raise ValueError(f"duration {value!r}: a number of ms or a text such as '10ms'")
    if isinstance(value, (int, float)):
        if value < 0:
            raise ValueError(f"duration {value!r} is negative")
        return round(value * 1_000_000)
    m = _DURATION.match(str(value))
    if m is None:
        raise ValueError(f"duration {value!r}: a number of ms or a text such as '10ms', '150us'")
    return round(float(m.group(1)) * _UNITS_NS[m.group(2)])


@dataclass
class Frame:
    """A frame (or error frame) of a bus's candump log."""

    timestamp: float  # seconds: simulated time (canemud's recorders)
    bus: str
    id: int
    data: bytes
    is_extended_id: bool
    is_fd: bool = False
    bitrate_switch: bool = False
    is_remote_frame: bool = False
    is_error_frame: bool = False
    line: str = ""  # as the log has it

    def __str__(self) -> str:
        return self.line


_CAN_ERR_FLAG = 0x20000000
_LOG_LINE = re.compile(r"^\((\d+\.\d+)\)\s+(\S+)\s+([0-9A-Fa-f]+)(##|#)(\S*)$")


def parse_candump_line(line: str) -> Optional[Frame]:
    """A candump -L line as a Frame; None for what is not one."""
    m = _LOG_LINE.match(line.strip())
    if m is None:
        return None
    stamp, bus, ident_text, sep, rest = m.groups()
    ident = int(ident_text, 16)
    extended = len(ident_text) == 8
    error = extended and bool(ident & _CAN_ERR_FLAG)
    fd = sep == "##"
    brs = remote = False
    if fd:
        flags, rest = int(rest[:1] or "0", 16), rest[1:]
        brs = bool(flags & 1)
    elif rest.startswith("R"):
        remote, rest = True, ""
    rest = rest.split("_", 1)[0]  # a classic frame's DLC above 8 (ID#DATA_X)
    return Frame(
        timestamp=float(stamp),
        bus=bus,
        id=ident & (0x1FFFFFFF if extended else 0x7FF),
        data=bytes.fromhex(rest),
        is_extended_id=extended and not error,
        is_fd=fd,
        bitrate_switch=brs,
        is_remote_frame=remote,
        is_error_frame=error,
        line=line.strip(),
    )


class Watch:
    """Wakes up when a file in a folder changes (inotify), so that waiting in real time waits on
    the recorders' writes, not on a clock."""

    _IN_MODIFY = 0x2
    _IN_NONBLOCK = 0o4000
    _IN_CLOEXEC = 0o2000000

    def __init__(self, folder: Path) -> None:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        self.fd = libc.inotify_init1(self._IN_NONBLOCK | self._IN_CLOEXEC)
        if self.fd < 0:
            raise OSError(ctypes.get_errno(), "inotify_init1")
        if libc.inotify_add_watch(self.fd, str(folder).encode(), self._IN_MODIFY) < 0:
            os.close(self.fd)
            raise OSError(ctypes.get_errno(), f"inotify_add_watch {folder}")

    def wait(self, seconds: float) -> None:
        """Until a file changed or `seconds` passed."""
        ready, _, _ = select.select([self.fd], [], [], max(seconds, 0.0))
        if ready:
            try:
                while os.read(self.fd, 4096):
                    pass
            except BlockingIOError:
                pass

    def close(self) -> None:
        os.close(self.fd)
