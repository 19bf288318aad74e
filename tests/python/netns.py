"""Hosts on one machine for tests across hosts: one Linux network namespace per host, joined by a
hub, each with its own address, its own canemud and its own Cyclone DDS configuration.

Tests across hosts
------------------

    with Hosts(("a", "b", "c")) as hosts:
        daemon = hosts.daemon("a", config_text, args=["--time", "stepped"])
        peer = hosts.popen("b", [sys.executable, "peer.py"], stdout=subprocess.PIPE)
        hosts.disconnect("c")                 # c leaves the hub: a network partition

How the hosts are made: a namespace per host (named ``canemu-<pid>-<n>-<host>``, so runs never
meet) and one more for the hub, which holds a Linux bridge (``br0``, no STP, no multicast
snooping). Each host has a veth pair: ``eth0`` inside the host, with address 10.77.0.<i>/24 (i
from 1, in the order of `names`) and ``lo`` up; its other end, named after the host, is a port
of the hub's bridge. Nothing is added to the machine's own namespace, so the machine's network
and routes are not touched. Before it returns, the constructor checks that every host reaches
every other one by a UDP datagram each way (sockets made inside the namespaces with setns(2);
no ping needed) and raises RuntimeError naming the pairs that did not.

Processes run inside a host through ``ip netns exec`` with ``CYCLONEDDS_URI`` set to that
host's Cyclone DDS configuration (`cyclone_uri`): its interface ``eth0`` by name, unicast
discovery with every host's address as a peer and multicast off (the default: it needs no
multicast on the link), or with ``multicast=True`` Cyclone's default SPDP multicast on the
link instead; test_netns_dds.py runs both. Discovery between two hosts takes some 50 ms either
way. canemud's AF_UNIX socket is a path in the file system, which network namespaces do not
separate, so clients of a host's canemud (python-can, ``canemu``) may run in any namespace.

`HostProgram` runs a program inside a host with its output read by threads of its own, so that
a test waits for its next line with a deadline and a failure shows what it wrote to stderr.

Closing (the ``with`` block's end, also on a failure) kills what was started (SIGTERM, then
SIGKILL; canemud by `Daemon.stop`), then every process still inside the namespaces, and
deletes the namespaces, which removes their links. Namespaces left by a run that was killed
(its pid gone) are removed when the next `Hosts` starts.

What is needed: root (creating namespaces and links needs CAP_SYS_ADMIN and CAP_NET_ADMIN; CI
runs the tests as root), ``ip`` (iproute2) and ``unshare`` (util-linux, for the side-effect free
probe of `netns_available`), and a kernel with network namespaces, veth and bridge. A test calls
``pytest.skip(reason)`` when `netns_available()` says no, so it is reported as skipped with the
reason.

Standard library only (canemu.testing is imported by `Hosts.daemon` alone).
"""

from __future__ import annotations

import ctypes
import itertools
import os
import queue
import re
import selectors
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
import warnings
from contextlib import contextmanager
from typing import Dict, Iterator, List, Mapping, Optional, Sequence, Tuple

PREFIX = "canemu-"
INTERFACE = "eth0"
BRIDGE = "br0"
CLONE_NEWNET = 0x40000000
_serial = itertools.count()


def netns_available() -> Tuple[bool, str]:
    """(True, "") when this process can make hosts; else (False, why)."""
    if not sys.platform.startswith("linux"):
        return False, "network namespaces are Linux's"
    if os.geteuid() != 0:
        return False, "network namespaces and links need root (CAP_SYS_ADMIN, CAP_NET_ADMIN)"
    for tool, package in (("ip", "iproute2"), ("unshare", "util-linux")):
        if shutil.which(tool) is None:
            return False, f"{tool} ({package}) is not on PATH"
    # A bridge and a veth pair in a namespace that vanishes with the probe: nothing is left.
    probe = subprocess.run(
        ["unshare", "--net", "sh", "-c",
         f"ip link add {BRIDGE} type bridge && ip link add x type veth peer name y"],
        capture_output=True, text=True, timeout=20)
    if probe.returncode != 0:
        return False, ("no network namespace with a bridge and a veth pair here: "
                       + (probe.stderr.strip() or f"status {probe.returncode}"))
    return True, ""


