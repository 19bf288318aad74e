"""CAN databases (DBC) as simulated CAN nodes of canemud (``[[can_node]]``, docs/restbus.md),
read with the cantools package.

Every node of the DBC that no real program plays (``real``) becomes a ``[[can_node]]`` on the
given bus with the messages it sends and their signals' layout. From the command line::

    python -m canemu.dbc vehicle.dbc --bus can0 --real GATEWAY >> canemu.toml

Decisions (docs/restbus.md, "DBC import"), where the DBC leaves a choice open:

- Nodes come in the order of the DBC's ``BU_`` line, then senders the line does not list;
  messages and signals in the order the DBC writes them. Names stay as the DBC writes them.
  A node that sends nothing is a node all the same (it acknowledges frames as its ECU would).
- A message with several senders (``BO_TX_BU_``) goes to the first of them that is not real;
  a message whose senders are all real is left to them; a message without a sender
  (``Vector__XXX``) is skipped with a note.
- The send type is ``GenMsgSendType`` (Vector's names, compared without regard to case):
  ``Cyclic``; ``Spontaneous``, ``OnChange``, ``Event`` (on change); ``CyclicIfActive``,
  ``IfActive``; ``CyclicAndSpontaneous``, ``CyclicAndSpontan``. Without one (also
  ``NoMsgSendType`` and Vector's empty ``vector_leerstring``): cyclic when ``GenMsgCycleTime``
  is above 0, else on change. Any other name is refused. A cyclic kind needs a cycle time.
- The cycle is ``GenMsgCycleTime`` (ms). The first frame's delay after the node starts is
  ``GenMsgStartDelayTime`` (ms), else 0. ``GenMsgDelayTime`` is not a start delay (Vector's
  minimum gap between two spontaneous sends) and is not imported.
- ``GenSigStartValue`` is a raw value; the table's ``initial`` is physical (raw * scale +
  offset). Without one (the signal's attribute, else the attribute definition's default) the
  raw start value is 0, so ``initial`` is the offset. ``GenSigInactiveValue`` (raw, likewise)
  is written as a physical ``inactive`` on the signals of ``cyclic_if_active`` messages only.
  A start value outside ``minimum``..``maximum`` (an "Init" code) is written as it is.
- ``minimum``/``maximum`` are written when the DBC gives a range (not ``[0|0]``). A float
  signal (``SIG_VALTYPE_`` 1 or 2) is ``signed = false`` whatever its ``+``/``-``: IEEE 754
  carries its own sign.
- A CAN FD message (``VFrameFormat`` ``StandardCAN_FD``/``ExtendedCAN_FD``) switches its bit
  rate (``brs``) unless a ``CANFD_BRS`` attribute says ``"0"``.
- Simple multiplexing is carried (one multiplexor; ``SG_MUL_VAL_`` ranges become
  ``multiplexer_ids``); a simulated message with several multiplexors or a multiplexed
  multiplexor (extended multiplexing) is refused.
- ``--counter MSG.SIG``: an integer signal, not the multiplexor. ``--checksum
  MSG.SIG=ALGO[:DATA_ID]``: an 8-bit integer signal in one whole byte; the data ID (0..65535,
  default 0) only for ``crc8_sae_j1850``.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Tuple

from canemu._toml_text import toml_value

CHECKSUMS = ("crc8_sae_j1850", "xor8", "sum8")

_SEND_TYPES = {
    "cyclic": "cyclic",
    "spontaneous": "on_change",
    "onchange": "on_change",
    "event": "on_change",
    "cyclicifactive": "cyclic_if_active",
    "ifactive": "cyclic_if_active",
    "cyclicandspontaneous": "cyclic_and_on_change",
    "cyclicandspontan": "cyclic_and_on_change",
}
_NO_SEND_TYPE = ("", "nomsgsendtype", "vector_leerstring")
_CYCLIC = ("cyclic", "cyclic_if_active", "cyclic_and_on_change")
_FD_LENGTHS = tuple(range(9)) + (12, 16, 20, 24, 32, 48, 64)
_HOUR_MS = 3_600_000


class DbcError(ValueError):
    """A DBC or an option that cannot become canemud's tables; the text names what."""


def _cantools_version() -> str:
    try:
        from importlib.metadata import version
        return version("cantools")
    except Exception:  # not installed as a distribution
        return "(unknown version)"


def _attribute(obj: Any, name: str, definitions: Mapping[str, Any]) -> Any:
    """The value of attribute `name` on a cantools message or signal, else its definition's
    default, else None; enumerations as their names."""
    specifics = getattr(obj, "dbc", None)
    attrs = specifics.attributes if specifics is not None else {}
    definition = definitions.get(name)
    if name in attrs:
        value = attrs[name].value
        if definition is not None and definition.choices and isinstance(value, int):
            return definition.choices[value]
        return value
    if definition is not None:
        return definition.default_value
    return None


