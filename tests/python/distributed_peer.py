"""A python-can program of its own on one daemon, for tests with several daemons (one process
talks to one canemud): opens can0 on the socket given, then obeys lines on standard input:
"send ID HEXDATA" queues a frame, "recv" prints the frames received so far as a JSON list of
[id, hexdata, timestamp_ns] (error frames it keeps for "errors", which prints them as [can_id,
hexdata]) and "quit" ends it. It answers every line with one line."""

import json
import sys

import can

bus = can.Bus(interface="canemu", channel="can0", socket=sys.argv[1])
print("ready", flush=True)
errors = []
for line in sys.stdin:
    words = line.split()
    if not words:
        continue
    if words[0] == "send":
        data = bytes.fromhex(words[2]) if len(words) > 2 else b""
        bus.send(can.Message(arbitration_id=int(words[1], 16), is_extended_id=False, data=data))
        print("sent", flush=True)
    elif words[0] == "recv":
        got = []
        while (m := bus.recv(0)) is not None:
            if m.is_error_frame:
                errors.append([m.arbitration_id, bytes(m.data).hex()])
            else:
                got.append([m.arbitration_id, bytes(m.data).hex(), round(m.timestamp * 1e9)])
        print(json.dumps(got), flush=True)
    elif words[0] == "errors":
        while (m := bus.recv(0)) is not None:
            if m.is_error_frame:
                errors.append([m.arbitration_id, bytes(m.data).hex()])
        print(json.dumps(errors), flush=True)
        errors = []
    elif words[0] == "quit":
        break
bus.shutdown()
print("bye", flush=True)
