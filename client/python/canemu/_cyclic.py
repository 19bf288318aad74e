"""Cyclic transmission: send_periodic through the adapter's cyclic transmit list when it can
do the job, python-can's software scheduler otherwise."""

from __future__ import annotations

import ctypes
import logging
import threading
from typing import TYPE_CHECKING, Optional, Sequence, Union

import can
from can import Message
from can.broadcastmanager import (
    LimitedDurationCyclicSendTaskABC,
    ModifiableCyclicTaskABC,
    RestartableCyclicTaskABC,
)

from . import _vci
from ._calls import _call, _can_error, _vci_errors
from ._vci import VciError

if TYPE_CHECKING:  # pragma: no cover
    from .bus import CanemuBus

log = logging.getLogger("can.canemu")


class _CyclicMixin:
    """CanemuBus's cyclic list. Uses the bus's _device, _controller, _scheduler, _sched_lock
    and channel_info; the list's entries are made by _SendMixin._wire_fields."""

    def _send_periodic_internal(self, msgs, period: float, duration: Optional[float] = None,
                                *args, **kwargs):
        """The adapter's cyclic transmit list when it can do the job (one message, a period of
        whole milliseconds up to 65.535 s, a repeat count up to 65535, no modifier callback);
        python-can's software scheduler otherwise."""
        messages = msgs if isinstance(msgs, (list, tuple)) else [msgs]
        autostart = kwargs.get("autostart", args[0] if args else True)
        modifier = kwargs.get("modifier_callback", args[1] if len(args) > 1 else None)
        ticks = round(period * 1000)
        repeat = 0 if duration is None else round(duration / period)
        usable = (
            len(messages) == 1
            and modifier is None
            and 1 <= ticks <= 0xFFFF
            and abs(ticks - period * 1000) < 1e-6
            and repeat <= 0xFFFF
            and (duration is None or repeat >= 1)
        )
        if usable:
            scheduler = self._open_scheduler()
            if scheduler is not None:
                task = CanemuCyclicTask(self, scheduler, messages[0], period, duration,
                                        ticks, repeat)
                if not autostart or task._start(refused_ok=True):
                    return task
                # The list has no room for the period (16 entries, or the entries' shares of
                # its 1 ms ticks would add up to more than one frame per tick).
                log.info("%s: cyclic list full; software scheduling", self.channel_info)
        return super()._send_periodic_internal(msgs, period, duration, *args, **kwargs)

    def _open_scheduler(self):
        """The cyclic list's handle, opened and resumed on first use; None when another
        program holds the list (or the adapter has none). CanOperationError when canemud is
        gone or the list cannot be resumed."""
        with self._sched_lock:
            if self._scheduler is None:
                handle = _vci.HANDLE()
                hr = _vci.lib().canSchedulerOpen(self._device, self._controller,
                                                 ctypes.byref(handle))
                if hr == _vci.VCI_E_DISCONNECTED:
                    raise _can_error(VciError("canSchedulerOpen", hr, _vci.error_text(hr)))
                if hr != _vci.VCI_OK:
                    log.info("%s: cyclic list not available (%s); software scheduling",
                             self.channel_info, _vci.error_text(hr))
                    return None
                try:
                    with _vci_errors():
                        _call("canSchedulerActivate", handle.value, 1)
                except can.CanError:
                    _vci.lib().canSchedulerClose(handle.value)
                    raise
                self._scheduler = handle.value
            return self._scheduler


class CanemuCyclicTask(LimitedDurationCyclicSendTaskABC, ModifiableCyclicTaskABC,
                       RestartableCyclicTaskABC):
    """A message in the adapter's cyclic transmit list (sent by the emulated firmware, with
    the list's 1 ms ticks)."""

    def __init__(self, bus: CanemuBus, scheduler, message: Message, period: float,
                 duration: Optional[float], ticks: int, repeat: int) -> None:
        super().__init__(message, period, duration)
        self._bus = bus
        self._scheduler = scheduler
        self._ticks = ticks
        self._repeat = repeat
        self._index: Optional[int] = None
        self._lock = threading.Lock()

    def _entry(self) -> _vci.CANCYCLICTXMSG2:
        msg = self.messages[0]
        entry = _vci.CANCYCLICTXMSG2()
        entry.wCycleTime = self._ticks
        entry.dwMsgId = msg.arbitration_id
        entry.bType = _vci.CAN_MSGTYPE_DATA
        entry.bFlags, entry.bFlags2, data = self._bus._wire_fields(msg)
        ctypes.memmove(entry.abData, data, len(data))
        return entry

    def start(self) -> None:
        self._start()

    def _start(self, refused_ok: bool = False) -> bool:
        """Adds and starts the entry. False when the list refuses it for want of room
        (VCI_E_OUTOFMEMORY) and `refused_ok`; otherwise a refusal raises."""
        with self._lock:
            if self._index is not None:
                return True
            index = ctypes.c_uint32()
            entry = self._entry()
            with _vci_errors():
                hr = _vci.lib().canSchedulerAddMessage(self._scheduler, ctypes.byref(entry),
                                                       ctypes.byref(index))
                if hr == _vci.VCI_E_OUTOFMEMORY and refused_ok:
                    return False
                _vci.check("canSchedulerAddMessage", hr)
                _call("canSchedulerStartMessage", self._scheduler, index.value, self._repeat)
            self._index = index.value
            return True

    def stop(self) -> None:
        with self._lock:
            if self._index is None:
                return
            lib = _vci.lib()
            lib.canSchedulerStopMessage(self._scheduler, self._index)
            lib.canSchedulerRemMessage(self._scheduler, self._index)
            self._index = None

    def modify_data(self, messages: Union[Sequence[Message], Message]) -> None:
        messages = self._check_and_convert_messages(messages)
        self._check_modified_messages(messages)
        running = self._index is not None
        self.stop()
        self.messages = messages
        if running:
            self.start()
