"""The example scenarios of config/faults/ (docs/faults.md, Examples), each loaded as it is with
`canemu fault load` into canemud on its embedded default configuration (can0 and can1 at
500 kbit/s, ixxat0:0 on can0, ixxat0:1 on can1) in stepped time, and watched through python-can:
every documented outcome, with exact counts and instants, and `canemu fault list` after it.
A scenario's `at` times count from the load; a fresh daemon per test."""

from __future__ import annotations

import re
import subprocess

import can
import pytest

import canemu
from canemu.bus import (
    CAN_ERR_ACK,
    CAN_ERR_BUSERROR,
    CAN_ERR_BUSOFF,
    CAN_ERR_CNT,
    CAN_ERR_CRTL,
    CAN_ERR_CRTL_TX_PASSIVE,
    CAN_ERR_CRTL_TX_WARNING,
    CAN_ERR_PROT,
    CAN_ERR_PROT_BIT,
    CAN_ERR_PROT_FORM,
    CAN_ERR_PROT_LOC_ACK,
    CAN_ERR_PROT_LOC_CRC_SEQ,
    CAN_ERR_PROT_STUFF,
)
from canemu.testing import Daemon

from conftest import CANEMU_CLI, CANEMUD, REPO, bus_errors, drain, frames, ns

EXAMPLES = REPO / "config" / "faults"
US = 1_000
MS = 1_000_000
S = 1_000_000_000
BIT = 2 * US  # every bus of the default configuration runs at 500 kbit/s
Active = canemu.ControllerState.ERROR_ACTIVE
Warning_ = canemu.ControllerState.ERROR_WARNING
Passive = canemu.ControllerState.ERROR_PASSIVE
BusOff = canemu.ControllerState.BUS_OFF


def start_default_daemon() -> Daemon:
    """canemud without --config (its embedded default), in stepped time."""
    d = Daemon(None, canemud=str(CANEMUD), args=["--time", "stepped"])
    assert canemu.sim_time() == (0, 2)  # stepped, nothing run yet
    assert [(b["name"], b["kind"], b["bitrate"]) for b in canemu.buses()] == [
        ("can0", "can", 500_000), ("can1", "can", 500_000), ("lin0", "lin", 19_200)]
    return d


@pytest.fixture
def daemon():
    d = start_default_daemon()
    yield d
    d.stop()


@pytest.fixture
def open_bus(daemon):
    """python-can buses on the daemon, shut down at the test's end (before the daemon)."""
    opened = []

    def make(channel: str) -> can.BusABC:
        bus = can.Bus(interface="canemu", channel=channel, auto_restart=False)
        drain(bus)
        opened.append(bus)
        return bus

    yield make
    for bus in opened:
        bus.shutdown()


def cli(daemon: Daemon, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([str(CANEMU_CLI), "--socket", daemon.socket, *args],
                          capture_output=True, text=True, timeout=30)


def load_example(daemon: Daemon, file: str) -> int:
    """`canemu fault load config/faults/FILE`; the simulated time of the load (the scenario's 0)."""
    t0 = now()
    done = cli(daemon, "fault", "load", str(EXAMPLES / file))
    assert done.returncode == 0, done.stderr
    assert now() == t0
    return t0


ROW = re.compile(r"^(?P<scenario>.+?)\s+(?P<line>\d+) (?P<effect>\S+)\s+(?P<target>\S+)\s+"
                 r"(?P<at>\d+\.\d{6})\s+(?P<until>\S+)\s+(?P<seen>\d+)\s+(?P<hits>\d+) "
                 r"(?P<state>\w+)\s+(?P<match>\S.*)$")


def fault_list(daemon: Daemon) -> list:
    """`canemu fault list`, one dict per fault."""
    done = cli(daemon, "fault", "list")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].split() == ["SCENARIO", "LINE", "EFFECT", "TARGET", "AT", "UNTIL", "SEEN",
                                "HITS", "STATE", "MATCH"]
    rows = []
    for line in lines[1:]:
        m = ROW.match(line)
        assert m, line
        rows.append(m.groupdict())
    return rows


def seconds(t_ns: int) -> str:
    """An instant as `canemu fault list` prints it."""
    return f"{t_ns / 1e9:.6f}"


