"""DBC import (canemu.dbc): public DBC files (tests/data/dbc, from cantools' sources) and one
written here as canemud's [[can_node]] tables; every signal's table keys checked against
cantools' own encoding with an encoder of the keys' meaning written here."""

from __future__ import annotations

import hashlib
import struct
import subprocess
import sys
import tomllib
from pathlib import Path

import cantools
import pytest

from canemu import dbc

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data" / "dbc"
SOCIALLEDGE = DATA / "socialledge.dbc"
MOTOHAWK = DATA / "motohawk.dbc"
NEGATIVE_SCALE = DATA / "issue_636_negative_scaling.dbc"
CASCADED = DATA / "issue_184_extended_mux_cascaded.dbc"

# Written for these tests: send types, delays, CAN FD, a float, an extended ID, two senders, a
# message without a sender, raw start and inactive values.
BENCH = """VERSION ""

NS_ :

BS_:

BU_: GW BCM ENG

BO_ 2566844926 ENG_FD: 16 ENG
 SG_ ENG_FD_temp : 0|32@1- (1,0) [0|0] "degC" GW
 SG_ ENG_FD_crc : 39|8@0+ (1,0) [0|0] "" GW
 SG_ ENG_FD_alive : 40|4@1+ (1,0) [0|0] "" GW
 SG_ ENG_FD_odd : 45|8@1+ (1,0) [0|0] "" GW

BO_ 300 BCM_LIGHTS: 2 BCM
 SG_ BCM_LIGHTS_on : 0|1@1+ (1,0) [0|1] "" GW
 SG_ BCM_LIGHTS_level : 8|8@1+ (0.5,-10) [-10|117.5] "%" GW

BO_ 301 BCM_DOORS: 1 BCM
 SG_ BCM_DOORS_open : 0|1@1+ (1,0) [0|0] "" GW

BO_ 302 SHARED: 1 GW
 SG_ SHARED_x : 0|8@1+ (1,0) [0|0] "" BCM

BO_ 303 ORPHAN: 1 Vector__XXX
 SG_ ORPHAN_x : 0|8@1+ (1,0) [0|0] "" GW

BO_TX_BU_ 302 : GW,BCM;

BA_DEF_ BO_ "GenMsgCycleTime" INT 0 65535;
BA_DEF_ BO_ "GenMsgSendType" ENUM "Cyclic","Spontaneous","CyclicIfActive","CyclicAndSpontaneous",\
"NoMsgSendType","NotUsed";
BA_DEF_ BO_ "GenMsgStartDelayTime" INT 0 65535;
BA_DEF_ BO_ "GenMsgDelayTime" INT 0 65535;
BA_DEF_ SG_ "GenSigStartValue" INT 0 10000;
BA_DEF_ SG_ "GenSigInactiveValue" INT 0 10000;
BA_DEF_ BO_ "VFrameFormat" ENUM "StandardCAN","ExtendedCAN","reserved","reserved","reserved",\
"reserved","reserved","reserved","reserved","reserved","reserved","reserved","reserved",\
"reserved","StandardCAN_FD","ExtendedCAN_FD";
BA_DEF_ BO_ "CANFD_BRS" ENUM "0","1";
BA_DEF_DEF_ "GenMsgCycleTime" 0;
BA_DEF_DEF_ "GenMsgSendType" "NoMsgSendType";
BA_DEF_DEF_ "GenMsgStartDelayTime" 0;
BA_DEF_DEF_ "GenMsgDelayTime" 0;
BA_DEF_DEF_ "GenSigStartValue" 0;
BA_DEF_DEF_ "GenSigInactiveValue" 0;
BA_DEF_DEF_ "VFrameFormat" "StandardCAN";
BA_DEF_DEF_ "CANFD_BRS" "1";
BA_ "GenMsgCycleTime" BO_ 2566844926 10;
BA_ "GenMsgSendType" BO_ 2566844926 3;
BA_ "VFrameFormat" BO_ 2566844926 15;
BA_ "CANFD_BRS" BO_ 2566844926 0;
BA_ "GenMsgStartDelayTime" BO_ 2566844926 5;
BA_ "GenMsgDelayTime" BO_ 2566844926 20;
BA_ "GenMsgCycleTime" BO_ 300 50;
BA_ "GenMsgSendType" BO_ 300 2;
BA_ "GenSigStartValue" SG_ 300 BCM_LIGHTS_level 100;
BA_ "GenSigInactiveValue" SG_ 300 BCM_LIGHTS_level 40;
BA_ "GenMsgSendType" BO_ 301 1;
BA_ "GenMsgCycleTime" BO_ 302 100;
SIG_VALTYPE_ 2566844926 ENG_FD_temp : 1;
"""


