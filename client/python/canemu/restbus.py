"""canemu.restbus: canemud's simulated CAN nodes (the rest of a vehicle's bus) from Python, as
``canemu restbus`` and ``canemu signal`` give them on the command line (docs/restbus.md, "From
Python"):

    import can
    from canemu import restbus

    restbus.load("vehicle.dbc", bus="can0", real=["GATEWAY"])   # every other node runs
    restbus.set_signal("can0", "MOTOR_STATUS.MOTOR_STATUS_speed_kph", 12.345)
    restbus.get_signal("can0", "MOTOR_STATUS.MOTOR_STATUS_speed_kph")  # 12.345
    restbus.power("MOTOR", False)                                # it leaves the bus

    decoder = restbus.Decoder("vehicle.dbc")
    with can.Bus(interface="canemu", channel="can0") as bus:
        msg = bus.recv(1.0)
        print(decoder.decode(msg))   # ('MOTOR_STATUS', {'MOTOR_STATUS_speed_kph': 12.345, ...})
        print(decoder.text(msg))     # MOTOR_STATUS(MOTOR_STATUS_wheel_error: 0, ...) as dump --dbc

The calls go through canemu's VCI library (libvcinpl2.so) to the canemud this process talks to
(``canemu.connect``). What canemud refuses raises RestbusError, whose text is canemud's reason
("65.536 is outside the range of ..."), and changes nothing.
"""

from __future__ import annotations

import ctypes
import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Iterable, List, Mapping, Optional, Tuple, Union

from . import _vci, dbc_decode
from ._vci import VciError

try:
    import tomllib
except ImportError:  # Python < 3.11
    import tomli as tomllib  # type: ignore[no-redef]


class CANEMU_CANNODEINFO(ctypes.Structure):
    _pack_ = 1
    _fields_ = [
        ("szName", ctypes.c_char * 32),
        ("szBus", ctypes.c_char * 32),
        ("bPowered", ctypes.c_uint8),
        ("abReserved", ctypes.c_uint8 * 3),
        ("dwMessages", ctypes.c_uint32),
        ("qwFrames", ctypes.c_uint64),
    ]


assert ctypes.sizeof(CANEMU_CANNODEINFO) == 80

_SIGNATURES = {
    "canemuLoadCanNodes": (ctypes.c_char_p, ctypes.c_char_p),
    "canemuEnumCanNodes": (ctypes.c_uint32, ctypes.POINTER(CANEMU_CANNODEINFO)),
    "canemuPowerCanNode": (ctypes.c_char_p, ctypes.c_int32),
    "canemuRemoveCanNode": (ctypes.c_char_p,),
    "canemuSetSignal": (ctypes.c_char_p, ctypes.c_char_p, ctypes.c_double),
    "canemuGetSignal": (ctypes.c_char_p, ctypes.c_char_p, ctypes.POINTER(ctypes.c_double)),
}
_declared = False


class RestbusError(VciError):
    """canemud refused a request about its simulated CAN nodes; the text is its reason (one line
    per error), and nothing changed. `call` and `hr` as VciError's."""

    def __init__(self, call: str, hr: int, reason: str) -> None:
        Exception.__init__(self, reason)
        self.call = call
        self.hr = hr
        self.text = reason


def _lib() -> ctypes.CDLL:
    global _declared
    if not _declared:
        _vci.declare(_SIGNATURES)
        _declared = True
    return _vci.lib()


def _call(name: str, *args) -> None:
    """Calls `name`; RestbusError with canemud's reason when it refused, VciError otherwise."""
    hr = getattr(_lib(), name)(*args)
    if hr == _vci.VCI_OK:
        return
    if hr == _vci.VCI_E_INVALIDARG:
        # The library's text is "invalid argument (REASON)": the reason is the call's detail.
        buf = ctypes.create_string_buffer(8192)
        _vci.lib().vciFormatError(hr, buf, len(buf))
        text = buf.value.decode(errors="replace")
        _, paren, reason = text.partition(" (")
        if paren and reason.endswith(")"):
            raise RestbusError(name, hr, reason[:-1])
    _vci.check(name, hr)


