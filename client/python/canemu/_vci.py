"""ctypes bindings of canemu's VCI C API v2 (libvcinpl2.so) and its canemu extensions.

Only what the python-can interface uses. The structs mirror cantype.h, vcitype.h and
canemu_vci.h byte for byte (their sizes are checked when the module loads).
"""

from __future__ import annotations

import ctypes
import importlib
import importlib.machinery
import importlib.util
import os
import shutil
import sys
from pathlib import Path
from typing import Optional

HRESULT = ctypes.c_uint32  # read unsigned: the VCI_E_* codes have the top bit set
HANDLE = ctypes.c_void_p

VCI_OK = 0


def _code(n: int) -> int:
    return 0xE0010000 | n


VCI_E_TIMEOUT = _code(0x000B)
VCI_E_OUTOFMEMORY = _code(0x0003)
VCI_E_INVALIDARG = _code(0x0004)
VCI_E_ACCESSDENIED = _code(0x000A)
VCI_E_NO_MORE_ITEMS = _code(0x000F)
VCI_E_RXQUEUE_EMPTY = _code(0x0012)
VCI_E_TXQUEUE_FULL = _code(0x0013)
VCI_E_DISCONNECTED = _code(0x0019)
VCI_E_INVALID_STATE = _code(0x0015)

CAN_OPMODE_STANDARD = 0x01
CAN_OPMODE_EXTENDED = 0x02
CAN_OPMODE_ERRFRAME = 0x04
CAN_OPMODE_LISTONLY = 0x08
CAN_EXMODE_DISABLED = 0x00
CAN_EXMODE_EXTDATA = 0x01
CAN_EXMODE_FASTDATA = 0x02
CAN_BTMODE_RAW = 0x01
CAN_BTMODE_TSM = 0x02

CAN_FILTER_LOCK = 0x01
CAN_FILTER_PASS = 0x02
CAN_FILTER_INCL = 0x03
CAN_FILTER_SRRA = 0x80  # flag of a v2 channel's filter mode: self-reception of the others too

CAN_MSGTYPE_DATA = 0
CAN_MSGTYPE_INFO = 1
CAN_MSGTYPE_ERROR = 2
CAN_MSGTYPE_STATUS = 3
CAN_MSGTYPE_TIMEOVR = 5

CAN_ERROR_STUFF = 1
CAN_ERROR_FORM = 2
CAN_ERROR_ACK = 3
CAN_ERROR_BIT = 4
CAN_ERROR_FDB = 5
CAN_ERROR_CRC = 6

CAN_STATUS_TXPEND = 0x01
CAN_STATUS_ERRLIM = 0x04
CAN_STATUS_BUSOFF = 0x08
CAN_STATUS_ININIT = 0x10
CAN_STATUS_BUSCERR = 0x20

CANEMU_STATE_ACTIVE = 0
CANEMU_STATE_WARNING = 1
CANEMU_STATE_PASSIVE = 2
CANEMU_STATE_BUSOFF = 3

CANEMU_LINE_ONLINE = 2

CANEMU_TIME_REALTIME = 0
CANEMU_TIME_SCALED = 1
CANEMU_TIME_STEPPED = 2

CANEMU_BUS_CAN = 0
CANEMU_BUS_CANFD = 1
CANEMU_BUS_LIN = 2

CANEMU_MAX_CONTROLLERS = 4
CANEMU_LIN_CONTROLLER = 2  # CANEMU_DEVICEINFO.abFd of a LIN controller
CANEMU_MAX_EPHEMERAL = 16  # canemuCreateDevice: adapters per connection (process)
INFINITE = 0xFFFFFFFF

# Data bytes of each DLC (ISO 11898-1).
DLC_TO_LEN = (0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64)


def len_to_dlc(length: int) -> int:
    for dlc, n in enumerate(DLC_TO_LEN):
        if n >= length:
            return dlc
    raise ValueError(f"{length} data bytes do not fit a CAN FD frame (at most 64)")


