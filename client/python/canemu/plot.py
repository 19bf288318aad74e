"""canemu.plot: a picture of what happened on a bus over simulated time, drawn with matplotlib.

`canemu plot BUS [NODE...] -o FILE` fetches the timeline from canemud (the JSON object that
`canemu timeline BUS --json` prints) and pipes it into `python -m canemu.plot --output FILE`.
The picture has two panels over the same time axis: the bus load in percent per 100 ms bin,
and TEC and REC of each node with the error-warning (96), error-passive (128) and bus-off (256)
limits. The file's extension chooses the format (.png, .svg, .pdf).

Every error is told for what it is, with exit status 2: a format that is not one of these, a
folder that is not there, matplotlib missing (with how to install it), a file that cannot be
written, input that is not the timeline.

`series()` gives the lines as numbers, so that what is drawn can be checked without looking.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

FORMATS = {".png", ".svg", ".pdf"}
LIMITS = {"warning": 96, "passive": 128, "bus-off": 256}


def series(timeline: dict) -> dict:
    """The lines of the picture, times in seconds: `load` (x, percent) with a point at the start
    and end of every bin, and per node `tec` and `rec` as steps (x, value): from simulated time 0
    (counters 0), one point at the instant of each of the node's samples (every row of `canemu
    timeline`), and the last value held to the timeline's end, or for a node whose device has
    gone (`gone_at_ns`) to the instant it went."""
    end = timeline["now_ns"] / 1e9
    load = timeline["load"]
    bin_s = load["bin_ns"] / 1e9
    xs: list[float] = []
    ys: list[float] = []
    for k, busy in enumerate(load["busy_ns"]):
        start = load["start_ns"] / 1e9 + k * bin_s
        percent = 100.0 * busy / load["bin_ns"]
        xs += [start, start + bin_s]
        ys += [percent, percent]
    nodes = {}
    for node in timeline["nodes"]:
        steps = {"tec": ([0.0], [0]), "rec": ([0.0], [0])}
        for s in node["samples"]:
            for key in ("tec", "rec"):
                x, y = steps[key]
                x.append(s["at_ns"] / 1e9)
                y.append(s[key])
        until = node["gone_at_ns"] / 1e9 if "gone_at_ns" in node else end
        for x, y in steps.values():
            x.append(max(until, x[-1]))
            y.append(y[-1])
        nodes[node["name"]] = {key: (x, y) for key, (x, y) in steps.items()}
    return {"load": (xs, ys), "nodes": nodes, "end": end}


def figure(timeline: dict, title: str | None = None):
    """The matplotlib Figure of `timeline`: its second axes hold one line per node and counter,
    labelled "NODE TEC" and "NODE REC", drawn as steps after each point of series()."""
    import matplotlib

    matplotlib.use("Agg")  # files only, no display
    import matplotlib.pyplot as plt

    lines = series(timeline)
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(10, 6))
    fig.suptitle(title or f"bus {timeline['bus']}")
    x, y = lines["load"]
    top.plot(x, y, color="tab:blue", linewidth=1)
    top.set_ylabel("bus load (%)")
    top.set_ylim(0, 100)
    top.grid(True, alpha=0.3)
    gone = {n["name"] for n in timeline["nodes"] if "gone_at_ns" in n}
    for name, counters in lines["nodes"].items():
        suffix = " (gone)" if name in gone else ""
        (line,) = bottom.step(*counters["tec"], where="post", label=f"{name} TEC{suffix}")
        bottom.step(*counters["rec"], where="post", label=f"{name} REC{suffix}", linestyle="--",
                    color=line.get_color())
    for label, value in LIMITS.items():
        bottom.axhline(value, color="grey", linewidth=0.6, linestyle=":")
        bottom.annotate(label, (0, value), xycoords=("axes fraction", "data"), fontsize=7,
                        color="grey", va="bottom")
    bottom.set_ylabel("error counters")
    bottom.set_xlabel("simulated time (s)")
    bottom.set_xlim(0, max(lines["end"], 1e-9))
    bottom.grid(True, alpha=0.3)
    if lines["nodes"]:
        bottom.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return fig


class PlotError(Exception):
    """What keeps the picture from being drawn, in words for the person who asked."""


def check_output(output: str) -> None:
    """Refuses, before anything is drawn, a name whose extension is not a format of FORMATS and
    a folder that is not there."""
    path = Path(output)
    suffix = path.suffix.lower()
    formats = sorted(FORMATS)
    if not suffix:
        raise PlotError(f"{output}: the name needs an extension for the format: "
                        f"{', '.join(formats[:-1])} or {formats[-1]}")
    if suffix not in FORMATS:
        raise PlotError(f"{output}: cannot draw a {suffix} file; the formats are "
                        f"{', '.join(formats[:-1])} and {formats[-1]}")
    folder = path.parent
    if not folder.exists():
        raise PlotError(f"{output}: no folder {folder} (make it first)")
    if not folder.is_dir():
        raise PlotError(f"{output}: {folder} is not a folder")


def draw(timeline: dict, output: str, title: str | None = None) -> None:
    """Writes the picture of `timeline` to `output` (PlotError when it cannot)."""
    check_output(output)
    try:
        import matplotlib  # noqa: F401
    except ImportError as e:
        raise PlotError(
            f"matplotlib is not installed for {sys.executable} ({e}): install it with "
            f"`sudo apt install python3-matplotlib` (Debian's python3) or `{sys.executable} -m pip "
            f"install matplotlib` (a virtual environment), or name an interpreter that has it in "
            f"CANEMU_PYTHON") from e
    fig = figure(timeline, title)
    import matplotlib.pyplot as plt

    try:
        fig.savefig(output)
    except OSError as e:
        raise PlotError(f"{output}: cannot write it: {e.strerror or e}") from e
    finally:
        plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m canemu.plot", description=__doc__.split("\n")[0])
    parser.add_argument("--output", "-o", required=True, help="FILE.png, FILE.svg or FILE.pdf")
    parser.add_argument("--title", default=None)
    parser.add_argument("--input", default="-", help="the timeline JSON (default: standard input)")
    args = parser.parse_args(argv)
    try:
        check_output(args.output)
        try:
            text = sys.stdin.read() if args.input == "-" else Path(args.input).read_text()
        except OSError as e:
            raise PlotError(f"{args.input}: cannot read the timeline: {e.strerror or e}") from e
        try:
            timeline = json.loads(text)
        except ValueError as e:
            raise PlotError(f"the timeline is not JSON: {e}") from e
        try:
            draw(timeline, args.output, args.title)
        except (KeyError, TypeError) as e:
            raise PlotError(f"the timeline lacks {e} (the JSON of canemu timeline --json)") from e
    except PlotError as e:
        print(f"canemu: plot: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
