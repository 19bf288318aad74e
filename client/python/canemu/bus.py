"""python-can interface for canemu: `can.Bus(interface="canemu", channel=...)`.

Every bus object is a program on an emulated IXXAT adapter, driven through canemu's VCI C API
(libvcinpl2.so): a channel on one of the adapter's CAN controllers, and the controller's control
unit when nobody else holds it. See docs/python.md.

This module opens and closes the bus; the bus's other jobs are mixins in modules of their own:
receiving (_receive), error state and error frames (_state), sending (_send), filters
(_filters), the cyclic list (_cyclic); canemud as a whole (connect, step, sim_time, buses,
devices) is _daemon. Every public name stays importable from here.
"""

from __future__ import annotations

import ctypes
import logging
import threading
from collections import deque
from typing import Any, Deque, Dict, List, Optional, Union

import can
from can import BusABC, Message

from . import _timing, _vci, _xcan, xcan_bus
from ._calls import CanTimeoutError, _call, _can_error  # noqa: F401 (importable from here)
from ._cyclic import CanemuCyclicTask, _CyclicMixin
from ._daemon import _buses, _devices, _wall_offset, buses, connect, devices, sim_time, step
from ._daemon import current_socket as _current_socket
from ._filters import _FilterMixin
from ._receive import _RX_BATCH, _ReceiveMixin
from ._send import _SendMixin
from ._state import (  # noqa: F401 (SocketCAN's error frame constants, importable from here)
    CAN_ERR_ACK,
    CAN_ERR_BUSERROR,
    CAN_ERR_BUSOFF,
    CAN_ERR_CNT,
    CAN_ERR_CRTL,
    CAN_ERR_CRTL_ACTIVE,
    CAN_ERR_CRTL_RX_PASSIVE,
    CAN_ERR_CRTL_RX_WARNING,
    CAN_ERR_CRTL_TX_PASSIVE,
    CAN_ERR_CRTL_TX_WARNING,
    CAN_ERR_PROT,
    CAN_ERR_PROT_BIT,
    CAN_ERR_PROT_FORM,
    CAN_ERR_PROT_LOC_ACK,
    CAN_ERR_PROT_LOC_CRC_SEQ,
    CAN_ERR_PROT_STUFF,
    CAN_ERR_RESTARTED,
    CAN_ERR_TRX,
    ControllerState,
)
from ._vci import VciError
from .xcan_bus import XcanBus

log = logging.getLogger("can.canemu")

try:  # python-can 4.3 and later
    from can import CanProtocol
except ImportError:  # pragma: no cover - python-can 4.1 and 4.2
    CanProtocol = None

_FILTER_LIST_SIZE = 2048  # 29-bit ID list of each channel


