"""canemu web's actions: inject a fault (one of the documented effects), step stepped time,
unplug or plug a node (the node_off and node_on effects). Only with --allow-control, and then
only for a peer that the control socket's rule would let act as canemu web does: one whose uid
the kernel names (a loopback connection, found in /proc/net/tcp and tcp6) and that is root or
canemu web's own user, the user canemud accepted. Each action is `canemu fault inject` or
`canemu time step`, so canemud checks it as it checks those commands. docs/web.md."""

from __future__ import annotations

import ipaddress
import json
import os
import re
from typing import Any, Dict, List, Optional

ACTIONS = ("fault", "step", "unplug", "plug")

# docs/faults.md, "Effects" and "LIN effects": what the page offers; canemud checks the rest.
EFFECTS = ["bit_error", "stuff_error", "form_error", "crc_error", "ack_error", "ack_suppress",
           "stuck_dominant", "random_errors", "node_off", "node_on", "bus_off", "error_counters",
           "oscillator", "babble", "line_error", "lin_checksum_error", "lin_parity_error",
           "lin_sync_error", "lin_short_break", "lin_bit_error", "lin_no_response",
           "lin_responder_off", "lin_wakeup"]

# The fault's keys the page may give, each a `canemu fault inject` option.
OPTIONS = {"bus": "--bus", "node": "--node", "id": "--id", "mask": "--mask", "at": "--at",
           "until": "--until", "duration": "--duration", "count": "--count", "bit": "--bit",
           "probability": "--probability", "bit_error_rate": "--bit-error-rate", "tec": "--tec",
           "rec": "--rec", "ppm": "--ppm", "wire": "--wire", "data": "--data", "from": "--from",
           "where": "--where", "pulse": "--pulse"}
# A value: no option of its own (a leading "-" only for a negative number, as --ppm takes).
VALUE = re.compile(r"^(-[0-9][0-9.]*|[A-Za-z0-9_.:+][A-Za-z0-9_.:+-]{0,63})$")


def _uid_of_tcp_peer(peer_host: str, peer_port: int, local_port: int) -> Optional[int]:
    """The uid owning the other end of a loopback TCP connection, from /proc/net/tcp{,6}: the
    socket whose local end is the peer's address and whose remote end is our port."""
    try:
        address = ipaddress.ip_address(peer_host)
    except ValueError:
        return None
    if not address.is_loopback and not (address.version == 6 and address.ipv4_mapped
                                        and address.ipv4_mapped.is_loopback):
        return None  # a remote peer: no uid the kernel can name
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            with open(table) as f:
                lines = f.readlines()[1:]
        except OSError:
            continue
        for line in lines:
            fields = line.split()
            local, remote = fields[1], fields[2]
            if (int(local.rsplit(":", 1)[1], 16) == peer_port
                    and int(remote.rsplit(":", 1)[1], 16) == local_port):
                return int(fields[7])
    return None


def peer_allowed(request) -> Optional[str]:
    """None when the peer may act; otherwise why not."""
    peer = request.transport.get_extra_info("peername") if request.transport else None
    sock = request.transport.get_extra_info("sockname") if request.transport else None
    if not peer or not sock:
        return "the peer's address is unknown"
    uid = _uid_of_tcp_peer(peer[0], peer[1], sock[1])
    if uid is None:
        return (f"the peer {peer[0]} is not on this machine, so the control socket's rule "
                "cannot be applied to it (only local users act)")
    if uid not in (0, os.getuid()):
        return (f"uid {uid} may not act through canemu web: only root and uid {os.getuid()} "
                "(the user canemud accepted canemu web as) may")
    return None


def _bad(web, text: str):
    return web.Response(status=400, text=f"400 Bad Request: {text}\n")


def fault_arguments(body: Dict[str, Any], action: str) -> List[str]:
    """`canemu fault inject` arguments for an action's JSON; ValueError saying what is wrong."""
    if action in ("unplug", "plug"):
        node = body.get("node")
        if not isinstance(node, str) or not VALUE.match(node):
            raise ValueError(f"{action} needs \"node\": a node's name as canemu status shows it")
        return ["fault", "inject", "--effect", "node_off" if action == "unplug" else "node_on",
                "--node", node]
    effect = body.get("effect")
    if effect not in EFFECTS:
        raise ValueError(f"\"effect\" must be one of {', '.join(EFFECTS)} (docs/faults.md)")
    args = ["fault", "inject", "--effect", effect]
    for key, value in body.items():
        if key == "effect":
            continue
        if key not in OPTIONS:
            raise ValueError(f"unknown key {key!r}; the keys are effect, {', '.join(OPTIONS)}")
        text = str(value)
        if isinstance(value, (dict, list)) or not VALUE.match(text):
            raise ValueError(f"{key}: {text[:40]!r} is not a value (letters, digits, _.:+-; "
                             "a leading - only for a negative number)")
        args += [OPTIONS[key], text]
    return args


async def handle(request, feed, allow_control: bool):
    from aiohttp import web

    action = request.path.rsplit("/", 1)[1]
    if not allow_control:
        return web.Response(status=403, text=(
            f"403 Forbidden: canemu web is read-only; {action} needs canemu web --allow-control "
            "(docs/web.md)\n"))
    if request.content_type != "application/json":
        return _bad(web, "an action's body is JSON (Content-Type: application/json)")
    origin = request.headers.get("Origin")
    if origin is not None and origin.split("://", 1)[-1] != request.host:
        return web.Response(status=403, text=(
            f"403 Forbidden: a page from {origin} may not act on canemu web at {request.host}\n"))
    why = peer_allowed(request)
    if why is not None:
        return web.Response(status=403, text=f"403 Forbidden: {why}\n")
    try:
        body = json.loads(await request.text())
    except (ValueError, UnicodeDecodeError) as e:
        return _bad(web, f"the body is not JSON: {e}")
    if not isinstance(body, dict):
        return _bad(web, "the body is a JSON object")
    if action == "step":
        duration = body.get("duration")
        if set(body) != {"duration"} or not isinstance(duration, str) or not VALUE.match(duration):
            return _bad(web, "step needs only \"duration\": e.g. \"10ms\" (150ns, 20us, 10ms, 2s)")
        args = ["time", "step", duration]
    else:
        try:
            args = fault_arguments(body, action)
        except ValueError as e:
            return _bad(web, str(e))
    code, out, err = await feed.run_canemu(*args)
    feed.look_now()
    if code != 0:
        return web.Response(status=422, text=f"422: canemu {args[0]} refused: {err.strip()}\n")
    return web.json_response({"ok": True, "output": out.strip(), "command": ["canemu", *args]})