class VCIID(ctypes.Union):
    _fields_ = [("AsInt64", ctypes.c_int64)]


class CANBTP(ctypes.Structure):
    _pack_ = 1
    _fields_ = [
        ("dwMode", ctypes.c_uint32),
        ("dwBPS", ctypes.c_uint32),
        ("wTS1", ctypes.c_uint16),
        ("wTS2", ctypes.c_uint16),
        ("wSJW", ctypes.c_uint16),
        ("wTDO", ctypes.c_uint16),
    ]


class CANCAPABILITIES2(ctypes.Structure):
    """What a controller can do, as canControlGetCaps reports it: among others its CAN clock
    and the raw ranges of its nominal (SDR) and data (FDR) bit timing."""

    _pack_ = 1
    _fields_ = [
        ("wCtrlType", ctypes.c_uint16),
        ("wBusCoupling", ctypes.c_uint16),
        ("dwFeatures", ctypes.c_uint32),
        ("dwCanClkFreq", ctypes.c_uint32),
        ("sSdrRangeMin", CANBTP),
        ("sSdrRangeMax", CANBTP),
        ("sFdrRangeMin", CANBTP),
        ("sFdrRangeMax", CANBTP),
        ("dwTscClkFreq", ctypes.c_uint32),
        ("dwTscDivisor", ctypes.c_uint32),
        ("dwCmsClkFreq", ctypes.c_uint32),
        ("dwCmsDivisor", ctypes.c_uint32),
        ("dwCmsMaxTicks", ctypes.c_uint32),
        ("dwDtxClkFreq", ctypes.c_uint32),
        ("dwDtxDivisor", ctypes.c_uint32),
        ("dwDtxMaxTicks", ctypes.c_uint32),
    ]


class CANLINESTATUS2(ctypes.Structure):
    _pack_ = 1
    _fields_ = [
        ("bOpMode", ctypes.c_uint8),
        ("bExMode", ctypes.c_uint8),
        ("bBusLoad", ctypes.c_uint8),
        ("bReserved", ctypes.c_uint8),
        ("sBtpSdr", CANBTP),
        ("sBtpFdr", CANBTP),
        ("dwStatus", ctypes.c_uint32),
    ]


class CANCHANSTATUS2(ctypes.Structure):
    """A channel's status (canChannelGetStatus): the line's status and the FIFOs' fill levels,
    in percent of their capacity."""

    _pack_ = 1
    _fields_ = [
        ("sLineStatus", CANLINESTATUS2),
        ("fActivated", ctypes.c_uint8),
        ("fRxOverrun", ctypes.c_uint8),
        ("bRxFifoLoad", ctypes.c_uint8),
        ("bTxFifoLoad", ctypes.c_uint8),
    ]


# CANMSGINFO as its four bytes: type, flags2 (ssm hpm edl fdr esi), flags (dlc:4 ovr srr rtr
# ext), accept; then the data field. The end of CANMSG2 and CANCYCLICTXMSG2.
_INFO_AND_DATA = [
    ("bType", ctypes.c_uint8),
    ("bFlags2", ctypes.c_uint8),
    ("bFlags", ctypes.c_uint8),
    ("bAccept", ctypes.c_uint8),
    ("abData", ctypes.c_uint8 * 64),
]


class CANMSG2(ctypes.Structure):
    _pack_ = 1
    _fields_ = [
        ("dwTime", ctypes.c_uint32),
        ("_rsvd_", ctypes.c_uint32),
        ("dwMsgId", ctypes.c_uint32),
    ] + _INFO_AND_DATA


# CANMSGINFO bits in bFlags2 and bFlags.
FLAGS2_SSM = 0x01
FLAGS2_HPM = 0x02
FLAGS2_EDL = 0x04
FLAGS2_FDR = 0x08
FLAGS2_ESI = 0x10
FLAGS_DLC = 0x0F
FLAGS_OVR = 0x10
FLAGS_SRR = 0x20
FLAGS_RTR = 0x40
FLAGS_EXT = 0x80


