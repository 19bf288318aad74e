"""python-can on an interface of an emulated SORCUS X-CAN-2i: ``can.Bus(interface="canemu",
channel="xcan0:1")``, driven through canemu's libxcan.so (the module driver's channel services).

The bus is what the 82527 behind the driver allows (docs/python.md, "X-CAN-2i interfaces"):

- it sends through the interface's general-ID send channel (any identifier, 11 or 29 bits, data
  and remote frames; at most one such channel per interface, so one bus object per interface);
- it receives through the acceptance-filter device, i.e. the 82527's receive-only buffer 15,
  opened for every identifier: data frames of one identifier format (`rx_format`, 11 or 29), or
  remote frames instead (`rx_remote`); the 82527 does not receive its own frames;
- its error state is the driver's bus state word: bus-off, heavily disturbed (an error counter
  at the warning limit), line fault; the counters themselves are not readable, as on the chip.
"""

from __future__ import annotations

import ctypes
import logging
import queue
import threading
import time
from collections import deque
from typing import Any, Deque, List, Optional, Tuple, Union

import can
from can import BusABC, BusState, Message

from . import _daemon, _timing, _xcan
from ._calls import CanTimeoutError
from ._state import (
    CAN_ERR_ACK,
    CAN_ERR_BUSERROR,
    CAN_ERR_BUSOFF,
    CAN_ERR_CRTL,
    CAN_ERR_CRTL_RX_WARNING,
    CAN_ERR_CRTL_TX_WARNING,
    CAN_ERR_PROT,
    CAN_ERR_PROT_BIT,
    CAN_ERR_PROT_FORM,
    CAN_ERR_PROT_LOC_ACK,
    CAN_ERR_PROT_LOC_CRC_SEQ,
    CAN_ERR_PROT_STUFF,
    CAN_ERR_TRX,
    ControllerState,
)
from ._xcan import XcanError

log = logging.getLogger("can.canemu")

try:  # python-can 4.3 and later
    from can import CanProtocol
except ImportError:  # pragma: no cover - python-can 4.1 and 4.2
    CanProtocol = None

# The 82527 of an X-CAN-2i: 8 MHz system clock (a time quantum is 1..64 x 125 ns) and the
# driver's ranges (XCAN_BITPARAMS).
LIMITS = _timing.Limits(
    clock_hz=8_000_000,
    nominal=_timing.Range(brp=(1, 64), tseg1=(3, 16), tseg2=(2, 8), sjw=(1, 4)),
    data=None,
)

# The 82527's last error code -> SocketCAN error class, protocol error type, location.
_LEC_ERRORS = {
    _xcan.XCAN_LEC_STUFF: (CAN_ERR_PROT, CAN_ERR_PROT_STUFF, 0),
    _xcan.XCAN_LEC_FORM: (CAN_ERR_PROT, CAN_ERR_PROT_FORM, 0),
    _xcan.XCAN_LEC_ACK: (CAN_ERR_ACK, 0, CAN_ERR_PROT_LOC_ACK),
    _xcan.XCAN_LEC_BIT1: (CAN_ERR_PROT, CAN_ERR_PROT_BIT, 0),
    _xcan.XCAN_LEC_BIT0: (CAN_ERR_PROT, CAN_ERR_PROT_BIT, 0),
    _xcan.XCAN_LEC_CRC: (CAN_ERR_PROT, 0, CAN_ERR_PROT_LOC_CRC_SEQ),
}

_CLASSIC_BITS = 160  # the longest classic frame with stuff bits and intermission
_DRAIN_FACTOR = 1.5
_DRAIN_MARGIN_NS = 50_000_000
_POLL_S = 0.1  # waits are sliced so that shutdown gets through


def is_module(channel: str) -> bool:
    """Whether `channel` ("DEVICE:N") names an X-CAN-2i module (any N)."""
    device, _, number = channel.rpartition(":")
    return bool(device) and number.isdigit() and any(
        f.szDevice.decode() == device for f in _xcan.interfaces())


