"""Frames of a candump -L log decoded with a CAN database (DBC), as ``canemu dump BUS --dbc
FILE`` prints them (docs/restbus.md, "Reading frames: canemu dump --dbc").

Every line read is written again as it came; a frame whose identifier the DBC knows gets its
decoding after it on the same line, in the single-line form of ``cantools decode``::

    (0000000000.100236) can0 101#0000 :: MOTOR_STATUS(MOTOR_STATUS_wheel_error: 0, ...)

A frame the DBC does not know, an error frame and a line that is not a frame stay as they are;
a remote frame of a known identifier gets its message's name; a frame cantools cannot decode
(a length that is not the message's) gets the reason. As a filter::

    canemu dump can0 | python -m canemu.dbc_decode vehicle.dbc
    python -m canemu.dbc_decode vehicle.dbc < candump-2026-01-01_120000.log

``decode(db, arbitration_id, data, is_extended)`` gives the same text for one frame (python-can
users pass ``msg.arbitration_id``, ``msg.data``, ``msg.is_extended_id``).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
from typing import Any, List, Optional, Tuple

_ERR_FLAG = 0x20000000
_EFF_MASK = 0x1FFFFFFF


class DbcReadError(ValueError):
    """The file cannot be read as a DBC; the text names the file and why."""


def load(path: str) -> Any:
    """The cantools database of the DBC at `path`; DbcReadError naming what is wrong."""
    import cantools  # only needed here

    try:
        with open(path, "rb"):
            pass
    except OSError as e:
        raise DbcReadError(f"{path}: {e.strerror or e}") from None
    try:
        return cantools.database.load_file(path, database_format="dbc")
    except Exception as e:  # cantools' ParseError and the errors of its checks
        raise DbcReadError(f"{path}: not a DBC cantools {cantools.__version__} reads: {e}") from e


def signal_texts(message: Any, decoded: dict) -> List[Tuple[str, str]]:
    """(signal, value text) of a decoded frame in the message's order: a value with its unit,
    a choice by its name (without the unit); a multiplexed signal the multiplexor's value does
    not select is left out."""
    from cantools.database.namedsignalvalue import NamedSignalValue

    texts = []
    for s in message.signals:
        if s.name not in decoded:
            continue
        value = decoded[s.name]
        if s.unit and not isinstance(value, (NamedSignalValue, str)):
            texts.append((s.name, f"{value} {s.unit}"))
        else:
            texts.append((s.name, f"{value}"))
    return texts


def message_of(db: Any, arbitration_id: int, is_extended: bool) -> Any:
    """The cantools message of `db` with that identifier, or None (a standard and an extended
    identifier of one number are two messages)."""
    try:
        message = db.get_message_by_frame_id(arbitration_id)
    except KeyError:
        return None
    return message if bool(message.is_extended_frame) == bool(is_extended) else None


def frame_signals(db: Any, arbitration_id: int, data: Optional[bytes],
                  is_extended: bool) -> Optional[Tuple[str, Optional[List[Tuple[str, str]]], str]]:
    """One frame as `db` decodes it, in parts: (message name, its (signal, value text) pairs,
    "") or, when there are none, (name, None, why: "remote frame" or "not decoded: REASON");
    None when `db` does not know the identifier. `data` None: a remote frame."""
    message = message_of(db, arbitration_id, is_extended)
    if message is None:
        return None
    if data is None:
        return message.name, None, "remote frame"
    try:
        decoded = message.decode(bytes(data), decode_choices=True)
    except Exception as e:  # cantools' DecodeError: the length, a container, ...
        return message.name, None, f"not decoded: {str(e) or type(e).__name__}"
    return message.name, signal_texts(message, decoded), ""


def decode(db: Any, arbitration_id: int, data: Optional[bytes], is_extended: bool) -> str:
    """The decoding of one frame as a line shows it after ``::`` (cantools decode's single-line
    form: NAME(SIGNAL: VALUE UNIT, ...)); "" when `db` does not know the identifier (a standard
    and an extended identifier of one number are two messages). `data` None: a remote frame."""
    parts = frame_signals(db, arbitration_id, data, is_extended)
    if parts is None:
        return ""
    name, texts, why = parts
    if texts is None:
        return f"{name}: {why}"
    return f"{name}({', '.join(f'{signal}: {value}' for signal, value in texts)})"


def parse_frame(text: str) -> Optional[Tuple[int, Optional[bytes], bool]]:
    """A candump frame (123#11223344, 12345678#R, 123##1AABB, 123#1122334455667788_9) as
    (identifier, data or None for a remote frame, extended); None for an error frame or text
    that is not a frame."""
    ident, sep, rest = text.partition("#")
    if not sep or len(ident) not in (3, 8):
        return None
    try:
        can_id = int(ident, 16)
    except ValueError:
        return None
    extended = len(ident) == 8
    if can_id & _ERR_FLAG or can_id > _EFF_MASK:
        return None
    if rest.startswith("R"):
        return can_id, None, extended
    if rest.startswith("#"):
        rest = rest[2:]  # CAN FD: the flags nibble, then the data
    rest = rest.split("_")[0]  # a classic frame's DLC above 8
    try:
        return can_id, bytes.fromhex(rest), extended
    except ValueError:
        return None


def decode_line(db: Any, line: str) -> str:
    """`line` (without its newline) as it came, with " :: DECODING" when the DBC knows it."""
    words = line.split()
    if len(words) != 3 or not words[0].startswith("("):
        return line
    frame = parse_frame(words[2])
    if frame is None:
        return line
    text = decode(db, *frame)
    return f"{line} :: {text}" if text else line


def main(argv: Optional[list] = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m canemu.dbc_decode",
        description="a candump -L log on standard input, each known frame decoded with a DBC")
    parser.add_argument("dbc", help="the CAN database (DBC) file")
    parser.add_argument("--ready-fd", type=int, default=-1,
                        help="a file descriptor to write one line to once the DBC is read, "
                             "then close (canemu dump --dbc waits for it)")
    args = parser.parse_args(argv)
    # The command that feeds this stops on Ctrl-C; this goes on to the end of its lines.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        db = load(args.dbc)
    except DbcReadError as e:
        print(f"canemu: --dbc {e}", file=sys.stderr)
        return 2
    if args.ready_fd >= 0:
        os.write(args.ready_fd, b"ready\n")
        os.close(args.ready_fd)
    out = sys.stdout
    try:
        for line in sys.stdin:
            out.write(decode_line(db, line.rstrip("\n")) + "\n")
            out.flush()
    except BrokenPipeError:
        # The reader went away (canemu dump --dbc ... | head): the end, as for candump.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
