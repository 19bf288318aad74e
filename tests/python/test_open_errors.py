"""What a python-can program is told when its bus cannot be opened, through canemu's interface
(`interface="canemu"`) and through python-can's own `interface="ixxat"` on canemu's libvcinpl.so:
a controller the adapter does not have names the CAN controllers it has; an adapter that is not
there names the adapters that are; no canemud gives a short message naming the socket tried and
how to start canemud (docs/python.md).

canemud runs its embedded default configuration: the adapter ixxat0 with an SJA1000 on can0 and
one on can1, and a LIN controller (ixxat0:2) on lin0.
"""

from __future__ import annotations

import os
import subprocess
import sys

import can
import pytest

import canemu
from canemu import _vci, ixxat_shim
from canemu.testing import Daemon
from conftest import CANEMUD, REPO


@pytest.fixture(scope="module")
def daemon():
    d = Daemon(None, canemud=str(CANEMUD), args=["--time", "stepped"])
    yield d
    d.stop()


def opening_error(**kwargs) -> str:
    with pytest.raises(can.CanError) as e:
        can.Bus(**kwargs).shutdown()
    return str(e.value)


# A channel that is not there, or not a CAN controller, names what is: a controller the adapter
# lacks or its LIN controller names its CAN controllers; an adapter or a bus that is not there
# names the buses and the CAN controllers that are.
CHANNELS_NOT_THERE = {
    "ixxat0:5": "channel 'ixxat0:5': adapter ixxat0 has 2 CAN controllers, ixxat0:0 on can0 and "
                "ixxat0:1 on can1, and 1 LIN controller, ixxat0:2 on lin0",
    "ixxat0:2": "channel 'ixxat0:2' is the LIN controller of ixxat0 on lin0 (canemu.lin's "
                "Commander and Responder open it); its CAN controllers are ixxat0:0 on can0 and "
                "ixxat0:1 on can1",
    "ixxat9:0": "channel 'ixxat9:0': canemud has no adapter ixxat9 (buses: can0, can1, lin0; "
                "CAN controllers: ixxat0:0 on can0, ixxat0:1 on can1)",
    "can9": "channel 'can9' is neither a bus nor DEVICE:N of an adapter of canemud (buses: can0, "
            "can1, lin0; CAN controllers: ixxat0:0 on can0, ixxat0:1 on can1)",
}


@pytest.mark.parametrize("channel", CHANNELS_NOT_THERE)
def test_a_channel_that_is_not_there_names_what_is(daemon, channel):
    assert opening_error(interface="canemu", channel=channel) == CHANNELS_NOT_THERE[channel]


def test_no_daemon_is_a_short_message_naming_the_socket(daemon):
    missing = daemon.dir + "/nobody.sock"
    try:
        with pytest.raises(can.CanInitializationError) as e:
            can.Bus(interface="canemu", channel="can0", socket=missing)
    finally:
        canemu.connect(daemon.socket)
    assert str(e.value) == (
        f"canemud is not running at {missing}: start it with 'systemctl start canemud' or "
        f"'canemud --socket {missing}', or set CANEMU_SOCKET to the socket it listens on"
    )
    assert e.value.error_code == _vci.VCI_E_DISCONNECTED


def test_python_cans_ixxat_interface_names_the_can_controllers(daemon):
    ixxat_shim.install()
    for channel, says in (
        (5, "ixxat0 has no controller 5; its CAN controllers are 0 (can0) and 1 (can1), "
            "2 is its LIN controller (lin0)"),
        (2, "controller 2 of ixxat0 is its LIN controller (lin0); its CAN controllers are "
            "0 (can0) and 1 (can1)"),
    ):
        text = opening_error(interface="ixxat", channel=channel, bitrate=500000)
        assert text == ("Could not open and initialize channel: function canChannelOpen failed "
                        f"(invalid argument ({says}))"), text
    # The reason is that call's: the next failure does not carry it.
    import can.interfaces.ixxat.canlib_vcinpl as vcinpl

    closing = r"^function vciDeviceClose failed \(invalid handle\)$"
    with pytest.raises(vcinpl.VCIError, match=closing):
        vcinpl._canlib.vciDeviceClose(vcinpl.HANDLE(0x1234))


def test_python_cans_ixxat_interface_without_daemon_names_the_socket(daemon):
    """In a process of its own: the shim's library then has never talked to a canemud."""
    missing = daemon.dir + "/nobody.sock"
    program = (
        "import can, canemu.ixxat_shim\n"
        "canemu.ixxat_shim.install()\n"
        "try:\n"
        "    can.Bus(interface='ixxat', channel=0, bitrate=500000)\n"
        "except Exception as e:\n"
        "    print(e)\n"
    )
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                          timeout=60, env=dict(os.environ, CANEMU_SOCKET=missing), cwd=REPO)
    assert done.stdout == (
        "function vciEnumDeviceOpen failed (disconnected from canemud (canemud is not running "
        f"at {missing}: start it with 'systemctl start canemud' or 'canemud --socket "
        f"{missing}', or set CANEMU_SOCKET to the socket it listens on))\n"
    ), done.stdout + done.stderr
