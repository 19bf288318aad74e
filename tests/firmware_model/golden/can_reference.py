#!/usr/bin/env python3
"""Independent reference encoder for CAN / ISO CAN FD frames, the recipe of the golden bit
strings in wire_encoding_test.cpp.

It is written differently from the C++ encoder on purpose: fields are strings, the CRC is the
remainder of a polynomial long division (the ISO CAN FD start value 1 << (n-1) is the same as
inverting the first message bit), and stuffing is a scan over the string.

Usage: can_reference.py ID DLC HEXDATA [ext] [fd] [brs] [esi] [rtr]
Prints the transmitted bits, SOF through EOF (ACK slot recessive).
"""
import sys

POLY = {15: 0xC599, 17: 0x3685B, 21: 0x302899}  # with the x^n term
FD_LEN = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64]


def crc(bits: str, n: int, iso_fd_start: bool) -> str:
    if iso_fd_start:
        bits = ("1" if bits[0] == "0" else "0") + bits[1:]
    value = int(bits + "0" * n, 2)
    g = POLY[n]
    for shift in range(value.bit_length() - 1, n - 1, -1):
        if value >> shift & 1:
            value ^= g << (shift - n)
    return format(value, "0%db" % n)


def stuff(bits: str, no_stuff_after_last: bool):
    out, run, last, count = [], 0, "1", 0
    for i, b in enumerate(bits):
        out.append(b)
        run = run + 1 if b == last else 1
        last = b
        if run == 5 and not (no_stuff_after_last and i == len(bits) - 1):
            s = "0" if b == "1" else "1"
            out.append(s)
            last, run, count = s, 1, count + 1
    return "".join(out), count


def encode(ident, dlc, data, ext=False, fd=False, brs=False, esi=False, rtr=False):
    b = lambda v, n: format(v, "0%db" % n)
    if ext:
        head = "0" + b(ident >> 18, 11) + "11" + b(ident & 0x3FFFF, 18)
        head += ("0" if fd else ("1" if rtr else "0")) + ("1" if fd else "0") + "0"
    else:
        head = "0" + b(ident, 11) + ("0" if fd else ("1" if rtr else "0")) + "0"
        head += "1" + "0" if fd else "0"
    if fd:
        head += ("1" if brs else "0") + ("1" if esi else "0")
    head += b(dlc, 4)
    body = head + "".join(b(x, 8) for x in data)
    tail = "1" + "1" + "1" + "1" * 7
    if not fd:
        bits = body + crc(body, 15, False)
        stuffed, _ = stuff(bits, False)
        return stuffed + tail
    stuffed, count = stuff(body, True)
    gray = [0, 1, 3, 2, 6, 7, 5, 4][count % 8]
    sbc = b(gray, 3)
    sbc += "1" if sbc.count("1") % 2 else "0"
    n = 21 if FD_LEN[dlc] > 16 else 17
    c = crc(stuffed + sbc, n, True)
    field = sbc + c
    out = stuffed
    for i, bit in enumerate(field):
        if i % 4 == 0:
            out += "0" if out[-1] == "1" else "1"
        out += bit
    return out + tail


if __name__ == "__main__":
    a = sys.argv[1:]
    flags = set(a[3:])
    data = bytes.fromhex(a[2]) if a[2] != "-" else b""
    print(encode(int(a[0], 16), int(a[1]), data, "ext" in flags, "fd" in flags, "brs" in flags,
                 "esi" in flags, "rtr" in flags))
