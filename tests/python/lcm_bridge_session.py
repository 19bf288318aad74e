"""One session with canemud's LCM bridge, run by test_lcm_bridge.py inside a network namespace
of its own (`unshare -n`), so that LCM's UDP multicast stays on a loopback nobody else uses.

Sets up multicast on lo, starts lcm-logger and canemud (stepped time, an LCM bridge on can0),
plays an LCM peer (PyPI lcm: subscribes to FRAMES, ERRORS and STATES, publishes on TX) and a
python-can node on can0, and prints what everyone saw as one JSON object; the test asserts.

Usage: python lcm_bridge_session.py BUILD_DIR WORK_DIR"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import can
import lcm

import canemu
from canemu.testing import Daemon
from canemu_lcm import error_t, frame_t, state_t

from config_text import CAN0, CAN1, table, toml

URL = "udpm://239.255.76.67:7667?ttl=0"
TIMEOUT = 20.0
MS = 1_000_000

build, work = Path(sys.argv[1]), Path(sys.argv[2])
CLI = build / "bin" / "canemu"

CONFIG = toml(table("[simulation]", time="stepped", seed=1), CAN0, CAN1,
              table("[[bridge]]", kind="lcm", bus="can0"))


def wait_until(done, what: str, pump=None) -> None:
    """Until done() holds, looking every 5 ms (or handling LCM messages for up to 5 ms)."""
    deadline = time.monotonic() + TIMEOUT
    while not done():
        if time.monotonic() > deadline:
            raise AssertionError(f"{what}: not within {TIMEOUT} s")
        if pump is not None:
            pump.handle_timeout(5)
        else:
            threading.Event().wait(0.005)


def as_dict(m) -> dict:
    out = {name: getattr(m, name) for name in m.__slots__}
    if "data" in out:
        out["data"] = bytes(out["data"][: m.len]).hex()
    return out


def frame(ident: int, data: bytes = b"", extended=False, remote=False, dlc=None) -> frame_t:
    f = frame_t()
    f.id = ident
    f.extended = extended
    f.remote = remote
    f.dlc = len(data) if dlc is None else dlc
    f.len = len(data)
    f.data = data + bytes(64 - len(data))
    return f


subprocess.run(["ip", "link", "set", "lo", "up", "multicast", "on"], check=True)
subprocess.run(["ip", "route", "add", "224.0.0.0/4", "dev", "lo"], check=True)

result: dict = {}
peer = lcm.LCM(URL)

# lcm-logger records the session; it is ready when a probe it was sent reaches its file.
log_path = work / "session.lcmlog"
logger = subprocess.Popen(["lcm-logger", "-q", "-f", f"--lcm-url={URL}", "--channel=CANEMU_.*",
                           "--flush-interval=5", str(log_path)])


def logger_ready() -> bool:
    peer.publish("CANEMU_PROBE", b"probe")
    return log_path.exists() and log_path.stat().st_size > 0


wait_until(logger_ready, "lcm-logger records")

daemon = Daemon(CONFIG, canemud=str(build / "bin" / "canemud"))


def cli(*args: str) -> str:
    done = subprocess.run([str(CLI), "--socket", daemon.socket, *args], capture_output=True,
                          text=True, timeout=TIMEOUT)
    if done.returncode != 0:
        raise AssertionError(f"canemu {' '.join(args)}: {done.stderr}")
    return done.stdout


def bridges() -> list:
    return json.loads(cli("bridge", "list", "--json"))


try:
    got: dict = {"FRAMES": [], "ERRORS": [], "STATES": []}
    for name, kind in (("FRAMES", frame_t), ("ERRORS", error_t), ("STATES", state_t)):
        peer.subscribe(f"CANEMU_CAN0_{name}",
                       lambda channel, data, name=name, kind=kind: got[name].append(
                           as_dict(kind.decode(data))))
    ecu = can.Bus(interface="canemu", channel="can0")  # acknowledges; sends one frame later
    while ecu.recv(0) is not None:
        pass

    # 1. Three frames and one whose length disagrees with its DLC, on TX at t = 0; counted in
    # as they arrive, then sent in the step.
    for f in (frame(0x123, b"\x11\x22"), frame(0x12345678, extended=True, remote=True, dlc=4),
              frame(0x7FF), frame(0x100, b"\x01", dlc=2)):
        peer.publish("CANEMU_CAN0_TX", f.encode())
    wait_until(lambda: bridges()[0]["received"] == 4, "the bridge received 4 messages on TX")
    result["sim_time_before"] = canemu.sim_time()[0]
    canemu.step(MS)
    result["ecu"] = []
    while (m := ecu.recv(0)) is not None:
        if not m.is_error_frame:
            result["ecu"].append([m.arbitration_id, m.is_remote_frame, bytes(m.data).hex(),
                                  round(m.timestamp * 1e9)])

    # 2. A frame of the python-can node, from t = 1 ms.
    ecu.send(can.Message(arbitration_id=0x321, is_extended_id=False, data=[1, 2, 3]))
    canemu.step(MS)
    wait_until(lambda: len(got["FRAMES"]) >= 4, "4 frames on FRAMES", pump=peer)
    result["list"] = bridges()
    result["status"] = json.loads(cli("status", "--json"))["bridges"]
    result["table"] = cli("bridge", "list")

    # 3. Alone on the bus: ACK errors take the bridge's node to warning and error-passive.
    ecu.shutdown()
    peer.publish("CANEMU_CAN0_TX", frame(0x555, b"\x55").encode())
    wait_until(lambda: bridges()[0]["received"] == 5, "the bridge received the 5th message")
    canemu.step(3 * MS)
    published = bridges()[0]["published_events"]
    wait_until(lambda: len(got["ERRORS"]) + len(got["STATES"]) >= published,
               f"{published} errors and states", pump=peer)
    result["published_events"] = published

    # 4. A bridge added, listed and removed at run time.
    result["add"] = cli("bridge", "add", "can1", "--lcm", "--prefix", "ROBOT_CAN1_")
    result["list2"] = bridges()
    result["remove"] = cli("bridge", "remove", "can1", "--lcm")
    result["list3"] = bridges()
finally:
    daemon.stop()
    logger.send_signal(signal.SIGINT)
    logger.wait(TIMEOUT)

result.update(got)
result["log"] = []
for event in lcm.EventLog(str(log_path), "r"):
    if event.channel in ("CANEMU_CAN0_FRAMES", "CANEMU_CAN0_TX"):
        result["log"].append([event.channel, as_dict(frame_t.decode(event.data))])
    elif event.channel != "CANEMU_PROBE":
        result["log"].append([event.channel, None])
print(json.dumps(result))