def _ms(value: Any, what: str) -> str:
    """A duration attribute in ms as canemud's duration text."""
    try:
        ms = float(value)
    except (TypeError, ValueError):
        raise DbcError(f"{what} {value!r} is not a number of milliseconds") from None
    us = round(ms * 1000)
    return f"{us // 1000}ms" if us % 1000 == 0 else f"{us}us"


def _send(message: Any, definitions: Mapping[str, Any]) -> Tuple[str, Optional[str]]:
    """(send kind, cycle) of a message."""
    name = message.name
    written = _attribute(message, "GenMsgSendType", definitions)
    cycle_ms = message.cycle_time or 0
    if written is None or str(written).lower() in _NO_SEND_TYPE:
        send = "cyclic" if cycle_ms > 0 else "on_change"
    else:
        send = _SEND_TYPES.get(str(written).lower())
        if send is None:
            raise DbcError(f"message {name}: GenMsgSendType {written!r} is not a send type "
                           f"canemu knows (Cyclic, Spontaneous, OnChange, Event, "
                           f"CyclicIfActive, IfActive, CyclicAndSpontaneous, NoMsgSendType)")
    if send not in _CYCLIC:
        return send, None
    if not 1 <= cycle_ms <= _HOUR_MS:
        raise DbcError(f"message {name}: send type {send} needs a GenMsgCycleTime from 1 ms to "
                       f"1 hour, the DBC gives {cycle_ms} ms")
    return send, _ms(cycle_ms, f"message {name}: GenMsgCycleTime")


def _physical(signal: Any, message: str, raw: Any, attribute: str) -> float:
    """The physical value of a raw attribute value of `signal`."""
    try:
        number = float(raw)
    except (TypeError, ValueError):
        raise DbcError(f"signal {message}.{signal.name}: {attribute} {raw!r} is not a "
                       f"number") from None
    return number * float(signal.scale) + float(signal.offset)


def _signal_type(signal: Any, message: str) -> str:
    if not signal.conversion.is_float:
        return "integer"
    if signal.length in (32, 64):
        return f"float{signal.length}"
    raise DbcError(f"signal {message}.{signal.name}: a float of {signal.length} bits (SIG_VALTYPE_ "
                   f"needs 32 or 64)")


def _signal(signal: Any, message: Any, send: str, definitions: Mapping[str, Any]) -> Dict:
    kind = _signal_type(signal, message.name)
    out: Dict[str, Any] = {
        "name": signal.name,
        "start": signal.start,
        "length": signal.length,
        "byte_order": signal.byte_order,
        "signed": bool(signal.is_signed) and kind == "integer",  # a float carries its own sign
        "type": kind,
        "scale": float(signal.scale),
        "offset": float(signal.offset),
    }
    if signal.minimum is not None or signal.maximum is not None:
        out["minimum"] = float(signal.minimum)
        out["maximum"] = float(signal.maximum)
    raw = signal.raw_initial
    if raw is None:
        raw = _attribute(signal, "GenSigStartValue", definitions)
    out["initial"] = _physical(signal, message.name, raw if raw is not None else 0,
                               "GenSigStartValue")
    if send == "cyclic_if_active":
        inactive = _attribute(signal, "GenSigInactiveValue", definitions)
        if inactive is not None:
            out["inactive"] = _physical(signal, message.name, inactive,
                                        "GenSigInactiveValue")
    if signal.unit:
        out["unit"] = signal.unit
    if signal.is_multiplexer:
        out["multiplexer"] = True
    if signal.multiplexer_ids:
        out["multiplexer_ids"] = sorted(int(i) for i in signal.multiplexer_ids)
    return out


