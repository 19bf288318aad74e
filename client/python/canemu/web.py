"""canemu web: a live page of canemud's buses, nodes, ID tables and faults, pushed to the browser
by server-sent events, and /metrics in the Prometheus text format. `canemu web` runs
`python3 -m canemu.web`; the HTTP server is aiohttp's, the charts Chart.js as Debian ships it
(libjs-chart.js), served by this server itself. docs/web.md.

    GET  /                the page (index.html, app.js, app.css under /static/)
    GET  /events          server-sent events: a snapshot, then one update per look
    GET  /api/state       the snapshot as JSON
    GET  /metrics         `canemu metrics`, as a scraper wants it
    GET  /chart.js        Chart.js from /usr/share/javascript/chart.js
    POST /api/fault, /api/step, /api/unplug, /api/plug   actions (--allow-control only)
"""

from __future__ import annotations

import argparse
import asyncio
import json
import signal
import sys
from pathlib import Path
from typing import List, Optional

from . import _web_control
from ._web_feed import RESYNC, Feed, SignalDecoder, parse_dbc_option

STATIC = Path(__file__).resolve().parent / "web_static"
CHART_JS = Path("/usr/share/javascript/chart.js/chart.min.js")
PAGES = "/, /events, /api/state, /metrics"
MAX_BODY = 16 * 1024  # an action's JSON is small


def _missing_aiohttp() -> int:
    print("canemu: web needs aiohttp for this Python ("
          f"{sys.executable}): apt install python3-aiohttp, or pip install aiohttp",
          file=sys.stderr)
    return 2


def make_app(feed: Feed, allow_control: bool, chart_js: Path = CHART_JS):
    from aiohttp import web

    @web.middleware
    async def errors(request, handler):
        try:
            return await handler(request)
        except web.HTTPNotFound:
            return web.Response(status=404, text=(
                f"404 Not Found: canemu web has no page {request.path!r}; it serves {PAGES} "
                "(and POST /api/fault, /api/step, /api/unplug, /api/plug with --allow-control)\n"))
        except web.HTTPMethodNotAllowed as e:
            return web.Response(status=405, headers={"Allow": ", ".join(sorted(e.allowed_methods))},
                                text=f"405 Method Not Allowed: {request.method} {request.path}; "
                                     f"allowed: {', '.join(sorted(e.allowed_methods))}\n")

    app = web.Application(middlewares=[errors], client_max_size=MAX_BODY)

    async def index(request):
        return web.FileResponse(STATIC / "index.html")

    async def chart(request):
        if not chart_js.exists():
            return web.Response(status=503, text=(
                f"503: {chart_js} is missing: apt install libjs-chart.js (the page's charts)\n"))
        return web.FileResponse(chart_js, headers={"Content-Type": "text/javascript"})

    async def state(request):
        return web.json_response(feed.snapshot())

    async def metrics(request):
        code, out, err = await feed.run_canemu("metrics")
        if code != 0:
            return web.Response(status=503, text=f"503: canemu metrics failed: {err.strip()}\n")
        return web.Response(body=out.encode(),
                            headers={"Content-Type": "text/plain; version=0.0.4; charset=utf-8"})

    async def events(request):
        response = web.StreamResponse(headers={
            "Content-Type": "text/event-stream", "Cache-Control": "no-cache"})
        await response.prepare(request)
        queue: asyncio.Queue = asyncio.Queue()
        feed.subscribers.add(queue)
        try:
            await response.write(b"data: " + json.dumps(feed.snapshot()).encode() + b"\n\n")
            while True:
                try:
                    text = await asyncio.wait_for(queue.get(), 5)
                except asyncio.TimeoutError:  # also finds a page that has gone
                    await response.write(b": keep-alive\n\n")
                    continue
                if text is None:  # canemu web ends
                    break
                if text == RESYNC:  # it fell behind: the whole state again
                    text = json.dumps(feed.snapshot())
                await response.write(b"data: " + text.encode() + b"\n\n")
        except (ConnectionResetError, asyncio.CancelledError):
            pass
        finally:
            feed.subscribers.discard(queue)
        return response

    async def control(request):
        return await _web_control.handle(request, feed, allow_control)

    async def settings(request):
        return web.json_response({"allow_control": allow_control,
                                  "effects": _web_control.EFFECTS})

    async def no_icon(request):
        return web.Response(status=204)

    async def end_streams(app):
        for queue in list(feed.subscribers):
            queue.put_nowait(None)

    app.on_shutdown.append(end_streams)
    app.router.add_get("/", index)
    app.router.add_get("/favicon.ico", no_icon)
    app.router.add_get("/chart.js", chart)
    app.router.add_get("/events", events)
    app.router.add_get("/api/state", state)
    app.router.add_get("/api/settings", settings)
    app.router.add_get("/metrics", metrics)
    for action in _web_control.ACTIONS:
        app.router.add_post(f"/api/{action}", control)
    app.router.add_static("/static/", STATIC)
    return app


