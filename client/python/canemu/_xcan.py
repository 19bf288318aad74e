"""ctypes bindings of canemu's SORCUS X-CAN-2i library (libxcan.so, xcan.h and xcan_types.h).

Only what the python-can interface uses. The structs mirror xcan_types.h and xcan.h byte for
byte (their sizes are checked when the module loads); the constants are canemu's values of the
manual's names (docs/sorcus.md).
"""

from __future__ import annotations

import ctypes
import threading
from typing import List, Optional

from ._vci import _library_candidates

ULONG = ctypes.c_uint32
USHORT = ctypes.c_uint16
MAX_HANDLE = ctypes.c_uint32

DEVICE_CTRL = 1
DEVICE_BUS_OUT = 2
XCAN_BUS_CTRL_INDEX = 0x0100
XCAN_GENERAL_ID = 0xFFFFFFFE
XCAN_AUTO_ID = 0xFFFFFFFF
_CP_EXCLUSIVE = 0x0002
XCAN_REMOTE = 0x0010
XCAN_29BIT_ID = 0x0100
XCAN_MIXED_FORMAT = 0x00FF
XCAN_MAX_ID_11 = 0x7EF
XCAN_MAX_ID_29 = 0x1FFFFFEF

CMD_START = 1
CMD_STOP = 2
INFO_DEVICE = 1

XCAN_BUS_ON = 0x0001
XCAN_BUS_HEAVY = 0x0002
XCAN_BUS_OFF = 0x0004
XCAN_LINE_ERROR = 0x0008

XCAN_LEC_STUFF = 1
XCAN_LEC_FORM = 2
XCAN_LEC_ACK = 3
XCAN_LEC_BIT1 = 4
XCAN_LEC_BIT0 = 5
XCAN_LEC_CRC = 6

ERR_OK = 0
ERR_XCAN_PARAM = 0x24
ERR_XCAN_EXCL_LIMIT = 0x27
ERR_XCAN_FIFO_FULL = 0x2B
ERR_XCAN_CHANNEL_BUSY = 0x42
ERR_XCAN_ID_RANGE = 0x41
ERR_XCAN_NOT_READY = 0x48
ERR_XCAN_NO_DAEMON = 0x60
ERR_XCAN_NO_MODULE = 0x61

_ERROR_NAMES = {
    0x21: "ERR_XCAN_NO_MEMORY",
    0x24: "ERR_XCAN_PARAM",
    0x27: "ERR_XCAN_EXCL_LIMIT",
    0x28: "ERR_XCAN_CPS_MISMATCH",
    0x29: "ERR_XCAN_MASK_EXCLUDES",
    0x2A: "ERR_XCAN_WRONG_TYPE",
    0x2B: "ERR_XCAN_FIFO_FULL",
    0x2C: "ERR_XCAN_BUFFER15_MIXED",
    0x40: "ERR_XCAN_INVALID_CPS",
    0x41: "ERR_XCAN_ID_RANGE",
    0x42: "ERR_XCAN_CHANNEL_BUSY",
    0x43: "ERR_XCAN_TIMEOUT",
    0x44: "ERR_XCAN_DATA_SIZE",
    0x45: "ERR_XCAN_INVALID_HANDLE",
    0x46: "ERR_XCAN_INDEX",
    0x47: "ERR_XCAN_AUTO_ID_REQUIRED",
    0x48: "ERR_XCAN_NOT_READY",
    0x50: "ERR_DATA_NOT_READY",
    0x60: "ERR_XCAN_NO_DAEMON",
    0x61: "ERR_XCAN_NO_MODULE",
}


def error_name(code: int) -> str:
    return f"{_ERROR_NAMES.get(code, 'error')} (0x{code:02X})"


class XcanError(Exception):
    """A libxcan call that failed: the call and its error code."""

    def __init__(self, call: str, code: int, text: str = "") -> None:
        super().__init__(f"{call}: {error_name(code)}{': ' + text if text else ''}")
        self.call = call
        self.code = code


class CPS_XCAN(ctypes.Structure):
    _fields_ = [
        ("usDevice", USHORT),
        ("usChannel", USHORT),
        ("usIndexFirst", USHORT),
        ("usIndexLast", USHORT),
        ("usFlags", USHORT),
        ("usTimeout", USHORT),
        ("ulCanID", ULONG),
    ]


class XCAN_BITPARAMS(ctypes.Structure):
    _fields_ = [
        ("Tq", USHORT),
        ("Tseg1", USHORT),
        ("Tseg2", USHORT),
        ("Tsjw", USHORT),
        ("SpB", USHORT),
        ("Rbus", USHORT),
        ("MsgFormat", USHORT),
    ]


