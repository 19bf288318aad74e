"""What a running canemud shows of the faults it applies: `canemu dump` error frames at their
exact instants, `canemu status` counters, the log with simulated times, `canemu fault list`
states; runtime loads that are rejected whole, clearing, `canemu fault inject` and its options,
faults of a device that goes, and byte-for-byte identical traces for the same scenario and seed.
Stepped time and a fresh daemon per test."""

from __future__ import annotations

import json
import os
import select
import subprocess

import can
import pytest

import canemu
from canemu.bus import CAN_ERR_PROT_BIT, CAN_ERR_PROT_STUFF

from conftest import (CANEMU_CLI, Canemud, bus_errors, drain, fault, fault_load, frames, load,
                      missing_acks, scenario)

US = 1_000
MS = 1_000_000
BIT = 2 * US  # at 500 kbit/s




def cli(daemon, *args, check=True) -> subprocess.CompletedProcess:
    done = subprocess.run(
        [str(CANEMU_CLI), "--socket", daemon.socket, *args],
        capture_output=True,
        text=True,
        timeout=30,
    )
    if check:
        assert done.returncode == 0, done.stderr
    return done



def status(daemon) -> dict:
    return json.loads(cli(daemon, "status", "--json").stdout)


def faults(daemon) -> list:
    return status(daemon)["faults"]



def msg(arbitration_id=0x123, data=(1, 2), remote=False):
    return can.Message(
        arbitration_id=arbitration_id,
        data=None if remote else list(data),
        is_extended_id=False,
        is_remote_frame=remote,
        dlc=len(data),
    )


