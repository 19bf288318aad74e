"""python-can interface for canemu: `can.Bus(interface="canemu", channel=...)`.

Every bus object is a program on an emulated IXXAT adapter, driven through canemu's VCI C API
(libvcinpl2.so): a channel on one of the adapter's CAN controllers, and the controller's control
unit when nobody else holds it. See docs/python.md.
"""

from __future__ import annotations

import contextlib
import ctypes
import enum
import logging
import struct
import threading
import time
from collections import deque
from typing import Any, Deque, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import can
from can import BusABC, BusState, Message
from can.broadcastmanager import (
    LimitedDurationCyclicSendTaskABC,
    ModifiableCyclicTaskABC,
    RestartableCyclicTaskABC,
)

from . import _timing, _vci
from ._vci import VciError

log = logging.getLogger("can.canemu")

try:  # python-can 4.3 and later
    from can import CanProtocol
except ImportError:  # pragma: no cover - python-can 4.1 and 4.2
    CanProtocol = None

CanTimeoutError = getattr(can, "CanTimeoutError", can.CanOperationError)

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
_HEADER = struct.Struct("<IIIBBBB")  # dwTime, _rsvd_, dwMsgId, type, flags2, flags, accept
_WAIT_SLICE_MS = 100  # blocking calls wait in slices so that Ctrl-C and shutdown get through
_FILTER_LIST_SIZE = 2048  # 29-bit ID list of each channel


