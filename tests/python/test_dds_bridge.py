"""The DDS bridge between processes: canemud (stepped time) with a DDS bridge on can0 and the
ROS 2 topics, a DDS peer made with Cyclone DDS's Python binding (PyPI cyclonedds, an independent
implementation of the wire protocol's other end) and a python-can node on the bus. Both sides
speak to each other over the loopback interface by unicast (CYCLONEDDS_URI), in a DDS domain of
this run's own, so no root and no network namespace are needed. Every time stamp is simulated
time, exact."""

from __future__ import annotations

import json
import os
import subprocess
from dataclasses import dataclass

import can
import pytest

from conftest import BUILD, CAN0, CAN1, CANEMU_CLI, table, toml
from distributed_support import LOOPBACK_URI, TIMEOUT, frame_ns, wait_until

cyclonedds = pytest.importorskip(
    "cyclonedds", reason="PyPI's cyclonedds is not in this Python environment (requirements.txt, "
    ".venv)")

import canemu  # noqa: E402
from canemu.testing import Daemon  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.idl.annotations import final  # noqa: E402
from cyclonedds.idl.types import int64  # noqa: E402


@dataclass
@final
class Short(IdlStruct, typename="canemu::dds::Frame"):
    """Another type of canemu's Frame's name: only a time stamp, so canemud cannot decode it."""

    timestamp_ns: int64 = 0

MS = 1_000_000
DOMAIN = 1 + os.getpid() % 200
URI = LOOPBACK_URI

CONFIG = toml(table("[simulation]", time="stepped"), CAN0, CAN1,
              table("[[bridge]]", kind="dds", bus="can0", domain=DOMAIN, ros2=True))


@pytest.fixture(scope="module")
def world():
    os.environ["CYCLONEDDS_URI"] = URI  # canemud inherits it
    from cyclonedds.core import Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter, Publisher
    from cyclonedds.sub import DataReader, Subscriber
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration

    import canemu_dds

    daemon = Daemon(CONFIG, canemud=str(BUILD / "bin" / "canemud"))
    participant = DomainParticipant(DOMAIN)
    qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepAll,
              Policy.Durability.Volatile)
    ours = Qos(Policy.Partition(["canemu"]))
    pub, sub = Publisher(participant, qos=ours), Subscriber(participant, qos=ours)

    def topic(name, kind):
        return Topic(participant, name, kind)

    w = {
        "tx": DataWriter(pub, topic("canemu/can0/tx", canemu_dds.Frame), qos=qos),
        "ros_to": DataWriter(participant, topic("rt/can0/to_can_bus", canemu_dds.RosFrame),
                             qos=qos),
    }
    r = {
        "frames": DataReader(sub, topic("canemu/can0/frames", canemu_dds.Frame), qos=qos),
        "errors": DataReader(sub, topic("canemu/can0/errors", canemu_dds.BusError), qos=qos),
        "states": DataReader(sub, topic("canemu/can0/states", canemu_dds.NodeState), qos=qos),
        "ros_from": DataReader(participant, topic("rt/can0/from_can_bus", canemu_dds.RosFrame),
                               qos=qos),
    }
    # Discovery: both writers matched by the bridge's readers, and the bridge's writers by ours.
    wait_until(lambda: all(len(x.get_matched_subscriptions()) == 1 for x in w.values()) and
               all(len(x.get_matched_publications()) == 1 for x in r.values()),
               "the DDS peer and canemud's bridge discover each other")
    ecu = can.Bus(interface="canemu", channel="can0")
    yield {"daemon": daemon, "w": w, "r": r, "dds": canemu_dds, "ecu": ecu}
    ecu.shutdown()
    daemon.stop()
    del os.environ["CYCLONEDDS_URI"]


def cli(world, *args: str) -> str:
    done = subprocess.run([str(CANEMU_CLI), "--socket", world["daemon"].socket, *args],
                          capture_output=True, text=True, timeout=TIMEOUT)
    if done.returncode != 0:
        raise AssertionError(f"canemu {' '.join(args)}: {done.stderr}")
    return done.stdout


def bridges(world) -> list:
    return json.loads(cli(world, "bridge", "list", "--json"))


def take(world, name: str, count: int) -> list:
    got: list = []
    wait_until(lambda: got.extend(world["r"][name].take(N=64)) or len(got) >= count,
               f"{count} samples on {name}")
    return got


def ecu_frames(ecu) -> list:
    out = []
    while (m := ecu.recv(0)) is not None:
        if not m.is_error_frame:
            out.append((m.arbitration_id, m.is_extended_id, m.is_remote_frame, bytes(m.data).hex(),
                        round(m.timestamp * 1e9)))
    return out


