"""The device under test's side of a restbus (docs/restbus.md, "Tutorial"): a python-can program
in the DRIVER's place of socialledge.dbc that watches MOTOR_STATUS, which canemud's simulated
MOTOR sends every 100 ms. It prints each change of the motor's speed, and a message that comes
back after more than 2.5 cycles without it, each with the frame's time stamp counted from the
first frame it saw (simulated time in stepped time, wall-clock time in real time).

    python client/examples/restbus_watch.py tests/data/dbc/socialledge.dbc --seconds 10
"""

from __future__ import annotations

import argparse
from typing import Callable, Optional

import can
import cantools

TIMEOUT_S = 0.25  # 2.5 cycles of MOTOR_STATUS


def watch(bus: can.BusABC, db, seconds: float, say: Callable[[str], None] = print) -> None:
    """Reads `bus` until a frame stamped `seconds` after the first one (or none for 1 s)."""
    status = db.get_message_by_name("MOTOR_STATUS")
    first: Optional[float] = None
    last: Optional[float] = None
    speed: Optional[float] = None
    while (msg := bus.recv(1.0)) is not None:
        first = msg.timestamp if first is None else first
        t = msg.timestamp - first
        if t >= seconds:
            return
        if msg.is_error_frame or msg.arbitration_id != status.frame_id or msg.is_extended_id:
            continue
        if last is not None and msg.timestamp - last > TIMEOUT_S:
            say(f"{t:7.3f} s  MOTOR_STATUS back after {msg.timestamp - last:.3f} s without it")
        last = msg.timestamp
        now = status.decode(bytes(msg.data))["MOTOR_STATUS_speed_kph"]
        if now != speed:
            say(f"{t:7.3f} s  speed {now:g} kph")
            speed = now


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dbc", help="socialledge.dbc")
    parser.add_argument("--channel", default="can0")
    parser.add_argument("--seconds", type=float, default=10.0)
    args = parser.parse_args()
    db = cantools.database.load_file(args.dbc)
    with can.Bus(interface="canemu", channel=args.channel) as bus:
        watch(bus, db, args.seconds)


if __name__ == "__main__":
    main()
