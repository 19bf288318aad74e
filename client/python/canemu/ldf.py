"""LIN description files (LDF) as simulated LIN nodes of canemud (``[[lin_node]]``,
docs/lin.md), read with the ldfparser package.

Every node of the LDF becomes a ``[[lin_node]]`` on the given bus, except those a real program
plays (``real``): each responds with the frames it publishes, their signals at their initial
values; the master (unless it is real) runs the LDF's schedule tables. From the command line::

    python -m canemu.ldf doors.ldf --bus lin0 --real DoorRight >> canemu.toml

Decisions (docs/lin.md, "LDF import"):

- A frame's data are its signals' initial values, encoded by ldfparser.
- The checksum of a frame follows its publisher's protocol (a slave's ``LIN_protocol``, the
  master's: the cluster's ``LIN_protocol_version``): classic for LIN 1.x, enhanced for LIN 2.x,
  ISO 17987 (``"ISO17987:2015"``) and SAE J2602-1 (``"J2602_1_1.0"``, built on LIN 2.0);
  diagnostic frames are classic on the wire whatever the cluster.
- SAE J2602 where it differs from LIN 2.0: its language version (``"J2602_3_1.0"``) is read as
  LIN 2.0's; node attributes without a ``response_tolerance`` get J2602's 40 % (ldfparser's
  defaults: 40 %, a 48-bit header, 100 ms wake-up and power-on), which canemud's LIN timing
  (the 1.4 factor of LIN 2.x) already is. J2602-1 names 10.417 kbit/s: an LDF that says
  otherwise is taken as written (the import warns). ``J2602_1_2.0`` (J2602:2021) is refused by
  ldfparser; its error is shown.
- An event-triggered frame's associated frames answer it from their publishers; the LDF's
  collision resolving table is not needed (the commander polls the associated frames itself)
  but stays a table of its own.
- Diagnostic and node configuration entries of a schedule table become slots of the master
  request frame 3Ch (the slave response entry: 3Dh); the emulated nodes carry no diagnostic
  data, so a 3Dh slot is unanswered unless a real program answers it.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any, Callable, Dict, Iterable, List, Optional

from canemu._toml_text import toml_value

MASTER_REQUEST = 0x3C
SLAVE_RESPONSE = 0x3D


J2602_BITRATE = 10417  # SAE J2602-1: 10.417 kbit/s


def _is_j2602(version: Any) -> bool:
    return type(version).__name__ == "J2602Version"


def _checksum(version: Any, path: str) -> str:
    """The checksum model of a node speaking `version` (ldfparser's LinVersion,
    Iso17987Version or J2602Version)."""
    kind = type(version).__name__
    if kind in ("Iso17987Version", "J2602Version"):
        return "enhanced"  # ISO 17987 is LIN 2.2A's successor; J2602-1 is built on LIN 2.0
    if kind == "LinVersion":
        return "enhanced" if version.major >= 2 else "classic"
    raise ValueError(f"{path}: protocol version {version!s} is not LIN 1.x/2.x, ISO 17987 or "
                     f"SAE J2602")


def _ldfparser_version() -> str:
    try:
        from importlib.metadata import version
        return version("ldfparser")
    except Exception:  # not installed as a distribution
        return "(unknown version)"


def _delay(seconds: float) -> str:
    us = round(seconds * 1_000_000)
    return f"{us // 1000}ms" if us % 1000 == 0 else f"{us}us"


def lin_nodes(path: str, bus: str, real: Iterable[str] = (),
              schedule: Optional[str] = None,
              warn: Optional[Callable[[str], None]] = None) -> List[Dict[str, Any]]:
    """The ``[[lin_node]]`` tables (as dicts) for the LDF at `path` on `bus`, without the nodes
    named in `real`. `schedule`: the table the master runs from the start (default: the
    first). `warn` gets what is imported although a standard says otherwise. ValueError naming
    what does not fit."""
    import ldfparser  # only needed here

    try:
        ldf = ldfparser.parse_ldf(path)
    except ValueError as e:  # what ldfparser refuses, e.g. a J2602:2021 ("J2602_1_2.0") LDF
        raise ValueError(f"{path}: ldfparser {_ldfparser_version()} does not take it: {e}") from e
    master = ldf.get_master()
    slaves = ldf.get_slaves()
    names = [master.name] + [s.name for s in slaves]
    real = list(real)
    for r in real:
        if r not in names:
            raise ValueError(f"{path}: no node is named {r!r} (nodes: {', '.join(names)})")
    cluster = ldf.get_protocol_version()
    bitrate = int(ldf.get_baudrate())
    checksum_of = {master.name: _checksum(cluster, path)}
    for s in slaves:
        checksum_of[s.name] = _checksum(getattr(s, "lin_protocol", None) or cluster, path)
    if _is_j2602(cluster) and bitrate != J2602_BITRATE and warn is not None:
        warn(f"{path}: an SAE J2602 cluster at {bitrate} bit/s (J2602-1 names 10417 bit/s); "
             f"taken as written")

    carried_by: Dict[int, int] = {}  # frame ID -> the event-triggered frame that carries it
    for et in ldf.get_event_triggered_frames():
        for f in et.frames:
            carried_by[f.frame_id] = et.frame_id

    def responses(node_name: str) -> List[Dict[str, Any]]:
        out = []
        for f in ldf.get_unconditional_frames():
            if f.publisher is None or f.publisher.name != node_name:
                continue
            values = {s.name: s.init_value for _, s in f.signal_map}
            entry: Dict[str, Any] = {
                "id": f.frame_id,
                "data": list(f.encode_raw(values)),
                "checksum": checksum_of[node_name],
            }
            if f.frame_id in carried_by:
                entry["event_triggered"] = carried_by[f.frame_id]
            out.append(entry)
        return out

    def slot(entry) -> Dict[str, Any]:
        delay = _delay(entry.delay)
        frame = getattr(entry, "frame", None)
        kind = type(frame).__name__ if frame is not None else type(entry).__name__
        if kind == "LinUnconditionalFrame":
            return {"frame": frame.frame_id, "delay": delay}
        if kind == "LinEventTriggeredFrame":
            return {"event_triggered": frame.frame_id,
                    "frames": [f.frame_id for f in frame.frames], "delay": delay}
        if kind == "LinSporadicFrame":
            return {"sporadic": [f.frame_id for f in frame.frames], "delay": delay}
        if kind == "SlaveResponseEntry":
            return {"frame": SLAVE_RESPONSE, "delay": delay}
        return {"frame": MASTER_REQUEST, "delay": delay}  # diagnostic, node configuration

    nodes = []
    for name in names:
        if name in real:
            continue
        node: Dict[str, Any] = {"name": _node_name(name), "bus": bus, "bitrate": bitrate}
        if name == master.name:
            tables = list(ldf.get_schedule_tables())
            if tables:
                chosen = schedule or tables[0].name
                if chosen not in [t.name for t in tables]:
                    raise ValueError(f"{path}: no schedule table is named {chosen!r} (tables: "
                                     f"{', '.join(t.name for t in tables)})")
                node["schedule"] = _node_name(chosen)
                node["schedules"] = [
                    {"name": _node_name(t.name), "slots": [slot(e) for e in t.schedule]}
                    for t in tables if t.schedule
                ]
        node["response"] = responses(name)
        nodes.append(node)
    return nodes


def _node_name(name: str) -> str:
    """An LDF identifier as a canemud name (lower case; a-z, 0-9, '_', '-')."""
    out = "".join(c if c.isalnum() or c in "_-" else "_" for c in name.lower())
    return out[:28]


def _value(v: Any) -> str:
    """A TOML value; identifiers and data bytes in hexadecimal."""
    return toml_value(v, hex_ints=True)


def to_toml(nodes: List[Dict[str, Any]], source: str = "") -> str:
    """The ``[[lin_node]]`` tables as TOML text for canemud's configuration."""
    lines = [f"# LIN nodes from {source} (canemu.ldf)" if source else "# LIN nodes (canemu.ldf)"]
    for node in nodes:
        lines += ["", "[[lin_node]]"]
        for key in ("name", "bus", "bitrate", "schedule"):
            if key in node:
                value = node[key]
                lines.append(f"{key} = {value if key == 'bitrate' else _value(value)}")
        for table in node.get("schedules", []):
            lines += ["", "[[lin_node.schedules]]", f"name = {_value(table['name'])}", "slots = ["]
            lines += [f"  {_value(s)}," for s in table["slots"]]
            lines.append("]")
        for r in node.get("response", []):
            lines += ["", "[[lin_node.response]]"]
            lines += [f"{k} = {_value(v)}" for k, v in r.items()]
    return "\n".join(lines) + "\n"


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m canemu.ldf",
        description="an LDF as canemud's simulated LIN nodes ([[lin_node]] TOML on stdout)")
    parser.add_argument("ldf", help="the LIN description file")
    parser.add_argument("--bus", required=True, help="the LIN bus of canemud's configuration")
    parser.add_argument("--real", action="append", default=[],
                        help="a node a real program plays (not simulated); repeatable")
    parser.add_argument("--schedule", help="the table the master runs (default: the first)")
    args = parser.parse_args(argv)
    try:
        nodes = lin_nodes(args.ldf, args.bus, args.real, args.schedule,
                          warn=lambda text: print(f"canemu.ldf: warning: {text}", file=sys.stderr))
    except (OSError, ValueError) as e:
        print(f"canemu.ldf: {e}", file=sys.stderr)
        return 1
    except Exception as e:  # ldfparser's syntax errors come as lark exceptions
        print(f"canemu.ldf: {args.ldf}: not a readable LDF: {e}", file=sys.stderr)
        return 1
    sys.stdout.write(to_toml(nodes, args.ldf))
    return 0


if __name__ == "__main__":
    sys.exit(main())
