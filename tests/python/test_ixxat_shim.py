"""python-can's own ``ixxat`` interface, its unmodified source, on canemu's libvcinpl.so through
canemu.ixxat_shim (docs/python-ixxat.md).

canemud runs its embedded default configuration (config/default.toml: the adapter ixxat0 with
one SJA1000 on can0 and one on can1, 500 kbit/s) in stepped time, one daemon per test. The
ixxat bus is channel 0 of ixxat0; the other node is canemu's own python-can interface on can0.
Run under both venvs (.venv: python-can 4.6, .venv-debian: Debian's 4.1); where python-can 4.1
itself behaves differently, the test says so and checks what 4.1 does.
"""

from __future__ import annotations

import ctypes
import inspect
import json
import os
import re
import subprocess
import sys

import can
import pytest

import canemu
from canemu import ixxat_shim
from canemu.testing import Daemon
from conftest import CANEMU_CLI, CANEMUD, REPO, drain, fault_load, frames

MS = 1_000_000
VERSION = tuple(int(x) for x in can.__version__.split(".")[:2])


@pytest.fixture
def daemon():
    d = Daemon(None, canemud=str(CANEMUD), args=["--time", "stepped"])
    ixxat_shim.install()
    yield d
    d.stop()


@pytest.fixture
def ixxat(daemon):
    bus = can.Bus(interface="ixxat", channel=0, bitrate=500000)
    yield bus
    bus.shutdown()


@pytest.fixture
def other(daemon):
    """Another node on can0: canemu's own interface (an adapter of its own)."""
    bus = can.Bus(interface="canemu", channel="can0", receive_own_messages=True)
    drain(bus)
    yield bus
    bus.shutdown()


def backend():
    import can.interfaces.ixxat.canlib_vcinpl as vcinpl

    return vcinpl


def controller_state(bus) -> tuple:
    """(CANEMU_STATE_*, TEC, REC) of the ixxat bus's controller, asked of libvcinpl.so with
    canemu's extension canemuGetControllerState on the backend's own control handle."""
    lib = ctypes.CDLL(ixxat_shim.library_path())
    state, tec, rec, line = ctypes.c_uint8(), ctypes.c_uint16(), ctypes.c_uint16(), ctypes.c_uint8()
    hr = lib.canemuGetControllerState(
        bus.bus._control_handle, ctypes.byref(state), ctypes.byref(tec), ctypes.byref(rec),
        ctypes.byref(line),
    )
    assert ctypes.c_uint32(hr).value == 0
    return state.value, tec.value, rec.value


def us(seconds: float) -> int:
    return round(seconds * 1e6)


def test_install_loads_libvcinpl_into_the_unmodified_backend(daemon):
    vcinpl = backend()
    import can.interfaces.ixxat.canlib_vcinpl2 as vcinpl2

    assert ixxat_shim.installed()
    assert sys.platform == "linux"  # only swapped while the backend was imported
    # The backend is python-can's own file, beside the rest of python-can.
    assert vcinpl.__file__.startswith(str(can.__path__[0]))
    assert vcinpl._canlib._name == ixxat_shim.library_path("vcinpl.dll")
    assert vcinpl._canlib._name.endswith("/libvcinpl.so")
    assert vcinpl2._canlib._name.endswith("/libvcinpl2.so")
    # HRESULT read as 32 bits unsigned, BOOL passed as 32 bits.
    assert vcinpl._canlib.canControlStart.restype is ctypes.c_uint32
    assert vcinpl._canlib.canControlStart.argtypes[1] is ctypes.c_int32
    assert vcinpl2._canlib.canControlStart.restype is ctypes.c_uint32
    assert vcinpl2._canlib.canControlStart.argtypes[1] is ctypes.c_int32
    ixxat_shim.install()  # again: nothing changes
    assert backend()._canlib is vcinpl._canlib
    # An error comes back as python-can's exception with libvcinpl's text for the code.
    text = r"^function vciDeviceClose failed \(invalid handle\)$"
    with pytest.raises(vcinpl.VCIError, match=text):
        vcinpl._canlib.vciDeviceClose(vcinpl.HANDLE(0x1234))
    hwids = vcinpl.get_ixxat_hwids()
    assert len(hwids) == 1 and re.fullmatch(r"HW\d{6}", hwids[0])
    configs = can.detect_available_configs(["ixxat"])
    if VERSION >= (4, 6):
        # Channels 0 and 1 are ixxat0's two CAN controllers; channel 2 (its LIN controller)
        # does not open as a CAN channel, which ends python-can's probe.
        assert [(c["channel"], c["unique_hardware_id"]) for c in configs] == [
            (0, hwids[0]),
            (1, hwids[0]),
        ]
    else:
        assert configs == []  # python-can 4.1's ixxat backend has no detection


