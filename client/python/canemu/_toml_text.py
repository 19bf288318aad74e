"""TOML values as text, for the tables canemu's importers write (canemu.ldf, canemu.dbc)."""

from __future__ import annotations

import math
from typing import Any


def toml_value(v: Any, hex_ints: bool = False) -> str:
    """`v` (bool, int, float, str, list or dict of them) as a TOML value; with `hex_ints`,
    integers from 0 on in hexadecimal (identifiers and data bytes read better so)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return f"0x{v:02X}" if hex_ints and v >= 0 else str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        out = v.replace("\\", "\\\\").replace('"', '\\"')
        out = "".join(c if 0x20 <= ord(c) != 0x7F else f"\\u{ord(c):04X}" for c in out)
        return f'"{out}"'
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x, hex_ints) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x, hex_ints)}" for k, x in v.items()) + " }"
    raise TypeError(f"no TOML for {v!r}")
