"""canemu for python-can: ``can.Bus(interface="canemu", channel="can0")``.

The interface registers itself with python-can through the ``can.interface`` entry point; this
package also offers canemud's time and topology to test code.
"""

from .bus import (
    CanemuBus,
    CanemuCyclicTask,
    ControllerState,
    XcanBus,
    buses,
    connect,
    devices,
    sim_time,
    step,
)

__all__ = [
    "CanemuBus",
    "CanemuCyclicTask",
    "ControllerState",
    "XcanBus",
    "buses",
    "connect",
    "devices",
    "sim_time",
    "step",
]
