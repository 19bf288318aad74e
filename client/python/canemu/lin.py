"""canemu.lin: LIN nodes for Python programs, on canemu's VCI LIN API (libvcinpl2.so).

python-can has no LIN; this module gives a program what an IXXAT adapter's LIN controller
offers through the VCI (docs/lin.md, "Python"):

    from canemu.lin import Commander, Responder

    with Responder("lin0") as door, Commander("lin0") as master:
        door.set_response(0x20, b"\\x11\\x22")       # its response table
        master.send_header(0x20)                     # the commander asks, the door answers
        canemu.step(10_000_000)                      # stepped time: 10 ms
        print(master.recv(0))                        # LinMessage(kind='frame', id=0x20, ...)

A node is an IXXAT adapter's LIN controller: ``"lin0"`` (a LIN bus) makes an adapter of its own
on that bus (gone with the node), ``"ixxat0:2"`` takes controller 2 of a configured adapter. Its
monitor receives every frame on the bus, the errors its controller sees, wake-up pulses of the
other nodes and its own start; ``recv()`` returns them as ``LinMessage`` with simulated time
stamps in seconds, to the microsecond (the VCI's LIN time stamps count whole microseconds from
the adapter's power-on).
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from typing import Optional

from . import _vci
from ._vci import HANDLE, VciError

LIN_OPMODE_SLAVE = 0x00
LIN_OPMODE_MASTER = 0x01
LIN_OPMODE_ERRORS = 0x02

LIN_MSGTYPE_DATA = 0
LIN_MSGTYPE_INFO = 1
LIN_MSGTYPE_ERROR = 2
LIN_MSGTYPE_STATUS = 3
LIN_MSGTYPE_WAKEUP = 4
LIN_MSGTYPE_SLEEP = 5
LIN_MSGTYPE_TMOVR = 6

LIN_MSGFLAGS_ECS = 0x01
LIN_MSGFLAGS_SOR = 0x02
LIN_MSGFLAGS_OVR = 0x04
LIN_MSGFLAGS_IDO = 0x08

# abData[0] of an error message, by name
ERRORS = {1: "bit", 2: "checksum", 3: "parity", 4: "no-response", 5: "sync", 6: "no-bus",
          7: "other"}
INFOS = {1: "start", 2: "stop", 3: "reset"}


class LINMSG(ctypes.Structure):
    _pack_ = 1
    _fields_ = [
        ("dwTime", ctypes.c_uint32),
        ("bPid", ctypes.c_uint8),
        ("bType", ctypes.c_uint8),
        ("bDlen", ctypes.c_uint8),
        ("bFlags", ctypes.c_uint8),
        ("abData", ctypes.c_uint8 * 8),
    ]


assert ctypes.sizeof(LINMSG) == 16

_SIGNATURES = {
    "linControlOpen": (HANDLE, ctypes.c_uint32, ctypes.POINTER(HANDLE)),
    "linControlClose": (HANDLE,),
    "linControlInitialize": (HANDLE, ctypes.c_uint8, ctypes.c_uint16),
    "linControlReset": (HANDLE,),
    "linControlStart": (HANDLE, ctypes.c_int),
    "linControlWriteMessage": (HANDLE, ctypes.c_int, ctypes.POINTER(LINMSG)),
    "linMonitorOpen": (HANDLE, ctypes.c_uint32, ctypes.c_int, ctypes.POINTER(HANDLE)),
    "linMonitorClose": (HANDLE,),
    "linMonitorInitialize": (HANDLE, ctypes.c_uint16, ctypes.c_uint16),
    "linMonitorActivate": (HANDLE, ctypes.c_int),
    "linMonitorPeekMessage": (HANDLE, ctypes.POINTER(LINMSG)),
    "linMonitorReadMessage": (HANDLE, ctypes.c_uint32, ctypes.POINTER(LINMSG)),
}
_declared = False


def _lib() -> ctypes.CDLL:
    global _declared
    if not _declared:
        _vci.declare(_SIGNATURES)
        _declared = True
    return _vci.lib()


def _call(name: str, *args) -> None:
    _vci.check(name, getattr(_lib(), name)(*args))


@dataclass(frozen=True)
class LinMessage:
    """What a LIN node's monitor received.

    kind: ``"frame"`` (id, data, enhanced, own: this node sent the response), ``"error"``
    (error: ``"checksum"``, ``"parity"``, ``"no-response"``, ...), ``"wakeup"`` (another node's
    pulse ended), ``"info"`` (info: ``"start"``, ``"stop"``, ``"reset"``). timestamp: simulated
    seconds.
    """

    kind: str
    timestamp: float
    id: Optional[int] = None
    data: bytes = b""
    enhanced: bool = False
    own: bool = False
    error: Optional[str] = None
    info: Optional[str] = None


def protected_id(frame_id: int) -> int:
    """The identifier with its two parity bits (LIN 2.x): P0 = ID0^ID1^ID2^ID4 in bit 6,
    P1 = not(ID1^ID3^ID4^ID5) in bit 7."""
    bit = [(frame_id >> n) & 1 for n in range(6)]
    p0 = bit[0] ^ bit[1] ^ bit[2] ^ bit[4]
    p1 = 1 ^ bit[1] ^ bit[3] ^ bit[4] ^ bit[5]
    return frame_id | (p0 << 6) | (p1 << 7)


class LinNode:
    """A LIN controller with its monitor; Commander and Responder say which mode."""

    _mode = LIN_OPMODE_SLAVE

    def __init__(self, channel: str, bitrate: Optional[int] = None, fifo_size: int = 256,
                 errors: bool = True) -> None:
        self._device = None
        self._control = None
        self._monitor = None
        self._ephemeral: Optional[str] = None
        self._initialized = False
        info = _vci.CANEMU_DEVICEINFO()
        device, _, number = channel.rpartition(":")
        if device and number.isdigit():
            controller = int(number)
            _call("canemuFindDevice", device.encode(), ctypes.byref(info))
        else:
            vciid = _vci.VCIID()
            name = ctypes.create_string_buffer(32)
            _vci.check("canemuCreateDevice",
                       _lib().canemuCreateDevice(channel.encode(), None, ctypes.byref(vciid),
                                                 name, 32))
            self._ephemeral = name.value.decode()
            _call("canemuFindDevice", name.value, ctypes.byref(info))
            controller = 0
        try:
            if controller >= info.bControllers or info.abFd[controller] != _vci.CANEMU_LIN_CONTROLLER:
                raise ValueError(f"channel {channel!r}: {info.szName.decode()}:{controller} is "
                                 f"not a LIN controller")
            self.name = f"{info.szName.decode()}:{controller}"
            self.bus = info.aszBus[controller].value.decode()
            self._epoch_ns = info.qwEpochNs
            self._last_ticks = 0
            self._wraps = 0
            if bitrate is None:
                bitrate = next((b["bitrate"] for b in _vci_buses() if b["name"] == self.bus),
                               19200)
            handle = HANDLE()
            _call("vciDeviceOpen", ctypes.byref(info.VciObjectId), ctypes.byref(handle))
            self._device = handle.value
            handle = HANDLE()
            _call("linMonitorOpen", self._device, controller, 0, ctypes.byref(handle))
            self._monitor = handle.value
            _call("linMonitorInitialize", self._monitor, fifo_size, 1)
            _call("linMonitorActivate", self._monitor, 1)
            handle = HANDLE()
            _call("linControlOpen", self._device, controller, ctypes.byref(handle))
            self._control = handle.value
            self._opmode = self._mode | (LIN_OPMODE_ERRORS if errors else 0)
            self._bitrate = bitrate
            _call("linControlInitialize", self._control, self._opmode, bitrate)
            self._initialized = True
            _call("linControlStart", self._control, 1)
        except (VciError, ValueError):
            self.close()
            raise

    # ---- the response table and the bus ----

    def set_response(self, frame_id: int, data: bytes, enhanced: bool = True) -> None:
        """Puts the response to `frame_id` (0..3Fh; 1 to 8 bytes) in the response table: the
        node answers that header with it from now on. Only a reset clears the table."""
        self._write(False, self._frame(frame_id, data, enhanced))

    def wakeup(self) -> None:
        """A wake-up pulse (250 us); the other nodes report it at its end."""
        m = LINMSG()
        m.bType = LIN_MSGTYPE_WAKEUP
        self._write(True, m)

    def recv(self, timeout: Optional[float] = None) -> Optional[LinMessage]:
        """The next message of the monitor, waiting up to `timeout` seconds (None: forever,
        0: not at all; in stepped time nothing comes while time stands still)."""
        m = LINMSG()
        while True:
            if timeout == 0:
                hr = _lib().linMonitorPeekMessage(self._monitor, ctypes.byref(m))
            else:
                ms = 0xFFFFFFFF if timeout is None else max(1, int(timeout * 1000))
                hr = _lib().linMonitorReadMessage(self._monitor, ms, ctypes.byref(m))
            if hr in (_vci.VCI_E_RXQUEUE_EMPTY, _vci.VCI_E_TIMEOUT):
                return None
            _vci.check("linMonitorReadMessage", hr)
            message = self._message(m)
            if message is not None:
                return message

    def reset(self) -> None:
        """Takes the node off the bus and empties its response table (the VCI's ResetLine:
        the controller is left uninitialised). start() goes on."""
        _call("linControlReset", self._control)
        self._initialized = False

    def start(self) -> None:
        """Puts the node on the bus again: after reset(), first initialised with the mode and
        bit rate it was opened with (as a VCI program calls InitLine after ResetLine); its
        response table starts empty."""
        if not self._initialized:
            _call("linControlInitialize", self._control, self._opmode, self._bitrate)
            self._initialized = True
        _call("linControlStart", self._control, 1)

    def close(self) -> None:
        for name, handle in (("linControlClose", self._control),
                             ("linMonitorClose", self._monitor), ("vciDeviceClose", self._device)):
            if handle:
                getattr(_lib(), name)(handle)
        self._control = self._monitor = self._device = None
        if self._ephemeral:
            _lib().canemuRemoveDevice(self._ephemeral.encode())
            self._ephemeral = None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ---- inside ----

    def _write(self, send: bool, m: LINMSG) -> None:
        _call("linControlWriteMessage", self._control, 1 if send else 0, ctypes.byref(m))

    @staticmethod
    def _frame(frame_id: int, data: bytes, enhanced: bool, header_only: bool = False) -> LINMSG:
        if not 0 <= frame_id <= 0x3F:
            raise ValueError(f"LIN identifiers are 0..3Fh, not {frame_id:#x}")
        if len(data) > 8 or (not data and not header_only):
            raise ValueError("a LIN response has 1 to 8 data bytes")
        m = LINMSG()
        m.bType = LIN_MSGTYPE_DATA
        m.bPid = frame_id
        m.bDlen = len(data)
        m.bFlags = (LIN_MSGFLAGS_ECS if enhanced else 0) | (LIN_MSGFLAGS_IDO if header_only else 0)
        for i, b in enumerate(data):
            m.abData[i] = b
        return m

    def _seconds(self, ticks: int) -> float:
        if ticks < self._last_ticks:
            self._wraps += 1  # the 32-bit microsecond counter wrapped
        self._last_ticks = ticks
        return (self._epoch_ns + ((self._wraps << 32) | ticks) * 1000) / 1e9

    def _message(self, m: LINMSG) -> Optional[LinMessage]:
        if m.bType == LIN_MSGTYPE_TMOVR:
            self._wraps += 1
            return None
        t = self._seconds(m.dwTime)
        if m.bType == LIN_MSGTYPE_DATA:
            n = min(m.bDlen, 8)
            return LinMessage("frame", t, id=m.bPid & 0x3F, data=bytes(m.abData[:n]),
                              enhanced=bool(m.bFlags & LIN_MSGFLAGS_ECS),
                              own=bool(m.bFlags & LIN_MSGFLAGS_SOR))
        if m.bType == LIN_MSGTYPE_ERROR:
            return LinMessage("error", t, error=ERRORS.get(m.abData[0], str(m.abData[0])))
        if m.bType == LIN_MSGTYPE_WAKEUP:
            return LinMessage("wakeup", t)
        if m.bType == LIN_MSGTYPE_INFO:
            return LinMessage("info", t, info=INFOS.get(m.abData[0], str(m.abData[0])))
        return None


class Responder(LinNode):
    """A LIN slave: it answers the headers of its response table."""

    _mode = LIN_OPMODE_SLAVE


class Commander(LinNode):
    """A LIN master: it sends headers (answered by a responder or by itself), the go-to-sleep
    command, and answers from its own response table too."""

    _mode = LIN_OPMODE_MASTER

    def send_header(self, frame_id: int) -> None:
        """The header of `frame_id`: a responder answers, or nobody (a no-response error)."""
        self._write(True, self._frame(frame_id, b"", True, header_only=True))

    def send_frame(self, frame_id: int, data: bytes, enhanced: bool = True) -> None:
        """The header of `frame_id` and this node's own response."""
        self._write(True, self._frame(frame_id, data, enhanced))

    def sleep(self) -> None:
        """The go-to-sleep command (3Ch 00 FF FF FF FF FF FF FF, classic checksum)."""
        m = LINMSG()
        m.bType = LIN_MSGTYPE_SLEEP
        self._write(True, m)


def _vci_buses() -> list:
    from ._daemon import _buses

    return _buses()
