"""A private canemud for test suites and benchmarks: started on its own socket and configuration
in a fresh temporary folder, ready when it says it listens, killed on stop().

    with canemu.testing.Daemon(config_text) as daemon:
        bus = can.Bus(interface="canemu", channel="can0")
        ...
"""

from __future__ import annotations

import os
import select
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Dict, Optional

from .bus import connect


def find_canemud() -> str:
    """$CANEMUD, else the build tree of a source checkout, else canemud on PATH."""
    if os.environ.get("CANEMUD"):
        return os.environ["CANEMUD"]
    build = Path(os.environ.get("CANEMU_BUILD_DIR", Path(__file__).resolve().parents[3] / "build"))
    candidate = build / "bin" / "canemud"
    if candidate.exists():
        return str(candidate)
    found = shutil.which("canemud")
    if found is None:
        raise FileNotFoundError("canemud not found: build canemu or set CANEMUD")
    return found


class Daemon:
    """canemud as a child process.

    :param config: the configuration's text (TOML).
    :param files: more files for the configuration's folder (scenarios), name -> text.
    :param canemud: the program; default find_canemud().
    :param timeout: seconds to wait for it to listen.

    The process talks to this daemon from now on (canemu.connect).
    """

    def __init__(
        self,
        config: str,
        files: Optional[Dict[str, str]] = None,
        canemud: Optional[str] = None,
        timeout: float = 10.0,
    ) -> None:
        self.dir = tempfile.mkdtemp(prefix="canemu-")
        self.socket = os.path.join(self.dir, "canemud.sock")
        self.config = os.path.join(self.dir, "canemu.toml")
        for name, text in (files or {}).items():
            Path(self.dir, name).write_text(text)
        Path(self.config).write_text(config)
        self.proc = subprocess.Popen(
            [canemud or find_canemud(), "--config", self.config, "--socket", self.socket],
            stderr=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
        )
        self.log = b""
        want = f"listening on {self.socket}".encode()
        deadline = time.monotonic() + timeout
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
        connect(self.socket)

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        if self.proc.stderr is not None:
            self.proc.stderr.close()
        shutil.rmtree(self.dir, ignore_errors=True)

    def __enter__(self) -> "Daemon":
        return self

    def __exit__(self, *exc) -> None:
        self.stop()
