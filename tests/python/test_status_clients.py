"""canemu status names a python-can process by its program and counts its VCI channels."""

from __future__ import annotations

import json
import os
import subprocess

import can

from conftest import CANEMU_CLI


def test_a_python_can_program_is_named_by_its_program_and_its_channels_are_counted(daemon):
    a = can.Bus(interface="canemu", channel="can0")
    b = can.Bus(interface="canemu", channel="can1")
    try:
        status = json.loads(subprocess.run(
            [str(CANEMU_CLI), "--socket", daemon.socket, "status", "--json"],
            capture_output=True, text=True, timeout=30, check=True).stdout)
        [me] = [c for c in status["client_list"] if c["pid"] == os.getpid()]
        # pytest runs as "python -m pytest" (or python3...): the interpreter and its module.
        assert me["name"].startswith("python") and me["name"].endswith(" -m pytest (VCI)")
        assert me["channels"] == 2
    finally:
        a.shutdown()
        b.shutdown()
