#!/usr/bin/env python3
"""Runs the examples of a Markdown page word for word and compares what they print.

Every ```console block of the page is an example to run. In it, a line starting with `$ ` is a
command; the lines under it, up to the next command or the end of the block, are what it prints
(standard output and standard error together). A command ending in `&` runs in the background as
a job of the session (a simple command, so that `kill %?name` and `wait` work as in a
terminal); the next command starts once it has printed its first line (as a user waits to see
a program come up), and the lines under it are the whole output of that process, whenever it
comes (the runner waits for it at the end of the page, up to --timeout seconds). A line `...`
stands for any number of lines; `...` inside a line stands for any text; runs of blanks count
as one. Nothing under a command: its output is not compared. Blocks tagged ```sh or ```python
are for reading and are not run.

All blocks of one page run in one bash session, in order, in a scratch directory that holds
`build`, `config`, `client`, `docs` and `.venv` as links to the repository's, so that `export`, `cd`
and files written by one command are seen by the next. Background processes still running at
the end of the page are stopped. The page fails at the first command whose output differs, with
both texts.

Pages keep what is the reader's own in `$XDG_RUNTIME_DIR` (sockets; config/examples/
cyclonedds-loopback.xml makes it Cyclone DDS's discovery tag too), so that two users on one
machine do not meet. The session gets a `$XDG_RUNTIME_DIR` of its own, a fresh directory in the
scratch directory, so that two runs at once (two checkouts, two build trees) do not share a
daemon's socket or a DDS rig either. A command that names a path in /tmp, which every user and
every run shares, fails the page before anything runs.

Usage: run_examples.py PAGE.md [--repo DIR] [--build DIR] [--timeout S] [--show]
(--build: what `build` stands for, default the repository's build/)
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import signal
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

MARK = "@@canemu-example@@"
SHARED_PATH = re.compile(r"(?<![\w./$}-])/tmp(/|\b)")


@dataclass
class Command:
    line: int  # of the page, 1-based
    text: str
    expected: list[str] = field(default_factory=list)
    background: bool = False


def parse(page: str) -> list[Command]:
    commands: list[Command] = []
    in_block = False
    for number, raw in enumerate(page.splitlines(), start=1):
        stripped = raw.strip()
        if not in_block:
            if stripped == "```console":
                in_block = True
            continue
        if stripped.startswith("```"):
            in_block = False
            continue
        if raw.startswith("$ "):
            text = raw[2:].rstrip()
            background = text.endswith("&") and not text.endswith("&&")
            if background:
                text = text[:-1].rstrip()
            commands.append(Command(number, text, background=background))
        elif commands:
            commands[-1].expected.append(raw.rstrip())
    for c in commands:
        while c.expected and c.expected[-1] == "":
            c.expected.pop()
    return commands


def squeeze(line: str) -> str:
    """Runs of blanks count as one (a table's column widths are not the point of an example)."""
    return " ".join(line.split())


def line_pattern(expected: str) -> re.Pattern:
    parts = [re.escape(p) for p in squeeze(expected).split("...")]
    return re.compile("^" + ".*".join(parts) + "$")


def matches(expected: list[str], actual: list[str]) -> bool:
    """Line by line; a line `...` takes any number of lines (backtracking)."""

    def go(i: int, j: int) -> bool:
        if i == len(expected):
            return j == len(actual)
        if expected[i].strip() == "...":
            return any(go(i + 1, k) for k in range(j, len(actual) + 1))
        return (j < len(actual) and bool(line_pattern(expected[i]).match(squeeze(actual[j])))
                and go(i + 1, j + 1))

    return go(0, 0)


def script_for(commands: list[Command], logs: Path, timeout: float) -> str:
    lines = ["set +e", "exec 2>&1"]
    for n, c in enumerate(commands):
        lines.append(f"echo {MARK}{n}")
        if c.background:
            log = logs / f"bg{n}.log"
            q = shlex.quote(str(log))
            lines.append(f"{c.text} > {q} 2>&1 &")
            lines.append(f"echo $! > {shlex.quote(str(logs / f'bg{n}.pid'))}")
            # As a user waits to see a program say it is up before typing on: the next command
            # starts once this one printed its first line (or ended), at most --timeout seconds.
            lines.append(f"for _ in $(seq {int(timeout * 100)}); do [ -s {q} ] && break; "
                         f"kill -0 $! 2>/dev/null || break; sleep 0.01; done")
        else:
            lines.append(c.text)
    lines.append(f"echo {MARK}end")
    return "\n".join(lines) + "\n"


def stop(pid: int) -> None:
    try:
        os.killpg(pid, signal.SIGTERM)
    except ProcessLookupError:
        pass


def run_page(page_path: Path, repo: Path, timeout: float, show: bool = False,
             build: Path | None = None) -> int:
    commands = parse(page_path.read_text())
    if not commands:
        # A page on the list of tests with nothing to run would pass whatever it says.
        print(f"{page_path}: no ```console examples to run: take the page off the list")
        return 1
    shared = [c for c in commands if SHARED_PATH.search(c.text)]
    for c in shared:
        print(f"{page_path}:{c.line}: $ {c.text}")
        print("  names a path in /tmp, which every user and every test run shares: use "
              "$XDG_RUNTIME_DIR (tests/README.md)")
    if shared:
        print(f"{page_path}: {len(commands)} commands, FAILED")
        return 1
    with tempfile.TemporaryDirectory(prefix="canemu-examples-") as scratch:
        work = Path(scratch)
        logs = work / ".logs"
        logs.mkdir()
        # The reader's runtime directory: this run's own (mode 0700, as systemd makes it).
        runtime = work / ".run"
        runtime.mkdir(mode=0o700)
        for name in ("config", "client", "docs", ".venv"):
            if (repo / name).exists():
                (work / name).symlink_to(repo / name)
        (work / "build").symlink_to(build or repo / "build")
        env = dict(os.environ)
        env.pop("CANEMU_SOCKET", None)
        env["XDG_RUNTIME_DIR"] = str(runtime)
        proc = subprocess.Popen(
            ["bash", "--noprofile", "--norc", "-m"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            cwd=work,
            env=env,
            text=True,
            start_new_session=True,
        )
        try:
            out, _ = proc.communicate(script_for(commands, logs, timeout), timeout=timeout * 4)
        except subprocess.TimeoutExpired:
            stop(proc.pid)
            print(f"{page_path}: the examples did not finish within {timeout * 4:.0f} s")
            return 1
        # Split the session's output at the markers.
        outputs: dict[int, list[str]] = {}
        current = None
        for raw in out.splitlines():
            if raw.startswith(MARK):
                tag = raw[len(MARK):]
                current = None if tag == "end" else int(tag)
                if current is not None:
                    outputs[current] = []
            elif current is not None:
                outputs[current].append(raw.rstrip())
        failures = 0
        for n, c in enumerate(commands):
            if c.background:
                pid_file = logs / f"bg{n}.pid"
                pid = int(pid_file.read_text()) if pid_file.exists() else None
                if c.expected and pid is not None:
                    waited = wait_for(pid, timeout)
                    if not waited:
                        stop(pid)
                actual = (logs / f"bg{n}.log").read_text().splitlines() if c.expected else []
            else:
                actual = outputs.get(n, [])
            if c.background and not c.expected and show:
                log = logs / f"bg{n}.log"
                actual = log.read_text().splitlines() if log.exists() else []
            if show:
                print(f"$ {c.text}{' &' if c.background else ''}")
                print("\n".join(actual))
            if c.expected and not show and not matches(c.expected, [a.rstrip() for a in actual]):
                failures += 1
                print(f"{page_path}:{c.line}: $ {c.text}{' &' if c.background else ''}")
                print("  expected:")
                print("\n".join("    " + e for e in c.expected))
                print("  got:")
                print("\n".join("    " + a for a in actual) or "    (nothing)")
                break
        # Whatever the page left running (its session's process group: the shell started a new
        # session, and its background jobs stay in it).
        stop(proc.pid)
        ran = len(commands)
        print(f"{page_path}: {ran} commands, {'all as shown' if not failures else 'FAILED'}")
        return 1 if failures else 0


def wait_for(pid: int, timeout: float) -> bool:
    """Waits until process `pid` (not our child) has exited."""
    import time

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        # A zombie of the finished session still answers kill(0); /proc tells.
        try:
            state = Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0]
            if state == "Z":
                return True
        except OSError:
            return True
        time.sleep(0.02)
    return False


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("page", type=Path)
    parser.add_argument("--repo", type=Path, default=Path(__file__).resolve().parents[2])
    parser.add_argument("--build", type=Path, default=None)
    parser.add_argument("--timeout", type=float, default=20.0)
    parser.add_argument("--show", action="store_true",
                        help="print what every command printed (to write a page's examples)")
    args = parser.parse_args()
    return run_page(args.page, args.repo.resolve(), args.timeout, args.show,
                    args.build.resolve() if args.build else None)


if __name__ == "__main__":
    sys.exit(main())