def find_interface(channel: str) -> _xcan.CANEMU_XCAN_INTERFACE:
    """The X-CAN-2i interface `channel` ("DEVICE:N") names; ValueError naming those there are
    when there is none."""
    device, _, number = channel.rpartition(":")
    found = _xcan.interfaces()
    for f in found:
        if f.szDevice.decode() == device and number.isdigit() and f.usChannel == int(number):
            return f
    names = ", ".join(f"{f.szDevice.decode()}:{f.usChannel}" for f in found) or "none"
    raise ValueError(f"channel {channel!r} is no interface of an X-CAN-2i of canemud "
                     f"(X-CAN-2i interfaces: {names})")


def bit_params(bitrate: Optional[int], timing, low_speed: bool) -> _xcan.XCAN_BITPARAMS:
    """The XCAN_BITPARAMS for a bit rate or a can.BitTiming, with 11- and 29-bit identifiers
    (mixed format). ValueError when the 82527 at 8 MHz cannot make it."""
    if timing is not None:
        if hasattr(timing, "nom_brp"):
            raise ValueError("a BitTimingFd needs a CAN FD controller; the 82527 is classic CAN")
        btp, _ = _timing.from_python_can(timing, LIMITS)
    else:
        btp = _timing.from_bitrate(int(bitrate), 0.875, LIMITS.clock_hz, LIMITS.nominal,
                                   "bitrate")
    params = _xcan.XCAN_BITPARAMS(
        Tq=btp.dwBPS * 125,
        Tseg1=btp.wTS1,
        Tseg2=btp.wTS2,
        Tsjw=btp.wSJW,
        SpB=3 if btp.dwMode & _timing._vci.CAN_BTMODE_TSM else 1,
        Rbus=0,
        MsgFormat=_xcan.XCAN_MIXED_FORMAT,
    )
    if params.Tseg1 + params.Tseg2 < 7:
        raise ValueError(f"bit timing: Tseg1 + Tseg2 = {params.Tseg1 + params.Tseg2}, but the "
                         f"X-CAN-2i needs at least 7")
    if low_speed and params.Tq * (1 + params.Tseg1 + params.Tseg2) < 8000:
        raise ValueError("a low-speed fault-tolerant interface runs at most 125000 bit/s")
    return params


def bitrate_of(p: _xcan.XCAN_BITPARAMS) -> int:
    return 1_000_000_000 // (p.Tq * (1 + p.Tseg1 + p.Tseg2))


