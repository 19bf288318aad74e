"""Calling canemu's VCI library and turning its failures into python-can's exceptions: the one
place where a VCI result becomes a python-can error (docs/python.md)."""

from __future__ import annotations

import contextlib
import struct
from typing import Iterator

import can

from . import _vci
from ._vci import VciError

CanTimeoutError = getattr(can, "CanTimeoutError", can.CanOperationError)

# The head of a CANMSG2: dwTime, _rsvd_, dwMsgId, type, flags2, flags, accept.
_HEADER = struct.Struct("<IIIBBBB")
_WAIT_SLICE_MS = 100  # blocking calls wait in slices so that Ctrl-C and shutdown get through


_DISCONNECTED = "disconnected from canemud ("


def _can_error(e: VciError, initializing: bool = False) -> can.CanError:
    """The python-can exception for a failed VCI call: CanInitializationError while a bus is
    being made (or the process connects), CanOperationError otherwise. Every VciError that
    reaches a caller of this package goes through here. `error_code` is the VCI result."""
    text = str(e)
    library_text = getattr(e, "text", "")
    if (initializing and e.hr == _vci.VCI_E_DISCONNECTED
            and library_text.startswith(_DISCONNECTED) and library_text.endswith(")")):
        # Not reaching canemud: the library's reason alone says it all (canemud not running
        # at the socket, and how to start it; the path is no socket; this user may not use it;
        # canemud refused this client), without the call, the code in hex and python-can's
        # "[Error Code N]".
        error = can.CanInitializationError(library_text[len(_DISCONNECTED):-1])
        error.error_code = e.hr
        return error
    if initializing:
        return can.CanInitializationError(text, error_code=e.hr)
    return can.CanOperationError(text, error_code=e.hr)


@contextlib.contextmanager
def _vci_errors(initializing: bool = False) -> Iterator[None]:
    """Turns a VciError raised inside the block into _can_error's exception."""
    try:
        yield
    except VciError as e:
        raise _can_error(e, initializing) from None


def _call(name: str, *args) -> int:
    """Calls a library function; VciError when it fails."""
    hr = getattr(_vci.lib(), name)(*args)
    _vci.check(name, hr)
    return hr

