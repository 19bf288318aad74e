"""python-can's own ``ixxat`` interface, unmodified, on canemu's VCI C libraries.

    import canemu.ixxat_shim; canemu.ixxat_shim.install()
    bus = can.Bus(interface="ixxat", channel=0, bitrate=500000)

python-can's IXXAT backend (``can.interfaces.ixxat``) is written for Windows: it loads
``vcinpl.dll`` / ``vcinpl2.dll`` only when ``sys.platform`` is ``"win32"`` or ``"cygwin"``, it
imports ``HRESULT`` from ``can.ctypesutil`` (which defines it only on those two platforms, so the
import fails anywhere else), and its ctypes prototypes use ``c_long`` / ``c_ulong`` for the
VCI's 32-bit ``HRESULT`` and ``BOOL`` (32 bits on Windows, 64 on Linux). ``install()`` imports
the backend with exactly these four things bridged, and changes nothing else:

1. ``can.ctypesutil.HRESULT`` is defined (a signed 32-bit integer, as in ``vcitype.h``) when
   python-can did not define it;
2. while the backend's two modules execute, ``sys.platform`` reads ``"win32"`` and
   ``can.ctypesutil.CLibrary`` is a subclass that
3. loads canemu's ``libvcinpl.so`` for ``"vcinpl.dll"`` and ``libvcinpl2.so`` for
   ``"vcinpl2.dll"`` (looked for like the rest of this package does: ``$CANEMU_LIBDIR``, the
   ``build/lib`` of the source tree, then the dynamic linker), and
4. maps each prototype's ``c_long`` / ``c_ulong`` to 32 bits: results are read as unsigned
   32-bit values (what python-can's status check compares with its ``VCI_E_*`` constants;
   a 64-bit read would take the undefined upper half of the register too), ``BOOL``
   arguments are passed as 32-bit ints.

Both are put back when the import is done. python-can's files are not touched; the backend's
code runs as shipped, with its Windows branch taken. libvcinpl.so talks to the canemud this
package talks to: the one of ``canemu.connect()`` (also a later one: libvcinpl.so goes over when
the backend next enumerates adapters, at its next bus; ``install(socket)`` picks one
explicitly), else ``$CANEMU_SOCKET`` or the default path. docs/python-ixxat.md says what
python-can's backend then does on canemu.
"""

from __future__ import annotations

import ctypes
import importlib
import logging
import sys
import threading
from typing import Optional

from . import _daemon, _vci

log = logging.getLogger("canemu.ixxat_shim")

__all__ = ["HRESULT", "install", "installed", "library_path", "use_socket"]

# The Windows names python-can asks for and canemu's libraries that stand for them.
LIBRARIES = {"vcinpl.dll": "libvcinpl.so", "vcinpl2.dll": "libvcinpl2.so"}
# The backend's modules that load a library (the package imports both through canlib).
MODULES = ("can.interfaces.ixxat.canlib_vcinpl", "can.interfaces.ixxat.canlib_vcinpl2")


class HRESULT(ctypes.c_int32):
    """A VCI result: 32-bit signed, negative for errors (``vcitype.h``)."""


_lock = threading.Lock()
_paths: dict = {}  # Windows name -> the path of canemu's library loaded for it
_own: dict = {}  # Windows name -> this module's own CDLL of that library (canemuConnect)
_socket: Optional[str] = None  # the socket libvcinpl.so was pointed at (None: its own search)
_wanted: Optional[str] = None  # the socket it is to talk to from its next enumeration on


def _find(filename: str) -> str:
    """The first of canemu's usual places where `filename` loads (OSError naming them all)."""
    if filename == "libvcinpl2.so":
        # The library canemu's own interface uses: one and the same connection to canemud.
        return _vci.lib()._name
    tried = []
    for name in _vci._library_candidates(filename):
        try:
            ctypes.CDLL(name)
        except OSError as e:
            tried.append(f"{name} ({e})")
            continue
        return name
    raise OSError(
        f"canemu's VCI library {filename} was not found; build canemu (make build) or set "
        "CANEMU_LIBDIR to the folder that holds it. Tried: " + "; ".join(tried)
    )


def _narrow(t):
    """A ctypes type of python-can's prototypes as wide as it is on Windows (LLP64)."""
    if t is ctypes.c_long:
        return ctypes.c_int32
    if t is ctypes.c_ulong:
        return ctypes.c_uint32
    return t


