"""canemu's DDS types for Cyclone DDS's Python binding (PyPI: cyclonedds).

The same types as daemon/src/bridges/dds_types/canemu_dds.idl and ros2_can_msgs.idl, which canemud's DDS
bridge is built from (docs/bridges.md): Frame, BusError and NodeState on the topics
<prefix>frames, <prefix>errors, <prefix>states and <prefix>tx (prefix canemu/<bus>/ by default,
partition "canemu"), and ROS 2's can_msgs/msg/Frame as ROS 2's middleware names it, on
rt/<bus>/from_can_bus and rt/<bus>/to_can_bus (no partition).

    from cyclonedds.domain import DomainParticipant
    from cyclonedds.topic import Topic
    import canemu_dds
    participant = DomainParticipant(0)
    frames = Topic(participant, "canemu/can0/frames", canemu_dds.Frame)
"""

from dataclasses import dataclass, field

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.annotations import final
from cyclonedds.idl.types import array, bounded_str, int32, int64, uint8, uint16, uint32

ERROR_BIT, ERROR_STUFF, ERROR_FORM, ERROR_CRC, ERROR_ACK = 0, 1, 2, 3, 4
ROLE_TRANSMITTER, ROLE_RECEIVER = 0, 1
STATE_ACTIVE, STATE_WARNING, STATE_PASSIVE, STATE_BUS_OFF = 0, 1, 2, 3


@dataclass
@final
class Frame(IdlStruct, typename="canemu::dds::Frame"):
    """A CAN or CAN FD frame; timestamp_ns is simulated time (ignored on <prefix>tx)."""

    timestamp_ns: int64 = 0
    id: uint32 = 0
    extended: bool = False
    remote: bool = False
    fd: bool = False
    brs: bool = False
    esi: bool = False
    dlc: uint8 = 0
    len: uint8 = 0
    data: array[uint8, 64] = field(default_factory=lambda: [0] * 64)
    from_tx: bool = False


@dataclass
@final
class BusError(IdlStruct, typename="canemu::dds::BusError"):
    """A bus error the bridge's node detected, with its counters after it."""

    timestamp_ns: int64 = 0
    type: uint8 = 0
    role: uint8 = 0
    bit: uint16 = 0
    destuffed_bit: uint16 = 0
    field: bounded_str[15] = ""
    in_frame: bool = False
    state: uint8 = 0
    tec: uint16 = 0
    rec: uint16 = 0


@dataclass
@final
class NodeState(IdlStruct, typename="canemu::dds::NodeState"):
    """The bridge's node changed its error state, or was restarted after bus-off."""

    timestamp_ns: int64 = 0
    state: uint8 = 0
    tec: uint16 = 0
    rec: uint16 = 0
    restarted: bool = False


@dataclass
@final
class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
@final
class Header_(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time_ = field(default_factory=Time_)
    frame_id: str = ""


@dataclass
@final
class RosFrame(IdlStruct, typename="can_msgs::msg::dds_::Frame_"):
    """ROS 2's can_msgs/msg/Frame (classic CAN: 8 data bytes)."""

    header: Header_ = field(default_factory=Header_)
    id: uint32 = 0
    is_rtr: bool = False
    is_extended: bool = False
    is_error: bool = False
    dlc: uint8 = 0
    data: array[uint8, 8] = field(default_factory=lambda: [0] * 8)