class XCAN_MESSAGE(ctypes.Structure):
    _fields_ = [
        ("ulCanId", ULONG),
        ("usDataSize", USHORT),
        ("usFlags", USHORT),
        ("aucData", ctypes.c_uint8 * 8),
    ]


class CANEMU_XCAN_INTERFACE(ctypes.Structure):
    _fields_ = [
        ("szDevice", ctypes.c_char * 32),
        ("szBus", ctypes.c_char * 32),
        ("usChannel", USHORT),
        ("usLowSpeed", USHORT),
        ("ulBitrate", ULONG),
    ]


for _struct, _size in ((CPS_XCAN, 16), (XCAN_BITPARAMS, 14), (XCAN_MESSAGE, 16),
                       (CANEMU_XCAN_INTERFACE, 72)):
    assert ctypes.sizeof(_struct) == _size, f"{_struct.__name__} is not {_size} bytes"

# void (*MAX_CALLBACK)(MAX_HANDLE hChan, ULONG ulSize, const void* pData)
MAX_CALLBACK = ctypes.CFUNCTYPE(None, MAX_HANDLE, ULONG, ctypes.c_void_p)

_SIGNATURES = {
    "canemu_xcan_connect": (ctypes.c_char_p,),
    "canemu_xcan_enum_interfaces": (ULONG, ctypes.POINTER(CANEMU_XCAN_INTERFACE)),
    "canemu_xcan_callback_time": (ctypes.POINTER(ctypes.c_ulonglong),),
    "canemu_open_module": (ctypes.c_char_p, ctypes.POINTER(MAX_HANDLE)),
    "max_load_mdd": (MAX_HANDLE, USHORT, USHORT, USHORT, USHORT, ctypes.c_void_p,
                     ctypes.POINTER(MAX_HANDLE)),
    "max_open_channel": (MAX_HANDLE, ctypes.POINTER(CPS_XCAN), MAX_CALLBACK,
                         ctypes.POINTER(MAX_HANDLE)),
    "max_close_channel": (MAX_HANDLE,),
    "max_write_channel_block": (MAX_HANDLE, ctypes.POINTER(ULONG), ctypes.c_void_p),
    "max_read_channel_block": (MAX_HANDLE, ctypes.POINTER(ULONG), ctypes.c_void_p),
    "max_write_channel_ulong": (MAX_HANDLE, ULONG),
    "max_channel_control": (MAX_HANDLE, USHORT),
    "max_channel_info": (MAX_HANDLE, USHORT, ctypes.POINTER(ULONG)),
}

_lib: Optional[ctypes.CDLL] = None
_lock = threading.Lock()
_socket: Optional[str] = None  # the socket libxcan was pointed at (None: its own search)


def lib() -> ctypes.CDLL:
    """libxcan.so, loaded once (OSError naming every place looked at when it is missing)."""
    global _lib
    with _lock:
        if _lib is not None:
            return _lib
        tried = []
        for name in _library_candidates("libxcan.so"):
            try:
                loaded = ctypes.CDLL(name)
            except OSError as e:
                tried.append(f"{name} ({e})")
                continue
            for func, args in _SIGNATURES.items():
                f = getattr(loaded, func)
                f.argtypes = args
                f.restype = ULONG
            _lib = loaded
            return _lib
    raise OSError(
        "canemu's X-CAN-2i library libxcan.so was not found; build canemu (make build) or set "
        "CANEMU_LIBDIR to the folder that holds it. Tried: " + "; ".join(tried)
    )


def check(call: str, code: int, text: str = "") -> None:
    if code != ERR_OK:
        raise XcanError(call, code, text)


def use_socket(socket: Optional[str]) -> None:
    """Points libxcan at `socket` (None: $CANEMU_SOCKET or the default path), unless it talks
    to that one already: a reconnection drops every X-CAN handle of the process."""
    global _socket
    if socket == _socket:
        return
    code = lib().canemu_xcan_connect(socket.encode() if socket else None)
    check("canemu_xcan_connect", code, f"canemud does not answer at {socket}" if socket else "")
    _socket = socket


def interfaces() -> List[CANEMU_XCAN_INTERFACE]:
    """canemud's X-CAN-2i interfaces; XcanError when canemud cannot be asked."""
    out = []
    index = 0
    while True:
        info = CANEMU_XCAN_INTERFACE()
        code = lib().canemu_xcan_enum_interfaces(index, ctypes.byref(info))
        if code == ERR_XCAN_NO_MODULE:
            return out
        check("canemu_xcan_enum_interfaces", code)
        out.append(info)
        index += 1


def callback_time() -> int:
    """In a callback: the simulated instant (ns) of what it reports."""
    at = ctypes.c_ulonglong()
    check("canemu_xcan_callback_time", lib().canemu_xcan_callback_time(ctypes.byref(at)))
    return at.value
