"""LIN faults of the scenario language against a running canemud in stepped time: each lin_*
effect seen as `canemu send` and `canemu dump` show LIN frames and errors, counted by `canemu
fault list`, logged, cleared; a scenario file and `canemu fault inject` alike; refused whole
with the reason when a name does not fit."""

from __future__ import annotations

import json
import subprocess

import pytest

from conftest import CANEMU_CLI, LIN0, LIN_ADAPTER, cli, fault, fault_load, scenario, table, toml

EXTRA = toml(LIN0, LIN_ADAPTER, table("[[lin_node]]", name="door", bus="lin0"),
             table("[[lin_node.response]]", id=0x20, data=[0x11, 0x22]))

# At 19200 bit/s (bit k from the break at floor(k * 1e9 / 19200) ns): a header ends at bit 34,
# a two-byte response at bit 64, a no-response error 126 bits after the header.
def at_bits(start_ms: int, bits: int) -> str:
    ns = start_ms * 1_000_000 + bits * 1_000_000_000 // 19200
    return f"({ns // 1_000_000_000:010}.{ns % 1_000_000_000 // 1000:06})"


def send(daemon, *frames) -> list[str]:
    """`canemu send lin0 FRAMES --step 30ms`: the outcome lines (errors give exit code 1)."""
    return cli(daemon, "send", "lin0", *frames, "--step", "30ms", check=False).stdout.splitlines()


def faults(daemon) -> list:
    return json.loads(cli(daemon, "status", "--json").stdout)["faults"]


@pytest.mark.parametrize("effect, extra, outcome", [
    ("lin_checksum_error", [], "error checksum"),
    ("lin_no_response", [], "error no-response"),
    ("lin_responder_off", ["--node", "door"], "error no-response"),
    # The responder stops after the flipped character: a commander that did not know the
    # response's length takes that character for a checksum, a wrong one.
    ("lin_bit_error", ["--where", "response"], "(0000000000.002291) lin0 error checksum"),
])
def test_each_effect_hits_one_frame_and_the_next_goes_through(daemon, effect, extra, outcome):
    where = [] if "--node" in extra else ["--bus", "lin0"]
    cli(daemon, "fault", "inject", "--effect", effect, *where, "--id", "0x20", "--count", "1",
        *extra)
    first, second = send(daemon, "20#", "20#")
    assert first.endswith(outcome), first
    assert second.endswith("lin0 20#1122 pid 20 enhanced checksum AC"), second
    [f] = faults(daemon)
    assert (f["effect"], f["seen"], f["hits"], f["state"]) == (effect, 2, 1, "done")
    daemon.wait_log(f"{effect}: first hit, frame 20")


# A broken header: the commander reads back what it sent and sees nothing wrong (so `send` finds
# no outcome of its own), a listener (the dump) reports the header's error at the header's end
# (bit 34), as for every header error.
@pytest.mark.parametrize("effect, seen", [
    ("lin_parity_error", f"{at_bits(0, 34)} lin0 error parity"),
    ("lin_sync_error", f"{at_bits(0, 34)} lin0 error sync"),
    ("lin_short_break", f"{at_bits(0, 34)} lin0 error other"),
])
def test_a_broken_header_is_what_the_listeners_see_and_nobody_answers(daemon, effect, seen):
    dump = subprocess.Popen([str(CANEMU_CLI), "--socket", daemon.socket, "dump", "lin0", "-n", "2"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert "listening on lin0" in dump.stderr.readline()
    fault_load(daemon, scenario(
        fault(at="0s", bus="lin0", effect=effect, match={"id": 0x20}, count=1)))
    assert send(daemon, "20#") == []
    cli(daemon, "send", "lin0", "20#", "--step", "30ms")
    out, _ = dump.communicate(timeout=30)
    lines = out.splitlines()
    assert lines[0] == seen
    assert lines[1].endswith("lin0 20#1122 pid 20 enhanced checksum AC")


def test_a_wakeup_pulse_from_a_node_at_its_instant(daemon):
    dump = subprocess.Popen([str(CANEMU_CLI), "--socket", daemon.socket, "dump", "lin0", "-n", "1"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert "listening on lin0" in dump.stderr.readline()
    cli(daemon, "fault", "inject", "--effect", "lin_wakeup", "--node", "door", "--at", "5ms",
        "--pulse", "1ms")
    cli(daemon, "time", "step", "10ms")
    out, _ = dump.communicate(timeout=30)
    assert out.splitlines() == ["(0000000000.006000) lin0 wake-up"]
    daemon.wait_log("lin_wakeup")


def test_lin_names_are_checked_and_nothing_is_applied(daemon):
    bad = cli(daemon, "fault", "inject", "--effect", "lin_checksum_error", "--bus", "can0",
              check=False)
    assert bad.returncode == 1
    assert "bus can0 is a CAN bus; LIN faults need a LIN bus" in bad.stderr
    bad = cli(daemon, "fault", "inject", "--effect", "lin_responder_off", "--node", "nobody",
              check=False)
    assert 'no LIN node named "nobody"' in bad.stderr
    bad = cli(daemon, "fault", "inject", "--effect", "bit_error", "--bus", "lin0", check=False)
    assert "bus lin0 is a LIN bus; CAN faults need a CAN bus" in bad.stderr
    bad = cli(daemon, "fault", "inject", "--effect", "lin_wakeup", "--node", "door",
              "--pulse", "10ms", check=False)
    assert "a LIN wake-up pulse lasts 250 us to 5 ms" in bad.stderr
    assert faults(daemon) == []


def test_a_cleared_fault_stops_hitting(daemon):
    cli(daemon, "fault", "inject", "--effect", "lin_checksum_error", "--bus", "lin0")
    assert send(daemon, "20#")[0].endswith("error checksum")
    cli(daemon, "fault", "clear", "all")
    assert send(daemon, "20#")[0].endswith("lin0 20#1122 pid 20 enhanced checksum AC")
    [f] = faults(daemon)
    assert (f["hits"], f["state"]) == (1, "cleared")
