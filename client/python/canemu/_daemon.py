"""canemud as a whole: which daemon this process talks to, its simulated time (and stepping it),
its buses and adapters."""

from __future__ import annotations

import ctypes
import sys
import threading
import time
from typing import Any, Dict, Iterator, List, Optional, Tuple

from . import _vci
from ._calls import _call, _vci_errors

_offset_lock = threading.Lock()
_offset: Optional[float] = None
_socket: Optional[str] = None  # what connect() chose (None: $CANEMU_SOCKET or the default)


def _wall_offset() -> float:
    """What is added to simulated seconds to make a time stamp: in real time the wall-clock
    instant of simulated time 0 (measured once per daemon, so that every bus of the process
    agrees), otherwise 0."""
    global _offset
    with _offset_lock:
        if _offset is None:
            before = time.time()
            now_ns, mode = _sim_time()
            after = time.time()
            realtime = mode == _vci.CANEMU_TIME_REALTIME
            _offset = (before + after) / 2 - now_ns / 1e9 if realtime else 0.0
        return _offset


def connect(socket: Optional[str]) -> None:
    """Talks to the canemud at `socket` from now on (None: $CANEMU_SOCKET or the default path).
    The choice is for the whole process, and it ends the process's connection to the daemon it
    talked to before: buses opened there stop working (their adapters are closed with it), so
    close them first. A program talks to one canemud; run one per daemon."""
    global _offset, _socket
    with _offset_lock:
        _offset = None
    with _vci_errors(initializing=True):
        _call("canemuConnect", socket.encode() if socket else None)
    _socket = socket  # libxcan follows when an X-CAN-2i is next asked for (_xcan.use_socket)
    shim = sys.modules.get("canemu.ixxat_shim")
    if shim is not None:  # python-can's ixxat interface on libvcinpl.so follows at once
        shim.use_socket(socket)


def current_socket() -> Optional[str]:
    """The socket connect() chose for the process (None: the default search)."""
    return _socket


def step(nanoseconds: int) -> int:
    """Stepped time: runs canemud's emulation `nanoseconds` further; returns the simulated time
    in ns after the step. CanOperationError when canemud does not run in stepped time."""
    now = ctypes.c_uint64()
    hr = _vci.lib().canemuStepTime(int(nanoseconds), ctypes.byref(now))
    if hr != _vci.VCI_OK:  # (the block only then: a program may step after every frame)
        with _vci_errors():
            _vci.check("canemuStepTime", hr)
    return now.value


def _sim_time() -> Tuple[int, int]:
    now = ctypes.c_uint64()
    mode = ctypes.c_uint8()
    _call("canemuGetTime", ctypes.byref(now), ctypes.byref(mode))
    return now.value, mode.value


def sim_time() -> Tuple[int, int]:
    """(simulated time in ns, time mode: 0 real time, 1 scaled, 2 stepped).
    CanOperationError when canemud cannot be asked."""
    with _vci_errors():
        return _sim_time()


def _enumerate(call: str, info) -> Iterator[None]:
    """Fills `info` with item 0, 1, ... of an enumeration call until it says there are no
    more; VciError for any other failure (canemud gone)."""
    index = 0
    while True:
        hr = getattr(_vci.lib(), call)(index, ctypes.byref(info))
        if hr == _vci.VCI_E_NO_MORE_ITEMS:
            return
        _vci.check(call, hr)
        yield
        index += 1


def _buses() -> List[Dict[str, Any]]:
    kinds = {_vci.CANEMU_BUS_CAN: "can", _vci.CANEMU_BUS_CANFD: "can-fd", _vci.CANEMU_BUS_LIN: "lin"}
    out = []
    info = _vci.CANEMU_BUSINFO()
    for _ in _enumerate("canemuEnumBuses", info):
        out.append(
            {
                "name": info.szName.decode(),
                "kind": kinds.get(info.bKind, "unknown"),
                "transceiver": "low-speed" if info.bLowSpeed else "high-speed",
                "bitrate": info.dwBitrate,
                "data_bitrate": info.dwDataBitrate,
            }
        )
    return out


def buses() -> List[Dict[str, Any]]:
    """canemud's buses: name, kind ("can", "can-fd", "lin"), transceiver ("high-speed",
    "low-speed"), bitrate, data_bitrate. CanOperationError when canemud cannot be asked."""
    with _vci_errors():
        return _buses()


def _devices() -> List[_vci.CANEMU_DEVICEINFO]:
    out = []
    info = _vci.CANEMU_DEVICEINFO()
    for _ in _enumerate("canemuEnumDevices", info):
        out.append(_vci.CANEMU_DEVICEINFO.from_buffer_copy(info))
    return out


def devices() -> List[_vci.CANEMU_DEVICEINFO]:
    """canemud's adapters, configured and ephemeral (CANEMU_DEVICEINFO). CanOperationError
    when canemud cannot be asked."""
    with _vci_errors():
        return _devices()