def _encode(text: str, what: str) -> bytes:
    if not isinstance(text, str):
        raise ValueError(f"{what} is a str, not {type(text).__name__}")
    return text.encode()


@dataclass(frozen=True)
class CanNode:
    """A simulated CAN node: its name and bus, whether it is on, how many messages it sends and
    how many frames it sent whole."""

    name: str
    bus: str
    powered: bool
    messages: int
    frames: int


def _checksum_map(checksums: Union[Mapping[str, str], Iterable[str]]) -> Dict[str, str]:
    """`checksums` as canemu.dbc takes them: "MSG.SIG" -> "ALGO[:DATA_ID]", from a mapping or
    from "MSG.SIG=ALGO[:DATA_ID]" strings (the command line's form)."""
    if isinstance(checksums, Mapping):
        return dict(checksums)
    out: Dict[str, str] = {}
    for item in checksums:
        spec, eq, value = str(item).partition("=")
        if not eq:
            raise ValueError(f"checksum {item!r}: write MSG.SIG=ALGO[:DATA_ID]")
        if spec in out:
            raise ValueError(f"checksum {spec}: given twice")
        out[spec] = value
    return out


def load(path_or_text: Union[str, "os.PathLike[str]"], bus: Optional[str] = None,
         real: Iterable[str] = (), counters: Iterable[str] = (),
         checksums: Union[Mapping[str, str], Iterable[str]] = ()) -> List[str]:
    """Starts simulated CAN nodes; returns their names in the order of the tables.

    `path_or_text`: a DBC file (a name ending in ``.dbc``), imported here by canemu.dbc with
    `bus`, `real` (nodes a program under test plays), `counters` ("MSG.SIG") and `checksums`
    ("MSG.SIG" -> "ALGO[:DATA_ID]", or "MSG.SIG=ALGO[:DATA_ID]" strings); any other file, or a
    str holding a newline, is ``[[can_node]]`` TOML. The tables are checked as a configuration
    file's are and all start at the instant canemud takes them (in stepped time, the current
    simulated time), or none does. A node of a name that runs on its bus already is replaced.
    The import's notes (a message without a sender skipped) are warnings. RestbusError with canemud's reasons; canemu.dbc.DbcError (a ValueError) for what the
    import cannot carry; ValueError for DBC options with TOML; OSError for a file that cannot
    be read."""
    from . import dbc  # cantools is needed for a DBC only

    if isinstance(path_or_text, str) and "\n" in path_or_text:
        path, text, source = None, path_or_text, ""
    else:
        path = os.fspath(path_or_text)
        text, source = None, path
    if path is not None and path.lower().endswith(".dbc"):
        if not bus:
            raise ValueError(f"{path}: a DBC file needs bus= (the CAN bus its nodes send on)")
        nodes = dbc.can_nodes(path, bus, real, counters, _checksum_map(checksums),
                              warn=lambda note: warnings.warn(f"canemu.dbc: note: {note}"))
        text = dbc.to_toml(nodes, path)
        names = [n["name"] for n in nodes]
    else:
        if bus is not None or list(real) or list(counters) or list(checksums):
            raise ValueError("bus, real, counters and checksums belong to a DBC file")
        if text is None:
            text = Path(path).read_text()
        names = []
    _call("canemuLoadCanNodes", _encode(text, "the tables"), source.encode())
    if path is None or not path.lower().endswith(".dbc"):
        # Taken whole: canemud started exactly the tables' nodes, in their order.
        names = [str(n.get("name", "")) for n in tomllib.loads(text).get("can_node", [])]
    return names