@pytest.fixture
def bench(tmp_path: Path) -> Path:
    path = tmp_path / "bench.dbc"
    path.write_text(BENCH)
    return path


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "canemu.dbc", *args], capture_output=True,
                          text=True)


def sig(name, start, length, *, signed=False, scale=1.0, offset=0.0, initial=None, **more):
    """The table of a little-endian integer signal, `more` its other keys."""
    out = {"name": name, "start": start, "length": length, "byte_order": "little_endian",
           "signed": signed, "type": "integer", "scale": scale, "offset": offset}
    out["initial"] = offset if initial is None else initial
    out.update(more)
    return out


def msg(name, id_, length, signal, *, send="cyclic", cycle="100ms", delay="0ms", **more):
    out = {"name": name, "id": id_, "extended": False, "fd": False, "brs": False,
           "length": length, "send": send}
    if cycle is not None:
        out["cycle"] = cycle
    out["delay"] = delay
    out.update(more)
    out["signal"] = signal
    return out


def sonar(name, start, mux):
    return sig(f"SENSOR_SONARS_{name}", start, 12, scale=0.1, multiplexer_ids=[mux])


SOCIALLEDGE_WITHOUT_DRIVER = {"can_node": [
    {"name": "DBG", "bus": "can0"},
    {"name": "IO", "bus": "can0", "message": [
        msg("IO_DEBUG", 500, 4, [
            sig("IO_DEBUG_test_unsigned", 0, 8),
            sig("IO_DEBUG_test_enum", 8, 8),
            sig("IO_DEBUG_test_signed", 16, 8, signed=True),
            sig("IO_DEBUG_test_float", 24, 8, scale=0.5),
        ]),
    ]},
    {"name": "MOTOR", "bus": "can0", "message": [
        msg("MOTOR_STATUS", 400, 3, [
            sig("MOTOR_STATUS_wheel_error", 0, 1),
            sig("MOTOR_STATUS_speed_kph", 8, 16, scale=0.001, unit="kph"),
        ]),
    ]},
    {"name": "SENSOR", "bus": "can0", "message": [
        msg("SENSOR_SONARS", 200, 8, [
            sig("SENSOR_SONARS_mux", 0, 4, multiplexer=True),
            sig("SENSOR_SONARS_err_count", 4, 12),
            sonar("left", 16, 0), sonar("middle", 28, 0), sonar("right", 40, 0),
            sonar("rear", 52, 0),
            sonar("no_filt_left", 16, 1), sonar("no_filt_middle", 28, 1),
            sonar("no_filt_right", 40, 1), sonar("no_filt_rear", 52, 1),
        ]),
    ]},
]}


def test_socialledge_without_the_driver_is_every_other_nodes_messages_exactly():
    done = run(str(SOCIALLEDGE), "--bus", "can0", "--real", "DRIVER")
    assert done.returncode == 0 and done.stderr == ""
    assert done.stdout.startswith(f"# CAN nodes from {SOCIALLEDGE} (canemu.dbc)\n")
    assert "\nid = 500  # 0x1F4\n" in done.stdout
    assert tomllib.loads(done.stdout) == SOCIALLEDGE_WITHOUT_DRIVER
    assert dbc.tables_from_dbc(str(SOCIALLEDGE), "can0", real=["DRIVER"]) == done.stdout


