"""The examples' program under test written in C: the heartbeat program beside canemud (a build
tree's build/bin), else compiled from heartbeat.c against the installed VCI library."""

import shutil
import subprocess
from pathlib import Path

import pytest

from canemu.testing import find_canemud


@pytest.fixture(scope="session")
def heartbeat(tmp_path_factory: pytest.TempPathFactory) -> str:
    built = Path(find_canemud()).with_name("heartbeat")
    if built.exists():
        return str(built)
    source = Path(__file__).with_name("heartbeat.c")
    program = tmp_path_factory.mktemp("heartbeat") / "heartbeat"
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "canemu-vcinpl"],
                           capture_output=True, text=True)
    if shutil.which("cc") is None or flags.returncode != 0:
        pytest.fail("heartbeat: not built beside canemud, and no cc with pkg-config's "
                    f"canemu-vcinpl to build it ({flags.stderr.strip()})")
    subprocess.run(["cc", "-std=c99", "-o", str(program), str(source), *flags.stdout.split()],
                   check=True)
    return str(program)