def _library_class(base):
    """python-can's CLibrary with the library name and the prototypes mapped for Linux."""

    class CanemuVciLibrary(base):
        def __init__(self, library_or_path) -> None:
            if isinstance(library_or_path, str) and library_or_path in _paths:
                library_or_path = _paths[library_or_path]
            super().__init__(library_or_path)

        def map_symbol(self, func_name, restype=None, argtypes=(), errcheck=None):
            if restype in (ctypes.c_long, ctypes.c_ulong):
                restype = ctypes.c_uint32  # HRESULT, read unsigned like python-can's constants
            argtypes = tuple(_narrow(t) for t in argtypes)
            func = super().map_symbol(func_name, restype, argtypes, errcheck)
            if func_name != "vciEnumDeviceOpen" or self._name != _paths.get("vcinpl.dll"):
                return func

            # Every bus (and hardware-id listing) of the backend starts by enumerating: the
            # moment libvcinpl.so goes over to the canemud canemu.connect() chose last.
            def enum_open(*args):
                _follow()
                return func(*args)

            enum_open._name = func_name
            setattr(self, func_name, enum_open)
            return enum_open

    return CanemuVciLibrary


def installed() -> bool:
    """Whether python-can's ixxat backend runs on canemu's library in this process."""
    module = sys.modules.get(MODULES[0])
    return module is not None and type(module._canlib).__name__ == "CanemuVciLibrary"


def use_socket(socket: Optional[str]) -> None:
    """Makes libvcinpl.so talk to the canemud at `socket` (None: $CANEMU_SOCKET or the default
    path) from the backend's next bus on: canemu.connect() calls it once the shim is installed
    (libvcinpl2.so is canemu's own library and follows canemu.connect() by itself). The switch
    waits for that bus, so that a process that opens no ixxat bus keeps no connection of
    libvcinpl.so; it drops the ixxat handles still open on the previous canemud."""
    global _wanted
    with _lock:
        _wanted = socket


def _follow() -> None:
    global _socket
    with _lock:
        if _wanted == _socket:
            return
        hr = _own["vcinpl.dll"].canemuConnect(_wanted.encode() if _wanted else None)
        if hr != _vci.VCI_OK:
            raise OSError(f"libvcinpl.so: canemud does not answer at {_wanted} (0x{hr:08X})")
        _socket = _wanted


def library_path(dll: str = "vcinpl.dll") -> Optional[str]:
    """The path of canemu's library that was loaded for `dll` (None before install())."""
    return _paths.get(dll)


def install(socket: Optional[str] = None) -> None:
    """Makes ``can.Bus(interface="ixxat", ...)`` run python-can's IXXAT backend on canemu's
    libvcinpl.so (and its CAN FD module, ``fd=True``, on libvcinpl2.so). Idempotent. Call it
    before the first ixxat bus, best at program start: for the import it swaps
    ``sys.platform`` process-wide (a thread reading it meanwhile would see ``"win32"``).

    `socket`: the canemud to talk to (as canemu.connect()); default: canemu's current one.
    OSError when libvcinpl.so cannot be found; ImportError when the backend still did not
    load it (the reason is in python-can's log, logger ``can.ixxat``)."""
    if socket is not None:
        _daemon.connect(socket)
    if not installed():
        _import_backend()
    use_socket(_daemon.current_socket())


def _import_backend() -> None:
    import can.ctypesutil as ctypesutil

    with _lock:
        for dll, filename in LIBRARIES.items():
            _paths[dll] = _find(filename)
        vcinpl = ctypes.CDLL(_paths["vcinpl.dll"])
        vcinpl.canemuConnect.argtypes = (ctypes.c_char_p,)
        vcinpl.canemuConnect.restype = ctypes.c_uint32
        _own["vcinpl.dll"] = vcinpl

        if not hasattr(ctypesutil, "HRESULT"):
            ctypesutil.HRESULT = HRESULT
        original_library = ctypesutil.CLibrary
        original_platform = sys.platform
        ctypesutil.CLibrary = _library_class(original_library)
        sys.platform = "win32"
        try:
            for name in MODULES:
                module = sys.modules.get(name)
                if module is not None and module._canlib is None:
                    importlib.reload(module)  # imported before without a library: run it again
            importlib.import_module("can.interfaces.ixxat")  # imports both through canlib
        finally:
            sys.platform = original_platform
            ctypesutil.CLibrary = original_library
    if not installed():
        raise ImportError(
            "python-can's ixxat backend did not load canemu's libvcinpl.so "
            f"({_paths['vcinpl.dll']}); see the log of logger 'can.ixxat'"
        )
    log.debug("python-can's ixxat backend runs on %s", _paths["vcinpl.dll"])
