"""python-can's own ``ixxat`` interface with ``fd=True`` (its ``canlib_vcinpl2`` module, unmodified)
on canemu's libvcinpl2.so through canemu.ixxat_shim: python-can gives its default timing presets
as bit/s CANBTPs whose segments are weights of a bit ({500000, 6400, 1600, 1600} nominal,
{2000000, 1600, 400, 400, TDO 1600} data), which the emulated CAN FD controller takes as the
nearest timing it has (docs/vci.md, "Bit timing in bit/s form"). Issue 34.

canemud runs in stepped time with one CAN FD adapter (the ixxat bus, channel 0 of the first
adapter python-can finds) on fd0 at 500 kbit/s / 2 Mbit/s; the other node is canemu's own
python-can interface on fd0.
"""

from __future__ import annotations

import ctypes

import can
import pytest

import canemu
from canemu import ixxat_shim
from canemu.testing import Daemon
from conftest import CAN0, CANEMUD, FD0, device, drain, table, toml

MS = 1_000_000

CONFIG = toml(table("[simulation]", time="stepped", seed=1), FD0,
              device("ixxatfd", "ixxat-usb-to-can-fd", ["fd0"]))


@pytest.fixture
def daemon():
    d = Daemon(CONFIG, canemud=str(CANEMUD))
    ixxat_shim.install()
    yield d
    d.stop()


@pytest.fixture
def ixxat(daemon):
    bus = can.Bus(interface="ixxat", channel=0, fd=True, bitrate=500000, data_bitrate=2000000)
    yield bus
    bus.shutdown()


@pytest.fixture
def other(daemon):
    """Another node on fd0: canemu's own interface (an adapter of its own)."""
    bus = can.Bus(interface="canemu", channel="fd0", fd=True, receive_own_messages=True)
    drain(bus)
    yield bus
    bus.shutdown()


class CANBTP(ctypes.Structure):
    _fields_ = [("dwMode", ctypes.c_uint32), ("dwBPS", ctypes.c_uint32),
                ("wTS1", ctypes.c_uint16), ("wTS2", ctypes.c_uint16),
                ("wSJW", ctypes.c_uint16), ("wTDO", ctypes.c_uint16)]


class CANLINESTATUS2(ctypes.Structure):
    """cantype.h's (python-can's own declares the two CANBTPs as bytes, 16 bytes long)."""

    _pack_ = 1
    _fields_ = [("bOpMode", ctypes.c_uint8), ("bExMode", ctypes.c_uint8),
                ("bBusLoad", ctypes.c_uint8), ("bReserved", ctypes.c_uint8),
                ("sBtpSdr", CANBTP), ("sBtpFdr", CANBTP), ("dwStatus", ctypes.c_uint32)]


def line_status(bus):
    """The CANLINESTATUS2 of the ixxat bus's controller, asked of libvcinpl2.so on the
    backend's own control handle."""
    backend = getattr(bus, "bus", bus)  # python-can 4.6 wraps the module's bus
    lib = ctypes.CDLL(ixxat_shim.library_path("vcinpl2.dll"))
    status = CANLINESTATUS2()
    assert ctypes.sizeof(status) == 40
    hr = lib.canControlGetStatus(backend._control_handle, ctypes.byref(status))
    assert ctypes.c_uint32(hr).value == 0
    return status


def btp(b) -> tuple:
    return (b.dwMode, b.dwBPS, b.wTS1, b.wTS2, b.wSJW, b.wTDO)


