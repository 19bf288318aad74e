"""A DDS peer of canemud's DDS bridge on another host, for test_netns_dds.py: run inside a host's
network namespace (netns.Hosts.popen), with Cyclone DDS's Python binding (PyPI cyclonedds) and
the types of canemu_dds, configured by CYCLONEDDS_URI.

It joins the domain, waits until canemud's bridge matched its writer on <prefix>tx and its
reader on <prefix>frames, writes the frames given by --write, and takes --take frames; what
happens is told on standard output as one JSON object a line:

    {"event": "matched", "seconds": S}     discovery took S seconds (from the participant)
    {"event": "written", "count": N}
    {"event": "frames", "frames": [[timestamp_ns, id, extended, remote, dlc, len, hex, from_tx]]}
    {"event": "alone", "tx": n, "frames": n}    no match within --timeout (--expect-alone)
    {"event": "timeout", "what": ...}           exit status 1

With --expect-alone it only waits --timeout seconds for a match and tells "matched" or
"alone".

A frame is written as `canemu calc frame` and cansend take it: 123#1122, 12345678#R4 (an id of
more than three digits is extended).
"""

from __future__ import annotations

import argparse
import json
import sys
import time

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter, Publisher
from cyclonedds.sub import DataReader, Subscriber
from cyclonedds.topic import Topic
from cyclonedds.util import duration

import canemu_dds


def say(**what) -> None:
    print(json.dumps(what), flush=True)


def parse(text: str) -> canemu_dds.Frame:
    ident, _, rest = text.partition("#")
    frame = canemu_dds.Frame(id=int(ident, 16), extended=len(ident) > 3)
    if rest.upper().startswith("R"):
        frame.remote = True
        frame.dlc = int(rest[1:] or "0")
    else:
        data = bytes.fromhex(rest)
        frame.dlc = frame.len = len(data)
        frame.data = list(data) + [0] * (64 - len(data))
    return frame


def main() -> int:
    p = argparse.ArgumentParser()
    p.add_argument("--domain", type=int, required=True)
    p.add_argument("--prefix", default="canemu/can0/")
    p.add_argument("--write", action="append", default=[])
    p.add_argument("--take", type=int, default=0)
    p.add_argument("--timeout", type=float, default=20.0)
    p.add_argument("--expect-alone", action="store_true")
    args = p.parse_args()

    started = time.monotonic()
    participant = DomainParticipant(args.domain)
    qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepAll,
              Policy.Durability.Volatile)
    ours = Qos(Policy.Partition(["canemu"]))
    tx = DataWriter(Publisher(participant, qos=ours),
                    Topic(participant, args.prefix + "tx", canemu_dds.Frame), qos=qos)
    frames = DataReader(Subscriber(participant, qos=ours),
                        Topic(participant, args.prefix + "frames", canemu_dds.Frame), qos=qos)

    def matched() -> bool:
        return (len(tx.get_matched_subscriptions()) >= 1 and
                len(frames.get_matched_publications()) >= 1)

    deadline = started + args.timeout
    while not matched():
        if time.monotonic() > deadline:
            if args.expect_alone:
                say(event="alone", tx=len(tx.get_matched_subscriptions()),
                    frames=len(frames.get_matched_publications()))
                return 0
            say(event="timeout", what="discovery of canemud's bridge")
            return 1
        time.sleep(0.005)  # polling a condition with a deadline, not waiting for time to pass
    say(event="matched", seconds=round(time.monotonic() - started, 3))
    if args.expect_alone:
        return 0

    for text in args.write:
        tx.write(parse(text))
    say(event="written", count=len(args.write))

    got: list = []
    deadline = time.monotonic() + args.timeout
    while len(got) < args.take:
        if time.monotonic() > deadline:
            say(event="timeout", what=f"{args.take} frames", frames=len(got))
            return 1
        for f in frames.take(N=64):
            got.append([f.timestamp_ns, f.id, f.extended, f.remote, f.dlc, f.len,
                        bytes(f.data[:f.len]).hex(), f.from_tx])
        time.sleep(0.005)  # as above
    say(event="frames", frames=got)
    return 0


if __name__ == "__main__":
    sys.exit(main())