def assert_listed(daemon, *, line, effect, target, at, until, hits, state, seen=None):
    """The list holds the one fault of a one-fault example, as given."""
    rows = fault_list(daemon)
    assert len(rows) == 1, rows
    row = rows[0]
    assert (int(row["line"]), row["effect"], row["target"]) == (line, effect, target)
    assert (row["at"], row["until"]) == (seconds(at), "-" if until is None else seconds(until))
    assert (int(row["hits"]), row["state"]) == (hits, state)
    if seen is not None:
        assert int(row["seen"]) == seen


def scenario_name(file: str) -> str:
    return re.search(r'^name = "(.*)"$', (EXAMPLES / file).read_text(), re.M).group(1)


def frame_bits(frame: str) -> int:
    """The frame's bits without intermission, from the wire model (`canemu calc frame`)."""
    text = subprocess.run([str(CANEMU_CLI), "calc", "frame", frame, "--bitrate", "500000"],
                          capture_output=True, text=True, check=True, timeout=30).stdout
    bits = int(re.search(r"bits: (\d+) \(\+3 intermission\)", text).group(1))
    assert int(re.search(r"(\d+) ns with intermission", text).group(1)) == (bits + 3) * BIT
    return bits


def now() -> int:
    return canemu.sim_time()[0]


def step_to(t_ns: int) -> None:
    assert t_ns >= now()
    if t_ns > now():
        canemu.step(t_ns - now())


def run_to(t_ns: int, *buses, chunk: int = 250 * MS) -> list:
    """Steps to `t_ns` in chunks (no receive FIFO overflows), each bus's messages meanwhile."""
    got = [[] for _ in buses]
    while now() < t_ns:
        canemu.step(min(chunk, t_ns - now()))
        for seen, bus in zip(got, buses):
            seen += drain(bus)
    return got


def msg(arbitration_id: int, data=(1, 2)) -> can.Message:
    return can.Message(arbitration_id=arbitration_id, data=list(data), is_extended_id=False)


def is_ack_error(m) -> bool:
    return m.arbitration_id == CAN_ERR_ACK | CAN_ERR_BUSERROR and m.data[3] == CAN_ERR_PROT_LOC_ACK


def is_prot_error(m, kind) -> bool:
    return m.arbitration_id == CAN_ERR_PROT | CAN_ERR_BUSERROR and m.data[2] == kind


def state_frames(msgs) -> list:
    """The error frames of state changes among `msgs`: (place in msgs, identifier, data[1], TEC,
    REC as data[6], data[7])."""
    return [(k, m.arbitration_id, m.data[1], m.data[6], m.data[7]) for k, m in enumerate(msgs)
            if m.is_error_frame and not m.arbitration_id & CAN_ERR_BUSERROR]


WARNING = CAN_ERR_CRTL
PASSIVE_OR_BACK = CAN_ERR_CRTL | CAN_ERR_CNT  # error-passive, or back below 128


def ids(msgs) -> list:
    return [m.arbitration_id for m in frames(msgs)]


def unacknowledged_attempts(start: int, end: int, bits: int, receiver: bool) -> list:
    """The start instants of a frame of `bits` bits sent at `start` and repeated, unacknowledged,
    as long as its attempts start before `end` (frame effects are decided at the start of frame,
    docs/faults.md). The ACK error is flagged at the ACK delimiter, bit d = bits - 8. Error-active:
    6 flag bits, +1 when a receiver's form-error flag (it sees the transmitter's flag in the ACK
    delimiter) ends a bit later, 8 delimiter bits, 3 intermission. The 16th error makes it
    error-passive (TEC 128): from then on 8 bits of suspend transmission after each attempt, and
    its passive flag overlaps the end of frame: d + 6 + 8 + 3 + 8 bits per attempt
    (docs/bus-engine.md)."""
    d = bits - 8
    active = (d + 17 + (1 if receiver else 0)) * BIT
    passive = (d + 25) * BIT
    sofs = []
    t = start
    while t < end:
        sofs.append(t)
        t += active if len(sofs) < 16 else active + 8 * BIT if len(sofs) == 16 else passive
    return sofs


def ack_errors_of_attempts(got: list, start: int, end: int, bits: int, receiver: bool):
    """The start instants of the unacknowledged attempts (unacknowledged_attempts) and the bus
    errors among `got`, the sender's: each of them an ACK error, one an attempt, flagged at its
    attempt's ACK delimiter."""
    sofs = unacknowledged_attempts(start, end, bits, receiver)
    errors = bus_errors(got)
    assert all(is_ack_error(e) for e in errors)
    assert [ns(e.timestamp) for e in errors] == [t + (bits - 8) * BIT for t in sofs]
    return sofs, errors