def test_frames_both_ways_with_exact_times_and_ros2_topics(world):
    dds, ecu = world["dds"], world["ecu"]
    ecu_frames(ecu)
    t0 = canemu.sim_time()[0]
    assert t0 == 0
    # 1. Two frames on canemu's TX topic and one on ROS 2's to_can_bus, all at t = 0; the ROS 2
    # one with is_error set is no frame: counted as rejected.
    world["w"]["tx"].write(dds.Frame(id=0x123, dlc=2, len=2, data=[0x11, 0x22] + [0] * 62))
    world["w"]["tx"].write(dds.Frame(id=0x12345678, extended=True, remote=True, dlc=4))
    world["w"]["ros_to"].write(dds.RosFrame(id=0x7FF, dlc=1, data=[0x55] + [0] * 7))
    world["w"]["ros_to"].write(dds.RosFrame(id=0x1, is_error=True))
    wait_until(lambda: bridges(world)[0]["received"] == 4, "the bridge received 4 samples")
    canemu.step(MS)
    first, first_gap = frame_ns("123#1122")
    second, second_gap = frame_ns("12345678#R4")
    third, _ = frame_ns("7FF#55")
    # The order of the two topics' samples within one turn of canemud's loop: canemu's own
    # topic first, then ROS 2's.
    assert ecu_frames(ecu) == [
        (0x123, False, False, "1122", first),
        (0x12345678, True, True, "", first_gap + second),
        (0x7FF, False, False, "55", first_gap + second_gap + third),
    ]
    # 2. A frame of the python-can node from t = 1 ms.
    ecu.send(can.Message(arbitration_id=0x321, is_extended_id=False, data=[1, 2, 3]))
    canemu.step(MS)
    own, _ = frame_ns("321#010203")
    frames = take(world, "frames", 4)
    assert [(f.timestamp_ns, f.id, f.extended, f.remote, f.dlc, f.len, bytes(f.data[:f.len]).hex(),
             f.from_tx) for f in frames] == [
        (first, 0x123, False, False, 2, 2, "1122", True),
        (first_gap + second, 0x12345678, True, True, 4, 0, "", True),
        (first_gap + second_gap + third, 0x7FF, False, False, 1, 1, "55", True),
        (MS + own, 0x321, False, False, 3, 3, "010203", False),
    ]
    ros = take(world, "ros_from", 4)
    assert [(f.header.stamp.sec, f.header.stamp.nanosec, f.header.frame_id, f.id, f.is_extended,
             f.is_rtr, f.is_error, f.dlc, bytes(f.data[:f.dlc]).hex() if not f.is_rtr else "")
            for f in ros] == [
        (0, first, "can0", 0x123, False, False, False, 2, "1122"),
        (0, first_gap + second, "can0", 0x12345678, True, True, False, 4, ""),
        (0, first_gap + second_gap + third, "can0", 0x7FF, False, False, False, 1, "55"),
        (0, MS + own, "can0", 0x321, False, False, False, 3, "010203"),
    ]
    (entry,) = bridges(world)
    assert entry["kind"] == "dds" and entry["bus"] == "can0"
    assert (entry["domain"], entry["partition"], entry["ros2"]) == (DOMAIN, "canemu", True)
    assert entry["topics"] == {
        "frames": "canemu/can0/frames", "errors": "canemu/can0/errors",
        "states": "canemu/can0/states", "tx": "canemu/can0/tx",
        "ros2_from_can_bus": "rt/can0/from_can_bus", "ros2_to_can_bus": "rt/can0/to_can_bus"}
    assert (entry["received"], entry["sent"], entry["rejected"], entry["published"]) == (4, 3, 1, 4)
    # Why: by reason, and the last one with its rule and topic (also in canemud's log).
    assert entry["rejected_by"] == {"not_a_frame": 0, "bad_fields": 0, "fd_on_classic_bus": 0,
                                    "error_frame": 1}
    why = ("rejected a Frame with is_error on rt/can0/to_can_bus: error frames are the bus's, "
           "not sent")
    assert entry["last_rejected"] == why
    world["daemon"].wait_log(f"DDS bridge of can0: {why}")
    assert json.loads(cli(world, "status", "--json"))["bridges"] == [entry]
    table = cli(world, "bridge", "list").splitlines()
    assert table[0].split()[:2] == ["DDS-BRIDGE", "TOPICS"]
    assert table[1].split() == ["can0", "canemu/can0/*", "error-active", "0", "0", "0", "4", "0",
                                "0", "4", "3", "0", "1", "0", f"{DOMAIN}/canemu+ros2"]