def _message(message: Any, definitions: Mapping[str, Any]) -> Dict[str, Any]:
    name = message.name
    multiplexors = [s.name for s in message.signals if s.is_multiplexer]
    nested = [s.name for s in message.signals if s.is_multiplexer and s.multiplexer_ids]
    if len(multiplexors) > 1 or nested:
        raise DbcError(f"message {name}: extended multiplexing (multiplexors "
                       f"{', '.join(multiplexors)}) is not supported; only one multiplexor per "
                       f"message")
    fd = bool(message.is_fd)
    allowed = _FD_LENGTHS if fd else tuple(range(9))
    if message.length not in allowed:
        kind = "a CAN FD" if fd else "a classic CAN"
        raise DbcError(f"message {name}: {message.length} bytes is not {kind} length")
    brs = fd
    if fd:
        switch = _attribute(message, "CANFD_BRS", definitions)
        if switch is not None:
            brs = str(switch) != "0"
    send, cycle = _send(message, definitions)
    out: Dict[str, Any] = {
        "name": name,
        "id": message.frame_id,
        "extended": bool(message.is_extended_frame),
        "fd": fd,
        "brs": brs,
        "length": message.length,
        "send": send,
    }
    if cycle is not None:
        out["cycle"] = cycle
    start_delay = _attribute(message, "GenMsgStartDelayTime", definitions)
    delay = _ms(start_delay or 0, f"message {name}: GenMsgStartDelayTime")
    if float(start_delay or 0) < 0 or float(start_delay or 0) > _HOUR_MS:
        raise DbcError(f"message {name}: GenMsgStartDelayTime {start_delay} ms is not 0 .. 1 hour")
    out["delay"] = delay
    out["signal"] = [_signal(s, message, send, definitions) for s in message.signals]
    return out


def _find(messages: Dict[str, Dict[str, Any]], owner: Dict[str, str], spec: str,
          option: str) -> Dict[str, Any]:
    """The signal table `spec` ("MSG.SIG") names."""
    msg, dot, sig = spec.partition(".")
    if not dot or not msg or not sig:
        raise DbcError(f"{option} {spec!r}: name a signal as MESSAGE.SIGNAL")
    if msg in owner:
        raise DbcError(f"{option} {spec}: message {msg} is sent by {owner[msg]}, which --real "
                       f"names (not simulated)")
    if msg not in messages:
        raise DbcError(f"{option} {spec}: no simulated message is named {msg!r}")
    for s in messages[msg]["signal"]:
        if s["name"] == sig:
            return s
    names = ", ".join(s["name"] for s in messages[msg]["signal"])
    raise DbcError(f"{option} {spec}: message {msg} has no signal {sig!r} (signals: {names})")


def _checksum_spec(spec: str, value: str) -> Tuple[str, Optional[int]]:
    algo, colon, data_id = value.partition(":")
    if algo not in CHECKSUMS:
        raise DbcError(f"--checksum {spec}: {algo!r} is not an algorithm canemud computes "
                       f"({', '.join(CHECKSUMS)})")
    if not colon:
        return algo, None
    if algo != "crc8_sae_j1850":
        raise DbcError(f"--checksum {spec}: {algo} takes no data ID")
    try:
        number = int(data_id, 0)
    except ValueError:
        number = -1
    if not 0 <= number <= 0xFFFF:
        raise DbcError(f"--checksum {spec}: data ID {data_id!r} is not a number 0..65535")
    return algo, number


def _holds_checksum(s: Dict[str, Any]) -> bool:
    if s["length"] != 8 or s["type"] != "integer" or s.get("multiplexer"):
        return False
    # A byte: its lowest bit (little endian) or its highest (big endian) starts the byte.
    return s["start"] % 8 == (0 if s["byte_order"] == "little_endian" else 7)