class Dump:
    """`canemu dump BUS --listen-only` (a silent observer) running beside the test: ready once
    it says it listens; lines() reads what it printed, up to a given line or a given number of
    lines, with a timeout."""

    def __init__(self, daemon, bus="can0"):
        self.proc = subprocess.Popen(
            [str(CANEMU_CLI), "--socket", daemon.socket, "dump", bus, "--listen-only"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        self.out = b""
        ready = select.select([self.proc.stderr], [], [], 10)[0]
        assert ready, "canemu dump did not start"
        assert b"listening on" in self.proc.stderr.readline()

    def lines(self, until: str = "", count: int = 0, timeout: float = 10.0) -> list[str]:
        """Lines up to and with the first that ends with `until`, or the first `count`."""
        while True:
            text = self.out.decode().splitlines()
            if count and len(text) >= count:
                return text[:count]
            for k, line in enumerate(text):
                if until and line.endswith(until):
                    return text[: k + 1]
            ready = select.select([self.proc.stdout], [], [], timeout)[0]
            assert ready, f"canemu dump printed only {text}"
            chunk = os.read(self.proc.stdout.fileno(), 65536)
            assert chunk, f"canemu dump ended after {text}"
            self.out += chunk

    def stop(self):
        self.proc.kill()
        self.proc.wait()
        self.proc.stdout.close()
        self.proc.stderr.close()


def dump_time(line: str) -> int:
    """The time stamp of a candump -L line, in ns."""
    seconds = line[1 : line.index(")")]
    whole, frac = seconds.split(".")
    return int(whole) * 1_000_000_000 + int(frac) * 1_000


def test_dump_and_log_show_bit_errors_at_their_instants(daemon, nodes):
    a, b = nodes
    assert canemu.sim_time()[0] == 0
    dump = Dump(daemon)
    load(daemon, scenario(
        fault(at="0s", bus="can0", effect="bit_error", bit=24, count=2),
        name="two bit errors"))
    a.send(msg())
    canemu.step(1 * MS)
    lines = dump.lines(count=3)
    dump.stop()
    # The sender sees its bit error at bit 24 of the frame (SOF at 0); its error flag starts
    # at bit 25 and the receivers (the dump's node among them) detect six dominant bits at the
    # end of bit 30: a stuff error at 31 bit times. Their own flags end at bit 36, then come
    # the delimiter (8) and intermission (3): the repetition starts at bit 48, is hit the same
    # way, and the third attempt (SOF at bit 96) takes its whole 64 bits (canemu calc frame).
    assert [dump_time(line) for line in lines] == [31 * BIT, (48 + 31) * BIT, (96 + 64) * BIT]
    assert lines[0].endswith(" can0 20000288#0000040A00000000")  # CAN_ERR_PROT_STUFF
    assert lines[1] == lines[0].replace("000062", "000158")
    assert lines[2].endswith(" can0 123#0102")
    # What the receiving node b sees is the same; the sender sees its bit errors at bit 24.
    got_b = drain(b)
    assert [round(m.timestamp * 1e9) for m in got_b] == [dump_time(line) for line in lines]
    assert [e.data[2] for e in bus_errors(got_b)] == [CAN_ERR_PROT_STUFF] * 2
    errors_a = bus_errors(drain(a))
    assert [round(e.timestamp * 1e9) for e in errors_a] == [25 * BIT, (48 + 25) * BIT]
    assert [e.data[2] for e in errors_a] == [CAN_ERR_PROT_BIT] * 2
    # The log: applied, the first frame hit at its start of frame, done at the second's.
    daemon.wait_log('fault: t=0.000000000 s: scenario "two bit errors" (')
    first = daemon.wait_log("first hit")
    assert first.endswith(
        f'fault: t=0.000000000 s: scenario "two bit errors" line 5: bit_error: first hit, '
        f"frame 123 from {a.node_name}"
    )
    done = daemon.wait_log("done, 2 hits")
    assert done.endswith('fault: t=0.000096000 s: scenario "two bit errors" line 5: bit_error: done, 2 hits')


def test_status_counts_what_a_fault_did(daemon, nodes):
    a, b = nodes
    load(daemon, missing_acks(3, "three acks missing"))
    a.send(msg(0x100))
    a.send(msg(0x123))
    canemu.step(5 * MS)
    s = status(daemon)
    can0 = next(x for x in s["buses"] if x["name"] == "can0")
    assert can0["frames"] == 2 and can0["error_frames"] == 3
    node_a = next(x for x in s["nodes"] if x["name"] == a.node_name)
    # 0x100 first (TEC stays 0), then 0x123: +8 per ACK error, -1 for its success.
    assert (node_a["tec"], node_a["rec"], node_a["state"]) == (3 * 8 - 1, 0, "error-active")
    assert (node_a["frames_sent"], node_a["errors"]) == (2, 3)
    [entry] = s["faults"]
    assert {k: entry[k] for k in ("scenario", "line", "effect", "target", "seen", "hits", "state")} == {
        "scenario": "three acks missing",
        "line": 5,
        "effect": "ack_error",
        "target": "can0",
        "seen": 4,  # three hit, the fourth attempt acknowledged
        "hits": 3,
        "state": "done",
    }
    text = cli(daemon, "status").stdout
    assert "three acks missing" in text and "ack_error" in text
    row = next(line for line in text.splitlines() if line.startswith("three acks missing"))
    assert row.split()[-7:] == ["4", "3", "done", "id", "0x123", "mask", "0x7FF"]


def test_a_rejected_load_changes_nothing(daemon, nodes):
    a, b = nodes
    load(daemon, scenario(
        fault(at="1s", bus="can0", effect="ack_suppress", duration="1ms"),
        name="kept"))
    before = cli(daemon, "fault", "list").stdout
    log_before = len(daemon.log)
    done = fault_load(daemon, scenario(
        fault(at="0s", bus="can0", match={"from": a.node_name}, effect="bit_error"),
        fault(at="0s", node="ghost:0", effect="bus_off"),
        name="half good"))
    assert done.returncode == 1
    assert ':11: bus_off: no node named "ghost:0"' in done.stderr
    assert "nothing of it applied" in done.stderr
    assert cli(daemon, "fault", "list").stdout == before
    a.send(msg())
    canemu.step(1 * MS)
    assert len(frames(drain(b))) == 1 and bus_errors(drain(a)) == []
    assert a.error_counters() == (0, 0)
    assert "half good" not in daemon.log[log_before:]


def test_clearing_an_active_fault_stops_its_hits(daemon, nodes):
    a, b = nodes
    load(daemon, scenario(fault(at="0s", bus="can0", effect="stuff_error"), name="endless"))
    a.send(msg())
    # A stuff error right after the arbitration field: the receivers' flags at bit 14, the
    # transmitter's on top, delimiter and intermission; attempts start every 35 bit times, at
    # 0, 70 and 140 us, each hit at its start of frame.
    canemu.step(200 * US)
    [entry] = faults(daemon)
    assert (entry["hits"], entry["state"]) == (3, "active")
    assert cli(daemon, "fault", "clear", "endless").stdout.strip() == "1 scenario cleared"
    canemu.step(1 * MS)
    assert len(bus_errors(drain(a))) == 3
    got = frames(drain(b))
    assert len(got) == 1 and round(got[0].timestamp * 1e9) == (3 * 35 + 64) * BIT
    [entry] = faults(daemon)
    assert (entry["hits"], entry["state"]) == (3, "cleared")
    daemon.wait_log('scenario "endless" cleared')


def test_faults_of_a_device_that_goes_end_with_it(daemon, nodes):
    a, b = nodes
    name = a.node_name
    load(daemon, scenario(
        fault(at="0s", until="1s", node=name, effect="node_off"),
        fault(at="500ms", node=name, effect="bus_off"),
        name="on a"))
    canemu.step(1 * MS)
    a.shutdown()
    assert [f["state"] for f in faults(daemon)] == ["cleared", "cleared"]
    device = name.split(":")[0]  # the ephemeral adapter, whose controller 0 a was
    daemon.wait_log(f'scenario "on a" line 5: node_off: ends, device {device} is gone')
    daemon.wait_log(f'scenario "on a" line 11: bus_off: ends, device {device} is gone')
    # A new node (the one a left, plugged in again) talks; the bus_off due at 500 ms never comes.
    c = can.Bus(interface="canemu", channel="can0", auto_restart=False)
    drain(c)
    drain(b)
    c.send(msg(0x321))
    canemu.step(600 * MS)
    assert [m.arbitration_id for m in frames(drain(b))] == [0x321]
    assert c.state == can.BusState.ACTIVE and c.error_counters() == (0, 0)
    c.shutdown()


def test_inject_matches_remote_frames_by_transmitter(daemon, nodes):
    a, b = nodes
    cli(daemon, "fault", "inject", "--effect", "bit_error", "--bus", "can0", "--from",
        a.node_name, "--rtr", "--id", "0x120", "--mask", "0x7F0", "--count", "1",
        "--bit", "20")
    b.send(msg(0x121, remote=True))  # another transmitter
    canemu.step(1 * MS)
    a.send(msg(0x121))  # a data frame
    canemu.step(1 * MS)
    a.send(msg(0x131, remote=True))  # outside the mask
    canemu.step(1 * MS)
    assert bus_errors(drain(a)) == []
    sent = canemu.sim_time()[0]  # the bus is idle: the frame starts now
    a.send(msg(0x122, remote=True))  # hit once, at bit 20 (in the CRC)
    canemu.step(1 * MS)
    errors = bus_errors(drain(a))
    assert len(errors) == 1 and errors[0].data[2] == CAN_ERR_PROT_BIT
    assert round(errors[0].timestamp * 1e9) == sent + 21 * BIT  # the end of bit 20
    [entry] = faults(daemon)
    assert (entry["effect"], entry["target"], entry["seen"], entry["hits"]) == ("bit_error", "can0", 2, 1)
    assert [m.arbitration_id for m in frames(drain(b))] == [0x121, 0x131, 0x122]


def test_inject_oscillator_counters_and_random_errors(daemon, nodes):
    a, b = nodes
    cli(daemon, "fault", "inject", "--effect", "oscillator", "--node", b.node_name,
        "--ppm", "-100000", "--until", "300us")
    a.send(msg())
    canemu.step(250 * US)
    assert frames(drain(b)) == [] and bus_errors(drain(a)) != []  # 10 % off: b cannot decode a
    canemu.step(1 * MS)
    assert len(frames(drain(b))) == 1  # nominal again
    cli(daemon, "fault", "inject", "--effect", "error_counters", "--node", a.node_name,
        "--tec", "130", "--rec", "7", "--at", "1ms")
    before = a.error_counters()
    canemu.step(999 * US)
    assert a.error_counters() == before
    canemu.step(1 * US)
    assert a.error_counters() == (130, 7) and a.state == can.BusState.PASSIVE
    cli(daemon, "fault", "inject", "--effect", "random_errors", "--bus", "can0",
        "--bit-error-rate", "0.01", "--until", "2ms")
    for k in range(20):
        b.send(msg(0x200 + k))
    canemu.step(20 * MS)
    listed = faults(daemon)
    assert [f["effect"] for f in listed] == ["oscillator", "error_counters", "random_errors"]
    assert [f["state"] for f in listed] == ["done", "done", "done"]
    rnd = listed[2]
    assert rnd["until_ns"] - rnd["at_ns"] == 2 * MS
    # b alone sends now: every hit is a bit error it sees as the transmitter. About half its
    # attempts in the window are hit (1 - 0.99^64); every frame gets through in the end.
    assert rnd["hits"] >= 3 and rnd["hits"] == len(bus_errors(drain(b)))
    assert [m.arbitration_id for m in frames(drain(a))] == [0x200 + k for k in range(20)]


@pytest.mark.parametrize(
    "args, says",
    [
        (["--effect", "bit_error", "--bus", "can0", "--id", "0xZZ"],
         "--id '0xZZ': not a hex identifier"),
        (["--effect", "babble", "--node", "ixxat0:0", "--duration", "1ms", "--id", "800"],
         "--id '800': above 7FF, the largest 11-bit identifier (29-bit ones with --ext)"),
        (["--effect", "bit_error", "--bus", "can0", "--count", "many"], "--count 'many': not a number"),
        (["--effect", "bit_error", "--bus", "can0", "--ext", "--std"], "--ext and --std"),
        (["--effect", "bit_error", "--bus", "can0", "--data", "11"], "--data: only babble"),
        (["--effect", "babble", "--node", "ixxat0:0", "--duration", "1ms", "--data", "1"],
         "two digits each"),
        (["--effect", "random_errors", "--bus", "can0", "--bit-error-rate", "0.5"],
         "bit_error_rate: must be above 0 and at most 0.1"),
        (["--effect", "bit_errors", "--bus", "can0"], "bit_errors"),
        (["--effect", "node_off", "--node", "nobody:0"], 'no node named "nobody:0"'),
    ],
)
def test_inject_names_what_is_wrong_and_applies_nothing(daemon, args, says):
    done = cli(daemon, "fault", "inject", *args, check=False)
    assert done.returncode != 0
    assert says in done.stderr
    assert faults(daemon) == []


def dump_trace(seed: int) -> list[str]:
    """The `canemu dump` lines of one run: random bit errors from `seed` on 30 frames of two
    senders, then a last frame (the end marker)."""
    d = Canemud("stepped")
    try:
        a = can.Bus(interface="canemu", channel="can0")
        b = can.Bus(interface="canemu", channel="can0")
        dump = Dump(d)
        load(d, scenario(fault(at="0s", until="20ms", bus="can0", effect="random_errors",
                               bit_error_rate=0.01), seed=seed))
        for k in range(15):
            a.send(msg(0x100 + k, (k, k)))
            b.send(msg(0x180 + k, (k,)))
        canemu.step(30 * MS)
        b.send(msg(0x7FF, (0xEE,)))
        canemu.step(1 * MS)
        lines = dump.lines(until=" can0 7FF#EE")
        dump.stop()
        a.shutdown()
        b.shutdown()
        return lines
    finally:
        d.stop()


def is_error_frame(line: str) -> bool:
    """A candump -L line of an error frame (CAN_ERR_FLAG in its 8-digit identifier)."""
    can_id = line.split()[-1].split("#")[0]
    return len(can_id) == 8 and int(can_id, 16) & 0x20000000 != 0


def test_the_same_scenario_and_seed_give_the_same_trace_byte_for_byte():
    first = dump_trace(3)
    assert first == dump_trace(3)
    assert sum(is_error_frame(line) for line in first) > 5
    assert sum(not is_error_frame(line) for line in first) == 31  # every frame got through
    assert first != dump_trace(4)