def test_big_endian_ranges_and_a_raw_start_value_are_physical_in_the_table():
    motohawk = tomllib.loads(dbc.tables_from_dbc(str(MOTOHAWK), "can0", real=["FOO"]))
    # No GenMsgCycleTime: on change. No GenSigStartValue: raw 0, so the offset.
    assert motohawk == {"can_node": [{"name": "PCM1", "bus": "can0", "message": [
        msg("ExampleMessage", 496, 8, send="on_change", cycle=None, signal=[
            sig("Temperature", 0, 12, signed=True, scale=0.01, offset=250.0, minimum=229.52,
                maximum=270.47, unit="degK", byte_order="big_endian"),
            sig("AverageRadius", 6, 6, scale=0.1, minimum=0.0, maximum=5.0, unit="m",
                byte_order="big_endian"),
            sig("Enable", 7, 1, unit="-", byte_order="big_endian"),
        ])]}]}
    negative = tomllib.loads(dbc.tables_from_dbc(str(NEGATIVE_SCALE), "can0"))
    # GenSigStartValue 4094 raw: 4094 * -0.01 + 4100.
    [temperature] = negative["can_node"][0]["message"][0]["signal"]
    assert temperature["initial"] == pytest.approx(4059.06, abs=1e-9)
    assert temperature["start"] == 3 and temperature["byte_order"] == "big_endian"
    assert negative["can_node"][1] == {"name": "FOO", "bus": "can0"}


def test_send_types_delays_fd_floats_and_the_first_sender_not_real(bench):
    notes = []
    text = dbc.tables_from_dbc(str(bench), "fd0", real=["GW"],
                               counters=["ENG_FD.ENG_FD_alive"],
                               checksums={"ENG_FD.ENG_FD_crc": "crc8_sae_j1850:0x12"},
                               warn=notes.append)
    assert notes == [f"{bench}: message ORPHAN has no sender; skipped"]
    bcm, eng = tomllib.loads(text)["can_node"]
    assert bcm == {"name": "BCM", "bus": "fd0", "message": [
        msg("BCM_LIGHTS", 300, 2, send="cyclic_if_active", cycle="50ms", signal=[
            # GenSigInactiveValue: the definition's default (raw 0) or the signal's (raw 40).
            sig("BCM_LIGHTS_on", 0, 1, minimum=0.0, maximum=1.0, inactive=0.0),
            sig("BCM_LIGHTS_level", 8, 8, scale=0.5, offset=-10.0, minimum=-10.0,
                maximum=117.5, initial=40.0, inactive=10.0, unit="%"),
        ]),
        msg("BCM_DOORS", 301, 1, send="on_change", cycle=None,
            signal=[sig("BCM_DOORS_open", 0, 1)]),
        # GW sends SHARED first; BCM (BO_TX_BU_) simulates it. NoMsgSendType and a cycle time:
        # cyclic.
        msg("SHARED", 302, 1, signal=[sig("SHARED_x", 0, 8)]),
    ]}
    assert eng == {"name": "ENG", "bus": "fd0", "message": [
        # GenMsgStartDelayTime 5 is the delay; GenMsgDelayTime 20 is not. CANFD_BRS "0".
        msg("ENG_FD", 0x18FEF1FE, 16, send="cyclic_and_on_change", cycle="10ms", delay="5ms",
            extended=True, fd=True, signal=[
                sig("ENG_FD_temp", 0, 32, type="float32", unit="degC"),
                sig("ENG_FD_crc", 39, 8, byte_order="big_endian", checksum="crc8_sae_j1850",
                    data_id=0x12),
                sig("ENG_FD_alive", 40, 4, counter=True),
                sig("ENG_FD_odd", 45, 8),
            ]),
    ]}
    # Without a CANFD_BRS attribute (its default "1"), an FD message switches its bit rate.
    plain = bench.parent / "brs.dbc"
    plain.write_text(BENCH.replace('BA_ "CANFD_BRS" BO_ 2566844926 0;\n', ""))
    [fd] = tomllib.loads(dbc.tables_from_dbc(str(plain), "fd0", real=["BCM"]))["can_node"][1][
        "message"]
    assert (fd["fd"], fd["brs"]) == (True, True)


