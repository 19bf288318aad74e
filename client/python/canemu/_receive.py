"""Receiving: the channel's messages as python-can Messages, with adapter time stamps turned
into simulated (or wall-clock) seconds."""

from __future__ import annotations

import ctypes
import logging
import struct
import time
from typing import Optional, Tuple

from can import BusABC, Message

from . import _vci
from ._calls import _HEADER, _WAIT_SLICE_MS, _call, _can_error, _vci_errors
from ._daemon import _sim_time
from ._state import _StateMixin
from ._vci import VciError

_RX_BATCH = 256  # messages taken from the receive ring in one call (CanemuBus)
_MSG_SIZE = ctypes.sizeof(_vci.CANMSG2)
# For the data-frame paths (a global is found faster than a module's attribute).
_DATA, _DLC, _EDL, _RTR, _SRR = (_vci.CAN_MSGTYPE_DATA, _vci.FLAGS_DLC, _vci.FLAGS2_EDL,
                                 _vci.FLAGS_RTR, _vci.FLAGS_SRR)
_EXT, _FDR, _ESI, _DLC_TO_LEN = _vci.FLAGS_EXT, _vci.FLAGS2_FDR, _vci.FLAGS2_ESI, _vci.DLC_TO_LEN
_PASSIVE = _vci.CANEMU_STATE_PASSIVE
# A Message without Message.__init__: _convert_run sets every attribute itself, each as
# __init__ would (tests/python/test_message_build.py compares it with _convert's).
_new_message = Message.__new__
# What _convert_run reads of a CANMSG2: dwTime, dwMsgId, bType and bFlags2 | bFlags << 8 (the
# data it slices from the batch's bytearray).
_CLASSIC = struct.Struct("<I4xIBH65x")
assert _CLASSIC.size == _MSG_SIZE and _HEADER.format == "<IIIBBBB"
# Below this an integer number of nanoseconds is exact as a float, and so are the sums
# _convert_run makes of a time stamp (a base below it, plus at most 2**32 ticks of 1000 ns).
_FLOAT_EXACT = 2**53 - 2**32 * 1000


def _frame_fields(flags2: int, flags: int) -> Tuple[bool, bool, bool, bool, bool, bool, int, int]:
    """What a data frame's bFlags2 and bFlags make of a Message, as _convert reads them:
    is_extended_id, is_rx, is_remote_frame, is_fd, bitrate_switch, error_state_indicator, dlc
    and the number of data bytes."""
    dlc = flags & _DLC
    if flags2 & _EDL:
        fd, remote, length = True, False, _DLC_TO_LEN[dlc]
        dlc = length
    else:
        fd, remote = False, bool(flags & _RTR)
        length = 0 if remote else (dlc if dlc < 8 else 8)
    return (bool(flags & _EXT), not flags & _SRR, remote, fd, bool(flags2 & _FDR),
            bool(flags2 & _ESI), dlc, length)


# _frame_fields of every bFlags2 | bFlags << 8, as _convert_run reads them in one number and
# looks them up (the same 8,192 tuples for bFlags2's bits other than EDL, FDR and ESI).
_FIELDS_OF = [_frame_fields(index >> 8, index & 0xFF) for index in range(0x2000)]
assert _vci.FLAGS2_EDL | _vci.FLAGS2_FDR | _vci.FLAGS2_ESI == 0x1C
_FRAME_FIELDS = [_FIELDS_OF[(bits & 0x1C) << 8 | bits >> 8] for bits in range(0x10000)]
# The logger and level of BusABC.recv's "Received" record, which recv's short path writes too.
_bus_log = logging.getLogger("can.bus")


