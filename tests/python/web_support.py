"""`canemu web` for the tests: started from the build tree on a port of its own (port 0: the
kernel picks one, and the tool says which), its log read by a thread, stopped at the end."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request
from typing import Any, Callable, Dict, List, Optional, Tuple

from conftest import CANEMU_CLI
from tools_support import WatchedText

TIMEOUT = 20.0
# Debian's chromium, kept off the network (docs/web.md, "Tests").
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update",
                 "--disable-sync"]


def cli(daemon, *args: str, check: bool = True) -> subprocess.CompletedProcess:
    done = subprocess.run([str(CANEMU_CLI), "--socket", daemon.socket, *args],
                          capture_output=True, text=True, timeout=60)
    if check:
        assert done.returncode == 0, done.stderr
    return done


def status(daemon) -> Dict[str, Any]:
    return json.loads(cli(daemon, "status", "--json").stdout)


class Web:
    """canemu web against `daemon` with `args`; `url` once it serves."""

    def __init__(self, daemon, *args: str) -> None:
        env = {**os.environ, "CANEMU_PYTHON": sys.executable, "PYTHONUNBUFFERED": "1"}
        self.proc = subprocess.Popen(
            [str(CANEMU_CLI), "--socket", daemon.socket, "web", "--listen", "127.0.0.1:0",
             *args], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE, env=env)
        self._log = WatchedText("canemu web's log")
        threading.Thread(target=self._read, daemon=True).start()
        served = self.wait_log(r"serving (http://\S+/)")
        self.url = served.group(1)

    def _read(self) -> None:
        for raw in self.proc.stderr:
            self._log.add(raw.decode(errors="replace"))
        self._log.end()

    @property
    def log(self) -> str:
        """What canemu web logged so far."""
        return self._log.text

    def wait_log(self, pattern: str, timeout: float = TIMEOUT) -> re.Match:
        """The first match of `pattern` in the log, waited for."""
        return self._log.wait_for(pattern, timeout)

    def get(self, path: str, headers: Optional[Dict[str, str]] = None) -> Tuple[int, str]:
        return self.request("GET", path, None, headers)

    def post(self, path: str, body: Any, headers: Optional[Dict[str, str]] = None):
        data = body.encode() if isinstance(body, str) else json.dumps(body).encode()
        return self.request("POST", path, data,
                            {"Content-Type": "application/json", **(headers or {})})

    def request(self, method: str, path: str, data, headers) -> Tuple[int, str]:
        req = urllib.request.Request(self.url + path.lstrip("/"), data=data, method=method,
                                     headers=headers or {})
        try:
            with urllib.request.urlopen(req, timeout=TIMEOUT) as r:
                return r.status, r.read().decode()
        except urllib.error.HTTPError as e:
            return e.code, e.read().decode()

    def state(self) -> Dict[str, Any]:
        code, text = self.get("/api/state")
        assert code == 200, text
        return json.loads(text)

    def wait_state(self, test: Callable[[Dict[str, Any]], bool], what: str) -> Dict[str, Any]:
        """The first snapshot or update the tool pushes (/events) for which `test` holds: each
        has `status`, `ids` and `listening`."""
        last: Dict[str, Any] = {}
        with urllib.request.urlopen(self.url + "events", timeout=TIMEOUT) as stream:
            deadline = time.monotonic() + TIMEOUT
            for raw in stream:
                line = raw.decode()
                if line.startswith("data: "):
                    last = json.loads(line[6:])
                    if last.get("status") is not None and test(last):
                        return last
                assert time.monotonic() < deadline, f"canemu web never showed {what}: {last}"
        raise AssertionError(f"canemu web's events ended before it showed {what}")

    def stop(self) -> int:
        if self.proc.poll() is None:
            self.proc.terminate()
        try:
            return self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            return self.proc.wait()


def browser(playwright):
    """Debian's chromium through Playwright, headless, off the network, in a fresh profile."""
    profile = tempfile.mkdtemp(prefix="canemu-web-chromium-")
    return playwright.chromium.launch_persistent_context(
        profile, executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS,
        viewport={"width": 1400, "height": 1000})


def frame_times(page, seconds: float = 1.0) -> List[float]:
    """The intervals between the page's animation frames over `seconds` of page time, in ms."""
    return page.evaluate("""(ms) => new Promise((done) => {
        const out = []; let last = performance.now(); const end = last + ms;
        const tick = (now) => { out.push(now - last); last = now;
            if (now < end) requestAnimationFrame(tick); else done(out); };
        requestAnimationFrame(tick); })""", seconds * 1000)