def clients(daemon) -> list:
    """This process's connections to `daemon`, as `canemu status` lists them."""
    status = json.loads(
        subprocess.run(
            [str(CANEMU_CLI), "--socket", daemon.socket, "status", "--json"],
            capture_output=True, text=True, timeout=30, check=True,
        ).stdout
    )
    return [(c["name"], c["channels"]) for c in status["client_list"] if c["pid"] == os.getpid()]


def test_libvcinpl_goes_to_canemus_daemon_with_the_first_ixxat_bus(daemon):
    """libvcinpl.so has a connection of its own (libvcinpl2.so's is canemu's interface's):
    it is made when the backend opens its first bus on the canemud of canemu.connect(), not
    before, so that a process without ixxat buses has none."""
    before = clients(daemon)
    assert len(before) == 1 and before[0][1] == 0
    bus = can.Bus(interface="ixxat", channel=0, bitrate=500000)
    try:
        assert clients(daemon) == before + [(before[0][0], 1)]  # the bus's channel
    finally:
        bus.shutdown()


def test_send_standard_and_extended(ixxat, other):
    ixxat.send(can.Message(arbitration_id=0x123, data=[0x11, 0x22, 0x33], is_extended_id=False))
    ixxat.send(
        can.Message(
            arbitration_id=0x1ABCDE0F,
            data=[0xDE, 0xAD, 0xBE, 0xEF, 0x00, 0x01, 0x02, 0x03],
            is_extended_id=True,
        )
    )
    canemu.step(1 * MS)
    got = drain(other)
    assert [(m.arbitration_id, m.is_extended_id, m.dlc, bytes(m.data)) for m in got] == [
        (0x123, False, 3, bytes([0x11, 0x22, 0x33])),
        (0x1ABCDE0F, True, 8, bytes([0xDE, 0xAD, 0xBE, 0xEF, 0x00, 0x01, 0x02, 0x03])),
    ]
    assert all(not m.is_error_frame and not m.is_remote_frame for m in got)
    assert ixxat.recv(0) is None  # no self reception asked for


def test_receive_standard_and_extended(ixxat, other):
    other.send(can.Message(arbitration_id=0x7FF, data=[0xA5], is_extended_id=False))
    other.send(
        can.Message(arbitration_id=0x18FF50E5, data=[1, 2, 3, 4, 5, 6], is_extended_id=True)
    )
    canemu.step(1 * MS)
    echoes = drain(other)
    assert [m.arbitration_id for m in echoes] == [0x7FF, 0x18FF50E5]
    first = ixxat.recv(1.0)
    second = ixxat.recv(1.0)
    assert (first.arbitration_id, first.is_extended_id, first.dlc, bytes(first.data)) == (
        0x7FF,
        False,
        1,
        bytes([0xA5]),
    )
    assert (second.arbitration_id, second.is_extended_id, second.dlc, bytes(second.data)) == (
        0x18FF50E5,
        True,
        6,
        bytes([1, 2, 3, 4, 5, 6]),
    )
    assert not first.is_remote_frame and not second.is_remote_frame
    assert first.channel == 0
    # The ixxat node's time stamps (libvcinpl's 1 µs ticks) are as far apart as the
    # sender's ends of transmission: the second frame's length on the wire plus intermission.
    assert us(second.timestamp - first.timestamp) == us(echoes[1].timestamp - echoes[0].timestamp)
    # The ticks count from the adapter's epoch, simulated time 0 here: python-can 4.1 gives
    # them as seconds, the instants the sender's echoes carry. python-can 4.6 adds an offset
    # it computes at the start (meant as the wall-clock instant of the start; its arithmetic
    # gives about 1.5 times that), which only shifts them.
    offset = getattr(ixxat.bus, "_timeoffset", 0.0)
    assert us(first.timestamp - offset) == us(echoes[0].timestamp)
    assert us(second.timestamp - offset) == us(echoes[1].timestamp)
    assert ixxat.recv(0) is None


