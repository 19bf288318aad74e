"""The controller's error state as python-can sees it: SocketCAN error frames made from the
adapter's ERROR and STATUS messages (and the error-passive crossings no message marks), the
state and counters read from the controller, restarting after bus-off."""

from __future__ import annotations

import ctypes
import enum
from typing import Optional, Tuple

import can
from can import BusState, Message

from . import _vci
from ._calls import _call, _vci_errors

# SocketCAN's error frame layout (linux/can/error.h), which python-can's users know.
CAN_ERR_CRTL = 0x00000004
CAN_ERR_PROT = 0x00000008
CAN_ERR_TRX = 0x00000010
CAN_ERR_ACK = 0x00000020
CAN_ERR_BUSOFF = 0x00000040
CAN_ERR_BUSERROR = 0x00000080
CAN_ERR_RESTARTED = 0x00000100
CAN_ERR_CNT = 0x00000200
CAN_ERR_CRTL_RX_WARNING = 0x04
CAN_ERR_CRTL_TX_WARNING = 0x08
CAN_ERR_CRTL_RX_PASSIVE = 0x10
CAN_ERR_CRTL_TX_PASSIVE = 0x20
CAN_ERR_CRTL_ACTIVE = 0x40
CAN_ERR_PROT_BIT = 0x01
CAN_ERR_PROT_FORM = 0x02
CAN_ERR_PROT_STUFF = 0x04
CAN_ERR_PROT_LOC_CRC_SEQ = 0x08
CAN_ERR_PROT_LOC_ACK = 0x19

# VCI error type -> (error class bits, protocol error type, location)
_BUS_ERRORS = {
    _vci.CAN_ERROR_BIT: (CAN_ERR_PROT, CAN_ERR_PROT_BIT, 0),
    _vci.CAN_ERROR_FDB: (CAN_ERR_PROT, CAN_ERR_PROT_BIT, 0),
    _vci.CAN_ERROR_STUFF: (CAN_ERR_PROT, CAN_ERR_PROT_STUFF, 0),
    _vci.CAN_ERROR_FORM: (CAN_ERR_PROT, CAN_ERR_PROT_FORM, 0),
    _vci.CAN_ERROR_CRC: (CAN_ERR_PROT, 0, CAN_ERR_PROT_LOC_CRC_SEQ),
    _vci.CAN_ERROR_ACK: (CAN_ERR_ACK, 0, CAN_ERR_PROT_LOC_ACK),
}

class ControllerState(enum.IntEnum):
    """The error state of the emulated controller (ISO 11898-1, with the warning limit)."""

    ERROR_ACTIVE = _vci.CANEMU_STATE_ACTIVE
    ERROR_WARNING = _vci.CANEMU_STATE_WARNING
    ERROR_PASSIVE = _vci.CANEMU_STATE_PASSIVE
    BUS_OFF = _vci.CANEMU_STATE_BUSOFF


_BUS_STATES = {
    _vci.CANEMU_STATE_ACTIVE: BusState.ACTIVE,
    _vci.CANEMU_STATE_WARNING: BusState.ACTIVE,
    _vci.CANEMU_STATE_PASSIVE: BusState.PASSIVE,
    _vci.CANEMU_STATE_BUSOFF: BusState.ERROR,
}

_REPORTED_STATUS = 0x02 | _vci.CAN_STATUS_ERRLIM | _vci.CAN_STATUS_BUSOFF | _vci.CAN_STATUS_BUSCERR


