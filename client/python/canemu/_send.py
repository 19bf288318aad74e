"""Sending: python-can Messages checked and put in the VCI's terms, queued in the transmit
FIFO."""

from __future__ import annotations

import time
from typing import Optional, Tuple

import can
from can import Message

from . import _vci
from ._calls import _HEADER, _WAIT_SLICE_MS, CanTimeoutError, _can_error
from ._vci import VciError


class _SendMixin:
    """CanemuBus's transmit side. Uses the bus's _channel, _control, _fd, _receive_own,
    _auto_restart, _closed, _tx_lock and its transmit buffer; state and restart come from
    _StateMixin."""

    def _wire_fields(self, msg: Message) -> Tuple[int, int, bytes]:
        """`msg` checked and in the VCI's terms: (bFlags, bFlags2, data padded to its DLC).
        CanOperationError naming what does not fit."""
        length = len(msg.data)
        flags2 = 0
        if msg.is_fd:
            if not self._fd:
                raise can.CanOperationError(
                    f"{self.channel_info}: a CAN FD frame needs a bus opened with fd=True")
            dlc = _vci.len_to_dlc(length)
            flags2 = _vci.FLAGS2_EDL | (_vci.FLAGS2_FDR if msg.bitrate_switch else 0)
            padded = _vci.DLC_TO_LEN[dlc]
        else:
            if length > 8:
                raise can.CanOperationError(
                    f"a classic CAN frame carries at most 8 data bytes, not {length}")
            dlc = msg.dlc if msg.is_remote_frame else length
            if msg.is_remote_frame and not 0 <= dlc <= 8:
                raise can.CanOperationError(f"a remote frame's DLC is 0..8, not {dlc}")
            padded = length
        limit = 0x1FFFFFFF if msg.is_extended_id else 0x7FF
        if not 0 <= msg.arbitration_id <= limit:
            raise can.CanOperationError(
                f"identifier 0x{msg.arbitration_id:X} does not fit "
                f"{'29' if msg.is_extended_id else '11'} bits")
        flags = dlc
        if msg.is_remote_frame and not msg.is_fd:
            flags |= _vci.FLAGS_RTR
        if msg.is_extended_id:
            flags |= _vci.FLAGS_EXT
        if self._receive_own:
            flags |= _vci.FLAGS_SRR  # self-reception (the cyclic list's too)
        data = bytes(msg.data)
        return flags, flags2, data + bytes(padded - length) if padded > length else data

    def send(self, msg: Message, timeout: Optional[float] = None) -> None:
        """Queues `msg` in the transmit FIFO, waiting up to `timeout` seconds (None: as long as
        it takes) while the FIFO is full. CanTimeoutError when it stays full."""
        lib = _vci.lib()
        with self._tx_lock:
            flags, flags2, data = self._wire_fields(msg)
            # The CANMSG2 header (dwTime 0: at once) and data in one go: the hot path.
            _HEADER.pack_into(self._tx_view, 0, 0, 0, msg.arbitration_id, _vci.CAN_MSGTYPE_DATA,
                              flags2, flags, 0)
            self._tx_view[16 : 16 + len(data)] = data
            hr = lib.canChannelPostMessage(self._channel, self._tx_ref)
            if hr == _vci.VCI_E_TXQUEUE_FULL:
                hr = self._send_waiting(self._tx_ref, timeout)
        if hr == _vci.VCI_OK:
            return
        if hr in (_vci.VCI_E_TIMEOUT, _vci.VCI_E_TXQUEUE_FULL):
            raise CanTimeoutError(
                f"{self.channel_info}: the transmit FIFO stayed full for {timeout} s "
                f"(state {self.state.name})")
        raise _can_error(VciError("canChannelSendMessage", hr, _vci.error_text(hr)))

    def _send_waiting(self, out, timeout: Optional[float]) -> int:
        if self._auto_restart and self._control is not None:
            if self._controller_state()[0] == _vci.CANEMU_STATE_BUSOFF:
                self.restart()
        lib = _vci.lib()
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self._closed:
            if deadline is None:
                wait_ms = _WAIT_SLICE_MS
            else:
                left = deadline - time.monotonic()
                if left <= 0:
                    return _vci.VCI_E_TIMEOUT
                wait_ms = min(_WAIT_SLICE_MS, max(1, int(left * 1000 + 0.999)))
            hr = lib.canChannelSendMessage(self._channel, wait_ms, out)
            if hr != _vci.VCI_E_TIMEOUT:
                return hr
        return _vci.VCI_E_TIMEOUT