class _ReceiveMixin(_StateMixin):
    """CanemuBus's receive side: the error frames a message causes come from _StateMixin."""

    def fileno(self) -> int:
        """A descriptor that is readable whenever messages wait (for select, Notifier,
        asyncio)."""
        # From now on one message at a time: a message taken from the ring into the batch would
        # no longer make the descriptor readable.
        self._rx_batch_max = 1
        if self._poll_fd is None:
            fd = ctypes.c_int(-1)
            with _vci_errors():
                _call("canemuChannelEventFd", self._channel, ctypes.byref(fd))
            self._poll_fd = fd.value
        return self._poll_fd

    def recv(self, timeout: Optional[float] = None) -> Optional[Message]:
        """BusABC.recv, with a short path for a message already converted (_rx_ready) when
        the channel does the filtering; everything else goes through BusABC.recv and
        _recv_internal.

        The short path takes no lock: deque.popleft is atomic, and _rx_ready and _pending are
        never both non-empty (_recv_internal fills _rx_ready only when _pending is empty, and
        _pending only when _rx_ready is), so that what it returns is in order, and a message
        in _rx_ready means that no error frame waits before it."""
        if self._hw_filtered:
            try:
                msg = self._rx_ready.popleft()
            except IndexError:
                pass
            else:
                if _bus_log.isEnabledFor(self.RECV_LOGGING_LEVEL):
                    _bus_log.log(self.RECV_LOGGING_LEVEL, "Received: %s", msg)
                return msg
        return BusABC.recv(self, timeout)

    def _recv_internal(self, timeout: Optional[float]) -> Tuple[Optional[Message], bool]:
        deadline = None if timeout is None else time.monotonic() + max(timeout, 0.0)
        lib = _vci.lib()
        with self._rx_lock:
            while True:
                if self._pending:
                    return self._pending.popleft(), True
                if self._rx_ready:
                    return self._rx_ready.popleft(), self._hw_filtered
                if self._rx_next < self._rx_count:
                    if self._reported != _PASSIVE:
                        self._convert_run()
                        if self._rx_ready:
                            continue
                    offset = self._rx_next * _MSG_SIZE
                    self._rx_next += 1
                    msg, filtered = self._convert(self._rx_batch_view, offset)
                    if msg is not None:
                        return msg, filtered
                    continue
                if self._closed:
                    return None, True
                hr = lib.canChannelPeekMsgMult(
                    self._channel, self._rx_batch, self._rx_batch_max, self._rx_taken_ref
                )
                if self._rx_taken.value > 0:
                    self._rx_count, self._rx_next = self._rx_taken.value, 0
                    continue
                if hr in (_vci.VCI_OK, _vci.VCI_E_TIMEOUT):
                    hr = _vci.VCI_E_RXQUEUE_EMPTY
                if hr == _vci.VCI_E_RXQUEUE_EMPTY:
                    if self._reported in (_vci.CANEMU_STATE_WARNING, _vci.CANEMU_STATE_PASSIVE):
                        # Nothing marks a counter crossing 128 by itself (a fault setting the
                        # counters, the own frame that got through): look now.
                        self._check_passive(None)
                        if self._pending:
                            continue
                    if deadline is None:
                        wait_ms = _WAIT_SLICE_MS
                    else:
                        left = deadline - time.monotonic()
                        if left <= 0:
                            # (The library's empty look gave up the processor once: a program
                            # polling recv(0) in a loop does not hold up canemud.)
                            return None, True
                        wait_ms = min(_WAIT_SLICE_MS, max(1, int(left * 1000 + 0.999)))
                    hr = lib.canChannelReadMessage(self._channel, wait_ms, self._rx_ref)
                    if hr == _vci.VCI_E_TIMEOUT:
                        continue
                if hr != _vci.VCI_OK:
                    raise _can_error(VciError("canChannelReadMessage", hr, _vci.error_text(hr)))
                msg, filtered = self._convert(self._rx_view, 0)
                if msg is not None:
                    return msg, filtered  # what it caused (self._pending) comes next

    def _convert_run(self) -> None:
        """The data frames of the batch from the next one up to the first message of another
        kind (or the batch's end) as python-can Messages in _rx_ready, each exactly as
        _convert makes it, in one pass: the receiving's hot path. Not while the error state is
        passive: then a frame may end a crossing (_convert), and a message of another kind
        changes the state, so that the run stops before it."""
        view, buf = self._rx_batch_view, self._rx_bytes
        at = self._rx_next * _MSG_SIZE
        wraps, last = self._wraps, self._last_ticks
        offset, channel, epoch = self._time_offset, self._channel_name, self._epoch_ns
        # _sim_ns: epoch + ((wraps << 32) | ticks) * 1000, the same integer as base + ticks *
        # 1000 (ticks < 2**32); _stamp divides it by 1e9 as a float. While base stays below
        # _FLOAT_EXACT the sum is made in floats, exactly, so that the time stamp is the same.
        base = epoch + (wraps << 32) * 1000
        exact = base < _FLOAT_EXACT
        if exact:
            base = float(base)
        append = self._rx_ready.append
        new, fields = _new_message, _FRAME_FIELDS
        data = at + 16  # where the message's data starts in the batch
        for ticks, ident, kind, bits in _CLASSIC.iter_unpack(view[at : self._rx_count * _MSG_SIZE]):
            if kind:  # not CAN_MSGTYPE_DATA
                break
            if ticks < last:  # _sim_ns, inline
                wraps += 1
                base = epoch + (wraps << 32) * 1000
                exact = base < _FLOAT_EXACT
                if exact:
                    base = float(base)
            last = ticks
            ext, rx, remote, fd, brs, esi, dlc, length = fields[bits]
            # Every attribute Message.__init__ sets, as it sets it from _convert's arguments.
            msg = new(Message)
            if exact:
                msg.timestamp = (base + ticks * 1000.0) / 1e9 + offset
            else:
                msg.timestamp = (base + ticks * 1000) / 1e9 + offset
            msg.arbitration_id = ident
            msg.is_extended_id = ext
            msg.is_remote_frame = remote
            msg.is_error_frame = False
            msg.channel = channel
            msg.is_fd = fd
            msg.is_rx = rx
            msg.bitrate_switch = brs
            msg.error_state_indicator = esi
            msg.data = buf[data : data + length]  # a bytearray of its own
            msg.dlc = dlc
            append(msg)
            data += _MSG_SIZE
        self._rx_next = (data - 16) // _MSG_SIZE
        self._wraps, self._last_ticks = wraps, last

    def _sim_ns(self, ticks: int) -> int:
        """The simulated time in ns of an adapter time stamp (microsecond ticks, 32 bits; the
        wraps are counted as the messages come, in order)."""
        if ticks < self._last_ticks:
            self._wraps += 1
        self._last_ticks = ticks
        return self._epoch_ns + ((self._wraps << 32) | ticks) * 1000

    def _stamp(self, sim_ns: int) -> float:
        return sim_ns / 1e9 + self._time_offset

    def _now_ns(self) -> int:
        """Simulated time now, on the adapter's microsecond grid."""
        with _vci_errors():
            now_ns, _ = _sim_time()
        return now_ns - (now_ns - self._epoch_ns) % 1000

    def _convert(self, view: memoryview, at: int) -> Tuple[Optional[Message], bool]:
        """The CANMSG2 at byte `at` of `view` as a python-can Message (None for those python-can
        has no use for). Error frames that the message also causes go to self._pending, after
        it."""
        ticks, _, ident, kind, flags2, flags, _ = _HEADER.unpack_from(view, at)
        body = at + 16
        if kind == _DATA:
            # The hot path: _sim_ns and _payload_length inline, constants from module globals.
            if ticks < self._last_ticks:
                self._wraps += 1
            self._last_ticks = ticks
            sim_ns = self._epoch_ns + ((self._wraps << 32) | ticks) * 1000
            dlc = flags & _DLC
            if flags2 & _EDL:
                fd, remote, length = True, False, _DLC_TO_LEN[dlc]
            else:
                fd, remote = False, bool(flags & _RTR)
                length = 0 if remote else (dlc if dlc < 8 else 8)
            own = bool(flags & _SRR)
            msg = Message(
                timestamp=sim_ns / 1e9 + self._time_offset,  # _stamp, inline
                arbitration_id=ident,
                is_extended_id=bool(flags & _EXT),
                is_remote_frame=remote,
                is_fd=fd,
                bitrate_switch=bool(flags2 & _FDR),
                error_state_indicator=bool(flags2 & _ESI),
                dlc=length if fd else dlc,
                data=bytes(view[body : body + length]),
                channel=self._channel_name,
                is_rx=not own,
                check=False,
            )
            if self._reported == _vci.CANEMU_STATE_PASSIVE:
                # A frame that got through lowers a counter: the one that made the node
                # error-passive may have fallen below 128.
                tec, rec = self._counters
                if (tec >= 128 and own) or (rec >= 128 and not own):
                    self._check_passive(sim_ns)
            return msg, self._hw_filtered
        if kind == _vci.CAN_MSGTYPE_ERROR:
            sim_ns = self._sim_ns(ticks)
            msg = self._bus_error(sim_ns, view[body])
            # The counters as the error was detected (canemu's firmware writes REC and TEC
            # beyond the message's dlc, docs/vci.md): the crossing at its instant.
            counters = (view[body + 4], view[body + 3])
            if self._reported == _vci.CANEMU_STATE_WARNING:
                self._check_passive(sim_ns, counters)
            else:
                self._counters = counters
            return msg, True
        if kind == _vci.CAN_MSGTYPE_STATUS:
            sim_ns = self._sim_ns(ticks)
            msg = self._status_change(sim_ns, view[body])
            if self._reported == _vci.CANEMU_STATE_WARNING:
                self._check_passive(sim_ns, self._counters)  # those of the last ERROR message
            elif self._reported == _vci.CANEMU_STATE_PASSIVE:
                self._check_passive(sim_ns)
            return msg, True
        if kind == _vci.CAN_MSGTYPE_TIMEOVR:
            self._wraps += 1
            self._last_ticks = 0
        return None, True