def can_nodes(path: str, bus: str, real: Iterable[str] = (), counters: Iterable[str] = (),
              checksums: Optional[Mapping[str, str]] = None,
              warn: Optional[Callable[[str], None]] = None) -> List[Dict[str, Any]]:
    """The ``[[can_node]]`` tables (as dicts) for the DBC at `path` on `bus`, without the nodes
    named in `real`. `counters`: "MSG.SIG" alive counters; `checksums`: "MSG.SIG" ->
    "ALGO[:DATA_ID]". `warn` gets the notes (messages skipped). DbcError naming what does not
    fit; OSError when the file cannot be read."""
    import cantools  # only needed here

    with open(path, "rb"):
        pass  # OSError (no such file, no permission) before cantools sees the name
    try:
        db = cantools.database.load_file(path, database_format="dbc", sort_signals=None)
    except Exception as e:  # cantools' ParseError and the errors of its checks
        raise DbcError(f"{path}: not a DBC cantools {_cantools_version()} reads: {e}") from e
    definitions = db.dbc.attribute_definitions if db.dbc is not None else {}
    names = [n.name for n in db.nodes]
    for m in db.messages:
        names += [s for s in m.senders if s not in names]
    real = list(real)
    for r in real:
        if r not in names:
            raise DbcError(f"{path}: no node is named {r!r} (nodes: {', '.join(names)})")

    sent: Dict[str, List[Dict[str, Any]]] = {n: [] for n in names if n not in real}
    messages: Dict[str, Dict[str, Any]] = {}
    owner: Dict[str, str] = {}  # messages real nodes send -> the first of them
    for m in db.messages:
        if not m.senders:
            if warn is not None:
                warn(f"{path}: message {m.name} has no sender; skipped")
            continue
        simulated = [s for s in m.senders if s not in real]
        if not simulated:
            owner[m.name] = m.senders[0]
            continue
        try:
            table = _message(m, definitions)
        except DbcError as e:
            raise DbcError(f"{path}: {e}") from None
        sent[simulated[0]].append(table)
        messages[m.name] = table

    marked: Dict[int, str] = {}
    for spec in counters:
        s = _find(messages, owner, spec, "--counter")
        if s["type"] != "integer" or s.get("multiplexer"):
            raise DbcError(f"--counter {spec}: a counter needs an integer signal that is not the "
                           f"multiplexor")
        s["counter"] = True
        marked[id(s)] = spec
    for spec, value in (checksums or {}).items():
        s = _find(messages, owner, spec, "--checksum")
        algo, data_id = _checksum_spec(spec, value)
        if id(s) in marked:
            raise DbcError(f"--checksum {spec}: the signal is already a counter or a checksum")
        if not _holds_checksum(s):
            raise DbcError(f"--checksum {spec}: a checksum needs an 8-bit integer signal in one "
                           f"whole byte (this one: {s['length']} bits from bit {s['start']}, "
                           f"{s['byte_order']}, {s['type']})")
        s["checksum"] = algo
        if data_id is not None:
            s["data_id"] = data_id
        marked[id(s)] = spec
    return [{"name": n, "bus": bus, "message": sent[n]} for n in sent]


def to_toml(nodes: List[Dict[str, Any]], source: str = "") -> str:
    """The ``[[can_node]]`` tables as TOML text for canemud's configuration."""
    lines = [f"# CAN nodes from {source} (canemu.dbc)" if source else "# CAN nodes (canemu.dbc)"]
    for node in nodes:
        lines += ["", "[[can_node]]"]
        lines += [f"{k} = {toml_value(v)}" for k, v in node.items() if k != "message"]
        for m in node["message"]:
            lines += ["", "[[can_node.message]]"]
            for k, v in m.items():
                if k == "signal":
                    continue
                comment = f"  # 0x{v:X}" if k == "id" else ""
                lines.append(f"{k} = {toml_value(v)}{comment}")
            for s in m["signal"]:
                lines += ["", "[[can_node.message.signal]]"]
                lines += [f"{k} = {toml_value(v)}" for k, v in s.items()]
    return "\n".join(lines) + "\n"


def tables_from_dbc(path: str, bus: str, real: Iterable[str] = (), counters: Iterable[str] = (),
                    checksums: Optional[Mapping[str, str]] = None,
                    warn: Optional[Callable[[str], None]] = None) -> str:
    """can_nodes() as TOML text."""
    return to_toml(can_nodes(path, bus, real, counters, checksums, warn), path)


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m canemu.dbc",
        description="a DBC as canemud's simulated CAN nodes ([[can_node]] TOML on stdout)")
    parser.add_argument("dbc", help="the CAN database (DBC) file")
    parser.add_argument("--bus", required=True, help="the CAN bus of canemud's configuration")
    parser.add_argument("--real", action="append", default=[],
                        help="a node a real program plays (not simulated); repeatable")
    parser.add_argument("--counter", action="append", default=[], metavar="MSG.SIG",
                        help="an alive counter signal (+1 per frame); repeatable")
    parser.add_argument("--checksum", action="append", default=[],
                        metavar="MSG.SIG=ALGO[:DATA_ID]",
                        help=f"a checksum signal, ALGO one of {', '.join(CHECKSUMS)}; repeatable")
    args = parser.parse_args(argv)
    checksums: Dict[str, str] = {}
    for item in args.checksum:
        spec, eq, value = item.partition("=")
        if not eq:
            parser.error(f"--checksum {item!r}: write MSG.SIG=ALGO[:DATA_ID]")
        if spec in checksums:
            parser.error(f"--checksum {spec}: given twice")
        checksums[spec] = value
    notes: List[str] = []  # shown with the tables, not with a refusal
    try:
        text = tables_from_dbc(args.dbc, args.bus, args.real, args.counter, checksums,
                               warn=notes.append)
    except OSError as e:
        print(f"canemu.dbc: {args.dbc}: {e.strerror or e}", file=sys.stderr)
        return 2
    except DbcError as e:
        print(f"canemu.dbc: {e}", file=sys.stderr)
        return 2
    for note in notes:
        print(f"canemu.dbc: note: {note}", file=sys.stderr)
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