class CANCYCLICTXMSG2(ctypes.Structure):
    _pack_ = 1
    _fields_ = [
        ("wCycleTime", ctypes.c_uint16),
        ("bIncrMode", ctypes.c_uint8),
        ("bByteIndex", ctypes.c_uint8),
        ("dwMsgId", ctypes.c_uint32),
    ] + _INFO_AND_DATA


class CANEMU_BUSINFO(ctypes.Structure):
    _fields_ = [
        ("szName", ctypes.c_char * 32),
        ("bKind", ctypes.c_uint8),
        ("bLowSpeed", ctypes.c_uint8),
        ("abReserved", ctypes.c_uint8 * 2),
        ("dwBitrate", ctypes.c_uint32),
        ("dwDataBitrate", ctypes.c_uint32),
        ("dwReserved", ctypes.c_uint32),
    ]


class CANEMU_DEVICEINFO(ctypes.Structure):
    _fields_ = [
        ("szName", ctypes.c_char * 32),
        ("VciObjectId", VCIID),
        ("qwEpochNs", ctypes.c_int64),
        ("bControllers", ctypes.c_uint8),
        ("bEphemeral", ctypes.c_uint8),
        ("abFd", ctypes.c_uint8 * CANEMU_MAX_CONTROLLERS),
        ("abReserved", ctypes.c_uint8 * 2),
        ("aszBus", (ctypes.c_char * 32) * CANEMU_MAX_CONTROLLERS),
    ]


for _struct, _size in (
    (CANBTP, 16),
    (CANCAPABILITIES2, 108),
    (CANMSG2, 80),
    (CANCYCLICTXMSG2, 76),
    (CANEMU_BUSINFO, 48),
    (CANEMU_DEVICEINFO, 184),
):
    assert ctypes.sizeof(_struct) == _size, f"{_struct.__name__} is not {_size} bytes"


class VciError(Exception):
    """A VCI call failed: `hr` is its result, the message the library's text for it."""

    def __init__(self, call: str, hr: int, text: str) -> None:
        super().__init__(f"{call}: {text} (0x{hr:08X})")
        self.call = call
        self.hr = hr
        self.text = text  # the library's own text (vciFormatError)


def _library_candidates(filename: str = "libvcinpl2.so") -> list:
    """Where one of canemu's libraries is looked for, in order."""
    names = []
    libdir = os.environ.get("CANEMU_LIBDIR")
    if libdir:
        names.append(str(Path(libdir) / filename))
    # A source checkout: client/python/canemu -> the repository's build tree.
    repo = Path(__file__).resolve().parents[3]
    names.append(str(repo / "build" / "lib" / filename))
    # The build tree of the canemud a test would start ($CANEMUD, else canemud on the PATH):
    # BUILD/bin/canemud -> BUILD/lib.
    canemud = os.environ.get("CANEMUD") or shutil.which("canemud")
    if canemud:
        beside = Path(canemud).resolve().parent.parent / "lib" / filename
        if str(beside) not in names:
            names.append(str(beside))
    names.append(filename)  # the dynamic linker's search (an installed canemu)
    return names


