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


def _can_error(e: VciError, initializing: bool = False) -> can.CanError:
    """The python-can exception for a failed VCI call: CanInitializationError while a bus is
    being made (or the process connects), CanOperationError otherwise. Every VciError that
    reaches a caller of this package goes through here."""
    text = str(e)
    # How to start canemud only when nobody listened (the library's text then asks "is canemud
    # running?"); not when canemud refused this client, closed the connection or went away: its
    # reason is in the text already.
    if e.hr == _vci.VCI_E_DISCONNECTED and "is canemud running?" in text:
        text += (
            "; canemud is not running or not reachable: start it with `make run` in the canemu "
            "folder, `systemctl start canemud`, or `canemud --config FILE`, and set CANEMU_SOCKET "
            "(or the bus's socket= argument) when it listens elsewhere"
        )
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