def test_send_type_names_of_other_spellings_mean_the_same(bench):
    """Vector's other names for the same send types, in any case; the empty name as none."""
    spelled = bench.parent / "spelled.dbc"
    spelled.write_text(BENCH.replace(
        '"Cyclic","Spontaneous","CyclicIfActive","CyclicAndSpontaneous","NoMsgSendType"',
        '"CYCLIC","Event","IfActive","CyclicAndSpontan","vector_leerstring"').replace(
        '"GenMsgSendType" "NoMsgSendType"', '"GenMsgSendType" "vector_leerstring"'))
    sends = {m["name"]: m["send"] for node in tomllib.loads(
        dbc.tables_from_dbc(str(spelled), "fd0"))["can_node"] for m in node.get("message", [])}
    assert sends == {"ENG_FD": "cyclic_and_on_change", "BCM_LIGHTS": "cyclic_if_active",
                     "BCM_DOORS": "on_change", "SHARED": "cyclic"}
    spelled.write_text(BENCH.replace('"Spontaneous"', '"OnChange"'))
    [doors] = [m for m in tomllib.loads(dbc.tables_from_dbc(str(spelled), "fd0"))["can_node"][1][
        "message"] if m["name"] == "BCM_DOORS"]
    assert doors["send"] == "on_change" and "cycle" not in doors


def _reference_encode(message: dict, raws: dict) -> bytes:
    """A frame's bytes from raw values by the table keys alone: little endian from `start` (the
    least significant bit) upwards; big endian from `start` (the most significant bit) down
    each byte, then on at the next byte's bit 7 (the DBC's sawtooth numbering)."""
    bits = [0] * (message["length"] * 8)
    for s in message["signal"]:
        if s["name"] not in raws:
            continue
        n = s["length"]
        raw = raws[s["name"]] & ((1 << n) - 1)
        if s["byte_order"] == "little_endian":
            for i in range(n):
                bits[s["start"] + i] = (raw >> i) & 1
        else:
            pos = s["start"]
            for i in range(n):
                bits[pos] = (raw >> (n - 1 - i)) & 1
                pos = pos + 15 if pos % 8 == 0 else pos - 1
    return bytes(sum(bits[8 * b + i] << i for i in range(8)) for b in range(message["length"]))


def _raw_values(s: dict) -> list:
    """Raw values that reach every bit: the extremes, 1 and alternating patterns."""
    n = s["length"]
    if s["type"] != "integer":
        return [0.0, 1.5, -2.25, 1000.0]
    if s["signed"]:
        return [-(1 << (n - 1)), -1, 0, (1 << (n - 1)) - 1, 1 if n > 1 else 0]
    return [0, 1, (1 << n) - 1, int("10" * 32, 2) & ((1 << n) - 1), int("01" * 32, 2) >> (64 - n)]


def _raw_bits(s: dict, value) -> int:
    """The raw bits of a value: the integer, or an IEEE 754 float's bit pattern."""
    if s["type"] == "float32":
        return struct.unpack("<I", struct.pack("<f", value))[0]
    if s["type"] == "float64":
        return struct.unpack("<Q", struct.pack("<d", value))[0]
    return value


@pytest.mark.parametrize("source", ["socialledge", "motohawk", "negative", "bench"])
def test_every_signals_table_keys_encode_as_cantools_does(source, bench):
    path = {"socialledge": SOCIALLEDGE, "motohawk": MOTOHAWK, "negative": NEGATIVE_SCALE,
            "bench": bench}[source]
    db = cantools.database.load_file(str(path))
    tables = tomllib.loads(dbc.tables_from_dbc(str(path), "can0"))
    messages = [m for node in tables["can_node"] for m in node.get("message", [])]
    assert len(messages) == len([m for m in db.messages if m.senders])
    checked = 0
    for message in messages:
        mux = next((s for s in message["signal"] if s.get("multiplexer")), None)
        selectors = sorted({i for s in message["signal"] for i in s.get("multiplexer_ids", [])})
        for selector in selectors or [None]:
            present = [s for s in message["signal"]
                       if "multiplexer_ids" not in s or selector in s["multiplexer_ids"]]
            for k in range(5):
                raws = {}
                for s in present:
                    values = _raw_values(s)
                    raws[s["name"]] = values[k % len(values)]
                if mux is not None:
                    raws[mux["name"]] = selector
                # Physical values from the table's scale and offset; cantools turns them back.
                physical = {s["name"]: raws[s["name"]] * s["scale"] + s["offset"]
                            for s in present}
                ours = _reference_encode(message, {s["name"]: _raw_bits(s, raws[s["name"]])
                                                   for s in present})
                theirs = db.encode_message(message["name"], physical, strict=False)
                assert ours == theirs, (message["name"], raws)
                checked += 1
        # The initial values, encoded by the keys, decode with cantools to the table's.
        initial = {s["name"]: round((s["initial"] - s["offset"]) / s["scale"])
                   for s in message["signal"]
                   if "multiplexer_ids" not in s or 0 in s["multiplexer_ids"]}
        decoded = db.decode_message(message["name"], _reference_encode(message, initial),
                                    decode_choices=False)
        for name, value in decoded.items():
            table = next(s for s in message["signal"] if s["name"] == name)
            assert value == pytest.approx(table["initial"], abs=1e-9), name
    assert checked >= 5 * len(messages)