def test_the_default_fd_presets_open_a_bus_and_show_the_timing_taken(daemon, ixxat):
    s = line_status(ixxat)
    # Nominal {500000, 6400, 1600, 1600}: 160 quanta of one 80 MHz clock, 80 %, SJW 32.
    assert btp(s.sBtpSdr) == (0, 500000, 128, 32, 32, 0)
    # Data {2000000, 1600, 400, 400, TDO 1600}: 40 quanta, 80 %, SJW 8, TDO 32.
    assert btp(s.sBtpFdr) == (0, 2000000, 32, 8, 8, 32)
    # canemud says what it took.
    assert daemon.wait_log("VCI ixxatfd CAN 0: nominal (sSdr) CANBTP").endswith(
        "VCI ixxatfd CAN 0: nominal (sSdr) CANBTP {dwBPS=500000, wTS1=6400, wTS2=1600, "
        "wSJW=1600, wTDO=0} taken as 500000 bit/s from the 80000000 Hz clock: prescaler 1, "
        "160 quanta (TS1 128 with the sync quantum, TS2 32), SJW 32, sample point 80.0 %"
    )
    assert daemon.wait_log("VCI ixxatfd CAN 0: data (sFdr) CANBTP").endswith(
        "VCI ixxatfd CAN 0: data (sFdr) CANBTP {dwBPS=2000000, wTS1=1600, wTS2=400, wSJW=400, "
        "wTDO=1600} taken as 2000000 bit/s from the 80000000 Hz clock: prescaler 1, 40 quanta "
        "(TS1 32 with the sync quantum, TS2 8), SJW 8, TDO 32, sample point 80.0 %"
    )
    # A timing still refused (VCI_E_INVALIDARG) says why in the log.
    from can.interfaces.ixxat import constants  # once the shim made the backend importable

    backend = getattr(ixxat, "bus", ixxat)
    lib = ctypes.CDLL(ixxat_shim.library_path("vcinpl2.dll"))
    slow = CANBTP(0, 100, 14, 2, 1, 0)
    data = CANBTP(0, 2000000, 1600, 400, 400, 1600)
    hr = lib.canControlInitialize(backend._control_handle, 1, 3, 2, 2, 0, 0,
                                  ctypes.byref(slow), ctypes.byref(data))
    assert ctypes.c_uint32(hr).value == constants.VCI_E_INVALIDARG
    assert daemon.wait_log("InitLine refused").endswith(
        "VCI ixxatfd CAN 0: InitLine refused (VCI_E_INVALIDARG): nominal (sSdr) CANBTP "
        "{dwBPS=100, wTS1=14, wTS2=2}: the 80000000 Hz controller clock gives 202.922 bit/s at "
        "best (prescaler 1024, 385 quanta), 102.922 % off; more than 0.5 % is refused"
    )


def test_fd_frames_with_bit_rate_switch_both_ways(ixxat, other):
    payload = bytes(range(48))
    ixxat.send(
        can.Message(arbitration_id=0x123, data=payload, is_fd=True, bitrate_switch=True,
                    is_extended_id=False)
    )
    canemu.step(1 * MS)
    got = [m for m in drain(other) if not m.is_error_frame]
    assert [(m.arbitration_id, m.is_fd, m.bitrate_switch, bytes(m.data)) for m in got] == [
        (0x123, True, True, payload)
    ]
    other.send(
        can.Message(arbitration_id=0x1ABCDE0F, data=payload[:12], is_fd=True,
                    bitrate_switch=True, is_extended_id=True)
    )
    canemu.step(1 * MS)
    echo = [m for m in drain(other) if not m.is_error_frame]
    assert [m.arbitration_id for m in echo] == [0x1ABCDE0F]
    back = ixxat.recv(1.0)
    assert back is not None
    assert (back.arbitration_id, back.is_extended_id, back.is_fd, back.bitrate_switch,
            bytes(back.data)) == (0x1ABCDE0F, True, True, True, payload[:12])
    # Nothing else: no error frames (both nodes run the same rates).
    assert ixxat.recv(0) is None


CLASSIC = toml(table("[simulation]", time="stepped", seed=1), CAN0,
               device("ixxat0", "ixxat-usb-to-can", ["can0"]))


def test_fd_frames_on_a_classic_adapter_are_refused_not_lost():
    """fd=True on an SJA1000 adapter: the bus opens (the backend sees no FD capability and asks
    for no FD mode), classic frames go out, and an FD frame is refused by send() with the
    reason instead of vanishing in the firmware."""
    d = Daemon(CLASSIC, canemud=str(CANEMUD))
    ixxat_shim.install()
    try:
        bus = can.Bus(interface="ixxat", channel=0, fd=True, bitrate=500000,
                      data_bitrate=2000000)
        other = can.Bus(interface="canemu", channel="can0")
        try:
            drain(other)
            with pytest.raises(can.CanOperationError,
                               match="a CAN FD message \\(id 0x123, edl = 1, fdr = 1\\) on a "
                                     "controller without CAN FD"):
                bus.send(can.Message(arbitration_id=0x123, data=bytes(12), is_fd=True,
                                     bitrate_switch=True, is_extended_id=False))
            bus.send(can.Message(arbitration_id=0x124, data=b"\x01", is_extended_id=False))
            canemu.step(1 * MS)
            got = [m for m in drain(other) if not m.is_error_frame]
            assert [(m.arbitration_id, m.is_fd, bytes(m.data)) for m in got] == [
                (0x124, False, b"\x01")]
        finally:
            other.shutdown()
            bus.shutdown()
    finally:
        d.stop()