def test_errors_and_states_of_a_node_left_alone(world):
    dds, ecu = world["dds"], world["ecu"]
    ecu.shutdown()  # nobody acknowledges now
    start = canemu.sim_time()[0]
    world["w"]["tx"].write(dds.Frame(id=0x555, dlc=1, len=1, data=[0x55] + [0] * 63))
    wait_until(lambda: bridges(world)[0]["received"] == 5, "the bridge received the 5th sample")
    canemu.step(3 * MS)
    states = take(world, "states", 2)
    published = bridges(world)[0]["published_events"]
    errors = take(world, "errors", published - len(states))
    assert len(errors) + len(states) == published  # nothing the bridge published was lost
    e = errors[0]
    # Sent at the step's start; its ACK slot is its 46th bit.
    assert (e.timestamp_ns, e.type, e.role, e.bit, e.destuffed_bit, e.field, e.in_frame, e.tec,
            e.rec) == (start + 46 * 2000, dds.ERROR_ACK, dds.ROLE_TRANSMITTER, 45, 43, "ACK", True,
                       8, 0)
    assert [x.tec for x in errors[:16]] == list(range(8, 129, 8))
    assert [(s.timestamp_ns, s.state, s.tec, s.restarted) for s in states] == [
        (errors[11].timestamp_ns, dds.STATE_WARNING, 96, False),
        (errors[15].timestamp_ns, dds.STATE_PASSIVE, 128, False),
    ]


def test_a_bridge_added_listed_and_removed_at_run_time(world):
    added = cli(world, "bridge", "add", "can1", "--dds", f"{DOMAIN}/rig-a", "--prefix",
                "robot/can1/")
    assert added == f"can1 bridged to DDS topics robot/can1/* in domain/partition {DOMAIN}/rig-a\n"
    assert [(b["bus"], b["topic_prefix"], b["partition"], b["ros2"]) for b in bridges(world)] == [
        ("can0", "canemu/can0/", "canemu", True), ("can1", "robot/can1/", "rig-a", False)]
    assert cli(world, "bridge", "remove", "can1", "--dds") == "DDS bridge of can1 removed\n"
    assert [b["bus"] for b in bridges(world)] == ["can0"]


def test_what_is_wrong_is_said(world):
    def refused(*args: str) -> str:
        done = subprocess.run([str(CANEMU_CLI), "--socket", world["daemon"].socket, *args],
                              capture_output=True, text=True, timeout=TIMEOUT)
        assert done.returncode != 0
        return done.stderr.strip()

    assert "is not DOMAIN/PARTITION" in refused("bridge", "add", "can1", "--dds", "999/x")
    assert refused("bridge", "add", "can0", "--dds", f"{DOMAIN}/canemu").endswith(
        "can0 has a DDS bridge already")
    assert refused("bridge", "add", "can1", "--ros2", "vcan0").endswith(
        "--ros2 is for DDS bridges (--dds)")
    assert refused("bridge", "remove", "can1", "--dds").endswith("no DDS bridge on bus \"can1\"")


def test_samples_that_do_not_decode_are_counted_with_the_reason(world):
    # A peer whose type has canemu's name and other fields (here: only a time stamp): Cyclone
    # DDS in canemud cannot decode its samples, which never reach the bridge's reader; they are
    # counted as rejected (not a frame), with the topic, and logged.
    from cyclonedds.core import Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter, Publisher
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration

    before = bridges(world)[0]
    other = DomainParticipant(DOMAIN)
    writer = DataWriter(Publisher(other, qos=Qos(Policy.Partition(["canemu"]))),
                        Topic(other, "canemu/can0/tx", Short),
                        qos=Qos(Policy.Reliability.Reliable(duration(seconds=1)),
                                Policy.History.KeepAll, Policy.Durability.Volatile))
    wait_until(lambda: len(writer.get_matched_subscriptions()) == 1,
               "the bridge's reader matches the peer's writer")
    writer.write(Short(timestamp_ns=1))
    writer.write(Short(timestamp_ns=2))
    wait_until(lambda: bridges(world)[0]["rejected"] == before["rejected"] + 2,
               "two undecodable samples counted")
    entry = bridges(world)[0]
    assert entry["received"] == before["received"] + 2
    assert entry["sent"] == before["sent"]
    assert entry["rejected_by"]["not_a_frame"] == before["rejected_by"]["not_a_frame"] + 2
    assert "on canemu/can0/tx that Cyclone DDS could not decode" in entry["last_rejected"]
    world["daemon"].wait_log("that Cyclone DDS could not decode (another type of the same name?)")
