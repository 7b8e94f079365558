"""Simulation time going backwards after a simulator restart is counted, logged and shown on /diagnostics."""

from __future__ import annotations

import json
import signal
import time

from harness import Rig, RosMaster, wait_until

from reliability.relkit import SCENE, SimPorts, probe, stamps, start_node, start_server, statuses


def diagnostics(process) -> list[dict]:
    prefix = "DIAG "
    return [
        json.loads(line[len(prefix) :]) for line in process.output().splitlines() if line.startswith(prefix)
    ]


def test_sim_time_going_back_after_a_restart_is_counted_logged_and_a_diagnostics_warning(
    launcher: Rig, ros_master: RosMaster
):
    ports = SimPorts.free()
    server = start_server(launcher, ports)
    node = start_node(launcher, ports, "--scene", SCENE, node_name="chrono")
    status = probe(launcher, "status", "status", "chrono")
    diag = probe(launcher, "diag", "diagnostics", "chrono")
    clock = probe(launcher, "clock", "watch", "/clock")  # the clock bridge is lazy
    wait_until(lambda: len(stamps(clock)) > 10, 30, what="/clock")
    time.sleep(3.0)  # sim time well past what a restarted server reaches before the node is back
    assert statuses(status)[-1]["sim_time_jumps_back"] == 0
    assert diagnostics(diag)[-1]["level"] == 0
    server.stop(signal.SIGKILL)
    start_server(launcher, ports, wait=False)

    def jumped() -> bool:
        reports = statuses(status)
        return bool(reports) and reports[-1]["sim_time_jumps_back"] >= 1

    wait_until(jumped, 30, what="the jump back counted on the status topic")
    assert statuses(status)[-1]["sim_time_last_jump_back_s"] > 2.0
    wait_until(lambda: diagnostics(diag)[-1]["level"] == 1, 10, what="a /diagnostics warning")
    warning = diagnostics(diag)[-1]
    assert warning["message"].startswith("connected; simulation time went back ")
    assert int(warning["values"]["sim_time_jumps_back"]) >= 1
    assert "sim time: simulation time went back" in node.output()
    assert node.alive()
