"""The VCI .NET API (docs/dotnet.md): a C# program on vcinet2.dll under Mono and a python-can
program exchange frames on one bus, in real time (client/examples/dotnet/dotnet_talk.cs)."""

from __future__ import annotations

import os
import shutil
import subprocess

import can
import pytest

from conftest import BUILD, Canemud

TALK = BUILD / "bin" / "dotnet_talk.exe"

pytestmark = pytest.mark.skipif(
    not TALK.exists() or shutil.which("mono") is None,
    reason="the C# examples are built when Mono's mcs is there (make build installs it)",
)


def test_a_csharp_program_and_python_can_exchange_frames_on_one_bus():
    with Canemud("realtime") as daemon:
        bus = can.Bus(interface="canemu", channel="can0")
        try:
            env = {**os.environ, "CANEMU_SOCKET": daemon.socket, "MONO_PATH": str(BUILD / "lib"),
                   "LD_LIBRARY_PATH": str(BUILD / "lib")}
            program = subprocess.Popen(["mono", str(TALK), "ixxat0"], env=env, text=True,
                                       stdout=subprocess.PIPE, stderr=subprocess.PIPE)
            try:
                hello = bus.recv(15)
                assert hello is not None, "nothing from the C# program"
                assert (hello.arbitration_id, bytes(hello.data)) == (0x100, b"\x01\x02\x03")
                assert not hello.is_extended_id
                bus.send(can.Message(arbitration_id=0x200, data=b"\xaa\xbb", is_extended_id=False))
                answer = bus.recv(15)
                while answer is not None and answer.arbitration_id == 0x200:
                    answer = bus.recv(15)  # python-can's own frame, when it receives its own
                assert answer is not None, "no answer from the C# program"
                assert (answer.arbitration_id, bytes(answer.data)) == (0x101, b"\xab\xbc")
                out, err = program.communicate(timeout=30)
            finally:
                if program.poll() is None:
                    program.kill()
                    program.wait()
            assert program.returncode == 0, err
            assert out.splitlines() == ["sent 100 01 02 03", "got 200 AA BB", "sent 101"]
        finally:
            bus.shutdown()
