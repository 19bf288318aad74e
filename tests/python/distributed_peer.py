"""A python-can program of its own on one daemon, for tests with several daemons (one process
talks to one canemud): opens can0 (or the bus named after the socket) on the socket given, then
obeys lines on standard input:
"send ID HEXDATA" queues a frame, "burst N ID" queues N frames of that ID whose two data bytes
count 0 to N - 1, "recv" prints the frames received so far as a JSON list of [id, hexdata,
timestamp_ns], "errors" the error frames received so far (kept aside by "recv") as the same
list, "name" the node's name (bus.node_name) and "quit" ends it. It answers every line with one
line ("error: ..." when python-can raised)."""

import json
import sys

import can

bus = can.Bus(interface="canemu", channel=sys.argv[2] if len(sys.argv) > 2 else "can0",
              socket=sys.argv[1])
print("ready", flush=True)
error_frames = []


def take() -> list:
    got = []
    while (m := bus.recv(0)) is not None:
        entry = [m.arbitration_id, bytes(m.data).hex(), round(m.timestamp * 1e9)]
        (error_frames if m.is_error_frame else got).append(entry)
    return got


for line in sys.stdin:
    words = line.split()
    if not words:
        continue
    try:
        if words[0] == "send":
            data = bytes.fromhex(words[2]) if len(words) > 2 else b""
            bus.send(can.Message(arbitration_id=int(words[1], 16), is_extended_id=False,
                                 data=data))
            print("sent", flush=True)
        elif words[0] == "burst":
            for i in range(int(words[1])):
                bus.send(can.Message(arbitration_id=int(words[2], 16), is_extended_id=False,
                                     data=i.to_bytes(2, "big")), timeout=10)
            print("sent", flush=True)
        elif words[0] == "recv":
            print(json.dumps(take()), flush=True)
        elif words[0] == "errors":
            take()
            print(json.dumps(error_frames), flush=True)
            error_frames.clear()
        elif words[0] == "name":
            print(bus.node_name, flush=True)
        elif words[0] == "quit":
            break
    except can.CanError as e:
        print(f"error: {e}".replace("\n", " "), flush=True)
bus.shutdown()
print("bye", flush=True)
