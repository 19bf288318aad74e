"""canemud's configuration and fault scenarios as text, written from Python values: one table
a call, laid out as a file would be (a blank first line, one blank line between tables), so
that a line number in a message is where a reader of the file would find it."""

from __future__ import annotations

import json


def toml_value(value) -> str:
    """`value` written as TOML: a string quoted, a list in brackets, a dict as an inline table."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + " }"
    return str(value)


def table(header: str, **fields) -> str:
    """A table (`header` such as "[simulation]" or "[[bus]]") with its keys in the order given."""
    return "\n".join([header] + [f"{k} = {toml_value(v)}" for k, v in fields.items()])


def toml(*tables: str) -> str:
    """`tables` as a file's text."""
    return "\n" + "\n\n".join(tables) + "\n"


def bus(name: str, kind: str, bitrate: int, **fields) -> str:
    return table("[[bus]]", name=name, kind=kind, bitrate=bitrate, **fields)


def device(name: str, model: str, controllers: list, **fields) -> str:
    return table("[[device]]", name=name, model=model, controllers=controllers, **fields)


def fault(**fields) -> str:
    """A `[[fault]]` of a scenario (`match` a dict: {"from": node} or {"id": 0x123})."""
    return table("[[fault]]", **fields)


def scenario(*faults: str, **fields) -> str:
    """A fault scenario's text: `[scenario]` with `fields` when there are any, then `faults`; a
    fault's line in messages is 5 after a `[scenario]` with a name, else 2."""
    return toml(*([table("[scenario]", **fields)] if fields else []), *faults)


def missing_acks(count: int, name: str) -> str:
    """A scenario named `name` in which nobody acknowledges the first `count` frames of ID 0x123
    on can0 (the fault matches all 11 bits)."""
    return scenario(fault(at="0s", bus="can0", match={"id": 0x123, "mask": 0x7FF},
                          effect="ack_error", count=count), name=name)


# The two classic buses most tests run on.
CAN0 = bus("can0", "can", 500000)
CAN1 = bus("can1", "can", 125000)
FD0 = bus("fd0", "can-fd", 500000, data_bitrate=2000000)

# A LIN bus at 19200 bit/s and an adapter with a LIN controller on it (and can0).
LIN0 = bus("lin0", "lin", 19200)
LIN_ADAPTER = device("ixxat1", "ixxat-usb-to-can", ["can0"], lin=["lin0"])