def test_the_examples_are_the_eight_documented():
    assert sorted(p.name for p in EXAMPLES.glob("*.toml")) == [
        "babbling-node.toml", "corrupt-id.toml", "drifting-oscillator.toml",
        "lin-checksum.toml", "nobody-acknowledges.toml", "noisy-bus.toml",
        "sender-bus-off.toml", "unplug-node.toml"]
    doc = (REPO / "docs" / "faults.md").read_text()
    for p in EXAMPLES.glob("*.toml"):
        assert f"| `{p.name}` |" in doc


def test_every_example_loads_lists_and_clears_by_its_name(daemon):
    """Each example's [scenario] name as `fault load` reports it, as `fault list` shows it, and
    as `fault clear NAME` takes it."""
    files = sorted(p.name for p in EXAMPLES.glob("*.toml"))
    problems = []
    for file in files:
        name = scenario_name(file)
        faults = (EXAMPLES / file).read_text().count("[[fault]]")
        done = cli(daemon, "fault", "load", str(EXAMPLES / file))
        assert done.returncode == 0, done.stderr
        expected = f'scenario "{name}": {faults} fault{"s" if faults > 1 else ""} applied\n'
        if done.stdout != expected:
            problems.append(f"{file}: fault load printed {done.stdout!r}, not {expected!r}")
    listed = [row["scenario"] for row in fault_list(daemon)]
    expected = [scenario_name(f) for f in files
                for _ in range((EXAMPLES / f).read_text().count("[[fault]]"))]
    if listed != expected:
        problems.append(f"fault list shows {listed}, not {expected}")
    for file in files:
        done = cli(daemon, "fault", "clear", scenario_name(file))
        if done.returncode != 0:
            problems.append(f"{file}: fault clear {scenario_name(file)!r}: {done.stderr.strip()}")
    states = [row["state"] for row in fault_list(daemon)]
    if states != ["cleared"] * len(expected):
        problems.append(f"states after clearing each by name: {states}")
    assert problems == []


def test_sender_bus_off(open_bus, daemon):
    """32 bit errors on ixxat0:0's frames: TEC 8 per error, warning at 96, error-passive at 128,
    bus-off at the 32nd (256)."""
    sender = open_bus("ixxat0:0")
    partner = open_bus("can0")  # an ephemeral node: the sender is not alone
    t0 = load_example(daemon, "sender-bus-off.toml")
    sender.send(msg(0x123))
    seen = []
    counted = 0
    while counted < 32 and now() < t0 + 10 * MS:
        canemu.step(BIT)
        seen += drain(sender)
        errors = len(bus_errors(seen))
        if errors != counted:
            assert errors == counted + 1  # one error per bit time at most
            counted = errors
            tec = sender.error_counters()[0]
            expected = (Active if tec < 96 else Warning_ if tec < 128 else Passive if tec < 256
                        else BusOff)
            assert (tec, sender.controller_state) == (8 * counted, expected), counted
    assert counted == 32
    assert sender.controller_state == BusOff and sender.state == can.BusState.ERROR
    errors = bus_errors(seen)
    assert all(is_prot_error(e, CAN_ERR_PROT_BIT) for e in errors)
    # Read as they come: warning right after the 12th error (TEC 96), error-passive right after
    # the 16th (128), bus-off after the 32nd (the TEC saturated at 255 in the frame).
    assert state_frames(seen) == [
        (12, WARNING, CAN_ERR_CRTL_TX_WARNING, 0, 0),
        (17, PASSIVE_OR_BACK, CAN_ERR_CRTL_TX_PASSIVE, 128, 0),
        (34, CAN_ERR_BUSOFF | CAN_ERR_CNT, 0, 255, 0)]
    assert seen[17].timestamp == errors[15].timestamp
    assert len(seen) == 35
    # The partner sees each of the sender's flags (a stuff error where it detects it, +1 each;
    # the flags overlap, so no +8) and never a frame.
    canemu.step(10 * MS)  # bus-off: silence
    assert drain(sender) == []
    got = drain(partner)
    assert len(bus_errors(got)) == 32 and frames(got) == []
    assert all(is_prot_error(e, CAN_ERR_PROT_STUFF) for e in bus_errors(got))
    # One per attempt: each comes after the sender's error of that attempt, before the next.
    ends = [ns(e.timestamp) for e in errors] + [ns(errors[-1].timestamp) + 50 * US]
    assert all(ends[k] < ns(e.timestamp) < ends[k + 1] for k, e in enumerate(bus_errors(got)))
    assert partner.error_counters() == (0, 32)
    assert sender.error_counters() == (256, 0)
    assert_listed(daemon, line=10, effect="bit_error", target="can0", at=t0, until=None,
                  seen=32, hits=32, state="done")


