"""pytest plugin of canemu (registered through the `pytest11` entry point, so installing the
canemu package brings it): the `canemu` fixture, a private canemud per test (canemu.bench.Bench),
and a failing test's report with its buses' traces. docs/testing.md is the tutorial.

    @pytest.mark.canemu(config="bench.toml", time="stepped")
    def test_sender(canemu):
        bus = canemu.bus("can0")
        ...

Where the configuration comes from, first found: the marker's `config_text`, the marker's
`config` (a path, from the test file's folder), the ini option `canemu_config` (from the ini
file's folder), canemud's embedded default. The time mode: the marker's `time`, the ini
option `canemu_time`, the configuration's.
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterator, Optional

import pytest

from .bench import Bench

_KEY = pytest.StashKey[Bench]()


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addini("canemu_config", "canemud's configuration for the canemu fixture (a TOML file, "
                  "relative to the ini file's folder)", default="")
    parser.addini("canemu_time", "time mode for the canemu fixture: realtime, stepped or scaled:F "
                  "(default: the configuration's)", default="")


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        "canemu(config=None, config_text=None, time=None, files=None): the canemu fixture's "
        "canemud: a configuration file (from the test file's folder) or its text, the time mode "
        "(realtime, stepped, scaled:F), more files for its folder (name -> text)")


def _settings(request: pytest.FixtureRequest):
    marker = request.node.get_closest_marker("canemu")
    kwargs = dict(marker.kwargs) if marker else {}
    unknown = set(kwargs) - {"config", "config_text", "time", "files"}
    if marker and (marker.args or unknown):
        raise pytest.UsageError(
            f"{request.node.nodeid}: @pytest.mark.canemu takes config=, config_text=, time= and "
            f"files= (got {', '.join([*map(repr, marker.args), *sorted(unknown)])})")
    text: Optional[str] = kwargs.get("config_text")
    folder: Optional[Path] = None
    path: Optional[Path] = None
    if text is None and kwargs.get("config"):
        path = Path(request.node.path).parent / kwargs["config"]
    elif text is None and request.config.getini("canemu_config"):
        base = request.config.inipath.parent if request.config.inipath else request.config.rootpath
        path = base / request.config.getini("canemu_config")
    if path is not None:
        if not path.is_file():
            raise pytest.UsageError(f"{request.node.nodeid}: canemu configuration {path}: no such "
                                    "file")
        text, folder = path.read_text(), path.parent
    time = kwargs.get("time") or request.config.getini("canemu_time") or None
    return text, folder, time, kwargs.get("files")


@pytest.fixture
def canemu(request: pytest.FixtureRequest, tmp_path: Path,
           monkeypatch: pytest.MonkeyPatch) -> Iterator[Bench]:
    """A private canemud for this test (its own socket and folder: tests and pytest-xdist
    workers run side by side), with its buses recorded into tmp_path/canemu."""
    text, folder, time, files = _settings(request)
    bench = Bench(text, trace_dir=tmp_path / "canemu", time=time, config_dir=folder,
                  files=files)
    monkeypatch.setenv("CANEMU_SOCKET", bench.socket)  # libraries and tools started by the test
    request.node.stash[_KEY] = bench
    try:
        yield bench
    finally:
        bench.close()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    outcome = yield
    report = outcome.get_result()
    bench = item.stash.get(_KEY, None)
    if bench is None or report.when != "call" or not report.failed:
        return
    for title, text in bench.report():
        report.sections.append((title, text))
    report.sections.append(("canemu files", f"traces, canemud's log and programs' output: "
                                            f"{bench.trace_dir}"))