class _StateMixin:
    """CanemuBus's error state and error frames. Uses the bus's _channel, _control,
    _listen_only, _start_line, _channel_name, _reported, _counters, _last_status, _was_bus_off,
    _auto_restart, _pending, _initializing; _stamp and _now_ns come from _ReceiveMixin."""

    def _error_frame(self, sim_ns: int, ident: int, data: bytes) -> Message:
        return Message(
            timestamp=self._stamp(sim_ns),
            arbitration_id=ident,
            is_error_frame=True,
            dlc=8,
            data=data,
            channel=self._channel_name,
        )

    def _bus_error(self, sim_ns: int, code: int) -> Optional[Message]:
        """An ERROR message with CAN_ERROR_* `code` as a SocketCAN error frame."""
        cls, prot, location = _BUS_ERRORS.get(code, (CAN_ERR_PROT, 0, 0))
        data = bytearray(8)
        data[2] = prot
        data[3] = location
        return self._error_frame(sim_ns, cls | CAN_ERR_BUSERROR, bytes(data))

    def _status_change(self, sim_ns: int, status: int) -> Optional[Message]:
        """A STATUS message: the line's ERRLIM, BUSOFF, BUSCERR (or OVRRUN) flag changed."""
        reported = status & _REPORTED_STATUS  # TXPEND and ININIT change without a message
        changed = reported ^ self._last_status
        self._last_status = reported
        data = bytearray(8)
        if changed == _vci.CAN_STATUS_BUSCERR:
            # The transceiver reports a wire fault (or its end: nothing to report then).
            if not status & _vci.CAN_STATUS_BUSCERR:
                return None
            return self._error_frame(sim_ns, CAN_ERR_TRX, bytes(data))
        if not changed & (_vci.CAN_STATUS_ERRLIM | _vci.CAN_STATUS_BUSOFF):
            return None  # the controller's overrun flag: no state change
        if status & _vci.CAN_STATUS_BUSOFF:
            _, tec, rec, _ = self._controller_state()
            data[6] = min(tec, 255)
            data[7] = min(rec, 255)
            self._reported = _vci.CANEMU_STATE_BUSOFF
            if self._auto_restart and self._control is not None:
                self.restart()
            return self._error_frame(sim_ns, CAN_ERR_BUSOFF | CAN_ERR_CNT, bytes(data))
        if status & _vci.CAN_STATUS_ERRLIM:
            # The warning limit: which counter passed it is read now (it may have moved on).
            _, tec, rec, _ = self._controller_state()
            if tec >= 96:
                data[1] |= CAN_ERR_CRTL_TX_WARNING
            if rec >= 96 or tec < 96:
                data[1] |= CAN_ERR_CRTL_RX_WARNING
            ident = CAN_ERR_CRTL
            self._reported = _vci.CANEMU_STATE_WARNING
        else:
            data[1] = CAN_ERR_CRTL_ACTIVE
            ident = CAN_ERR_CRTL | (CAN_ERR_RESTARTED if self._was_bus_off else 0)
            self._reported = _vci.CANEMU_STATE_ACTIVE
        self._was_bus_off = False
        return self._error_frame(sim_ns, ident, bytes(data))

    def _check_passive(self, sim_ns: Optional[int],
                       counters: Optional[Tuple[int, int]] = None) -> None:
        """When the controller crossed the error-passive limit (128) since the last error frame
        said where it was, queues the error frame that tells it, SocketCAN's: CAN_ERR_CRTL |
        CAN_ERR_CNT, data[1] TX_PASSIVE / RX_PASSIVE going in, TX_WARNING / RX_WARNING coming
        back (the counter that is higher; both when equal), data[6], data[7] TEC and REC.
        `counters` (TEC, REC) are those an ERROR message carries, exact at its instant; without
        them the controller is read now, and the frame carries the time stamp of the message at
        which the crossing was found (`sim_ns`; None: now). Only between the warning limit and
        bus-off: the status messages tell those exactly."""
        if counters is not None:
            tec, rec = counters
            state = (_vci.CANEMU_STATE_PASSIVE if max(tec, rec) >= 128
                     else _vci.CANEMU_STATE_WARNING)
        else:
            state, tec, rec, _ = self._controller_state()
        self._counters = (tec, rec)
        if self._reported == _vci.CANEMU_STATE_WARNING and state >= _vci.CANEMU_STATE_PASSIVE:
            # (Read bus-off: it went through error-passive; the bus-off status comes next.)
            tx, rx = CAN_ERR_CRTL_TX_PASSIVE, CAN_ERR_CRTL_RX_PASSIVE
            self._reported = _vci.CANEMU_STATE_PASSIVE
        elif self._reported == _vci.CANEMU_STATE_PASSIVE and state < _vci.CANEMU_STATE_PASSIVE:
            # Back below 128; at the warning limit until the status message says otherwise.
            tx, rx = CAN_ERR_CRTL_TX_WARNING, CAN_ERR_CRTL_RX_WARNING
            self._reported = _vci.CANEMU_STATE_WARNING
        else:
            return
        data = bytearray(8)
        data[1] = (tx if tec >= rec else 0) | (rx if rec >= tec else 0)
        data[6] = min(tec, 255)
        data[7] = min(rec, 255)
        when = self._now_ns() if sim_ns is None else sim_ns
        self._pending.append(self._error_frame(when, CAN_ERR_CRTL | CAN_ERR_CNT, bytes(data)))

    # ---- state ----

    def _controller_state(self) -> Tuple[int, int, int, int]:
        state = ctypes.c_uint8()
        tec = ctypes.c_uint16()
        rec = ctypes.c_uint16()
        line = ctypes.c_uint8()
        with _vci_errors(self._initializing):
            _call("canemuGetControllerState", self._channel, ctypes.byref(state),
                  ctypes.byref(tec), ctypes.byref(rec), ctypes.byref(line))
        return state.value, tec.value, rec.value, line.value

    @property
    def state(self) -> BusState:
        """The controller's error state in python-can's terms: ACTIVE while error-active (also
        at the warning limit), PASSIVE while error-passive or listen-only, ERROR while bus-off.
        See :attr:`controller_state` for the four ISO 11898-1 states."""
        state = _BUS_STATES[self._controller_state()[0]]
        if self._listen_only and state == BusState.ACTIVE:
            return BusState.PASSIVE
        return state

    @property
    def controller_state(self) -> "ControllerState":
        """ERROR_ACTIVE, ERROR_WARNING, ERROR_PASSIVE or BUS_OFF, from the controller."""
        return ControllerState(self._controller_state()[0])

    @state.setter
    def state(self, new_state: BusState) -> None:
        """PASSIVE: the controller only listens (no acknowledgement, no error flags, nothing
        sent: frames wait in the transmit FIFO); ACTIVE: it takes part again. Either way the
        line is initialized again with the same bit timing, so the controller starts
        error-active with both counters 0. ERROR cannot be set. Needs the control unit."""
        if new_state not in (BusState.ACTIVE, BusState.PASSIVE):
            raise ValueError(f"only BusState.ACTIVE and BusState.PASSIVE can be set, not "
                             f"{new_state}")
        if self._control is None:
            raise can.CanOperationError(
                f"{self.channel_info}: another program controls the line; it sets its mode")
        with _vci_errors():
            _call("canControlStart", self._control, 0)
            self._start_line(new_state == BusState.PASSIVE)
        self._reported = _vci.CANEMU_STATE_ACTIVE
        self._counters = (0, 0)
        self._last_status = 0
        self._was_bus_off = False

    def error_counters(self) -> Tuple[int, int]:
        """(TEC, REC) of the controller."""
        _, tec, rec, _ = self._controller_state()
        return tec, rec

    def restart(self) -> None:
        """Starts the line again after bus-off (stop, start); the controller then waits for
        128 x 11 recessive bits before it takes part again. Needs the control unit."""
        if self._control is None:
            raise can.CanOperationError(
                f"{self.channel_info}: another program controls the line; it must restart it")
        with _vci_errors():
            _call("canControlStart", self._control, 0)
            _call("canControlStart", self._control, 1)
        self._was_bus_off = True