def test_nobody_acknowledges(open_bus, daemon):
    """No acknowledgements on can0 from 1 s to 2 s: the sender climbs to TEC 128 and stays there
    (its ACK errors as an error-passive node do not count); afterwards it is acknowledged."""
    sender = open_bus("ixxat0:0")
    partner = open_bus("can0")
    bits = frame_bits("123#0102")
    t0 = load_example(daemon, "nobody-acknowledges.toml")
    sender.send(msg(0x123))  # before the window: acknowledged at once
    canemu.step(MS)
    assert [(m.arbitration_id, ns(m.timestamp)) for m in drain(partner)] == [
        (0x123, t0 + bits * BIT)]
    assert drain(sender) == [] and sender.error_counters() == (0, 0)

    w0, w1 = t0 + 1 * S, t0 + 2 * S
    step_to(w0)
    sender.send(msg(0x123))
    got_s, got_p = run_to(w0 + 3 * MS, sender, partner, chunk=BIT)  # read as they come
    more_s, more_p = run_to(t0 + 1500 * MS, sender, partner)
    got_s += more_s
    got_p += more_p
    assert sender.error_counters() == (128, 0) and sender.controller_state == Passive
    more_s, more_p = run_to(w1, sender, partner)
    assert sender.error_counters() == (128, 0) and sender.controller_state == Passive
    got_s += more_s
    got_p += more_p
    canemu.step(10 * MS)
    got_s += drain(sender)
    got_p += drain(partner)

    sofs, errors = ack_errors_of_attempts(got_s, w0, w1, bits, receiver=True)
    assert len(sofs) == 6175  # 16 error-active attempts, 6159 error-passive ones
    # Warning after the 12th error, error-passive after the 16th, and back below 128 (TEC 127)
    # once acknowledged (found when the FIFO is next read empty: at the end of the step).
    assert state_frames(got_s) == [
        (12, WARNING, CAN_ERR_CRTL_TX_WARNING, 0, 0),
        (17, PASSIVE_OR_BACK, CAN_ERR_CRTL_TX_PASSIVE, 128, 0),
        (len(got_s) - 1, PASSIVE_OR_BACK, CAN_ERR_CRTL_TX_WARNING, 127, 0)]
    assert got_s[17].timestamp == errors[15].timestamp
    assert len(got_s) == len(errors) + 3
    # The partner: a form error for each error-active attempt (the sender's flag in the ACK
    # delimiter), every error-passive attempt as a valid frame, then the acknowledged one.
    partner_errors = bus_errors(got_p)
    assert len(partner_errors) == 16
    assert all(is_prot_error(e, CAN_ERR_PROT_FORM) for e in partner_errors)
    first_acked = sofs[-1] + (bits + 17) * BIT  # the last attempt's passive end
    assert first_acked >= w1
    assert [ns(m.timestamp) for m in frames(got_p)] == [t + bits * BIT for t in sofs[16:]] + [
        first_acked + bits * BIT]
    assert set(ids(got_p)) == {0x123}
    # Acknowledged again: TEC - 1; the partner's REC - 1 (it acknowledged; in the window it
    # could not, and its REC stayed at the 16 form errors).
    assert sender.error_counters() == (127, 0)
    assert partner.error_counters() == (0, 15)
    for k in range(3):
        sender.send(msg(0x200 + k))
    canemu.step(10 * MS)
    assert ids(drain(partner)) == [0x200, 0x201, 0x202]
    assert bus_errors(drain(sender)) == []
    assert sender.error_counters() == (124, 0) and partner.error_counters() == (0, 12)
    assert_listed(daemon, line=7, effect="ack_suppress", target="can0", at=w0, until=w1,
                  hits=1, state="done")


