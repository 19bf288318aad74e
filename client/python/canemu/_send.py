"""Sending: python-can Messages checked and put in the VCI's terms, queued in the transmit
FIFO."""

from __future__ import annotations

import ctypes
import logging
import struct
import time
from typing import Optional, Tuple

import can
from can import Message

from . import _vci
from ._calls import _HEADER, _WAIT_SLICE_MS, CanTimeoutError, _call, _can_error
from ._daemon import _sim_time
from ._vci import VciError

# The longest frames in bits, with the most stuff bits and the intermission: a classic frame
# with a 29-bit identifier and 8 bytes; a CAN FD frame's nominal-rate part and its data phase
# of 64 bytes (CRC-21 with its fixed stuff bits).
_CLASSIC_BITS = 160
_FD_NOMINAL_BITS = 75
_FD_DATA_BITS = 680
# What the drain at shutdown allows on top of the frames' own time (simulated): error frames,
# suspend transmission, frames of other nodes that win arbitration.
_DRAIN_FACTOR = 1.5
_DRAIN_MARGIN_NS = 50_000_000
_DRAIN_POLL_S = 0.002  # between two looks at the FIFO while it drains

log = logging.getLogger("can.canemu")

# A classic data frame's CANMSG2 as bytes, from the identifier, bFlags and the data (send's
# hot path): dwTime 0 (at once), bType CAN_MSGTYPE_DATA (0), bFlags2 and bAccept 0 are pad
# bytes, which struct writes as zeros.
_pack_classic = struct.Struct("<8xI2xB1x8s56x").pack
assert _HEADER.format == "<IIIBBBB" and _vci.CAN_MSGTYPE_DATA == 0
assert struct.calcsize("<8xI2xB1x8s56x") == ctypes.sizeof(_vci.CANMSG2)
_FULL = _vci.VCI_E_TXQUEUE_FULL
assert _vci.VCI_OK == 0


