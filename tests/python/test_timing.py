"""Bit timing: the controller's clock and timing ranges come from the library
(canControlGetCaps), and the timings made from them."""

import ctypes

import can
import pytest

from canemu import _timing, _vci


def limits_of(bus) -> _timing.Limits:
    caps = _vci.CANCAPABILITIES2()
    _vci.check("canControlGetCaps", _vci.lib().canControlGetCaps(bus._control, ctypes.byref(caps)))
    return _timing.Limits.of(caps)


def limits_of_channel(channel, **kwargs) -> _timing.Limits:
    bus = can.Bus(interface="canemu", channel=channel, **kwargs)
    try:
        return limits_of(bus)
    finally:
        bus.shutdown()


def test_the_sja1000_reports_its_8_mhz_clock_and_ranges_and_no_data_phase(realtime_daemon):
    limits = limits_of_channel("ixxat0:1")
    assert limits == _timing.Limits(
        clock_hz=8_000_000,
        nominal=_timing.Range(brp=(1, 64), tseg1=(1, 16), tseg2=(1, 8), sjw=(1, 4)),
        data=None,
    )
    assert not limits.fd


def test_the_can_fd_controller_reports_its_80_mhz_clock_and_both_phases(realtime_daemon):
    limits = limits_of_channel("ixxatfd:0", fd=True)
    assert limits == _timing.Limits(
        clock_hz=80_000_000,
        nominal=_timing.Range(brp=(1, 1024), tseg1=(1, 256), tseg2=(2, 128), sjw=(1, 128)),
        data=_timing.Range(brp=(1, 32), tseg1=(1, 32), tseg2=(1, 16), sjw=(1, 16)),
    )
    assert limits.fd


def fields(btp):
    return (btp.dwMode, btp.dwBPS, btp.wTS1, btp.wTS2, btp.wSJW, btp.wTDO)


SMALL = _timing.Limits(
    clock_hz=8_000_000,
    nominal=_timing.Range(brp=(1, 64), tseg1=(1, 16), tseg2=(1, 8), sjw=(1, 4)),
    data=None,
)


def test_a_bit_rate_takes_the_smallest_prescaler_within_the_reported_ranges():
    nominal, data = _timing.nominal_and_data(500_000, None, SMALL, fd=False)
    # 8 MHz / 500 kbit/s = 16 quanta: 1 + 13 + 2 with the sample point at 87.5 %.
    assert fields(nominal) == (_vci.CAN_BTMODE_RAW, 1, 13, 2, 2, 0)
    assert data is None
    assert SMALL.bitrate(nominal) == 500_000


def test_a_bit_rate_the_reported_ranges_cannot_make_is_refused_naming_the_clock():
    with pytest.raises(ValueError, match="bitrate: 300000 bit/s cannot be made from the "
                                         "controller's 8000000 Hz clock"):
        _timing.nominal_and_data(300_000, None, SMALL, fd=False)