def _ip(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    done = subprocess.run(["ip", *args], capture_output=True, text=True, timeout=20)
    if check and done.returncode != 0:
        raise RuntimeError(f"ip {' '.join(args)}: {done.stderr.strip()}")
    return done


_libc = ctypes.CDLL(None, use_errno=True)


def _setns(fd: int) -> None:
    if _libc.setns(fd, CLONE_NEWNET) != 0:
        err = ctypes.get_errno()
        raise OSError(err, f"setns: {os.strerror(err)}")


@contextmanager
def _inside(namespace: str) -> Iterator[None]:
    """The calling thread in the named network namespace for the block (sockets made there stay
    in it)."""
    own = os.open("/proc/thread-self/ns/net", os.O_RDONLY)
    try:
        target = os.open(f"/run/netns/{namespace}", os.O_RDONLY)
        try:
            _setns(target)
            try:
                yield
            finally:
                _setns(own)
        finally:
            os.close(target)
    finally:
        os.close(own)


def _kill_inside(namespace: str, timeout: float = 5.0) -> None:
    """SIGKILL to every process in the namespace (all of them started by a Hosts), again until
    none is left in it (a process that ended is no longer in it, even before it is reaped)."""
    deadline = time.monotonic() + timeout
    while pids := _ip("netns", "pids", namespace, check=False).stdout.split():
        for pid in pids:
            try:
                os.kill(int(pid), signal.SIGKILL)
            except (ProcessLookupError, ValueError):
                pass
        if time.monotonic() > deadline:
            raise RuntimeError(f"processes {pids} in {namespace} do not end on SIGKILL")


def _remove_stale() -> None:
    """Deletes the namespaces of runs whose process is gone (killed before their cleanup)."""
    for line in _ip("netns", "list", check=False).stdout.splitlines():
        name = line.split()[0] if line.split() else ""
        m = re.match(rf"{re.escape(PREFIX)}(\d+)-\d+-", name)
        if not m or int(m.group(1)) == os.getpid():
            continue
        try:
            os.kill(int(m.group(1)), 0)
            continue  # its run is alive
        except ProcessLookupError:
            pass
        except PermissionError:
            continue
        _kill_inside(name)
        _ip("netns", "del", name, check=False)


class Hosts:
    """Hosts as network namespaces on one hub (module docstring).

    :param names: the hosts' names (1 to 10 lower-case letters and digits, first a letter).
    :param subnet: the first three octets of the hosts' addresses (a /24).
    :param multicast: `cyclone_uri`'s default: SPDP multicast instead of unicast peers.
    :param participants: Cyclone's MaxAutoParticipantIndex (DDS participants per host and domain
        found by unicast discovery).
    :param timeout: seconds for the reachability check.
    """

    def __init__(self, names: Sequence[str] = ("a", "b", "c"), subnet: str = "10.77.0",
                 multicast: bool = False, participants: int = 20, timeout: float = 5.0) -> None:
        started = time.monotonic()
        self.names = tuple(names)
        if not self.names or len(set(self.names)) != len(self.names):
            raise ValueError(f"host names must be given and distinct: {self.names}")
        for name in self.names:
            if not re.fullmatch(r"[a-z][a-z0-9]{0,9}", name):
                raise ValueError(f"host name {name!r}: 1 to 10 lower-case letters and digits")
        self.run_id = f"{PREFIX}{os.getpid()}-{next(_serial)}"
        self.hub = f"{self.run_id}-hub"
        self.namespace: Dict[str, str] = {n: f"{self.run_id}-{n}" for n in self.names}
        self.address: Dict[str, str] = {n: f"{subnet}.{i + 1}" for i, n in enumerate(self.names)}
        self.interface = INTERFACE
        self.multicast = multicast
        self.participants = participants
        self._made: List[str] = []
        self._procs: List[subprocess.Popen] = []
        self._daemons: list = []
        self._disconnected: set = set()
        try:
            _remove_stale()
            self._make()
            self.check(timeout)
        except BaseException:
            self.close(quiet=True)
            raise
        self.setup_seconds = time.monotonic() - started

    def _make(self) -> None:
        for ns in (self.hub, *self.namespace.values()):
            _ip("netns", "add", ns)
            self._made.append(ns)
        _ip("-n", self.hub, "link", "add", BRIDGE, "type", "bridge", "stp_state", "0",
            "mcast_snooping", "0")
        _ip("-n", self.hub, "link", "set", "dev", BRIDGE, "up")
        for name, ns in self.namespace.items():
            _ip("-n", ns, "link", "add", INTERFACE, "type", "veth", "peer", "name", name,
                "netns", self.hub)
            _ip("-n", self.hub, "link", "set", "dev", name, "master", BRIDGE, "up")
            _ip("-n", ns, "addr", "add", f"{self.address[name]}/24", "dev", INTERFACE)
            _ip("-n", ns, "link", "set", "dev", INTERFACE, "up")
            _ip("-n", ns, "link", "set", "dev", "lo", "up")

    # --- reachability ---

    def _udp(self, host: str) -> socket.socket:
        with _inside(self.namespace[host]):
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        s.bind((self.address[host], 0))
        s.setblocking(False)
        return s

    def probe(self, pairs: Sequence[Tuple[str, str]], timeout: float) -> set:
        """The (source, destination) pairs whose UDP datagram arrived within `timeout` seconds
        (each datagram sent again every 0.1 s until it did)."""
        hosts = sorted({h for pair in pairs for h in pair})
        socks = {h: self._udp(h) for h in hosts}
        arrived: set = set()
        try:
            with selectors.DefaultSelector() as sel:
                for h, s in socks.items():
                    sel.register(s, selectors.EVENT_READ, h)
                deadline = time.monotonic() + timeout
                while True:
                    for src, dst in pairs:
                        if (src, dst) not in arrived:
                            try:
                                socks[src].sendto(f"{src}>{dst}".encode(),
                                                  socks[dst].getsockname())
                            except OSError:
                                pass  # unreachable now: not arrived
                    resend = min(deadline, time.monotonic() + 0.1)
                    while (left := resend - time.monotonic()) > 0:
                        for key, _ in sel.select(left):
                            while True:
                                try:
                                    data, _ = key.fileobj.recvfrom(64)
                                except BlockingIOError:
                                    break
                                src, _, dst = data.decode().partition(">")
                                if dst == key.data and (src, dst) in pairs:
                                    arrived.add((src, dst))
                        if arrived >= set(pairs):
                            return arrived
                    if time.monotonic() >= deadline:
                        return arrived
        finally:
            for s in socks.values():
                s.close()

    def reachable(self, source: str, destination: str, timeout: float = 1.0) -> bool:
        """Whether a datagram from `source` arrives at `destination` within `timeout` s."""
        return (source, destination) in self.probe([(source, destination)], timeout)

    def check(self, timeout: float = 5.0) -> None:
        """RuntimeError unless every connected host reaches every other one."""
        on = [h for h in self.names if h not in self._disconnected]
        pairs = [(s, d) for s in on for d in on if s != d]
        missing = sorted(set(pairs) - self.probe(pairs, timeout))
        if missing:
            links = {h: _ip("-n", self.namespace[h], "-br", "addr", check=False).stdout.strip()
                     for h in on}
            raise RuntimeError(
                "hosts do not reach each other by UDP within "
                f"{timeout} s: {', '.join(f'{s} -> {d}' for s, d in missing)}; their links: "
                f"{links}")

    # --- partitions ---

    def disconnect(self, host: str) -> None:
        """Takes the host's link off the hub (it stays up, with its address): it reaches no one."""
        _ip("-n", self.hub, "link", "set", "dev", host, "nomaster")
        self._disconnected.add(host)

    def connect(self, host: str) -> None:
        """Puts the host's link back on the hub."""
        _ip("-n", self.hub, "link", "set", "dev", host, "master", BRIDGE)
        self._disconnected.discard(host)

    # --- Cyclone DDS and processes ---

    def cyclone_uri(self, host: str, multicast: Optional[bool] = None) -> str:
        """CYCLONEDDS_URI for processes in `host`: its link by name; unicast discovery with
        every host's address as a peer (multicast off), or SPDP multicast on the link."""
        if host not in self.namespace:
            raise KeyError(f"no host {host!r}")
        multicast = self.multicast if multicast is None else multicast
        general = (f'<General><Interfaces><NetworkInterface name="{self.interface}"/>'
                   f"</Interfaces><AllowMulticast>{'true' if multicast else 'false'}"
                   "</AllowMulticast></General>")
        if multicast:
            discovery = ""
        else:
            peers = "".join(f'<Peer address="{self.address[h]}"/>' for h in self.names)
            discovery = ("<Discovery><ParticipantIndex>auto</ParticipantIndex>"
                         f"<MaxAutoParticipantIndex>{self.participants}</MaxAutoParticipantIndex>"
                         f"<Peers>{peers}</Peers></Discovery>")
        return f'<CycloneDDS><Domain Id="any">{general}{discovery}</Domain></CycloneDDS>'

    def wrap(self, host: str) -> List[str]:
        """The argv prefix that runs a program inside `host`."""
        return ["ip", "netns", "exec", self.namespace[host]]

    def environment(self, host: str, env: Optional[Mapping[str, str]] = None) -> Dict[str, str]:
        """This process's environment, CYCLONEDDS_URI for `host`, then `env`."""
        return {**os.environ, "CYCLONEDDS_URI": self.cyclone_uri(host), **(env or {})}

    def popen(self, host: str, argv: Sequence[str], env: Optional[Mapping[str, str]] = None,
              **kw) -> subprocess.Popen:
        """A process inside `host` (subprocess.Popen's keywords), ended at close()."""
        proc = subprocess.Popen([*self.wrap(host), *argv], env=self.environment(host, env), **kw)
        self._procs.append(proc)
        return proc

    def run(self, host: str, argv: Sequence[str], env: Optional[Mapping[str, str]] = None,
            timeout: float = 60.0, **kw) -> subprocess.CompletedProcess:
        """subprocess.run inside `host`."""
        return subprocess.run([*self.wrap(host), *argv], env=self.environment(host, env),
                              timeout=timeout, **kw)

    def daemon(self, host: str, config: Optional[str], **kw):
        """canemu.testing.Daemon inside `host` (its keywords), stopped at close()."""
        from canemu.testing import Daemon

        d = Daemon(config, wrap=self.wrap(host), env={"CYCLONEDDS_URI": self.cyclone_uri(host)},
                   **kw)
        self._daemons.append(d)
        return d

    # --- cleanup ---

    def close(self, quiet: bool = False) -> None:
        """Ends everything started and deletes the namespaces; raises the first error of a
        daemon's stop after the whole cleanup (only warns when `quiet`)."""
        errors: List[BaseException] = []
        for proc in reversed(self._procs):
            if proc.poll() is None:
                proc.terminate()
                try:
                    proc.wait(5)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
            for pipe in (proc.stdin, proc.stdout, proc.stderr):
                if pipe is not None:
                    pipe.close()
        self._procs.clear()
        for d in reversed(self._daemons):
            try:
                d.stop()
            except Exception as e:  # noqa: BLE001 - reported after the cleanup
                errors.append(e)
        self._daemons.clear()
        for ns in reversed(self._made):
            _kill_inside(ns)
            _ip("netns", "del", ns, check=False)
        self._made.clear()
        if errors:
            if quiet:
                for e in errors:
                    warnings.warn(f"cleanup of hosts: {e}")
            else:
                raise errors[0]

    def __enter__(self) -> "Hosts":
        return self

    def __exit__(self, exc_type, *exc) -> None:
        self.close(quiet=exc_type is not None)


class HostProgram:
    """A program inside a host (`hosts.popen`, ended at its close()), its output lines read by a
    thread of their own and its stderr kept by another; with `stdin`, it reads from a pipe."""

    def __init__(self, hosts: Hosts, host: str, argv: Sequence[str], stdin: bool = False) -> None:
        self.host = host
        self.proc = hosts.popen(host, argv, stdin=subprocess.PIPE if stdin else None,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.lines: queue.Queue = queue.Queue()
        self.err: List[str] = []
        for pipe, put in ((self.proc.stdout, self.lines.put), (self.proc.stderr, self.err.append)):
            threading.Thread(target=self._read, args=(pipe, put), daemon=True).start()

    @staticmethod
    def _read(pipe, put) -> None:
        for line in pipe:
            put(line)
        put(None)

    def line(self, timeout: float) -> str:
        """The program's next line, waited for at most `timeout` seconds; an AssertionError
        with its exit status and stderr when none came."""
        try:
            line = self.lines.get(timeout=timeout)
        except queue.Empty:
            line = None
        if line is None:
            raise AssertionError(f"program in {self.host}: no line within {timeout} s or it ended "
                                 f"(status {self.proc.poll()}); stderr:\n{''.join(self.err)}")
        return line