def test_unplug_node(open_bus, daemon):
    """ixxat0:1 off can1 from 2 s to 2.5 s: a partner with no other node sees ACK errors then;
    ixxat0:1 neither sends nor receives; both before and after, the frames go through."""
    unplugged = open_bus("ixxat0:1")
    partner = open_bus("can1")
    bits11, bits22 = frame_bits("011#0102"), frame_bits("022#0102")
    t0 = load_example(daemon, "unplug-node.toml")
    partner.send(msg(0x10))
    unplugged.send(msg(0x20))
    w0, w1 = t0 + 2 * S, t0 + 2500 * MS
    step_to(w0 - MS)
    assert ids(drain(unplugged)) == [0x10] and ids(drain(partner)) == [0x20]
    assert partner.error_counters() == (0, 0) and unplugged.error_counters() == (0, 0)

    step_to(w0)
    partner.send(msg(0x11))
    unplugged.send(msg(0x22))
    got_p, got_u = run_to(w0 + 3 * MS, partner, unplugged, chunk=BIT)  # read as they come
    more_p, more_u = run_to(w1, partner, unplugged)
    got_p += more_p
    got_u += more_u
    assert got_u == []  # sees nothing
    assert frames(got_p) == []  # its own frame does not go out
    assert partner.error_counters() == (128, 0) and partner.controller_state == Passive
    assert unplugged.error_counters() == (0, 0)
    sofs, errors = ack_errors_of_attempts(got_p, w0, w1, bits11, receiver=False)
    assert len(sofs) == 3088  # 16 error-active attempts, 3072 error-passive ones
    assert state_frames(got_p) == [
        (12, WARNING, CAN_ERR_CRTL_TX_WARNING, 0, 0),
        (17, PASSIVE_OR_BACK, CAN_ERR_CRTL_TX_PASSIVE, 128, 0)]
    assert len(got_p) == len(errors) + 2

    canemu.step(MS)
    # Plugged in again at 2.5 s; the bus is idle then (the partner's last attempt, its
    # intermission over, leaves it in suspend transmission): ixxat0:1's frame goes first, the
    # partner's repetition right after it, acknowledged.
    idle = sofs[-1] + (bits11 + 9) * BIT
    assert idle <= w1
    got_p, got_u = drain(partner), drain(unplugged)
    assert [(m.arbitration_id, ns(m.timestamp)) for m in frames(got_p)] == [
        (0x22, w1 + bits22 * BIT)]
    # Its TEC back below 128, found when its FIFO is read empty (at the end of the step).
    assert state_frames(got_p) == [(1, PASSIVE_OR_BACK, CAN_ERR_CRTL_TX_WARNING, 127, 0)]
    assert ns(got_p[1].timestamp) == w1 + MS
    assert [(m.arbitration_id, ns(m.timestamp)) for m in got_u] == [
        (0x11, w1 + (bits22 + 3 + bits11) * BIT)]
    assert partner.error_counters() == (127, 0)
    assert unplugged.error_counters() == (0, 0)
    assert_listed(daemon, line=7, effect="node_off", target="ixxat0:1", at=w0, until=w1,
                  hits=2, state="done")  # fired twice: unplugged, plugged in


