"""A private canemud for test suites and benchmarks: started on its own socket and configuration
in a fresh temporary folder, ready when it says it listens, killed on stop().

    with canemu.testing.Daemon(config_text) as daemon:
        bus = can.Bus(interface="canemu", channel="can0")
        ...
        daemon.wait_log("fault: t=")      # a line of its log, waited for

Its log (standard error) is read all the time by a thread of its own, so that a chatty daemon
never blocks on a full pipe; `log` is what it wrote so far.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import threading
import time
from pathlib import Path
from typing import Dict, Mapping, Optional, Sequence

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

    :param config: the configuration's text (TOML); None: canemud's embedded default.
    :param files: more files for the configuration's folder (scenarios), name -> text.
    :param canemud: the program; default find_canemud().
    :param timeout: seconds to wait for it to listen.
    :param args: more command-line arguments (for example ``["--time", "stepped"]``).
    :param wrap: a command that runs canemud, put before it (for example
        ``["ip", "netns", "exec", "host-a"]``: canemud in that network namespace); it must end
        in canemud's own process (exec), as SIGTERM goes to the process started.
    :param env: more environment variables for canemud (on top of this process's own).
    :param links: more entries of the configuration's folder, name -> an existing path they
        link to (the files a configuration names by relative path); not the configuration's
        own name (canemu.toml), the socket's (canemud.sock) or one of `files`.

    The process talks to this daemon from now on (canemu.connect).
    """

    def __init__(
        self,
        config: Optional[str],
        files: Optional[Dict[str, str]] = None,
        canemud: Optional[str] = None,
        timeout: float = 10.0,
        args: Sequence[str] = (),
        wrap: Sequence[str] = (),
        env: Optional[Mapping[str, str]] = None,
        links: Optional[Mapping[str, Path]] = None,
    ) -> None:
        self.dir = tempfile.mkdtemp(prefix="canemu-")
        for name, target in (links or {}).items():
            if name not in ("canemu.toml", "canemud.sock") and name not in (files or {}):
                os.symlink(target, os.path.join(self.dir, name))
        self.socket = os.path.join(self.dir, "canemud.sock")
        self.config = os.path.join(self.dir, "canemu.toml") if config is not None else None
        for name, text in (files or {}).items():
            Path(self.dir, name).write_text(text)
        command = [*wrap, canemud or find_canemud(), "--socket", self.socket, *args]
        if self.config is not None:
            Path(self.config).write_text(config)
            command += ["--config", self.config]
        self._log = bytearray()
        self._log_changed = threading.Condition()
        self._eof = False
        environment = {**os.environ, **env} if env else None
        self.proc = subprocess.Popen(command, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL,
                                     env=environment)
        self._reader = threading.Thread(target=self._read_log, name="canemud-log", daemon=True)
        self._reader.start()
        try:
            self.wait_log(f"listening on {self.socket}", timeout)
        except RuntimeError as e:
            self.stop()
            raise RuntimeError(f"canemud did not start: {e}") from None
        connect(self.socket)

    def _read_log(self) -> None:
        fd = self.proc.stderr.fileno()
        while True:
            try:
                chunk = os.read(fd, 65536)
            except OSError:
                chunk = b""
            with self._log_changed:
                if chunk:
                    self._log += chunk
                else:
                    self._eof = True
                self._log_changed.notify_all()
            if not chunk:
                return

    @property
    def log(self) -> str:
        """Everything the daemon wrote to its standard error so far."""
        with self._log_changed:
            return self._log.decode(errors="replace")

    def wait_log(self, text: str, timeout: float = 10.0, start: int = 0) -> str:
        """Waits until the log, from character `start` on, holds `text`; returns the first whole
        line that holds it. RuntimeError, with the log, when it does not come in `timeout`
        seconds or the daemon ends first."""
        deadline = time.monotonic() + timeout
        with self._log_changed:
            while True:
                log = self._log.decode(errors="replace")
                at = log.find(text, start)
                if at >= 0:
                    begin = log.rfind("\n", 0, at) + 1
                    end = log.find("\n", at)
                    return log[begin : end if end >= 0 else len(log)]
                left = deadline - time.monotonic()
                if self._eof or left <= 0:
                    what = "it ended" if self._eof else f"not in {timeout} s"
                    raise RuntimeError(f"{text!r} not logged ({what}); the log:\n{log}")
                self._log_changed.wait(left)

    def stop(self, timeout: float = 10.0) -> int:
        """Stops canemud as systemd would (SIGTERM) and returns its exit status; SIGKILL only
        when it does not end within `timeout` seconds. RuntimeError, with its log, when a
        daemon that was running ends other than cleanly (a crash at shutdown is a bug), after
        the cleanup."""
        running = self.proc.poll() is None
        killed = False
        if running:
            self.proc.terminate()
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
                killed = True
        self._reader.join(5)
        if self.proc.stderr is not None:
            self.proc.stderr.close()
        shutil.rmtree(self.dir, ignore_errors=True)
        status = self.proc.returncode
        if running and (killed or status != 0):
            why = f"did not stop within {timeout} s" if killed else f"exited with status {status}"
            raise RuntimeError(f"canemud {why} on SIGTERM; its log:\n{self.log}")
        return status

    def __enter__(self) -> "Daemon":
        return self

    def __exit__(self, *exc) -> None:
        self.stop()
