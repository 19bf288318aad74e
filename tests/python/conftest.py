"""canemud for the python-can interface tests: a private daemon per test module, on its own
socket and configuration, started from the build tree and stopped at the module's end."""

from __future__ import annotations

import os
import select
import subprocess
import tempfile
import time
from pathlib import Path

import pytest

import canemu

REPO = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("CANEMU_BUILD_DIR", REPO / "build"))
CANEMUD = BUILD / "bin" / "canemud"
CANEMU_CLI = BUILD / "bin" / "canemu"

# Buses and adapters every test module gets; `time` is the module's choice.
TOPOLOGY = """
[[bus]]
name = "can0"
kind = "can"
bitrate = 500000

[[bus]]
name = "can1"
kind = "can"
bitrate = 125000

[[bus]]
name = "fd0"
kind = "can-fd"
bitrate = 500000
data_bitrate = 2000000

[[device]]
name = "ixxat0"
model = "ixxat-usb-to-can"
controllers = ["can0", "can1"]

[[device]]
name = "ixxatfd"
model = "ixxat-usb-to-can-fd"
controllers = ["fd0"]
"""


class Canemud:
    """canemud as a child process; ready once it says it listens (waited for with a timeout)."""

    def __init__(self, time_mode: str, extra: str = "", files: dict | None = None) -> None:
        self.dir = tempfile.mkdtemp(prefix="canemu-pytest-")
        self.socket = os.path.join(self.dir, "canemud.sock")
        for name, text in (files or {}).items():
            Path(self.dir, name).write_text(text)
        self.config = os.path.join(self.dir, "canemu.toml")
        Path(self.config).write_text(
            f'[simulation]\ntime = "{time_mode}"\nseed = 1\n' + TOPOLOGY + extra
        )
        self.proc = subprocess.Popen(
            [str(CANEMUD), "--config", self.config, "--socket", self.socket],
            stderr=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
        )
        self.log = b""
        want = f"listening on {self.socket}".encode()
        deadline = time.monotonic() + 10
        while want not in self.log:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.proc.stderr], [], [], left)[0]:
                self.stop()
                raise RuntimeError(f"canemud did not start: {self.log.decode(errors='replace')}")
            chunk = os.read(self.proc.stderr.fileno(), 4096)
            if not chunk:
                self.stop()
                raise RuntimeError(f"canemud exited: {self.log.decode(errors='replace')}")
            self.log += chunk
        canemu.connect(self.socket)

    def cli(self, *args: str) -> str:
        """Runs the canemu command against this daemon; its standard output."""
        done = subprocess.run(
            [str(CANEMU_CLI), "--socket", self.socket, *args],
            capture_output=True,
            text=True,
            timeout=30,
        )
        assert done.returncode == 0, done.stderr
        return done.stdout

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        self.proc.stderr.close()


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
