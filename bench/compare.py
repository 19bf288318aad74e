"""Compares two sets of `make bench` results: every figure of every benchmark found in both,
A beside B with the ratio B / A. A developer runs it before merging (results of main as A,
of the change as B; both measured on the same machine, one after the other).

    python bench/compare.py build-main/bench-results build/bench-results
    make bench-compare A=build-main/bench-results B=build/bench-results

Each directory holds the JSON files `make bench` writes (firmware_model.json, ipc.json,
daemon.json, python.json): a "benchmarks" list of entries with a "name" and numeric figures.
Book-keeping fields (iterations, repetition and family indices, threads) are left out. Whether
a ratio above 1 is better depends on the figure: times (real_time, cpu_time, *_us) are better
lower, rates (*_per_second, times_real_time) higher.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Dict, List, Tuple

SKIPPED = {"iterations", "repetitions", "repetition_index", "threads", "family_index",
           "per_family_instance_index"}


def figures(path: Path) -> Dict[str, Dict[str, float]]:
    """benchmark name -> figure name -> value, from one results file."""
    with open(path) as f:
        data = json.load(f)
    out: Dict[str, Dict[str, float]] = {}
    for entry in data.get("benchmarks", []):
        name = entry.get("name")
        if not isinstance(name, str):
            continue
        out[name] = {key: float(value) for key, value in entry.items()
                     if key not in SKIPPED and isinstance(value, (int, float))
                     and not isinstance(value, bool)}
    return out


def compare(a_dir: Path, b_dir: Path) -> List[Tuple[str, str, str, float, float, str]]:
    """Rows (file, benchmark, figure, A, B, ratio as text) for what both sets have."""
    rows = []
    for a_file in sorted(a_dir.glob("*.json")):
        b_file = b_dir / a_file.name
        if not b_file.exists():
            continue
        a, b = figures(a_file), figures(b_file)
        for bench in sorted(a.keys() & b.keys()):
            for key in sorted(a[bench].keys() & b[bench].keys()):
                x, y = a[bench][key], b[bench][key]
                ratio = f"{y / x:.3f}" if x != 0 else "-"
                rows.append((a_file.stem, bench, key, x, y, ratio))
    return rows


def number(v: float) -> str:
    return f"{v:.0f}" if abs(v) >= 1000 or v == int(v) else f"{v:.4g}"


def main(argv: List[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("a", type=Path, help="results directory A (the baseline)")
    parser.add_argument("b", type=Path, help="results directory B")
    args = parser.parse_args(argv)
    for d in (args.a, args.b):
        if not d.is_dir():
            print(f"bench-compare: {d} is not a directory of results (make bench writes "
                  f"BUILD/bench-results)", file=sys.stderr)
            return 2
    rows = compare(args.a, args.b)
    if not rows:
        print(f"bench-compare: {args.a} and {args.b} have no benchmark in common", file=sys.stderr)
        return 1
    widths = [max(len(r[i]) for r in rows) for i in (0, 1, 2)]
    print(f"{'file':{widths[0]}}  {'benchmark':{widths[1]}}  {'figure':{widths[2]}}  "
          f"{'A':>14}  {'B':>14}  {'B/A':>7}")
    for file, bench, key, x, y, ratio in rows:
        print(f"{file:{widths[0]}}  {bench:{widths[1]}}  {key:{widths[2]}}  {number(x):>14}  "
              f"{number(y):>14}  {ratio:>7}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
