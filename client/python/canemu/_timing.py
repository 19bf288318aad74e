"""Bit timing for the emulated controllers: bit rates and python-can's BitTiming/BitTimingFd
turned into the raw CANBTP values the VCI v2 interface takes.

The controller's clock and the ranges of its timing values are the library's: the
CANCAPABILITIES2 that canControlGetCaps reports (Limits.of); nothing here knows them."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Tuple

from . import _vci


@dataclass(frozen=True)
class Range:
    brp: Tuple[int, int]
    tseg1: Tuple[int, int]  # without the sync quantum
    tseg2: Tuple[int, int]
    sjw: Tuple[int, int]

    @classmethod
    def of(cls, low: "_vci.CANBTP", high: "_vci.CANBTP") -> "Range":
        """The range between two raw CANBTPs (dwBPS is the prescaler)."""
        return cls(
            brp=(low.dwBPS, high.dwBPS),
            tseg1=(low.wTS1, high.wTS1),
            tseg2=(low.wTS2, high.wTS2),
            sjw=(low.wSJW, high.wSJW),
        )


@dataclass(frozen=True)
class Limits:
    """A controller's CAN clock and timing ranges: `data` is None for a classic CAN controller
    (no fast data rate)."""

    clock_hz: int
    nominal: Range
    data: Optional[Range]

    @classmethod
    def of(cls, caps: "_vci.CANCAPABILITIES2") -> "Limits":
        fast = caps.sFdrRangeMax.dwBPS != 0  # all 0 without a fast data rate
        return cls(
            clock_hz=caps.dwCanClkFreq,
            nominal=Range.of(caps.sSdrRangeMin, caps.sSdrRangeMax),
            data=Range.of(caps.sFdrRangeMin, caps.sFdrRangeMax) if fast else None,
        )

    @property
    def fd(self) -> bool:
        return self.data is not None

    def bitrate(self, btp: "_vci.CANBTP") -> int:
        """The bit rate of a raw CANBTP on this controller."""
        return self.clock_hz // (btp.dwBPS * (1 + btp.wTS1 + btp.wTS2))


def _inside(value: int, bounds: Tuple[int, int]) -> bool:
    return bounds[0] <= value <= bounds[1]


def raw(brp: int, tseg1: int, tseg2: int, sjw: int, triple: bool = False, tdo: int = 0):
    return _vci.CANBTP(
        _vci.CAN_BTMODE_RAW | (_vci.CAN_BTMODE_TSM if triple else 0), brp, tseg1, tseg2, sjw, tdo
    )


def from_bitrate(
    bitrate: int, sample_point: float, clock_hz: int, limits: Range, what: str
) -> "_vci.CANBTP":
    """The timing with the most quanta per bit (smallest prescaler) whose sample point is
    nearest `sample_point` (a fraction, e.g. 0.875). ValueError naming `what` when the clock
    cannot make `bitrate`."""
    if bitrate <= 0:
        raise ValueError(f"{what}: the bit rate must be positive, not {bitrate}")
    for brp in range(limits.brp[0], limits.brp[1] + 1):
        if clock_hz % (bitrate * brp) != 0:
            continue
        quanta = clock_hz // (bitrate * brp)
        tseg2 = max(limits.tseg2[0], round(quanta * (1.0 - sample_point)))
        tseg1 = quanta - 1 - tseg2
        if not (_inside(tseg1, limits.tseg1) and _inside(tseg2, limits.tseg2)):
            continue
        sjw = min(tseg2, tseg1, limits.sjw[1])
        return raw(brp, tseg1, tseg2, sjw)
    raise ValueError(
        f"{what}: {bitrate} bit/s cannot be made from the controller's {clock_hz} Hz clock "
        f"(no prescaler gives a whole number of time quanta per bit within the controller's "
        f"limits)"
    )


def _percent_to_fraction(value: float) -> float:
    return value / 100.0 if value > 1.0 else value


def from_python_can(timing, limits: Limits):
    """(nominal CANBTP, data CANBTP or None) for a can.BitTiming or can.BitTimingFd."""
    clock = limits.clock_hz
    if hasattr(timing, "nom_brp"):  # BitTimingFd
        if limits.data is None:
            raise ValueError("a BitTimingFd needs a CAN FD controller; this one is classic CAN")
        nominal = _one_phase(
            timing.f_clock,
            timing.nom_brp,
            timing.nom_tseg1,
            timing.nom_tseg2,
            timing.nom_sjw,
            timing.nom_bitrate,
            timing.nom_sample_point,
            clock,
            limits.nominal,
            "nominal timing",
        )
        data = _one_phase(
            timing.f_clock,
            timing.data_brp,
            timing.data_tseg1,
            timing.data_tseg2,
            timing.data_sjw,
            timing.data_bitrate,
            timing.data_sample_point,
            clock,
            limits.data,
            "data timing",
        )
        with_tdo(data)
        return nominal, data
    f_clock = getattr(timing, "f_clock", None)
    nominal = _one_phase(
        f_clock,
        timing.brp,
        timing.tseg1,
        timing.tseg2,
        timing.sjw,
        timing.bitrate,
        timing.sample_point,
        clock,
        limits.nominal,
        "timing",
    )
    if getattr(timing, "nof_samples", 1) == 3:
        nominal.dwMode |= _vci.CAN_BTMODE_TSM
    return nominal, None


def _one_phase(
    f_clock: Optional[int],
    brp: int,
    tseg1: int,
    tseg2: int,
    sjw: int,
    bitrate: int,
    sample_point: float,
    clock_hz: int,
    limits: Range,
    what: str,
):
    if f_clock == clock_hz:
        fields = {"brp": brp, "tseg1": tseg1, "tseg2": tseg2, "sjw": sjw}
        for name, value in fields.items():
            if not _inside(value, getattr(limits, name)):
                lo, hi = getattr(limits, name)
                raise ValueError(f"{what}: {name} = {value} is outside {lo}..{hi}")
        return raw(brp, tseg1, tseg2, sjw)
    # Another clock: the same bit rate and sample point with this controller's clock.
    return from_bitrate(
        int(round(bitrate)), _percent_to_fraction(sample_point), clock_hz, limits, what
    )


def with_tdo(data) -> None:
    """Transceiver delay compensation at the data phase's sample point (when it fits)."""
    offset = data.dwBPS * (1 + data.wTS1)
    data.wTDO = offset if offset <= 255 else 0


def nominal_and_data(bitrate: int, data_bitrate: Optional[int], limits: Limits, fd: bool):
    """The CANBTPs for a nominal bit rate and, with `fd`, a data bit rate."""
    if limits.data is not None:
        nominal = from_bitrate(bitrate, 0.8, limits.clock_hz, limits.nominal, "bitrate")
        data_rate = data_bitrate if fd and data_bitrate else bitrate
        data = from_bitrate(data_rate, 0.75, limits.clock_hz, limits.data, "data_bitrate")
        with_tdo(data)
        return nominal, data
    return from_bitrate(bitrate, 0.875, limits.clock_hz, limits.nominal, "bitrate"), None