def send_periodic(bus, msg, period, duration=None):
    """bus.send_periodic: the backend's cyclic list. On python-can 4.1 the backend's own bus
    object's (see test_send_periodic_of_python_can_4_1)."""
    if hasattr(bus, "_periodic_tasks"):
        return bus.send_periodic(msg, period, duration)
    return bus.bus.send_periodic(msg, period, duration)


def test_send_periodic_of_python_can_4_1(ixxat, other):
    """python-can 4.1's IXXATBus never runs BusABC.__init__ (python-can issue #1285, fixed
    later; 4.6 has the fix): its send_periodic starts the backend's cyclic entry, then fails
    on the missing task list, so the entry runs without a task to stop it (shutdown() ends
    it). Its backend bus object (`bus.bus`) has the list and works; 4.6 keeps the task."""
    msg = can.Message(arbitration_id=0x0C0, data=[0xC0], is_extended_id=False)
    assert hasattr(ixxat, "_periodic_tasks") == (VERSION >= (4, 6))
    if VERSION >= (4, 6):
        task = ixxat.send_periodic(msg, 0.010)
        assert ixxat._periodic_tasks == [task]
        task.stop()
        assert ixxat._periodic_tasks == []
        canemu.step(30 * MS)
        assert drain(other) == []
        return
    with pytest.raises(AttributeError, match="_periodic_tasks"):
        ixxat.send_periodic(msg, 0.010)
    canemu.step(30 * MS)
    assert [us(m.timestamp) for m in drain(other)] == [10_110, 20_110]


def test_send_periodic_uses_the_cyclic_list(ixxat, other):
    vcinpl = backend()
    msg = can.Message(arbitration_id=0x0C1, data=[0xC1, 0x01], is_extended_id=False)
    task = send_periodic(ixxat, msg, 0.010)
    assert isinstance(task, vcinpl.CyclicSendTask)  # the hardware list, not a thread
    assert ixxat.bus._scheduler_resolution == 1000.0  # 1 ms ticks: wCycleTime 10
    canemu.step(100 * MS)
    got = drain(other)
    # The list sends one cycle after the start (simulated time 0): at 10, 20, ... 90 ms; the
    # 100 ms one is still on the wire. Each time stamp is the frame's end: 128 µs later.
    assert len(got) == 9
    assert us(got[0].timestamp) == 10_128
    assert all(bytes(m.data) == bytes([0xC1, 0x01]) for m in got)
    assert {us(b.timestamp - a.timestamp) for a, b in zip(got, got[1:])} == {10_000}
    task.stop()  # removes the entry; the frame on the wire is finished, no other follows
    canemu.step(50 * MS)
    assert [us(m.timestamp) for m in drain(other)] == [100_128]


def test_send_periodic_with_duration_sends_a_counted_burst(ixxat, other):
    msg = can.Message(arbitration_id=0x1000C2, data=[0xC2], is_extended_id=True)
    send_periodic(ixxat, msg, 0.005, duration=0.025)
    canemu.step(200 * MS)
    got = drain(other)
    assert [(m.arbitration_id, m.is_extended_id) for m in got] == [(0x1000C2, True)] * 5
    assert {us(b.timestamp - a.timestamp) for a, b in zip(got, got[1:])} == {5_000}


def bit_errors(daemon, count: int) -> None:
    """A scenario: the next `count` frames sent by ixxat0:0 on can0 meet a bit error."""
    done = fault_load(
        daemon,
        f"""
[scenario]
name = "ixxat shim errors"

[[fault]]
at = "0s"
bus = "can0"
match = {{ from = "ixxat0:0" }}
effect = "bit_error"
count = {count}
""",
    )
    assert done.returncode == 0, done.stderr


