"""A python-can program under test: sends frame 200h every 5 ms from the adapter controller it
is given (python-can's periodic send: canemu runs it in simulated time), prints what it
receives, and ends when a frame 7FFh comes.

    python sender.py ecu:0
"""

import sys

import can


def main() -> int:
    with can.Bus(interface="canemu", channel=sys.argv[1]) as bus:
        task = bus.send_periodic(
            can.Message(arbitration_id=0x200, data=b"\x01\x02", is_extended_id=False), 0.005)
        print("sending", flush=True)
        while True:
            msg = bus.recv(timeout=None)
            if msg is None or msg.is_error_frame:
                continue
            print(f"received {msg.arbitration_id:03X}", flush=True)
            if msg.arbitration_id == 0x7FF:
                task.stop()
                return 0


if __name__ == "__main__":
    sys.exit(main())