_SIGNATURES = {
    # name: (argument types)
    "vciFormatError": (HRESULT, ctypes.c_char_p, ctypes.c_uint32),
    "vciDeviceOpen": (ctypes.POINTER(VCIID), ctypes.POINTER(HANDLE)),
    "vciDeviceClose": (HANDLE,),
    "canControlOpen": (HANDLE, ctypes.c_uint32, ctypes.POINTER(HANDLE)),
    "canControlClose": (HANDLE,),
    "canControlGetCaps": (HANDLE, ctypes.POINTER(CANCAPABILITIES2)),
    "canControlInitialize": (
        HANDLE,
        ctypes.c_uint8,
        ctypes.c_uint8,
        ctypes.c_uint8,
        ctypes.c_uint8,
        ctypes.c_uint32,
        ctypes.c_uint32,
        ctypes.POINTER(CANBTP),
        ctypes.POINTER(CANBTP),
    ),
    "canControlStart": (HANDLE, ctypes.c_int),
    "canControlReset": (HANDLE,),
    "canChannelOpen": (HANDLE, ctypes.c_uint32, ctypes.c_int, ctypes.POINTER(HANDLE)),
    "canChannelClose": (HANDLE,),
    "canChannelInitialize": (
        HANDLE,
        ctypes.c_uint16,
        ctypes.c_uint16,
        ctypes.c_uint16,
        ctypes.c_uint16,
        ctypes.c_uint32,
        ctypes.c_uint8,
    ),
    "canChannelActivate": (HANDLE, ctypes.c_int),
    "canChannelGetStatus": (HANDLE, ctypes.POINTER(CANCHANSTATUS2)),
    "canChannelSetFilterMode": (
        HANDLE,
        ctypes.c_int,
        ctypes.c_uint8,
        ctypes.POINTER(ctypes.c_uint8),
    ),
    "canChannelSetAccFilter": (HANDLE, ctypes.c_int, ctypes.c_uint32, ctypes.c_uint32),
    "canChannelAddFilterIds": (HANDLE, ctypes.c_int, ctypes.c_uint32, ctypes.c_uint32),
    "canChannelRemFilterIds": (HANDLE, ctypes.c_int, ctypes.c_uint32, ctypes.c_uint32),
    "canChannelPeekMessage": (HANDLE, ctypes.POINTER(CANMSG2)),
    "canChannelPeekMsgMult": (
        HANDLE,
        ctypes.POINTER(CANMSG2),
        ctypes.c_uint32,
        ctypes.POINTER(ctypes.c_uint32),
    ),
    "canChannelReadMessage": (HANDLE, ctypes.c_uint32, ctypes.POINTER(CANMSG2)),
    "canChannelPostMessage": (HANDLE, ctypes.POINTER(CANMSG2)),
    "canChannelSendMessage": (HANDLE, ctypes.c_uint32, ctypes.POINTER(CANMSG2)),
    "canSchedulerOpen": (HANDLE, ctypes.c_uint32, ctypes.POINTER(HANDLE)),
    "canSchedulerClose": (HANDLE,),
    "canSchedulerActivate": (HANDLE, ctypes.c_int),
    "canSchedulerAddMessage": (
        HANDLE,
        ctypes.POINTER(CANCYCLICTXMSG2),
        ctypes.POINTER(ctypes.c_uint32),
    ),
    "canSchedulerRemMessage": (HANDLE, ctypes.c_uint32),
    "canSchedulerStartMessage": (HANDLE, ctypes.c_uint32, ctypes.c_uint16),
    "canSchedulerStopMessage": (HANDLE, ctypes.c_uint32),
    "canemuConnect": (ctypes.c_char_p,),
    "canemuGetControllerState": (
        HANDLE,
        ctypes.POINTER(ctypes.c_uint8),
        ctypes.POINTER(ctypes.c_uint16),
        ctypes.POINTER(ctypes.c_uint16),
        ctypes.POINTER(ctypes.c_uint8),
    ),
    "canemuStepTime": (ctypes.c_uint64, ctypes.POINTER(ctypes.c_uint64)),
    "canemuCreateDevice": (
        ctypes.c_char_p,
        ctypes.c_char_p,
        ctypes.POINTER(VCIID),
        ctypes.c_char_p,
        ctypes.c_uint32,
    ),
    "canemuRemoveDevice": (ctypes.c_char_p,),
    "canemuEnumBuses": (ctypes.c_uint32, ctypes.POINTER(CANEMU_BUSINFO)),
    "canemuEnumDevices": (ctypes.c_uint32, ctypes.POINTER(CANEMU_DEVICEINFO)),
    "canemuFindDevice": (ctypes.c_char_p, ctypes.POINTER(CANEMU_DEVICEINFO)),
    "canemuGetTime": (ctypes.POINTER(ctypes.c_uint64), ctypes.POINTER(ctypes.c_uint8)),
    "canemuChannelEventFd": (HANDLE, ctypes.POINTER(ctypes.c_int)),
}