def test_bus_state_active(ixxat, other):
    assert ixxat.state == can.BusState.ACTIVE
    assert controller_state(ixxat) == (canemu.ControllerState.ERROR_ACTIVE, 0, 0)


def test_error_passive_is_not_a_bus_state_but_recv_reports_the_warning_limit(daemon, ixxat, other):
    vcinpl = backend()
    bit_errors(daemon, 17)
    ixxat.send(can.Message(arbitration_id=0x0E1, data=[0xE1], is_extended_id=False))
    canemu.step(20 * MS)
    # 17 bit errors (TEC 17 x 8 = 136), then the frame went through (TEC 135): error-passive.
    assert controller_state(ixxat) == (canemu.ControllerState.ERROR_PASSIVE, 135, 0)
    assert [m.arbitration_id for m in frames(drain(other))] == [0x0E1]
    # python-can's ixxat backend maps only bus-off and bus-coupling errors to ERROR (and
    # listen-only to PASSIVE): an error-passive controller is ACTIVE to it...
    assert ixxat.state == can.BusState.ACTIVE
    # ... and a read that brings no data frame raises for the warning limit in the status.
    with pytest.raises(vcinpl.VCIError, match="Error warning limit exceeded"):
        ixxat.recv(0)


def test_bus_off(daemon, ixxat, other):
    vcinpl = backend()
    bit_errors(daemon, 32)
    ixxat.send(can.Message(arbitration_id=0x0F1, data=[0xF1], is_extended_id=False))
    canemu.step(20 * MS)
    assert controller_state(ixxat)[:2] == (canemu.ControllerState.BUS_OFF, 256)
    canemu.step(50 * MS)  # python-can never restarts the controller: it stays bus-off
    assert controller_state(ixxat)[0] == canemu.ControllerState.BUS_OFF
    assert frames(drain(other)) == []  # the other node saw the 32 bit errors, no frame
    assert ixxat.state == can.BusState.ERROR
    with pytest.raises(vcinpl.VCIError, match="Error warning limit exceeded"):
        ixxat.recv(0)


def low_speed_default_config() -> str:
    """The default configuration with can1 made a fault-tolerant low-speed bus at 125 kbit/s
    (the only change): the line_error fault needs a low-speed transceiver."""
    text = (REPO / "config" / "default.toml").read_text()
    can1 = 'name = "can1"\nkind = "can"\nbitrate = 500000\n'
    assert can1 in text
    text = text.replace(can1, 'name = "can1"\nkind = "can"\nbitrate = 125000\n'
                        'transceiver = "low-speed"\n')
    return text.replace('time = "realtime"', 'time = "stepped"')


@pytest.fixture
def low_speed_daemon():
    d = Daemon(low_speed_default_config(), canemud=str(CANEMUD))
    ixxat_shim.install()
    yield d
    d.stop()


def test_bus_coupling_error(low_speed_daemon):
    """A wire fault at ixxat0:1's low-speed transceiver: CAN_STATUS_BUSCERR in the line
    status while it lasts. python-can 4.6 reports ERROR; python-can 4.1 raises the enum member
    instead of returning it (`raise BusState.ERROR`: a TypeError), the one path where its
    state differs."""
    d = low_speed_daemon
    vcinpl = backend()
    bus = can.Bus(interface="ixxat", channel=1, bitrate=125000)
    try:
        assert bus.state == can.BusState.ACTIVE
        done = fault_load(
            d,
            """
[[fault]]
at = "1ms"
until = "10ms"
node = "ixxat0:1"
effect = "line_error"
""",
        )
        assert done.returncode == 0, done.stderr
        canemu.step(2 * MS)
        if "raise BusState.ERROR" in inspect.getsource(vcinpl.IXXATBus.state.fget):
            with pytest.raises(TypeError, match="exceptions must derive from BaseException"):
                bus.state
        else:
            assert bus.state == can.BusState.ERROR
        with pytest.raises(vcinpl.VCIError, match="Bus coupling error"):
            bus.recv(0)
        canemu.step(10 * MS)  # the wire is back at 10 ms
        assert bus.state == can.BusState.ACTIVE
    finally:
        bus.shutdown()