def test_the_test_files_are_the_ones_their_readme_names():
    for line in (DATA / "README.md").read_text().splitlines():
        if line.startswith("| `") and ".dbc`" in line:
            name, digest = [cell.strip(" `") for cell in line.split("|")[1:3]]
            assert hashlib.sha256((DATA / name).read_bytes()).hexdigest() == digest, name


def refused(*args: str) -> str:
    """stderr of a refused run (status 2, nothing on stdout)."""
    done = run(*args)
    assert (done.returncode, done.stdout) == (2, ""), done.stderr
    assert "Traceback" not in done.stderr
    return done.stderr


def test_unreadable_files_and_unknown_names_are_refused(tmp_path):
    missing = tmp_path / "none.dbc"
    assert refused(str(missing), "--bus", "can0") == (
        f"canemu.dbc: {missing}: No such file or directory\n")
    garbage = tmp_path / "garbage.dbc"
    garbage.write_text("this is not a CAN database\n")
    assert refused(str(garbage), "--bus", "can0").startswith(
        f"canemu.dbc: {garbage}: not a DBC cantools 45.1.0 reads: ")
    social = str(SOCIALLEDGE)
    assert refused(social, "--bus", "can0", "--real", "TRUNK") == (
        f"canemu.dbc: {social}: no node is named 'TRUNK' (nodes: DBG, DRIVER, IO, MOTOR, "
        f"SENSOR)\n")
    assert refused(social, "--bus", "can0", "--counter", "NOPE.x") == (
        "canemu.dbc: --counter NOPE.x: no simulated message is named 'NOPE'\n")
    assert refused(social, "--bus", "can0", "--counter", "MOTOR_STATUS") == (
        "canemu.dbc: --counter 'MOTOR_STATUS': name a signal as MESSAGE.SIGNAL\n")
    assert refused(social, "--bus", "can0", "--counter", "MOTOR_STATUS.rpm") == (
        "canemu.dbc: --counter MOTOR_STATUS.rpm: message MOTOR_STATUS has no signal 'rpm' "
        "(signals: MOTOR_STATUS_wheel_error, MOTOR_STATUS_speed_kph)\n")
    assert refused(social, "--bus", "can0", "--real", "DRIVER", "--checksum",
                   "MOTOR_CMD.MOTOR_CMD_drive=xor8") == (
        "canemu.dbc: --checksum MOTOR_CMD.MOTOR_CMD_drive: message MOTOR_CMD is sent by DRIVER, "
        "which --real names (not simulated)\n")