def nodes() -> List[CanNode]:
    """The simulated CAN nodes, the configuration's then the loaded ones in the order they
    started (at most 48)."""
    out = []
    info = CANEMU_CANNODEINFO()
    index = 0
    while True:
        hr = _lib().canemuEnumCanNodes(index, ctypes.byref(info))
        if hr == _vci.VCI_E_NO_MORE_ITEMS:
            return out
        _vci.check("canemuEnumCanNodes", hr)
        out.append(CanNode(info.szName.decode(), info.szBus.decode(), bool(info.bPowered),
                           info.dwMessages, info.qwFrames))
        index += 1


def power(name: str, on: bool) -> None:
    """Switches the node `name` (NAME, or BUS/NAME where several buses have that NAME) on or
    off. Off, it leaves the bus (a frame on the wire completes) and its waiting frames are
    dropped; its signals keep their values. On, its controller is reset and every message's
    schedule starts again from now. RestbusError for an unknown node."""
    _call("canemuPowerCanNode", _encode(name, "a node"), 1 if on else 0)


def remove(name: str) -> None:
    """Takes the node `name` off its bus. RestbusError for an unknown node."""
    _call("canemuRemoveCanNode", _encode(name, "a node"))


def set_signal(bus: str, signal: str, value: float) -> None:
    """Sets the physical value of `signal`, "MESSAGE.SIGNAL", of the message a simulated node
    sends on `bus`; its next frame carries it (an on-change message goes at once).
    RestbusError naming the reason: no such message on the bus or signal in it, a value outside
    the signal's range or bits, a checksum signal."""
    _call("canemuSetSignal", _encode(bus, "the bus"), _encode(signal, "the signal"),
          float(value))


def get_signal(bus: str, signal: str) -> float:
    """The physical value of `signal` ("MESSAGE.SIGNAL" on `bus`) that its next frame carries:
    what was set, rounded to the signal's bits. RestbusError as set_signal's."""
    value = ctypes.c_double()
    _call("canemuGetSignal", _encode(bus, "the bus"), _encode(signal, "the signal"),
          ctypes.byref(value))
    return value.value


class Decoder:
    """A python-can message's signals by a CAN database (DBC), as cantools decodes them."""

    def __init__(self, dbc_path: Union[str, "os.PathLike[str]"]) -> None:
        """Reads the DBC; canemu.dbc_decode.DbcReadError (a ValueError) naming the file and what
        is wrong."""
        self.db = dbc_decode.load(os.fspath(dbc_path))

    def decode(self, msg: Any) -> Optional[Tuple[str, Dict[str, Any]]]:
        """(message name, {signal: physical value}) of a python-can message: scale and offset
        applied, a value with a choice (VAL_) as cantools' NamedSignalValue, a multiplexed
        message's signals as its multiplexor selects them. None for a frame the DBC does not
        know (a standard and an extended identifier of one number are two messages) and for an
        error frame; a remote frame gives its name and no signals. ValueError with cantools'
        reason for a frame it cannot decode (too short)."""
        if getattr(msg, "is_error_frame", False):
            return None
        message = dbc_decode.message_of(self.db, msg.arbitration_id, msg.is_extended_id)
        if message is None:
            return None
        if msg.is_remote_frame:
            return message.name, {}
        try:
            return message.name, message.decode(bytes(msg.data), decode_choices=True)
        except Exception as e:  # cantools' DecodeError: the length, a container, ...
            raise ValueError(f"{message.name}: not decoded: {str(e) or type(e).__name__}") from e

    def text(self, msg: Any) -> str:
        """The decoding as ``canemu dump --dbc`` prints it after ``::`` (cantools decode's
        single-line form); "" for a frame the DBC does not know and for an error frame."""
        if getattr(msg, "is_error_frame", False):
            return ""
        data = None if msg.is_remote_frame else bytes(msg.data)
        return dbc_decode.decode(self.db, msg.arbitration_id, data, msg.is_extended_id)
