"""A program under test that canemu.bench started: its output in files, waited on without
sleeping blindly."""

from __future__ import annotations

import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import List, Optional

from ._trace import Watch


class ExpectationFailed(AssertionError):
    """What a test waited for did not come; the message says what came instead."""


@dataclass
class Program:
    """A program under test started by Bench.start, its output going to files in the trace
    folder (so that it never blocks on a full pipe)."""

    args: List[str]
    proc: subprocess.Popen
    stdout_path: Path
    stderr_path: Path
    returncode: Optional[int] = None
    _watch: Optional[Watch] = field(default=None, repr=False)

    @property
    def stdout(self) -> str:
        return self.stdout_path.read_text(errors="replace")

    @property
    def stderr(self) -> str:
        return self.stderr_path.read_text(errors="replace")

    def wait(self, timeout: float = 30.0) -> int:
        """Its exit status once it ends; ExpectationFailed, with its output, when it runs on
        for `timeout` seconds (it is killed then)."""
        try:
            self.returncode = self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.kill()
            raise ExpectationFailed(
                f"{self.args[0]} did not end within {timeout} s; its output:\n"
                f"{self.stdout}{self.stderr}") from None
        return self.returncode

    def expect_output(self, text: str, timeout: float = 10.0) -> str:
        """Waits until its standard output holds `text`; returns the first line holding it.
        ExpectationFailed with what it printed when it does not come in `timeout` seconds of
        wall-clock time or the program ends first."""
        deadline = time.monotonic() + timeout
        while True:
            out = self.stdout
            at = out.find(text)
            if at >= 0:
                begin = out.rfind("\n", 0, at) + 1
                end = out.find("\n", at)
                return out[begin : end if end >= 0 else len(out)]
            ended = self.proc.poll() is not None
            left = deadline - time.monotonic()
            if ended or left <= 0:
                what = (f"it ended with status {self.proc.returncode}" if ended else
                        f"not within {timeout} s")
                raise ExpectationFailed(f"{self.args[0]} did not print {text!r} ({what}); "
                                        f"its output:\n{out}{self.stderr}")
            assert self._watch is not None
            self._watch.wait(min(left, 0.5))  # a write to its output files wakes this up

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
        self.returncode = self.proc.wait()