def _can_error(e: VciError, initializing: bool = False) -> can.CanError:
    """The python-can exception for a failed VCI call: CanInitializationError while a bus is
    being made (or the process connects), CanOperationError otherwise. Every VciError that
    reaches a caller of this package goes through here."""
    text = str(e)
    if e.hr == _vci.VCI_E_DISCONNECTED:
        text += (
            "; canemud is not running or not reachable: start it with `make run` in the canemu "
            "folder, `systemctl start canemu`, or `canemud --config FILE`, and set CANEMU_SOCKET "
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


def _payload_length(flags: int, flags2: int) -> int:
    """Data bytes of a CAN message from its CANMSGINFO flags (a remote frame has none)."""
    dlc = flags & _vci.FLAGS_DLC
    if flags2 & _vci.FLAGS2_EDL:
        return _vci.DLC_TO_LEN[dlc]
    return 0 if flags & _vci.FLAGS_RTR else min(dlc, 8)


def _call(name: str, *args) -> int:
    """Calls a library function; VciError when it fails."""
    hr = getattr(_vci.lib(), name)(*args)
    _vci.check(name, hr)
    return hr


_offset_lock = threading.Lock()
_offset: Optional[float] = None


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
    The choice is for the whole process; buses opened before stay with their daemon."""
    global _offset
    with _offset_lock:
        _offset = None
    with _vci_errors(initializing=True):
        _call("canemuConnect", socket.encode() if socket else None)


def step(nanoseconds: int) -> int:
    """Stepped time: runs canemud's emulation `nanoseconds` further; returns the simulated time
    in ns after the step. CanOperationError when canemud does not run in stepped time."""
    now = ctypes.c_uint64()
    with _vci_errors():
        _call("canemuStepTime", int(nanoseconds), ctypes.byref(now))
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


class CanemuBus(BusABC):
    """A node on a bus that canemud emulates.

    :param channel: ``"DEVICE:N"`` for CAN controller N of a configured adapter (``"ixxat0:0"``)
        or an adapter's name; a bus name (``"can0"``) for a new adapter of its own on that bus,
        gone when the bus object shuts down.
    :param bitrate: nominal bit rate in bit/s; default: the bus's configured one.
    :param data_bitrate: CAN FD data-phase bit rate; default: the bus's configured one.
    :param fd: send and receive CAN FD frames (needs a CAN FD bus).
    :param timing: a ``can.BitTiming`` or ``can.BitTimingFd``; overrides the bit rates (a
        ``BitTiming`` on a CAN FD controller the nominal one: the data phase then follows
        `data_bitrate`).
    :param receive_own_messages: frames this bus sends come back from ``recv`` with
        ``is_rx = False``, also those of the adapter's cyclic list (``send_periodic``).
    :param listen_only: the controller only listens (no acknowledgement, no error flags).
    :param auto_restart: a controller that went bus-off is started again (it then waits
        128 x 11 recessive bits, as ISO 11898-1 says); False leaves it bus-off until
        :meth:`restart`.
    :param rx_fifo_size: receive FIFO of the channel, in messages.
    :param tx_fifo_size: transmit FIFO, in messages; ``send`` waits while it is full.
    :param socket: canemud's socket (default: $CANEMU_SOCKET, else its default path); applies
        to the whole process.
    """

    def __init__(
        self,
        channel: Union[str, int],
        can_filters=None,
        receive_own_messages: bool = False,
        bitrate: Optional[int] = None,
        data_bitrate: Optional[int] = None,
        fd: bool = False,
        timing=None,
        listen_only: bool = False,
        auto_restart: bool = True,
        rx_fifo_size: int = 4096,
        tx_fifo_size: int = 256,
        socket: Optional[str] = None,
        **kwargs: Any,
    ) -> None:
        self._device = None
        self._control = None
        self._channel = None
        self._scheduler = None
        self._ephemeral: Optional[str] = None
        self._channel_name = channel
        self._poll_fd: Optional[int] = None
        self._closed = False
        self._receive_own = bool(receive_own_messages)
        self._auto_restart = bool(auto_restart)
        self._hw_filtered = True
        self._initializing = True
        self._was_bus_off = False
        self._last_status = 0
        # The controller state the error frames have told so far (CANEMU_STATE_*), and the
        # counters when it was last read.
        self._reported = _vci.CANEMU_STATE_ACTIVE
        self._counters = (0, 0)
        self._pending: Deque[Message] = deque()  # error frames made but not yet returned
        self._wraps = 0
        self._last_ticks = 0
        self._rx_lock = threading.Lock()
        self._tx_lock = threading.Lock()
        self._rx_msg = _vci.CANMSG2()
        self._rx_view = memoryview(self._rx_msg).cast("B")
        self._rx_ref = ctypes.byref(self._rx_msg)  # made once: a call per frame is the hot path
        self._tx_msg = _vci.CANMSG2()
        self._tx_view = memoryview(self._tx_msg).cast("B")
        self._tx_ref = ctypes.byref(self._tx_msg)
        self._sched_lock = threading.Lock()
        try:
            _vci.lib()
        except OSError as e:
            raise can.CanInitializationError(str(e)) from None
        try:
            if socket is not None:
                connect(socket)
            self._open(str(channel), bitrate, data_bitrate, bool(fd), timing, listen_only,
                       rx_fifo_size, tx_fifo_size)
            super().__init__(channel=channel, can_filters=can_filters, **kwargs)
        except VciError as e:
            self._close_handles()
            raise _can_error(e, initializing=True) from None
        except ValueError as e:
            self._close_handles()
            raise can.CanInitializationError(str(e)) from None
        except BaseException:
            self._close_handles()
            raise
        finally:
            self._initializing = False

    # ---- opening ----

    def _open(self, channel, bitrate, data_bitrate, fd, timing, listen_only, rx_size, tx_size):
        info = _vci.CANEMU_DEVICEINFO()
        device, _, number = channel.rpartition(":")
        if device and number.isdigit():
            controller = int(number)
            _call("canemuFindDevice", device.encode(), ctypes.byref(info))
        else:
            controller = 0
            if not self._find_bus(channel):
                raise ValueError(self._unknown_channel(channel))
            vciid = _vci.VCIID()
            name = ctypes.create_string_buffer(32)
            hr = _vci.lib().canemuCreateDevice(channel.encode(), None, ctypes.byref(vciid),
                                               name, 32)
            if hr == _vci.VCI_E_OUTOFMEMORY:
                raise ValueError(
                    f"channel {channel!r}: canemud makes at most {_vci.CANEMU_MAX_EPHEMERAL} "
                    f"adapters of their own per process, and this process has them all; shut "
                    f"down bus objects it no longer needs, or open controllers of configured "
                    f"adapters (\"DEVICE:N\")")
            _vci.check("canemuCreateDevice", hr)
            self._ephemeral = name.value.decode()
            _call("canemuFindDevice", name.value, ctypes.byref(info))
        if controller >= info.bControllers:
            raise ValueError(
                f"channel {channel!r}: adapter {info.szName.decode()} has "
                f"{info.bControllers} CAN controller(s), numbered from 0"
            )
        self._device_name = info.szName.decode()
        self._controller = controller
        self._epoch_ns = info.qwEpochNs
        self._fd_controller = bool(info.abFd[controller])
        bus_name = info.aszBus[controller].value.decode()
        bus = self._find_bus(bus_name) or {}
        if bus.get("kind") == "lin":
            raise ValueError(f"channel {channel!r} is on the LIN bus {bus_name}")
        if fd and not self._fd_controller:
            raise ValueError(
                f"fd=True needs a CAN FD controller; {self._device_name}:{controller} on "
                f"{bus_name} is a classic CAN controller"
            )
        self._fd = fd
        #: The node's name in canemud (`canemu status`, fault scenarios' `node` and `from`).
        self.node_name = f"{self._device_name}:{controller}"
        self.channel_info = f"canemu {self.node_name} on {bus_name}"
        self._bus_name = bus_name
        if CanProtocol is not None:
            self._can_protocol = CanProtocol.CAN_FD if fd else CanProtocol.CAN_20

        handle = _vci.HANDLE()
        _call("vciDeviceOpen", ctypes.byref(info.VciObjectId), ctypes.byref(handle))
        self._device = handle.value

        handle = _vci.HANDLE()
        _call("canChannelOpen", self._device, controller, 0, ctypes.byref(handle))
        self._channel = handle.value
        # With receive_own_messages the channel also takes the cyclic list's echoes (SRRA):
        # the firmware hands them only to channels that ask for every self-reception.
        mode = _vci.CAN_FILTER_PASS | (_vci.CAN_FILTER_SRRA if self._receive_own else 0)
        _call("canChannelInitialize", self._channel, rx_size, 1, tx_size, 1, _FILTER_LIST_SIZE,
              mode)
        _call("canChannelActivate", self._channel, 1)

        handle = _vci.HANDLE()
        hr = _vci.lib().canControlOpen(self._device, controller, ctypes.byref(handle))
        if hr == _vci.VCI_E_ACCESSDENIED:
            log.info("%s: another program controls the line; this bus only uses it",
                     self.channel_info)
        else:
            _vci.check("canControlOpen", hr)
            self._control = handle.value
            self._init_line(bus, bitrate, data_bitrate, timing, listen_only)

        # Where the error frames start: the controller as it is now (another program may hold
        # a line that is already at the warning limit or error-passive).
        state = ctypes.c_uint8()
        tec = ctypes.c_uint16()
        rec = ctypes.c_uint16()
        _call("canemuGetControllerState", self._channel, ctypes.byref(state), ctypes.byref(tec),
              ctypes.byref(rec), None)
        self._reported = state.value
        self._counters = (tec.value, rec.value)
        if state.value != _vci.CANEMU_STATE_ACTIVE:
            self._last_status |= _vci.CAN_STATUS_ERRLIM
        if state.value == _vci.CANEMU_STATE_BUSOFF:
            self._last_status |= _vci.CAN_STATUS_BUSOFF
        self._time_offset = _wall_offset()

    def _find_bus(self, name: str) -> Optional[Dict[str, Any]]:
        for b in _buses():
            if b["name"] == name:
                return b
        return None

    def _unknown_channel(self, channel: str) -> str:
        names = [b["name"] for b in _buses()]
        adapters = [
            f"{d.szName.decode()}:{k}" for d in _devices() for k in range(d.bControllers)
        ]
        return (
            f"channel {channel!r} is neither a bus nor DEVICE:N of an adapter of canemud "
            f"(buses: {', '.join(names) or 'none'}; controllers: {', '.join(adapters) or 'none'})"
        )

    def _init_line(self, bus, bitrate, data_bitrate, timing, listen_only):
        if timing is not None:
            nominal, data = _timing.from_python_can(timing, self._fd_controller)
            if data is None and self._fd_controller:
                # A can.BitTiming gives the nominal phase only (python-can before 4.2 has no
                # BitTimingFd): the data phase as without `timing`.
                rate = self._rate_of(nominal, True)
                data_rate = int(data_bitrate) if data_bitrate else bus.get("data_bitrate") or rate
                data = _timing.nominal_and_data(rate, data_rate, True, self._fd)[1]
        else:
            rate = int(bitrate) if bitrate else bus.get("bitrate", 500_000)
            data_rate = int(data_bitrate) if data_bitrate else bus.get("data_bitrate") or rate
            nominal, data = _timing.nominal_and_data(rate, data_rate, self._fd_controller,
                                                     self._fd)
        op_mode = _vci.CAN_OPMODE_STANDARD | _vci.CAN_OPMODE_EXTENDED | _vci.CAN_OPMODE_ERRFRAME
        if listen_only:
            op_mode |= _vci.CAN_OPMODE_LISTONLY
        ex_mode = _vci.CAN_EXMODE_DISABLED
        if self._fd:
            ex_mode = _vci.CAN_EXMODE_EXTDATA | _vci.CAN_EXMODE_FASTDATA
        _call(
            "canControlInitialize",
            self._control,
            op_mode,
            ex_mode,
            _vci.CAN_FILTER_PASS,
            _vci.CAN_FILTER_PASS,
            0,
            0,
            ctypes.byref(nominal),
            ctypes.byref(data) if data is not None else None,
        )
        _call("canControlStart", self._control, 1)

    @staticmethod
    def _rate_of(btp, fd_controller: bool) -> int:
        clock = _timing.FD_CLOCK_HZ if fd_controller else _timing.CLASSIC_CLOCK_HZ
        return clock // (btp.dwBPS * (1 + btp.wTS1 + btp.wTS2))

    # ---- receiving ----

    def fileno(self) -> int:
        """A descriptor that is readable whenever messages wait (for select, Notifier,
        asyncio)."""
        if self._poll_fd is None:
            fd = ctypes.c_int(-1)
            with _vci_errors():
                _call("canemuChannelEventFd", self._channel, ctypes.byref(fd))
            self._poll_fd = fd.value
        return self._poll_fd

    def _recv_internal(self, timeout: Optional[float]) -> Tuple[Optional[Message], bool]:
        deadline = None if timeout is None else time.monotonic() + max(timeout, 0.0)
        lib = _vci.lib()
        with self._rx_lock:
            while True:
                if self._pending:
                    return self._pending.popleft(), True
                if self._closed:
                    return None, True
                hr = lib.canChannelPeekMessage(self._channel, self._rx_ref)
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
                            return None, True
                        wait_ms = min(_WAIT_SLICE_MS, max(1, int(left * 1000 + 0.999)))
                    hr = lib.canChannelReadMessage(self._channel, wait_ms, self._rx_ref)
                    if hr == _vci.VCI_E_TIMEOUT:
                        continue
                if hr != _vci.VCI_OK:
                    raise _can_error(VciError("canChannelReadMessage", hr, _vci.error_text(hr)))
                msg, filtered = self._convert()
                if msg is not None:
                    return msg, filtered  # what it caused (self._pending) comes next

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

    def _convert(self) -> Tuple[Optional[Message], bool]:
        """The message in self._rx_msg as a python-can Message (None for those python-can has no
        use for). Error frames that the message also causes go to self._pending, after it."""
        ticks, _, ident, kind, flags2, flags, _ = _HEADER.unpack_from(self._rx_view)
        if kind == _vci.CAN_MSGTYPE_DATA:
            sim_ns = self._sim_ns(ticks)
            dlc = flags & _vci.FLAGS_DLC
            fd = bool(flags2 & _vci.FLAGS2_EDL)
            remote = bool(flags & _vci.FLAGS_RTR) and not fd
            length = _payload_length(flags, flags2)
            data = bytes(self._rx_view[16 : 16 + length])
            own = bool(flags & _vci.FLAGS_SRR)
            msg = Message(
                timestamp=sim_ns / 1e9 + self._time_offset,  # _stamp, inline: the hot path
                arbitration_id=ident,
                is_extended_id=bool(flags & _vci.FLAGS_EXT),
                is_remote_frame=remote,
                is_fd=fd,
                bitrate_switch=bool(flags2 & _vci.FLAGS2_FDR),
                error_state_indicator=bool(flags2 & _vci.FLAGS2_ESI),
                dlc=length if fd else dlc,
                data=data,
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
            msg = self._bus_error(sim_ns)
            # The counters as the error was detected (canemu's firmware writes REC and TEC
            # beyond the message's dlc, docs/vci.md): the crossing at its instant.
            counters = (self._rx_view[16 + 4], self._rx_view[16 + 3])
            if self._reported == _vci.CANEMU_STATE_WARNING:
                self._check_passive(sim_ns, counters)
            else:
                self._counters = counters
            return msg, True
        if kind == _vci.CAN_MSGTYPE_STATUS:
            sim_ns = self._sim_ns(ticks)
            msg = self._status_change(sim_ns, self._rx_view[16])
            if self._reported == _vci.CANEMU_STATE_WARNING:
                self._check_passive(sim_ns, self._counters)  # those of the last ERROR message
            elif self._reported == _vci.CANEMU_STATE_PASSIVE:
                self._check_passive(sim_ns)
            return msg, True
        if kind == _vci.CAN_MSGTYPE_TIMEOVR:
            self._wraps += 1
            self._last_ticks = 0
        return None, True

    def _error_frame(self, sim_ns: int, ident: int, data: bytes) -> Message:
        return Message(
            timestamp=self._stamp(sim_ns),
            arbitration_id=ident,
            is_error_frame=True,
            dlc=8,
            data=data,
            channel=self._channel_name,
        )

    def _bus_error(self, sim_ns: int) -> Optional[Message]:
        cls, prot, location = _BUS_ERRORS.get(self._rx_view[16], (CAN_ERR_PROT, 0, 0))
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
        at the warning limit), PASSIVE while error-passive, ERROR while bus-off. See
        :attr:`controller_state` for the four ISO 11898-1 states."""
        return _BUS_STATES[self._controller_state()[0]]

    @property
    def controller_state(self) -> "ControllerState":
        """ERROR_ACTIVE, ERROR_WARNING, ERROR_PASSIVE or BUS_OFF, from the controller."""
        return ControllerState(self._controller_state()[0])

    @state.setter
    def state(self, new_state: BusState) -> None:
        raise NotImplementedError("the state follows the controller; use listen_only=True")

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

    # ---- sending ----

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

    # ---- filters ----

    def _apply_filters(self, filters) -> None:
        """Filters in the channel where the VCI filter can express them: a format's one
        can_id/can_mask becomes the channel's acceptance filter for that format, several go
        into its ID list. A set that does not fit the list (many wide 29-bit patterns) leaves
        both formats open and python-can matches every filter in software (`_recv_internal`
        says which). What an earlier call set is gone afterwards."""
        if self._channel is None:
            self._hw_filtered = True
            return
        self._hw_filtered = False  # until the channel holds the new filters
        with _vci_errors(self._initializing):
            _call("canChannelActivate", self._channel, 0)
            try:
                fits = [self._set_channel_filter(filters, extended) for extended in (False, True)]
                if not all(fits):
                    for extended in (0, 1):
                        _call("canChannelRemFilterIds", self._channel, extended, 0, 0)
                        _call("canChannelSetFilterMode", self._channel, extended,
                              _vci.CAN_FILTER_PASS, None)
            finally:
                _call("canChannelActivate", self._channel, 1)
        self._hw_filtered = all(fits)

    def _set_channel_filter(self, filters, extended: bool) -> bool:
        """Sets the channel's filter of one format (the channel is inactive); False when the
        filters do not fit its ID list. VciError when a call fails."""
        h = self._channel
        ext = int(extended)
        # The ID list empties first (code 0, mask 0 selects every value): the IDs an earlier
        # call listed must not pass any more.
        _call("canChannelRemFilterIds", h, ext, 0, 0)
        if not filters:
            _call("canChannelSetFilterMode", h, ext, _vci.CAN_FILTER_PASS, None)
            return True
        width = 0x1FFFFFFF if extended else 0x7FF
        patterns = []
        for f in filters:
            if f.get("extended", extended) != extended:
                continue
            can_id, can_mask = f["can_id"], f["can_mask"]
            if can_id & can_mask & ~width:
                continue  # wants identifier bits this format does not have: none of its frames
            # Filter values are (ID << 1) | RTR; RTR is left free (python-can ignores it).
            patterns.append(((can_id & can_mask & width) << 1, (can_mask & width) << 1))
        if not patterns:
            _call("canChannelSetFilterMode", h, ext, _vci.CAN_FILTER_LOCK, None)
            return True
        _call("canChannelSetFilterMode", h, ext, _vci.CAN_FILTER_INCL, None)
        if len(patterns) == 1:
            _call("canChannelSetAccFilter", h, ext, patterns[0][0], patterns[0][1])
            return True
        _call("canChannelSetAccFilter", h, ext, 0x80000000, 0xFFFFFFFF)  # accept none
        for code, mask in patterns:
            hr = _vci.lib().canChannelAddFilterIds(h, ext, code, mask)
            if hr == _vci.VCI_E_OUTOFMEMORY:
                return False  # does not fit the list: software
            _vci.check("canChannelAddFilterIds", hr)
        return True

    # ---- cyclic transmission ----

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
                if autostart:
                    task.start()
                return task
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

    # ---- shutting down ----

    def _close_handles(self) -> None:
        lib = _vci.lib() if _vci._lib is not None else None
        if lib is None:
            return
        for name, attr in (
            ("canSchedulerClose", "_scheduler"),
            ("canChannelClose", "_channel"),
            ("canControlClose", "_control"),
            ("vciDeviceClose", "_device"),
        ):
            handle = getattr(self, attr, None)
            if handle is not None:
                getattr(lib, name)(handle)
                setattr(self, attr, None)
        if self._ephemeral is not None:
            lib.canemuRemoveDevice(self._ephemeral.encode())
            self._ephemeral = None

    def shutdown(self) -> None:
        if self._closed:
            return
        super().shutdown()  # stops the periodic tasks first
        self._closed = True
        with self._rx_lock, self._tx_lock:
            self._close_handles()

    @staticmethod
    def _detect_available_configs() -> List[Dict[str, Any]]:
        """Every CAN controller of canemud's adapters (``"DEVICE:N"``) and every CAN bus (a new
        adapter of its own), or nothing when canemud cannot be reached."""
        try:
            found_devices = devices()
            found_buses = buses()
        except (OSError, can.CanError):
            return []
        kinds = {b["name"]: b["kind"] for b in found_buses}
        configs: List[Dict[str, Any]] = []
        for d in found_devices:
            for k in range(d.bControllers):
                configs.append({
                    "interface": "canemu",
                    "channel": f"{d.szName.decode()}:{k}",
                    "fd": bool(d.abFd[k]),
                    "bus": d.aszBus[k].value.decode(),
                })
        for b in found_buses:
            if b["kind"] == "lin":
                continue
            configs.append({
                "interface": "canemu",
                "channel": b["name"],
                "fd": kinds[b["name"]] == "can-fd",
                "bitrate": b["bitrate"],
            })
        return configs


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
        with self._lock:
            if self._index is not None:
                return
            index = ctypes.c_uint32()
            entry = self._entry()
            with _vci_errors():
                _call("canSchedulerAddMessage", self._scheduler, ctypes.byref(entry),
                      ctypes.byref(index))
                _call("canSchedulerStartMessage", self._scheduler, index.value, self._repeat)
            self._index = index.value

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
