"""The LCM bridge between processes: canemud with an LCM bridge on can0 in stepped time, a
Python LCM peer (PyPI lcm) on its channels, a python-can node on the bus and lcm-logger
recording, all in a network namespace of their own (lcm_bridge_session.py runs there and
reports; the assertions are here). Every time stamp is simulated time, exact."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import BUILD, CANEMU_CLI

SESSION = Path(__file__).with_name("lcm_bridge_session.py")


def _missing() -> str | None:
    if os.geteuid() != 0:
        return ("needs root: canemud and the LCM peer run in a network namespace of their own "
                "(unshare -n) with multicast routed on lo")
    for tool in ("unshare", "ip", "lcm-logger"):
        if shutil.which(tool) is None:
            return f"{tool} is not installed (scripts/apt-packages.txt)"
    try:
        import lcm
        lcm.LCM  # noqa: B018 (not a folder named lcm that happens to be on the path)
    except (ImportError, AttributeError):
        return "PyPI's lcm is not in this Python environment (requirements.txt, .venv)"
    if not (BUILD / "include" / "canemu_lcm").is_dir():
        return "canemu was built without LCM (liblcm-dev, liblcm-bin)"
    return None


pytestmark = pytest.mark.skipif(_missing() is not None, reason=_missing() or "")


def frame_ns(frame: str, bitrate: int = 500000) -> tuple[int, int]:
    """The frame's duration from SOF to the end of EOF and with its intermission
    (`canemu calc frame`)."""
    text = subprocess.run([str(CANEMU_CLI), "calc", "frame", frame, "--bitrate", str(bitrate)],
                          capture_output=True, text=True, check=True).stdout
    bare = int(re.search(r": (\d+) ns \(", text).group(1))
    return bare, int(re.search(r"(\d+) ns with intermission", text).group(1))


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    work = tmp_path_factory.mktemp("lcm")
    done = subprocess.run(["unshare", "-n", sys.executable, str(SESSION), str(BUILD), str(work)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def test_frames_from_tx_go_out_back_to_back_with_their_exact_times(session):
    assert session["sim_time_before"] == 0
    first, first_gap = frame_ns("123#1122")
    second, second_gap = frame_ns("12345678#R4")
    third, _ = frame_ns("7FF#")
    assert first == 124_000  # 62 bits at 500 kbit/s
    assert session["ecu"] == [
        [0x123, False, "1122", first],
        [0x12345678, True, "", first_gap + second],
        [0x7FF, False, "", first_gap + second_gap + third],
    ]


def test_frames_carries_every_frame_of_the_bus(session):
    t = [e[3] for e in session["ecu"]]
    base = {"extended": False, "remote": False, "fd": False, "brs": False, "esi": False}
    own, _ = frame_ns("321#010203")
    assert session["FRAMES"] == [
        {**base, "timestamp_ns": t[0], "id": 0x123, "dlc": 2, "len": 2, "data": "1122",
         "from_tx": True},
        {**base, "timestamp_ns": t[1], "id": 0x12345678, "extended": True, "remote": True,
         "dlc": 4, "len": 0, "data": "", "from_tx": True},
        {**base, "timestamp_ns": t[2], "id": 0x7FF, "dlc": 0, "len": 0, "data": "",
         "from_tx": True},
        # The python-can node's frame, sent at the start of the second 1 ms step.
        {**base, "timestamp_ns": 1_000_000 + own, "id": 0x321, "dlc": 3, "len": 3,
         "data": "010203", "from_tx": False},
    ]


def test_list_and_status_count_what_came_and_went(session):
    (entry,) = session["list"]
    assert session["status"] == session["list"]
    assert entry["kind"] == "lcm" and entry["bus"] == "can0"
    assert entry["url"] == "udpm://239.255.76.67:7667?ttl=0"
    assert entry["channels"] == {"frames": "CANEMU_CAN0_FRAMES", "errors": "CANEMU_CAN0_ERRORS",
                                 "states": "CANEMU_CAN0_STATES", "tx": "CANEMU_CAN0_TX"}
    assert (entry["received"], entry["sent"], entry["rejected"], entry["published"]) == (4, 3, 1, 4)
    assert (entry["queue_dropped"], entry["publish_failed"], entry["dropped"]) == (0, 0, 1)
    # Why it was rejected: by reason, and the last one with its rule and channel.
    assert entry["rejected_by"] == {"not_a_frame": 0, "bad_fields": 1, "fd_on_classic_bus": 0,
                                    "error_frame": 0}
    assert entry["last_rejected"] == ("rejected a frame_t on CANEMU_CAN0_TX: len 1 is not the 2 "
                                      "bytes a classic frame of dlc 2 has")
    assert entry["state"] == "error-active"
    assert session["table"].splitlines()[1].split() == [
        "can0", "CANEMU_CAN0_*", "error-active", "0", "0", "0", "4", "0", "0", "4", "3", "0", "1",
        "0", "udpm://239.255.76.67:7667?ttl=0"]


def test_errors_and_states_of_a_node_left_alone(session):
    errors, states = session["ERRORS"], session["STATES"]
    # Nothing the bridge published was lost on the way (a few dozen messages, read as they came).
    assert len(errors) + len(states) == session["published_events"]
    # The frame was published at t = 2 ms; its ACK slot is its 46th bit.
    assert errors[0] == {"timestamp_ns": 2_000_000 + 46 * 2000, "type": 4, "role": 0, "bit": 45,
                         "destuffed_bit": 43, "field": "ACK", "in_frame": True, "state": 0,
                         "tec": 8, "rec": 0}
    assert [e["tec"] for e in errors[:16]] == list(range(8, 129, 8))
    assert all(e["tec"] == 128 for e in errors[16:])  # error-passive: ACK errors count no more
    assert states == [
        {"timestamp_ns": errors[11]["timestamp_ns"], "state": 1, "tec": 96, "rec": 0,
         "restarted": False},
        {"timestamp_ns": errors[15]["timestamp_ns"], "state": 2, "tec": 128, "rec": 0,
         "restarted": False},
    ]
    assert session["list2"][0]["state"] == "error-passive"
    assert session["list2"][0]["published_events"] == session["published_events"]


def test_a_bridge_added_listed_and_removed_at_run_time(session):
    assert session["add"] == ("can1 bridged to LCM channels ROBOT_CAN1_* on "
                              "udpm://239.255.76.67:7667?ttl=0\n")
    assert [(b["bus"], b["channel_prefix"]) for b in session["list2"]] == [
        ("can0", "CANEMU_CAN0_"), ("can1", "ROBOT_CAN1_")]
    assert session["remove"] == "LCM bridge of can1 removed\n"
    assert [b["bus"] for b in session["list3"]] == ["can0"]


def test_lcm_logger_recorded_the_session(session):
    log = session["log"]
    assert [f for channel, f in log if channel == "CANEMU_CAN0_FRAMES"] == session["FRAMES"]
    tx = [f for channel, f in log if channel == "CANEMU_CAN0_TX"]
    assert [(f["id"], f["dlc"], f["len"], f["data"]) for f in tx] == [
        (0x123, 2, 2, "1122"), (0x12345678, 4, 0, ""), (0x7FF, 0, 0, ""), (0x100, 2, 1, "01"),
        (0x555, 1, 1, "55")]
    assert sum(channel == "CANEMU_CAN0_ERRORS" for channel, _ in log) == len(session["ERRORS"])
    assert sum(channel == "CANEMU_CAN0_STATES" for channel, _ in log) == len(session["STATES"])