def test_counters_and_checksums_where_they_cannot_be_are_refused(bench):
    b = str(bench)
    assert refused(b, "--bus", "fd0", "--counter", "ENG_FD.ENG_FD_temp") == (
        "canemu.dbc: --counter ENG_FD.ENG_FD_temp: a counter needs an integer signal that is "
        "not the multiplexor\n")
    assert refused(str(SOCIALLEDGE), "--bus", "can0", "--counter",
                   "SENSOR_SONARS.SENSOR_SONARS_mux").endswith("not the multiplexor\n")
    assert refused(b, "--bus", "fd0", "--checksum", "ENG_FD.ENG_FD_odd=sum8") == (
        "canemu.dbc: --checksum ENG_FD.ENG_FD_odd: a checksum needs an 8-bit integer signal in "
        "one whole byte (this one: 8 bits from bit 45, little_endian, integer)\n")
    assert refused(b, "--bus", "fd0", "--checksum", "ENG_FD.ENG_FD_alive=xor8") == (
        "canemu.dbc: --checksum ENG_FD.ENG_FD_alive: a checksum needs an 8-bit integer signal "
        "in one whole byte (this one: 4 bits from bit 40, little_endian, integer)\n")
    assert refused(b, "--bus", "fd0", "--checksum", "ENG_FD.ENG_FD_crc=crc16") == (
        "canemu.dbc: --checksum ENG_FD.ENG_FD_crc: 'crc16' is not an algorithm canemud "
        "computes (crc8_sae_j1850, xor8, sum8)\n")
    assert refused(b, "--bus", "fd0", "--checksum", "ENG_FD.ENG_FD_crc=xor8:7") == (
        "canemu.dbc: --checksum ENG_FD.ENG_FD_crc: xor8 takes no data ID\n")
    assert refused(b, "--bus", "fd0", "--checksum", "ENG_FD.ENG_FD_crc=crc8_sae_j1850:70000") == (
        "canemu.dbc: --checksum ENG_FD.ENG_FD_crc: data ID '70000' is not a number 0..65535\n")
    assert refused(b, "--bus", "fd0", "--counter", "ENG_FD.ENG_FD_crc", "--checksum",
                   "ENG_FD.ENG_FD_crc=xor8") == (
        "canemu.dbc: --checksum ENG_FD.ENG_FD_crc: the signal is already a counter or a "
        "checksum\n")
    assert "--checksum 'ENG_FD.ENG_FD_crc': write MSG.SIG=ALGO[:DATA_ID]" in refused(
        b, "--bus", "fd0", "--checksum", "ENG_FD.ENG_FD_crc")


def test_send_types_extended_multiplexing_and_lengths_that_do_not_fit_are_refused(bench):
    variants = {
        # BCM_DOORS: "NotUsed" is no send type; "Cyclic" without a cycle time.
        'BA_ "GenMsgSendType" BO_ 301 5;': (
            "message BCM_DOORS: GenMsgSendType 'NotUsed' is not a send type canemu knows "
            "(Cyclic, Spontaneous, OnChange, Event, CyclicIfActive, IfActive, "
            "CyclicAndSpontaneous, NoMsgSendType)"),
        'BA_ "GenMsgSendType" BO_ 301 0;': (
            "message BCM_DOORS: send type cyclic needs a GenMsgCycleTime from 1 ms to 1 hour, "
            "the DBC gives 0 ms"),
    }
    for line, reason in variants.items():
        bent = bench.parent / "bent.dbc"
        bent.write_text(BENCH.replace('BA_ "GenMsgSendType" BO_ 301 1;', line))
        assert refused(str(bent), "--bus", "can0") == f"canemu.dbc: {bent}: {reason}\n"
    # A classic frame of 9 bytes; an FD frame of 10.
    bent.write_text(BENCH.replace("BO_ 301 BCM_DOORS: 1 BCM", "BO_ 301 BCM_DOORS: 9 BCM"))
    assert refused(str(bent), "--bus", "can0") == (
        f"canemu.dbc: {bent}: message BCM_DOORS: 9 bytes is not a classic CAN length\n")
    bent.write_text(BENCH.replace("ENG_FD: 16 ENG", "ENG_FD: 10 ENG"))
    assert refused(str(bent), "--bus", "can0") == (
        f"canemu.dbc: {bent}: message ENG_FD: 10 bytes is not a CAN FD length\n")
    # cantools' cascaded multiplexors, with a sender (the file has none, so it is skipped).
    cascaded = bench.parent / "cascaded.dbc"
    cascaded.write_text(CASCADED.read_text().replace("BU_:", "BU_: GW").replace(
        "ext_MUX_cascaded: 8 Vector__XXX", "ext_MUX_cascaded: 8 GW"))
    assert refused(str(cascaded), "--bus", "can0") == (
        f"canemu.dbc: {cascaded}: message ext_MUX_cascaded: extended multiplexing (multiplexors "
        f"muxed_A_2_MUX_B, MUX_A) is not supported; only one multiplexor per message\n")
    done = run(str(CASCADED), "--bus", "can0")
    assert done.returncode == 0
    assert done.stderr == (f"canemu.dbc: note: {CASCADED}: message ext_MUX_cascaded has no "
                           f"sender; skipped\n")
    assert tomllib.loads(done.stdout) == {}