class XcanBus(BusABC):
    """A program on one CAN interface of an emulated SORCUS X-CAN-2i.

    Made by ``can.Bus(interface="canemu", channel="DEVICE:N")`` when DEVICE is a
    ``"sorcus-x-can-2i"`` device of canemud's configuration (N: interface 0 or 1).

    :param bitrate: bit rate in bit/s (default: the bus's configured one), written with the
        bus-control device. Another program's objects on the interface keep its format: then
        only a bit rate equal to the one set may be asked for.
    :param timing: a ``can.BitTiming`` (8 MHz for the values as they are; another clock: its
        bit rate and sample point).
    :param receive_own_messages: frames this bus sent come back from ``recv`` with
        ``is_rx = False``, at the instant the driver reports them acknowledged.
    :param auto_restart: after bus-off, the bus control device's CMD_STOP and CMD_START are
        given at once (the 82527 then waits 128 x 11 recessive bits); False leaves it to
        :meth:`restart`.
    :param rx_format: the identifier format received, 11 or 29 (buffer 15 takes one).
    :param rx_remote: receive remote frames instead of data frames.
    :param socket: canemud's socket (default: $CANEMU_SOCKET, else its default path); applies
        to the whole process.
    """

    def __init__(
        self,
        channel: Union[str, int],
        can_filters=None,
        receive_own_messages: bool = False,
        bitrate: Optional[int] = None,
        timing=None,
        fd: bool = False,
        listen_only: bool = False,
        auto_restart: bool = True,
        rx_format: int = 11,
        rx_remote: bool = False,
        socket: Optional[str] = None,
        **kwargs: Any,
    ) -> None:
        self._handles: List[int] = []  # opened channels, closed in reverse order
        self._bus_ctrl = 0
        self._general = 0
        self._filter = 0
        self._closed = False
        self._channel_name = str(channel)
        self._receive_own = bool(receive_own_messages)
        self._auto_restart = bool(auto_restart)
        self._rx: "queue.Queue[Message]" = queue.Queue()
        self._tx_cond = threading.Condition()
        self._in_flight: Deque[Message] = deque()  # sent, not yet reported acknowledged
        self._tx_flushed = False
        self._state_word = 0
        self._was_bus_off = False
        # ctypes keeps no reference to a function pointer it was given: these live with the bus.
        self._on_status = _xcan.MAX_CALLBACK(self._status_callback)
        self._on_sent = _xcan.MAX_CALLBACK(self._sent_callback)
        self._on_frame = _xcan.MAX_CALLBACK(self._frame_callback)
        try:
            if fd:
                raise ValueError(f"channel {channel!r}: the X-CAN-2i's 82527 is a classic CAN "
                                 f"controller (fd=True is not possible)")
            if listen_only:
                raise ValueError(f"channel {channel!r}: the 82527 has no listen-only mode")
            if rx_format not in (11, 29):
                raise ValueError(f"rx_format is 11 or 29, not {rx_format!r}")
            if socket is not None:
                _daemon.connect(socket)
            _xcan.use_socket(_daemon.current_socket())
            self._open(str(channel), bitrate, timing, rx_format, bool(rx_remote))
            super().__init__(channel=channel, can_filters=can_filters, **kwargs)
        except XcanError as e:
            self._close_handles()
            raise can.CanInitializationError(self._explain(e), error_code=e.code) from None
        except (ValueError, OSError) as e:
            self._close_handles()
            raise can.CanInitializationError(str(e)) from None
        except BaseException:
            self._close_handles()
            raise

    # ---- opening ----

    def _explain(self, e: XcanError) -> str:
        text = f"{self._channel_name}: {e}"
        if e.code == _xcan.ERR_XCAN_CHANNEL_BUSY:
            text += (" (an X-CAN-2i interface has one general-ID send channel and one "
                     "acceptance filter: another bus object or program holds them)")
        elif e.code == _xcan.ERR_XCAN_NO_DAEMON:
            text += ("; canemud is not running or not reachable: start it with `make run`, "
                     "`systemctl start canemud` or `canemud --config FILE`, and set "
                     "CANEMU_SOCKET (or the bus's socket= argument) when it listens elsewhere")
        return text

    def _open(self, channel, bitrate, timing, rx_format, rx_remote):
        lib = _xcan.lib()
        info = find_interface(channel)
        self._device_name = info.szDevice.decode()
        self._interface = info.usChannel
        self._bus_name = info.szBus.decode()
        #: The node's name in canemud (`canemu status`, fault scenarios' `node` and `from`).
        self.node_name = f"{self._device_name}:{self._interface}"
        self.channel_info = f"canemu {self.node_name} (X-CAN-2i) on {self._bus_name}"
        if CanProtocol is not None:
            self._can_protocol = CanProtocol.CAN_20
        self._time_offset = _daemon._wall_offset()  # before any callback can come

        module = _xcan.MAX_HANDLE()
        _xcan.check("canemu_open_module",
                    lib.canemu_open_module(info.szDevice, ctypes.byref(module)))
        mdd = _xcan.MAX_HANDLE()
        _xcan.check("max_load_mdd", lib.max_load_mdd(module, 1, 0, 0, 0x803A, None,
                                                     ctypes.byref(mdd)))
        self._bus_ctrl = self._open_channel(mdd, _xcan.DEVICE_CTRL, _xcan.XCAN_BUS_CTRL_INDEX,
                                            0, 0, self._on_status)
        self._set_timing(bitrate, timing, info)
        self._general = self._open_channel(mdd, _xcan.DEVICE_BUS_OUT, 0, _xcan._CP_EXCLUSIVE,
                                           _xcan.XCAN_GENERAL_ID, self._on_sent)
        flags = (_xcan.XCAN_29BIT_ID if rx_format == 29 else 0) | (
            _xcan.XCAN_REMOTE if rx_remote else 0)
        self._filter = self._open_channel(mdd, _xcan.DEVICE_CTRL, 0, flags, _xcan.XCAN_AUTO_ID,
                                          self._on_frame)
        # Mask 0: no bit compared, every identifier of the format passes buffer 15.
        _xcan.check("max_write_channel_ulong", lib.max_write_channel_ulong(self._filter, 0))
        self._state_word = self._info()

    def _open_channel(self, mdd, device: int, index: int, flags: int, ident: int,
                      callback) -> int:
        cps = _xcan.CPS_XCAN(usDevice=device, usChannel=self._interface, usIndexFirst=index,
                             usIndexLast=index, usFlags=flags, usTimeout=0, ulCanID=ident)
        handle = _xcan.MAX_HANDLE()
        _xcan.check("max_open_channel", _xcan.lib().max_open_channel(
            mdd, ctypes.byref(cps), callback, ctypes.byref(handle)))
        self._handles.append(handle.value)
        return handle.value

    def _set_timing(self, bitrate, timing, info) -> None:
        lib = _xcan.lib()
        current = _xcan.XCAN_BITPARAMS()
        size = _xcan.ULONG(ctypes.sizeof(current))
        _xcan.check("max_read_channel_block", lib.max_read_channel_block(
            self._bus_ctrl, ctypes.byref(size), ctypes.byref(current)))
        wanted = bit_params(bitrate or info.ulBitrate, timing, bool(info.usLowSpeed))
        if bytes(wanted) == bytes(current):
            self._bitrate = bitrate_of(current)
            return
        size = _xcan.ULONG(ctypes.sizeof(wanted))
        code = lib.max_write_channel_block(self._bus_ctrl, ctypes.byref(size),
                                           ctypes.byref(wanted))
        if code == _xcan.ERR_XCAN_PARAM and current.MsgFormat != _xcan.XCAN_MIXED_FORMAT:
            # Objects of another program fix the interface's format; its bit rate may do.
            if bitrate_of(current) == bitrate_of(wanted) and timing is None:
                log.info("%s: another program set the interface up for %d-bit identifiers "
                         "only", self.channel_info, current.MsgFormat)
                self._bitrate = bitrate_of(current)
                return
            raise ValueError(
                f"{self._channel_name}: another program's objects keep the interface at "
                f"{bitrate_of(current)} bit/s with {current.MsgFormat}-bit identifiers; "
                f"open the bus without bitrate/timing, or close that program first")
        _xcan.check("max_write_channel_block (XCAN_BITPARAMS)", code)
        self._bitrate = bitrate_of(wanted)

    # ---- callbacks (libxcan's callback thread) ----

    def _stamp(self, sim_ns: int) -> float:
        return sim_ns / 1e9 + self._time_offset

    def _frame_callback(self, _handle, size, data) -> None:
        if size < ctypes.sizeof(_xcan.XCAN_MESSAGE) or not data:
            return
        m = _xcan.XCAN_MESSAGE.from_address(data)
        remote = bool(m.usFlags & _xcan.XCAN_REMOTE)
        self._rx.put(Message(
            timestamp=self._stamp(_xcan.callback_time()),
            arbitration_id=m.ulCanId,
            is_extended_id=bool(m.usFlags & _xcan.XCAN_29BIT_ID),
            is_remote_frame=remote,
            dlc=m.usDataSize,
            data=None if remote else bytes(m.aucData[: m.usDataSize]),
            channel=self._channel_name,
        ))

    def _sent_callback(self, _handle, _size, _data) -> None:
        at = _xcan.callback_time()
        with self._tx_cond:
            sent = self._in_flight.popleft() if self._in_flight else None
            self._tx_cond.notify_all()
        if sent is not None and self._receive_own:
            self._rx.put(Message(
                timestamp=self._stamp(at),
                arbitration_id=sent.arbitration_id,
                is_extended_id=sent.is_extended_id,
                is_remote_frame=sent.is_remote_frame,
                dlc=sent.dlc,
                data=None if sent.is_remote_frame else bytes(sent.data),
                is_rx=False,
                channel=self._channel_name,
            ))

    def _status_callback(self, _handle, size, data) -> None:
        if size < 4 or not data:
            return
        status = ctypes.c_uint32.from_address(data).value
        frame = self._error_frame(status, _xcan.callback_time())
        if status & _xcan.XCAN_BUS_OFF and self._auto_restart and not self._closed:
            # Before the error frame is handed on: who reads it finds the restart under way.
            try:
                self.restart()
            except can.CanError as e:
                log.warning("%s: restart after bus-off failed: %s", self.channel_info, e)
        if frame is not None:
            self._rx.put(frame)

    def _error_frame(self, status: int, sim_ns: int) -> Optional[Message]:
        """The SocketCAN error frame for a state word the error callback brought: bus-off,
        the warning limit (which counter the 82527 does not say: both bits), a line fault,
        and the last error code as protocol error."""
        flags = status & 0xFFFF
        lec = status >> 16
        previous = self._state_word & 0xFFFF
        self._state_word = status
        ident = 0
        data = bytearray(8)
        if flags & _xcan.XCAN_BUS_OFF:
            ident |= CAN_ERR_BUSOFF
            self._was_bus_off = True
        elif flags & _xcan.XCAN_BUS_HEAVY and not previous & _xcan.XCAN_BUS_HEAVY:
            ident |= CAN_ERR_CRTL
            data[1] = CAN_ERR_CRTL_TX_WARNING | CAN_ERR_CRTL_RX_WARNING
        if flags & _xcan.XCAN_LINE_ERROR and not previous & _xcan.XCAN_LINE_ERROR:
            ident |= CAN_ERR_TRX
        if lec in _LEC_ERRORS:
            cls, prot, location = _LEC_ERRORS[lec]
            ident |= cls | CAN_ERR_BUSERROR
            data[2] = prot
            data[3] = location
        if ident == 0:
            return None
        return Message(timestamp=self._stamp(sim_ns), arbitration_id=ident,
                       is_error_frame=True, dlc=8, data=bytes(data),
                       channel=self._channel_name)

    # ---- receiving ----

    def _recv_internal(self, timeout: Optional[float]) -> Tuple[Optional[Message], bool]:
        # Not filtered here: python-can applies the bus's filters (buffer 15 takes every ID).
        deadline = None if timeout is None else time.monotonic() + max(timeout, 0.0)
        while not self._closed:
            wait = _POLL_S
            if deadline is not None:
                wait = min(wait, deadline - time.monotonic())
            try:
                if wait <= 0:
                    return self._rx.get_nowait(), False
                return self._rx.get(timeout=wait), False
            except queue.Empty:
                if wait <= 0:
                    return None, False
        return None, False

    # ---- sending ----

    def send(self, msg: Message, timeout: Optional[float] = None) -> None:
        """Hands `msg` to the general-ID send channel, waiting up to `timeout` seconds (None:
        as long as it takes) while the driver's FIFO is full. An error frame is not sent (a
        controller cannot send one at will)."""
        if msg.is_error_frame:
            log.debug("%s: error frame not sent: %s", self.channel_info, msg)
            return
        if msg.is_fd:
            raise can.CanOperationError(f"{self.channel_info}: the 82527 sends no CAN FD frames")
        length = len(msg.data)
        if length > 8:
            raise can.CanOperationError(
                f"a classic CAN frame carries at most 8 data bytes, not {length}")
        size = msg.dlc if msg.is_remote_frame else length
        if not 0 <= size <= 8:
            raise can.CanOperationError(f"a remote frame's DLC is 0..8, not {size}")
        limit = _xcan.XCAN_MAX_ID_29 if msg.is_extended_id else _xcan.XCAN_MAX_ID_11
        if not 0 <= msg.arbitration_id <= limit:
            raise can.CanOperationError(
                f"{self.channel_info}: identifier 0x{msg.arbitration_id:X} is beyond "
                f"0x{limit:X}, the highest {'29' if msg.is_extended_id else '11'}-bit "
                f"identifier the X-CAN-2i sends (the 16 highest are not allowed)")
        out = _xcan.XCAN_MESSAGE(ulCanId=msg.arbitration_id, usDataSize=size,
                                 usFlags=(_xcan.XCAN_29BIT_ID if msg.is_extended_id else 0)
                                 | (_xcan.XCAN_REMOTE if msg.is_remote_frame else 0))
        if not msg.is_remote_frame:
            out.aucData[:length] = bytes(msg.data)
        out_size = _xcan.ULONG(ctypes.sizeof(out))
        lib = _xcan.lib()
        self._tx_flushed = False
        deadline = None if timeout is None else time.monotonic() + timeout
        with self._tx_cond:
            while True:
                if self._closed:
                    raise can.CanOperationError(f"{self.channel_info}: the bus is shut down")
                # In flight before the write: its acknowledgement may come before the reply.
                self._in_flight.append(msg)
                code = lib.max_write_channel_block(self._general, ctypes.byref(out_size),
                                                   ctypes.byref(out))
                if code == _xcan.ERR_OK:
                    return
                self._in_flight.pop()
                if code != _xcan.ERR_XCAN_FIFO_FULL:
                    break
                left = _POLL_S if deadline is None else deadline - time.monotonic()
                if left <= 0:
                    raise CanTimeoutError(
                        f"{self.channel_info}: the driver's FIFO stayed full for {timeout} s")
                self._tx_cond.wait(min(left, _POLL_S))
        text = ("the interface is bus-off or stopped" if code == _xcan.ERR_XCAN_NOT_READY
                else "")
        raise can.CanOperationError(
            f"{self.channel_info}: {XcanError('max_write_channel_block', code, text)}",
            error_code=code)

    def flush_tx_buffer(self) -> None:
        """``shutdown()`` then closes without waiting for the frames sent so far to be
        acknowledged (they may still go out until the channel closes)."""
        self._tx_flushed = True

    # ---- state ----

    def _info(self) -> int:
        value = _xcan.ULONG()
        _xcan.check("max_channel_info", _xcan.lib().max_channel_info(
            self._bus_ctrl, _xcan.INFO_DEVICE, ctypes.byref(value)))
        return value.value

    def bus_status(self) -> int:
        """The driver's bus state word (INFO_DEVICE): XCAN_BUS_ON, XCAN_BUS_HEAVY, XCAN_BUS_OFF,
        XCAN_LINE_ERROR in the low word, the 82527's last error code in the high word."""
        try:
            return self._info()
        except XcanError as e:
            raise can.CanOperationError(f"{self._channel_name}: {e}", error_code=e.code) from None

    @property
    def state(self) -> BusState:
        """ERROR while bus-off, else ACTIVE (the 82527 shows no error-passive state)."""
        return BusState.ERROR if self.bus_status() & _xcan.XCAN_BUS_OFF else BusState.ACTIVE

    @state.setter
    def state(self, new_state: BusState) -> None:
        raise can.CanOperationError(
            f"{self.channel_info}: the 82527 has no listen-only mode; the state cannot be set")

    @property
    def controller_state(self) -> ControllerState:
        """BUS_OFF, ERROR_WARNING (heavily disturbed: a counter at 96 or more) or
        ERROR_ACTIVE; the 82527 does not tell error-passive apart from the warning level."""
        status = self.bus_status()
        if status & _xcan.XCAN_BUS_OFF:
            return ControllerState.BUS_OFF
        if status & _xcan.XCAN_BUS_HEAVY:
            return ControllerState.ERROR_WARNING
        return ControllerState.ERROR_ACTIVE

    def restart(self) -> None:
        """CMD_STOP then CMD_START on the bus-control device: the way out of bus-off (the
        82527 waits 128 x 11 recessive bits, then both counters are 0)."""
        lib = _xcan.lib()
        for command, name in ((_xcan.CMD_STOP, "CMD_STOP"), (_xcan.CMD_START, "CMD_START")):
            code = lib.max_channel_control(self._bus_ctrl, command)
            if code != _xcan.ERR_OK:
                raise can.CanOperationError(
                    f"{self.channel_info}: {XcanError('max_channel_control ' + name, code)}",
                    error_code=code)

    # ---- shutting down ----

    def _drain(self) -> Tuple[int, str]:
        """Waits until the frames sent are acknowledged, bounded in simulated time as the VCI
        bus's drain is (docs/python.md); (frames left, why)."""
        deadline_ns = None
        while True:
            with self._tx_cond:
                left = len(self._in_flight)
            if left == 0:
                return 0, ""
            if self.bus_status() & _xcan.XCAN_BUS_OFF:
                return left, "the interface is bus-off"
            now_ns, mode = _daemon._sim_time()
            if mode == _daemon._vci.CANEMU_TIME_STEPPED:
                return left, "in stepped time nothing moves at shutdown"
            if deadline_ns is None:
                bound_ns = int(left * _CLASSIC_BITS * 1_000_000_000 // self._bitrate
                               * _DRAIN_FACTOR) + _DRAIN_MARGIN_NS
                deadline_ns = now_ns + bound_ns
            elif now_ns >= deadline_ns:
                return left, (f"they were not acknowledged within {bound_ns / 1e9:.3f} s of bus "
                              f"time (is a node acknowledging?)")
            with self._tx_cond:
                self._tx_cond.wait(0.002)

    def _close_handles(self) -> None:
        lib = _xcan._lib
        while self._handles and lib is not None:
            lib.max_close_channel(self._handles.pop())

    def shutdown(self) -> None:
        """Lets the frames sent be acknowledged (unless ``flush_tx_buffer()`` came first;
        frames left are named in a warning on the "can.canemu" logger) and closes the
        channels."""
        if self._closed:
            return
        super().shutdown()
        try:
            if not self._tx_flushed and self._general:
                try:
                    left, why = self._drain()
                except (can.CanError, _daemon._vci.VciError) as e:
                    left, why = 0, ""
                    log.warning("%s: shutdown could not wait for the frames sent: %s",
                                self.channel_info, e)
                if left:
                    log.warning("%s: shutdown discards %d frame(s) not acknowledged: %s",
                                self.channel_info, left, why)
        finally:
            self._closed = True
            with self._tx_cond:
                self._tx_cond.notify_all()
            self._close_handles()


def available_configs() -> List[dict]:
    """Every X-CAN-2i interface as a python-can configuration ("DEVICE:N")."""
    _xcan.use_socket(_daemon.current_socket())
    return [
        {
            "interface": "canemu",
            "channel": f"{f.szDevice.decode()}:{f.usChannel}",
            "fd": False,
            "bus": f.szBus.decode(),
            "bitrate": f.ulBitrate,
        }
        for f in _xcan.interfaces()
    ]
