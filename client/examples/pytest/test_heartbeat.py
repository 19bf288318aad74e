"""A C program on the VCI C API under a bus-off fault, in real time: it must notice, restart its
line and go on sending."""

import pytest


@pytest.mark.canemu(config="bench.toml")
def test_heartbeat_restarts_after_bus_off(canemu, heartbeat):
    canemu.bus("can0")  # the tester's node: it acknowledges the heartbeat
    ecu = canemu.start([heartbeat, "ecu", "30"])
    ecu.expect_output("running")
    canemu.expect_frame("can0", id=0x100, within=1000)

    canemu.inject("bus_off", node="ecu:0")
    ecu.expect_output("bus-off after")
    ecu.expect_output("back on the bus")
    node = canemu.node("ecu:0")
    assert (node.state, node.tec, node.rec) == ("error-active", 0, 0)  # recovered: counters 0

    assert ecu.wait(timeout=30) == 0
    assert "sent 30" in ecu.stdout
    canemu.status()  # canemud writes its recorders before it answers
    beats = [f for f in canemu.frames("can0") if f.id == 0x100]
    assert [f.data[0] for f in beats] == list(range(1, 30))  # the first was taken above