def test_corrupt_id(open_bus, daemon):
    """From 12 s the next three frames 0x1A0 on can0 get a CRC error (the receivers flag it after
    the ACK delimiter and do not acknowledge); other identifiers are untouched."""
    sender = open_bus("ixxat0:0")
    partner = open_bus("can0")
    bits100, bits1a0 = frame_bits("100#0102"), frame_bits("1A0#0102")
    t0 = load_example(daemon, "corrupt-id.toml")
    w0 = t0 + 12 * S
    step_to(w0 - MS)
    sender.send(msg(0x1A0))  # before the window: clean
    canemu.step(MS)
    assert [(m.arbitration_id, ns(m.timestamp)) for m in drain(partner)] == [
        (0x1A0, w0 - MS + bits1a0 * BIT)]
    assert drain(sender) == []

    for ident in (0x100, 0x1A0, 0x1A1, 0x1A0):
        sender.send(msg(ident))
    partner.send(msg(0x2A0))
    # 0x100 goes first; then 0x1A0 three times, each unacknowledged: the sender flags an ACK
    # error at the ACK delimiter, the partner its CRC error right after it; 75 bits an attempt.
    first = w0 + (bits100 + 3) * BIT
    attempt = (bits1a0 + 10) * BIT
    step_to(first + 3 * attempt)
    got_s, got_p = drain(sender), drain(partner)
    assert [ns(e.timestamp) for e in got_s] == [
        first + k * attempt + (bits1a0 - 8) * BIT for k in range(3)]
    assert all(is_ack_error(e) for e in got_s)
    assert [(m.arbitration_id, ns(m.timestamp)) for m in frames(got_p)] == [
        (0x100, w0 + bits100 * BIT)]
    assert [ns(e.timestamp) for e in bus_errors(got_p)] == [
        first + k * attempt + (bits1a0 - 7) * BIT for k in range(3)]
    assert all(e.arbitration_id == CAN_ERR_PROT | CAN_ERR_BUSERROR
               and e.data[3] == CAN_ERR_PROT_LOC_CRC_SEQ for e in bus_errors(got_p))
    assert sender.error_counters() == (24, 0) and partner.error_counters() == (0, 3)

    canemu.step(10 * MS)  # the fourth attempt is clean, so are all after it
    got_s, got_p = drain(sender), drain(partner)
    assert (got_p[0].arbitration_id, ns(got_p[0].timestamp)) == (
        0x1A0, first + 3 * attempt + bits1a0 * BIT)
    assert ids(got_p) == [0x1A0, 0x1A1, 0x1A0] and bus_errors(got_p) == []
    assert ids(got_s) == [0x2A0] and bus_errors(got_s) == []
    assert sender.error_counters() == (21, 0) and partner.error_counters() == (0, 0)
    # seen: the three hit, the clean repetition, the second 0x1A0; 0x100, 0x1A1 and 0x2A0 are
    # not counted.
    assert_listed(daemon, line=6, effect="crc_error", target="can0", at=w0, until=None,
                  seen=5, hits=3, state="done")


def test_drifting_oscillator(open_bus, daemon):
    """ixxat0:0's oscillator 2 % fast from 5 s to 10 s: it and its partner cannot understand
    each other (errors both ways, no frame gets through); before and after they can."""
    drifting = open_bus("ixxat0:0")
    partner = open_bus("can0")
    t0 = load_example(daemon, "drifting-oscillator.toml")
    w0, w1 = t0 + 5 * S, t0 + 10 * S
    step_to(w0 - MS)
    drifting.send(msg(0x10))
    partner.send(msg(0x20))
    canemu.step(MS)
    assert ids(drain(partner)) == [0x10] and ids(drain(drifting)) == [0x20]
    assert drifting.error_counters() == (0, 0) and partner.error_counters() == (0, 0)

    drifting.send(msg(0x11))
    partner.send(msg(0x21))
    got_d, got_p = run_to(w1, drifting, partner)
    assert frames(got_d) == [] and frames(got_p) == []
    # The partner cannot decode the drifting node: a stuff error at the first bit after
    # arbitration (docs/bus-engine.md); its flag destroys the frame: the sender's bit error.
    assert is_prot_error(bus_errors(got_p)[0], CAN_ERR_PROT_STUFF)
    assert is_prot_error(bus_errors(got_d)[0], CAN_ERR_PROT_BIT)
    assert w0 / 1e9 <= bus_errors(got_p)[0].timestamp < (w0 + 100 * US) / 1e9
    # Errors all through the window, on both sides.
    for got in (got_d, got_p):
        assert len(bus_errors(got)) > 30_000
        assert bus_errors(got)[-1].timestamp > (w1 - MS) / 1e9
    assert drifting.error_counters()[0] == 128 and drifting.controller_state == Passive
    assert partner.controller_state == Passive  # its REC, beyond 127

    canemu.step(MS)  # nominal again: both frames go through
    got_d, got_p = drain(drifting), drain(partner)
    assert ids(got_p) == [0x11] and ids(got_d) == [0x21]
    assert all(w1 / 1e9 < m.timestamp < (w1 + MS) / 1e9 for m in frames(got_d + got_p))
    # One success each: TEC 127 for the sender, REC from above 127 back to 127.
    assert drifting.error_counters() == (127, 127) and partner.error_counters() == (0, 127)
    drifting.send(msg(0x12))
    partner.send(msg(0x22))
    canemu.step(MS)
    assert ids(drain(partner)) == [0x12] and ids(drain(drifting)) == [0x22]
    assert drifting.error_counters() == (126, 126) and partner.error_counters() == (0, 126)
    assert bus_errors(drain(drifting) + drain(partner)) == []
    assert_listed(daemon, line=7, effect="oscillator", target="ixxat0:0", at=w0, until=w1,
                  hits=2, state="done")  # fired twice: off, and back to nominal