_lib: Optional[ctypes.CDLL] = None


def lib() -> ctypes.CDLL:
    """libvcinpl2.so, loaded once (OSError naming every place looked at when it is missing)."""
    global _lib
    if _lib is not None:
        return _lib
    tried = []
    for name in _library_candidates():
        try:
            loaded = ctypes.CDLL(name)
        except OSError as e:
            tried.append(f"{name} ({e})")
            continue
        for func, args in _SIGNATURES.items():
            f = getattr(loaded, func)
            f.argtypes = args
            f.restype = None if func == "vciFormatError" else HRESULT
        _lib = loaded
        return _lib
    raise OSError(
        "canemu's VCI library libvcinpl2.so was not found; build canemu (make build) or set "
        "CANEMU_LIBDIR to the folder that holds it. Tried: " + "; ".join(tried)
    )


def declare(signatures: dict) -> None:
    """Gives the functions of `signatures` (name: argument types) their argument types and an
    HRESULT result in libvcinpl2.so, for a module with calls of its own (lin, restbus)."""
    loaded = lib()
    for func, args in signatures.items():
        f = getattr(loaded, func)
        f.argtypes = args
        f.restype = HRESULT


def unconverted(func: str, keep_gil: bool = False):
    """A second binding of `func` of libvcinpl2.so with its result type but no argtypes: ctypes
    then converts no argument, so the caller passes ctypes objects only (handles as c_void_p,
    pointers as byref). For the hot paths. With `keep_gil` the call holds Python's global lock
    instead of releasing and taking it again (about 20 ns less): only for calls that never wait
    (canChannelPostMessage)."""
    loaded = lib()
    f = (ctypes.PyDLL(loaded._name, handle=loaded._handle) if keep_gil else loaded)[func]
    f.restype = HRESULT
    return f


_SPEEDUPS = "canemu_speedups"
_speedups: Optional[object] = None
_speedups_looked = False


def speedups():
    """canemu_speedups, send()'s hot path in C (client/python/speedups), or None: the build's,
    beside the libvcinpl2.so that lib() loaded from a folder of its own (the two are made
    together), else one installed with the package (import canemu_speedups). None without it,
    before Python 3.10 (its stable ABI) and with CANEMU_SPEEDUPS=0: the Python path then does
    the same."""
    global _speedups, _speedups_looked
    if _speedups_looked:
        return _speedups
    _speedups_looked = True
    if os.environ.get("CANEMU_SPEEDUPS") == "0" or sys.version_info < (3, 10):
        return None
    name = lib()._name
    beside = Path(name).resolve().parent / f"{_SPEEDUPS}.abi3.so"
    # (Only beside a library loaded by its path, which has a '/': one the dynamic linker found
    # by its name has no folder here, and the current directory is nobody's to load code from.)
    if ("/" in name and beside.is_file()
            and ".abi3.so" in importlib.machinery.EXTENSION_SUFFIXES):
        spec = importlib.util.spec_from_file_location(_SPEEDUPS, beside)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        _speedups = module
        return _speedups
    try:
        _speedups = importlib.import_module(_SPEEDUPS)
    except ImportError:
        _speedups = None
    return _speedups


def address_of(func: str) -> int:
    """The address of `func` in libvcinpl2.so (for canemu_speedups)."""
    return ctypes.cast(getattr(lib(), func), ctypes.c_void_p).value


def error_text(hr: int) -> str:
    buf = ctypes.create_string_buffer(512)
    lib().vciFormatError(hr, buf, len(buf))
    return buf.value.decode(errors="replace")


def check(call: str, hr: int) -> None:
    """Raises VciError for a failed call."""
    if hr != VCI_OK:
        raise VciError(call, hr, error_text(hr))