class _SendMixin:
    """CanemuBus's transmit side. Uses the bus's _channel, _control, _fd, _receive_own,
    _auto_restart, _closed, _tx_lock, _tx_flushed, _listen_only, _bitrate, _data_bitrate,
    _tx_capacity, _tx_flags, _tx_flags_ext and its transmit buffer; state and restart come from
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
        it takes) while the FIFO is full. CanTimeoutError when it stays full. An error frame
        (what can.bridge and `can.player --error-frames` pass on) is not sent: a controller
        signals errors it detects, it cannot send one at will (fault scenarios make errors,
        docs/faults.md)."""
        fast = self._fast_post
        if fast is not None and fast(msg):
            # canemu_speedups took a classic data frame as the hot path below would have; it
            # leaves everything else (and a full FIFO, an error) to the paths below.
            self._tx_flushed = False
            return
        if msg.is_error_frame:
            log.debug("%s: error frame not sent: %s", self.channel_info, msg)
            return
        self._tx_flushed = False
        # The hot path: a classic data frame, header and data packed in one go into bytes,
        # which go to a binding that converts no arguments (bytes as a pointer to their data)
        # and keeps the GIL (_open); bFlags's EXT and SRR bits come ready (_tx_flags).
        data = msg.data
        ident = msg.arbitration_id
        length = len(data)
        if msg.is_extended_id:
            limit, flags = 0x1FFFFFFF, length | self._tx_flags_ext
        else:
            limit, flags = 0x7FF, length | self._tx_flags
        if length <= 8 and 0 <= ident <= limit and not (msg.is_fd or msg.is_remote_frame):
            lock = self._tx_lock
            lock.acquire()  # (cheaper than `with`)
            try:
                try:
                    packed = _pack_classic(ident, flags, data)
                except (struct.error, TypeError):
                    hr = None  # data that is neither bytes nor bytearray: the general path
                else:
                    hr = self._post(self._channel_arg, packed)
                    if hr and hr == _FULL:
                        self._tx_view[:] = packed
                        hr = self._send_waiting(self._tx_ref, timeout)
            finally:
                lock.release()
            if hr == 0:  # VCI_OK
                return
            if hr is not None:
                return self._sent(hr, timeout)
        lib = _vci.lib()
        with self._tx_lock:
            flags, flags2, data = self._wire_fields(msg)
            # The CANMSG2 header (dwTime 0: at once) and data in one go.
            _HEADER.pack_into(self._tx_view, 0, 0, 0, msg.arbitration_id, _vci.CAN_MSGTYPE_DATA,
                              flags2, flags, 0)
            self._tx_view[16 : 16 + len(data)] = data
            hr = lib.canChannelPostMessage(self._channel, self._tx_ref)
            if hr == _vci.VCI_E_TXQUEUE_FULL:
                hr = self._send_waiting(self._tx_ref, timeout)
        self._sent(hr, timeout)

    def _sent(self, hr: int, timeout: Optional[float]) -> None:
        """Raises what a failed post or send (`hr`) means to send's caller."""
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

    # ---- draining at shutdown ----

    def _tx_status(self) -> Tuple[int, int]:
        """(transmit FIFO load in percent, the line's CAN_STATUS_* flags)."""
        status = _vci.CANCHANSTATUS2()
        _call("canChannelGetStatus", self._channel, ctypes.byref(status))
        return status.bTxFifoLoad, status.sLineStatus.dwStatus

    def _tx_at_most(self, load: int, line: int) -> int:
        """The most frames still to send that `load` (the FIFO's fill level in percent, all the
        VCI tells) and the controller's TXPEND allow."""
        return ((load + 1) * self._tx_capacity - 1) // 100 + (line & _vci.CAN_STATUS_TXPEND)

    def _tx_count_left(self) -> int:
        """The frames not sent, exactly, for a channel about to close: the channel is
        deactivated (canemud takes nothing more from its FIFO), the FIFO's free places are
        counted by filling them with INFO messages (never frames: the firmware drops them),
        and the frame the controller holds is added."""
        _call("canChannelActivate", self._channel, 0)
        placeholder = _vci.CANMSG2()
        placeholder_ref = ctypes.byref(placeholder)
        _HEADER.pack_into(memoryview(placeholder).cast("B"), 0, 0, 0, 0, _vci.CAN_MSGTYPE_INFO,
                          0, 0, 0)
        lib = _vci.lib()
        free = 0
        while lib.canChannelPostMessage(self._channel, placeholder_ref) == _vci.VCI_OK:
            free += 1
        line = self._tx_status()[1]
        return self._tx_capacity - free + (line & _vci.CAN_STATUS_TXPEND)

    def _frame_ns(self) -> int:
        """The time the longest frame this bus sends takes on the wire, in ns."""
        if self._fd:
            return (_FD_NOMINAL_BITS * 1_000_000_000 // self._bitrate
                    + _FD_DATA_BITS * 1_000_000_000 // self._data_bitrate)
        return _CLASSIC_BITS * 1_000_000_000 // self._bitrate

    def _drain_tx(self) -> Tuple[int, str]:
        """Lets the frames in the transmit FIFO (and the controller) go out before the channel
        closes. Returns (0, "") when nothing is left, else (how many frames are left, why).
        The wait is bounded in simulated time: the time the frames queued at the start need on
        the wire at the bus's rates (as if all were the longest frames), times
        _DRAIN_FACTOR, plus _DRAIN_MARGIN_NS. Nothing is waited for when nothing can send:
        in stepped time (time moves only when the program steps it), on a listen-only line, or
        a line that is stopped or bus-off."""
        empty_reads = 0
        deadline_ns = None
        while True:
            load, line = self._tx_status()
            stuck = ("the line is listen-only" if self._listen_only
                     else "the controller is bus-off" if line & _vci.CAN_STATUS_BUSOFF
                     else "the line is stopped" if line & _vci.CAN_STATUS_ININIT else "")
            if stuck:
                left = self._tx_count_left()
                return left, stuck if left else ""
            if load == 0 and not line & _vci.CAN_STATUS_TXPEND:
                # A running line takes the next frame in the instant the last one ends, so it
                # is done when it holds none and the FIFO shows none (below 1 %: at most two
                # frames, which a running line would have taken). Twice in a row: the second
                # look is answered after canemud saw the doorbell of a frame posted before the
                # first.
                empty_reads += 1
                if empty_reads == 2:
                    return 0, ""
                continue
            empty_reads = 0
            now_ns, mode = _sim_time()
            if mode == _vci.CANEMU_TIME_STEPPED:
                return self._tx_count_left(), "in stepped time nothing moves at shutdown"
            if deadline_ns is None:
                frames = self._tx_at_most(load, line)
                bound_ns = int(frames * self._frame_ns() * _DRAIN_FACTOR) + _DRAIN_MARGIN_NS
                deadline_ns = now_ns + bound_ns
            elif now_ns >= deadline_ns:
                return self._tx_count_left(), (
                    f"they did not get through within {bound_ns / 1e9:.3f} s of bus time (is "
                    f"a node acknowledging?)")
            time.sleep(_DRAIN_POLL_S)
