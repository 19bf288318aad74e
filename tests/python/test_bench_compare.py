"""bench/compare.py: the figures two `make bench` result sets share, with B / A."""

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def write(directory: Path, name: str, benchmarks) -> None:
    directory.mkdir(exist_ok=True)
    (directory / name).write_text(json.dumps({"context": {}, "benchmarks": benchmarks}))


def run(*args):
    return subprocess.run([sys.executable, str(ROOT / "bench" / "compare.py"), *map(str, args)],
                          capture_output=True, text=True)


def test_shared_figures_side_by_side_with_their_ratio(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    write(a, "firmware_model.json", [
        {"name": "BM_Bus", "run_type": "iteration", "iterations": 100, "real_time": 0.02,
         "times_real_time": 500.0, "time_unit": "ms"},
        {"name": "BM_OnlyInA", "real_time": 1.0},
    ])
    write(b, "firmware_model.json", [
        {"name": "BM_Bus", "iterations": 300, "real_time": 0.01, "times_real_time": 1000.0},
    ])
    write(a, "python.json", [{"name": "canemu_plugin_stepped", "frames_per_second": 168000}])
    write(b, "python.json", [{"name": "canemu_plugin_stepped", "frames_per_second": 336000}])
    write(a, "ipc.json", [{"name": "BM_Ring", "items_per_second": 1e7}])  # not in B: left out
    done = run(a, b)
    assert done.returncode == 0, done.stderr
    lines = [line.split() for line in done.stdout.splitlines()]
    assert lines == [
        ["file", "benchmark", "figure", "A", "B", "B/A"],
        ["firmware_model", "BM_Bus", "real_time", "0.02", "0.01", "0.500"],
        ["firmware_model", "BM_Bus", "times_real_time", "500", "1000", "2.000"],
        ["python", "canemu_plugin_stepped", "frames_per_second", "168000", "336000", "2.000"],
    ]


def test_a_missing_directory_is_named_and_nothing_common_is_an_error(tmp_path):
    done = run(tmp_path / "nowhere", tmp_path)
    assert done.returncode == 2
    assert f"{tmp_path / 'nowhere'} is not a directory of results" in done.stderr
    a, b = tmp_path / "a", tmp_path / "b"
    write(a, "ipc.json", [{"name": "BM_Ring", "items_per_second": 1.0}])
    write(b, "daemon.json", [{"name": "BM_Latency", "p50_us": 1.0}])
    done = run(a, b)
    assert done.returncode == 1
    assert "have no benchmark in common" in done.stderr
