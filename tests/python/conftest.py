"""canemud for the python-can interface tests: a private daemon per test module, on its own
socket and configuration, started from the build tree and stopped at the module's end."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import can
import pytest

from canemu.bus import CAN_ERR_BUSERROR
from canemu.testing import Daemon

from config_text import (CAN0, CAN1, FD0, LIN0, LIN_ADAPTER, bus, device, fault,  # noqa: F401
                         missing_acks, scenario, table, toml)

REPO = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("CANEMU_BUILD_DIR", REPO / "build"))
CANEMUD = BUILD / "bin" / "canemud"
CANEMU_CLI = BUILD / "bin" / "canemu"

# Buses and adapters every test module gets; `time` is the module's choice.
TOPOLOGY = toml(CAN0, CAN1, FD0,
                device("ixxat0", "ixxat-usb-to-can", ["can0", "can1"]),
                device("ixxatfd", "ixxat-usb-to-can-fd", ["fd0"]))


class Canemud(Daemon):
    """canemud on TOPOLOGY in `time_mode`, plus `extra` configuration and `files`."""

    def __init__(self, time_mode: str, extra: str = "", files: dict | None = None) -> None:
        super().__init__(
            f'[simulation]\ntime = "{time_mode}"\nseed = 1\n' + TOPOLOGY + extra,
            files=files,
            canemud=str(CANEMUD),
        )


def drain(node) -> list:
    """Every message waiting now, without waiting (in stepped time nothing more comes)."""
    out = []
    while (msg := node.recv(0)) is not None:
        out.append(msg)
    return out


def bus_pair(channel: str, *, drained: bool, own: dict | None = None, **kwargs):
    """The body of a fixture of two canemu buses on `channel` (can.Bus arguments `kwargs`, the
    first's also `own`), their line start messages taken if `drained`: yields them as a pair
    and shuts them down after (`yield from bus_pair(...)`)."""
    a = can.Bus(interface="canemu", channel=channel, **kwargs, **(own or {}))
    b = can.Bus(interface="canemu", channel=channel, **kwargs)
    if drained:
        drain(a)
        drain(b)
    yield a, b
    a.shutdown()
    b.shutdown()


def frames(msgs) -> list:
    """The data and remote frames among `msgs` (no error frames)."""
    return [m for m in msgs if not m.is_error_frame]


def ns(seconds: float) -> int:
    """A python-can time stamp in whole nanoseconds."""
    return round(seconds * 1e9)


def fault_load(daemon: Daemon, text: str) -> subprocess.CompletedProcess:
    """`canemu fault load` of a scenario's text against `daemon` (its `at` times count from
    now); the finished command."""
    path = Path(daemon.dir, f"scenario-{len(list(Path(daemon.dir).glob('scenario-*')))}.toml")
    path.write_text(text)
    return subprocess.run(
        [str(CANEMU_CLI), "--socket", daemon.socket, "fault", "load", str(path)],
        capture_output=True,
        text=True,
        timeout=30,
    )


@pytest.fixture(scope="module")
def realtime_daemon():
    d = Canemud("realtime")
    yield d
    d.stop()


@pytest.fixture(scope="module")
def stepped_daemon():
    d = Canemud("stepped")
    yield d
    d.stop()


@pytest.fixture
def daemon(request):
    """A fresh canemud in stepped time for the test, with the test module's `EXTRA`
    configuration if it has one (modules with a daemon of their own override it)."""
    d = Canemud("stepped", extra=getattr(request.module, "EXTRA", ""))
    yield d
    d.stop()


@pytest.fixture
def nodes(daemon):
    """Two nodes of their own on can0 (500 kbit/s), the line start messages taken."""
    yield from bus_pair("can0", drained=True, auto_restart=False)


def bus_errors(msgs) -> list:
    """The bus-error frames among `msgs`."""
    return [m for m in msgs if m.is_error_frame and m.arbitration_id & CAN_ERR_BUSERROR]


def cli(daemon: Daemon, *args: str, check: bool = True, timeout: float = 60,
        env: dict | None = None) -> subprocess.CompletedProcess:
    """`canemu --socket SOCKET ARGS...` against `daemon`; with `check`, it must succeed."""
    done = subprocess.run([str(CANEMU_CLI), "--socket", daemon.socket, *args],
                          capture_output=True, text=True, timeout=timeout, env=env)
    if check:
        assert done.returncode == 0, done.stderr
    return done


def load(daemon: Daemon, text: str) -> None:
    """`canemu fault load` of a scenario that must be applied."""
    done = fault_load(daemon, text)
    assert done.returncode == 0, done.stderr