def test_babbling_node(open_bus, daemon):
    """ixxat0:0 (its line started by a program) floods can0 with 000#DEADBEEF from 1 s for
    500 ms, copies back to back; every other frame waits for the end."""
    babbler = open_bus("ixxat0:0")
    partner = open_bus("can0")
    bits = frame_bits("000#DEADBEEF")
    copy = (bits + 3) * BIT  # 168 us
    bits11, bits21 = frame_bits("011#0102"), frame_bits("021#0102")
    t0 = load_example(daemon, "babbling-node.toml")
    w0, w1 = t0 + 1 * S, t0 + 1500 * MS
    babbler.send(msg(0x10))
    partner.send(msg(0x20))
    step_to(w0)
    assert ids(drain(partner)) == [0x10] and ids(drain(babbler)) == [0x20]

    step_to(w0 + 100 * MS)
    babbler.send(msg(0x11))  # the program's own frame during the flood
    partner.send(msg(0x21))
    partner.send(msg(0x05))  # behind 0x21 in the partner's transmit FIFO
    got_p, got_b = run_to(t0 + 1600 * MS, partner, babbler)
    copies = [m for m in got_p if m.arbitration_id == 0]
    # Every copy that starts before the end goes out: ceil(500 ms / 168 us) = 2977.
    n = -(-(w1 - w0) // copy)
    assert n == 2977
    assert len(copies) == n and got_p[:n] == copies
    assert all(not m.is_extended_id and not m.is_error_frame and not m.is_remote_frame
               and bytes(m.data) == b"\xde\xad\xbe\xef" for m in copies)
    assert [ns(m.timestamp) for m in copies] == [w0 + k * copy + bits * BIT for k in range(n)]
    # Then the waiting frames: the babbler program's 0x11 wins against the partner's 0x21.
    end = w0 + n * copy  # the last copy's intermission is over
    assert [(m.arbitration_id, ns(m.timestamp)) for m in got_p[n:]] == [
        (0x11, end + bits11 * BIT)]
    assert [(m.arbitration_id, ns(m.timestamp)) for m in got_b] == [
        (0x21, end + (bits11 + 3 + bits21) * BIT),
        (0x05, end + (bits11 + 3 + bits21 + 3 + frame_bits("005#0102")) * BIT)]
    # The babbler's program sees none of the copies, and nobody any error.
    assert babbler.error_counters() == (0, 0) and partner.error_counters() == (0, 0)
    assert_listed(daemon, line=11, effect="babble", target="ixxat0:0", at=w0, until=w1,
                  hits=1, state="done")


def noisy_bus_run(daemon: Daemon) -> dict:
    """noisy-bus.toml with traffic both ways on can1 (ixxat0:1 and an ephemeral node); what each
    node saw."""
    n1 = can.Bus(interface="canemu", channel="ixxat0:1", auto_restart=False)
    n2 = can.Bus(interface="canemu", channel="can1", auto_restart=False)
    try:
        drain(n1)
        drain(n2)
        t0 = load_example(daemon, "noisy-bus.toml")
        seen1, seen2 = [], []
        counters_at_3s = None
        step_to(t0 + 900 * MS)
        for k in range(260):  # 0.9 s .. 3.5 s: ten frames each way every 10 ms
            for j in range(10):
                n1.send(msg(0x100 + j, [k % 256, j]))
                n2.send(msg(0x200 + j, [k % 256, j]))
            canemu.step(10 * MS)
            seen1 += drain(n1)
            seen2 += drain(n2)
            if now() == t0 + 3 * S:
                counters_at_3s = (n1.error_counters(), n2.error_counters())
        step_to(t0 + 4 * S - MS)
        seen1 += drain(n1)
        seen2 += drain(n2)
        quiet = (n1.error_counters(), n2.error_counters())
        step_to(t0 + 4 * S + MS)
        stuck = (drain(n1), drain(n2))
        after_stuck = (n1.error_counters(), n2.error_counters())
        n1.send(msg(0x7))
        canemu.step(MS)
        works = ids(drain(n2))
        return {
            "t0": t0,
            "errors": [[(ns(e.timestamp), bytes(e.data)) for e in bus_errors(s)]
                       for s in (seen1, seen2)],
            "received": [[(ns(m.timestamp), m.arbitration_id, bytes(m.data)) for m in frames(s)]
                         for s in (seen1, seen2)],
            "counters_at_3s": counters_at_3s,
            "quiet": quiet,
            "stuck": [[(ns(m.timestamp), m.arbitration_id, bytes(m.data)) for m in s]
                      for s in stuck],
            "after_stuck": after_stuck,
            "works": works,
            "list": fault_list(daemon),
        }
    finally:
        n1.shutdown()
        n2.shutdown()


def test_noisy_bus(daemon):
    """can1: a stuff error with probability 0.1 per frame from 1 s to 3 s, drawn from seed 7, the
    same in a second daemon; then 200 us of dominant bus at 4 s."""
    first = noisy_bus_run(daemon)
    t0 = first["t0"]
    rows = first["list"]
    assert [(int(r["line"]), r["effect"], r["target"], r["at"], r["until"], r["state"])
            for r in rows] == [
        (8, "stuff_error", "can1", seconds(t0 + S), seconds(t0 + 3 * S), "done"),
        (15, "stuck_dominant", "can1", seconds(t0 + 4 * S), seconds(t0 + 4 * S + 200 * US),
         "done")]
    hits, seen = int(rows[0]["hits"]), int(rows[0]["seen"])
    # Every hit is a stuff error detected by the receiver (reported by it), whatever the
    # transmitter then sees (a bit error under the receiver's flag, or an ACK error when an
    # error-passive receiver's flag is recessive).
    stuff = [e for errors in first["errors"] for e in errors if e[1][2] == CAN_ERR_PROT_STUFF]
    assert len(stuff) == hits
    all_errors = [e for errors in first["errors"] for e in errors]
    assert all(t0 + S <= t < t0 + 3 * S + MS for t, _ in all_errors)
    # 2 x 10 frames per 10 ms for 2 s, plus the repetitions, all seen by the fault.
    assert seen == 4000 + hits
    assert 0.07 * seen <= hits <= 0.13 * seen
    # All frames arrive, each once at least (a hit in the last EOF bit may double one).
    for received, base in ((first["received"][0], 0x200), (first["received"][1], 0x100)):
        assert {(i, d) for _, i, d in received} == {
            (base + j, bytes([k % 256, j])) for k in range(260) for j in range(10)}
    assert max(c for pair in first["counters_at_3s"] for c in pair) > 0
    # Errors over, the counters came back to 0; the dominant bus then gives every node
    # REC 97 (a stuff error, +1; 8 more at the first dominant bit after its flag, and at the
    # 14th dominant bit from the flag and every 8th after it: tests/python/test_faults.py).
    assert first["quiet"] == ((0, 0), (0, 0))
    assert first["after_stuck"] == ((0, 97), (0, 97))
    for got in first["stuck"]:
        assert got and got[0][1] == CAN_ERR_PROT | CAN_ERR_BUSERROR
        assert got[0][2][2] == CAN_ERR_PROT_STUFF
        assert all(t0 + 4 * S <= t <= t0 + 4 * S + MS for t, _, _ in got)
    assert first["works"] == [0x7]

    second_daemon = start_default_daemon()
    try:
        second = noisy_bus_run(second_daemon)
    finally:
        second_daemon.stop()
    assert int(second["list"][0]["hits"]) == hits
    assert second == first


def test_lin_checksum(daemon):
    """lin-checksum.toml: the next three responses to 20h on lin0 carry a wrong checksum (the
    sender of `canemu send` is its own responder, so it reports them too); the fourth is whole."""
    load_example(daemon, "lin-checksum.toml")
    done = cli(daemon, "send", "lin0", "20#1122", "20#1122", "20#1122", "20#1122", "--step", "50ms")
    assert done.returncode == 1  # outcomes with errors
    outcomes = [line.split(" ", 2)[2] for line in done.stdout.splitlines()]
    assert outcomes == ["error checksum"] * 3 + ["20#1122 pid 20 enhanced checksum AC"]
    [row] = fault_list(daemon)
    assert (row["effect"], row["target"], row["seen"], row["hits"], row["state"]) == (
        "lin_checksum_error", "lin0", "4", "3", "done")