def parse_listen(text: str):
    host, sep, port = text.rpartition(":")
    if not sep or not port.isdigit() or not 0 <= int(port) <= 65535:
        raise ValueError(f"--listen {text!r}: give HOST:PORT, e.g. 127.0.0.1:8047")
    return host.strip("[]") or "127.0.0.1", int(port)


def load_dbc_files(specs: List[str]) -> Optional[SignalDecoder]:
    """The decoder of --dbc's files (None without any); ValueError naming the file and what is
    wrong with it."""
    if not specs:
        return None
    from .dbc_decode import DbcReadError, load

    files = []
    for spec in specs:
        bus, path = parse_dbc_option(spec)
        try:
            files.append((bus, path, load(path)))
        except DbcReadError as e:
            raise ValueError(f"--dbc {e}") from None
        except ImportError as e:  # cantools, which load() imports
            raise ValueError(f"--dbc needs the cantools package for this Python "
                             f"({sys.executable}): {e}; it is in requirements-dbc.txt") from None
    return SignalDecoder(files)


async def serve(args, decoder: Optional[SignalDecoder] = None) -> int:
    from aiohttp import web

    base: List[str] = ["--socket", args.socket] if args.socket else []
    feed = Feed(args.canemu, base, args.interval / 1000.0, not args.no_frames, decoder)
    host, port = parse_listen(args.listen)
    app = make_app(feed, args.allow_control)
    runner = web.AppRunner(app, access_log=None)
    await runner.setup()
    site = web.TCPSite(runner, host, port)
    try:
        await site.start()
    except OSError as e:
        print(f"canemu: web cannot listen on {args.listen}: {e.strerror}", file=sys.stderr)
        await runner.cleanup()
        return 1
    bound = site._server.sockets[0].getsockname()[:2] if site._server else (host, port)
    mode = "actions allowed (--allow-control)" if args.allow_control else "read-only"
    print(f"canemu: web serving http://{bound[0]}:{bound[1]}/ ({mode})", file=sys.stderr,
          flush=True)
    loop = asyncio.get_running_loop()
    running = asyncio.ensure_future(feed.run())
    for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        loop.add_signal_handler(sig, running.cancel)
    try:
        await running
    except asyncio.CancelledError:
        pass
    finally:
        await runner.cleanup()
    return 0


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="canemu web")
    p.add_argument("--canemu", default="canemu", help="the canemu command line")
    p.add_argument("--socket", default="")
    p.add_argument("--listen", default="127.0.0.1:8047")
    p.add_argument("--interval", type=int, default=250)
    p.add_argument("--allow-control", action="store_true")
    p.add_argument("--no-frames", action="store_true")
    p.add_argument("--dbc", action="append", default=[], metavar="[BUS=]FILE")
    args = p.parse_args(argv)
    try:
        import aiohttp  # noqa: F401
    except ImportError:
        return _missing_aiohttp()
    try:
        parse_listen(args.listen)
    except ValueError as e:
        print(f"canemu: web: {e}", file=sys.stderr)
        return 1
    try:
        decoder = load_dbc_files(args.dbc)
    except ValueError as e:
        print(f"canemu: web: {e}", file=sys.stderr)
        return 2  # as canemu dump --dbc and canemu.dbc refuse a file
    try:
        return asyncio.run(serve(args, decoder))
    except KeyboardInterrupt:
        return 0


if __name__ == "__main__":
    sys.exit(main())