def _fifo_capacity(requested: int) -> int:
    """The messages a channel's FIFO of `requested` CANMSG2 holds: a ring of a 256-byte header
    and the messages, rounded up to whole 4 KiB pages (docs/vci.md), at most 65535."""
    size, page, header = ctypes.sizeof(_vci.CANMSG2), 4096, 256
    pages = -(-(header + requested * size) // page)
    return min((pages * page - header) // size, 65535)


def _is_xcan_channel(channel: Any, socket: Optional[str]) -> bool:
    """Whether `channel` ("DEVICE:N") names an interface of an X-CAN-2i rather than an IXXAT
    adapter's controller. Only asked of canemud when no VCI adapter has that name."""
    device, _, number = str(channel).rpartition(":")
    if not device or not number.isdigit():
        return False
    try:
        if socket is not None:
            connect(socket)
        info = _vci.CANEMU_DEVICEINFO()
        if _vci.lib().canemuFindDevice(device.encode(), ctypes.byref(info)) == _vci.VCI_OK:
            return False
        _xcan.use_socket(_current_socket())
        return xcan_bus.is_module(str(channel))
    except (OSError, can.CanError, _xcan.XcanError):
        return False  # the VCI path reports it


def _controller_names(info, lin: bool) -> List[str]:
    """An adapter's CAN (or LIN) controllers as "ixxat0:1 on can1"."""
    name = info.szName.decode()
    return [
        f"{name}:{k} on {info.aszBus[k].value.decode()}"
        for k in range(info.bControllers)
        if (info.abFd[k] == _vci.CANEMU_LIN_CONTROLLER) == lin
    ]


def _and(items: List[str]) -> str:
    """"a", "a and b", "a, b and c"."""
    return " and ".join(items) if len(items) < 3 else ", ".join(items[:-1]) + " and " + items[-1]


def _controllers_of(info) -> str:
    """What an adapter has: "adapter ixxat0 has 2 CAN controllers, ixxat0:0 on can0 and
    ixxat0:1 on can1, and 1 LIN controller, ixxat0:2 on lin0"."""
    can_ones = _controller_names(info, lin=False)
    lin_ones = _controller_names(info, lin=True)

    def counted(items: List[str], kind: str) -> str:
        return f"{len(items)} {kind} controller{'s' if len(items) != 1 else ''}" + (
            f", {_and(items)}" if items else "")

    text = f"adapter {info.szName.decode()} has {counted(can_ones, 'CAN')}"
    if lin_ones:
        text += f", and {counted(lin_ones, 'LIN')}"
    return text


class CanemuBus(_ReceiveMixin, _SendMixin, _FilterMixin, _CyclicMixin, BusABC):
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

    def __new__(cls, *args: Any, **kwargs: Any):
        """A channel "DEVICE:N" of a SORCUS X-CAN-2i makes an XcanBus (xcan_bus.py) instead."""
        if cls is CanemuBus:
            channel = args[0] if args else kwargs.get("channel")
            if _is_xcan_channel(channel, kwargs.get("socket")):
                return XcanBus(*args, **kwargs)
        return super().__new__(cls)

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
        self._channel_arg = ctypes.c_void_p()  # _channel as send's hot path passes it (_open)
        self._post = None
        self._poster = None  # canemu_speedups.ClassicPoster, when there is one (_open)
        self._fast_post = None  # its post(msg): True when msg went into the FIFO
        self._scheduler = None
        self._ephemeral: Optional[str] = None
        self._channel_name = channel
        self._poll_fd: Optional[int] = None
        self._closed = False
        self._receive_own = bool(receive_own_messages)
        # bFlags's bits of every frame send's hot path posts: self-reception, and with it the
        # extended identifier's.
        self._tx_flags = _vci.FLAGS_SRR if self._receive_own else 0
        self._tx_flags_ext = self._tx_flags | _vci.FLAGS_EXT
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
        # Messages are taken from the receive ring up to _RX_BATCH at a time (one call for
        # them all), the data frames among them converted in one pass into _rx_ready and
        # handed out one per recv; fileno() turns the batches off (batch of 1), so that a
        # descriptor that is not readable always means that nothing waits (_receive.py).
        # The batch's messages are a bytearray's bytes, which the library writes through a
        # ctypes array on them and _convert_run slices the data of Messages from.
        self._rx_bytes = bytearray(_RX_BATCH * ctypes.sizeof(_vci.CANMSG2))
        self._rx_batch = (_vci.CANMSG2 * _RX_BATCH).from_buffer(self._rx_bytes)
        self._rx_batch_view = memoryview(self._rx_bytes)
        self._rx_batch_max = _RX_BATCH
        self._rx_taken = ctypes.c_uint32()
        self._rx_taken_ref = ctypes.byref(self._rx_taken)
        self._rx_count = 0  # messages in the batch
        self._rx_next = 0  # the next one to convert
        self._rx_ready: Deque[Message] = deque()  # converted, not yet returned (_convert_run)
        self._tx_msg = _vci.CANMSG2()
        self._tx_view = memoryview(self._tx_msg).cast("B")
        self._tx_ref = ctypes.byref(self._tx_msg)
        self._sched_lock = threading.Lock()
        self._listen_only = bool(listen_only)
        self._tx_flushed = False
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
            hr = _vci.lib().canemuFindDevice(device.encode(), ctypes.byref(info))
            if hr == _vci.VCI_E_NO_MORE_ITEMS:
                raise ValueError(f"channel {channel!r}: canemud has no adapter {device} "
                                 f"({self._what_exists()})")
            _vci.check("canemuFindDevice", hr)
        else:
            controller = 0
            found = self._find_bus(channel)
            if not found:
                raise ValueError(self._unknown_channel(channel))
            if found.get("kind") == "lin":  # before canemud makes a LIN adapter for nothing
                raise ValueError(f"channel {channel!r} is on the LIN bus {channel}")
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
            raise ValueError(f"channel {channel!r}: {_controllers_of(info)}")
        if info.abFd[controller] == _vci.CANEMU_LIN_CONTROLLER:
            raise ValueError(
                f"channel {channel!r} is the LIN controller of {info.szName.decode()} on "
                f"{info.aszBus[controller].value.decode()} (canemu.lin's Commander and "
                f"Responder open it); its CAN controllers are "
                f"{_and(_controller_names(info, lin=False)) or 'none'}")
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
        # The line's rates as the bus runs them (what this bus sets when it holds the control
        # unit): the drain at shutdown reckons with them.
        self._bitrate = bus.get("bitrate") or 500_000
        self._data_bitrate = bus.get("data_bitrate") or self._bitrate
        self._tx_capacity = _fifo_capacity(tx_size)
        if CanProtocol is not None:
            self._can_protocol = CanProtocol.CAN_FD if fd else CanProtocol.CAN_20

        handle = _vci.HANDLE()
        _call("vciDeviceOpen", ctypes.byref(info.VciObjectId), ctypes.byref(handle))
        self._device = handle.value

        handle = _vci.HANDLE()
        _call("canChannelOpen", self._device, controller, 0, ctypes.byref(handle))
        self._channel = handle.value
        # canChannelPostMessage for send's hot path: without argtypes ctypes converts nothing
        # (about 0.1 us a call), so the handle goes as a ready c_void_p; it never waits, so the
        # call keeps the GIL.
        self._post = _vci.unconverted("canChannelPostMessage", keep_gil=True)
        self._channel_arg = ctypes.c_void_p(self._channel)
        # The same in C, when canemu_speedups is there: send() tries it first.
        speedups = _vci.speedups()
        if speedups is not None:
            self._poster = speedups.ClassicPoster(_vci.address_of("canChannelPostMessage"),
                                                  self._channel, self._tx_flags,
                                                  self._tx_flags_ext)
            self._fast_post = self._poster.post
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
        return (f"channel {channel!r} is neither a bus nor DEVICE:N of an adapter of canemud "
                f"({self._what_exists()})")

    def _what_exists(self) -> str:
        """canemud's buses and the CAN controllers of its adapters, with their buses."""
        names = [b["name"] for b in _buses()]
        controllers = [c for d in _devices() for c in _controller_names(d, lin=False)]
        return (f"buses: {', '.join(names) or 'none'}; "
                f"CAN controllers: {', '.join(controllers) or 'none'}")

    def _init_line(self, bus, bitrate, data_bitrate, timing, listen_only):
        # The controller's clock and timing ranges, as the library reports them.
        caps = _vci.CANCAPABILITIES2()
        _call("canControlGetCaps", self._control, ctypes.byref(caps))
        limits = _timing.Limits.of(caps)
        if timing is not None:
            nominal, data = _timing.from_python_can(timing, limits)
            if data is None and limits.fd:
                # A can.BitTiming gives the nominal phase only (python-can before 4.2 has no
                # BitTimingFd): the data phase as without `timing`.
                rate = limits.bitrate(nominal)
                data_rate = int(data_bitrate) if data_bitrate else bus.get("data_bitrate") or rate
                data = _timing.nominal_and_data(rate, data_rate, limits, self._fd)[1]
        else:
            rate = int(bitrate) if bitrate else bus.get("bitrate", 500_000)
            data_rate = int(data_bitrate) if data_bitrate else bus.get("data_bitrate") or rate
            nominal, data = _timing.nominal_and_data(rate, data_rate, limits, self._fd)
        self._nominal, self._data = nominal, data
        self._bitrate = limits.bitrate(nominal)
        if data is not None:
            self._data_bitrate = limits.bitrate(data)
        self._start_line(listen_only)

    def _start_line(self, listen_only: bool) -> None:
        """(Re)initializes the line with the bit timing chosen at opening, listen-only or not,
        and starts it. The controller is reset: error counters 0, error-active."""
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
            ctypes.byref(self._nominal),
            ctypes.byref(self._data) if self._data is not None else None,
        )
        _call("canControlStart", self._control, 1)
        self._listen_only = listen_only

    # ---- shutting down ----

    def _close_handles(self) -> None:
        lib = _vci.lib() if _vci._lib is not None else None
        if lib is None:
            return
        if self._poster is not None:  # no post from C once the channel closes
            self._poster.close()
            self._poster = self._fast_post = None
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
        self._channel_arg = ctypes.c_void_p()
        if self._ephemeral is not None:
            lib.canemuRemoveDevice(self._ephemeral.encode())
            self._ephemeral = None

    def flush_tx_buffer(self) -> None:
        """Gives up the frames queued so far: ``shutdown()`` then closes without waiting for
        them (a ``send`` afterwards makes it wait again). The VCI has no call that empties a
        running channel's transmit FIFO, so until then they may still go out."""
        self._tx_flushed = True

    def shutdown(self) -> None:
        """Stops the periodic tasks, lets the transmit FIFO drain (see _SendMixin._drain_tx:
        bounded by the time its frames need on the bus; frames left are named in a warning on
        the "can.canemu" logger), closes the channel and control unit and removes the adapter
        this bus made. ``flush_tx_buffer()`` before it discards the queued frames instead."""
        if self._closed:
            return
        super().shutdown()  # stops the periodic tasks first
        try:
            if self._channel is not None and not self._tx_flushed:
                try:
                    left, why = self._drain_tx()
                except VciError as e:  # canemud gone: nothing can be sent any more
                    left, why = 0, ""
                    log.warning("%s: shutdown could not drain the transmit FIFO: %s",
                                self.channel_info, e)
                if left:
                    log.warning("%s: shutdown discards %d frame(s) not sent: %s",
                                self.channel_info, left, why)
        finally:  # also when Ctrl-C ends the wait
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
                if d.abFd[k] == _vci.CANEMU_LIN_CONTROLLER:
                    continue  # a LIN controller: python-can has no LIN
                configs.append({
                    "interface": "canemu",
                    "channel": f"{d.szName.decode()}:{k}",
                    "fd": bool(d.abFd[k]),
                    "bus": d.aszBus[k].value.decode(),
                })
        try:
            configs.extend(xcan_bus.available_configs())
        except (OSError, _xcan.XcanError):
            pass  # no libxcan.so, or canemud went meanwhile
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
