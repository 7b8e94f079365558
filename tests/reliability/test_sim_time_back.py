"""Simulation time going backwards after a simulator restart is counted, logged and shown on /diagnostics."""

from __future__ import annotations

import json
import signal
import time

from harness import Rig, RosMaster, wait_until

from reliability.relkit import (
    ROBOT,
    SCENE,
    SimPorts,
    SimView,
    probe,
    stamps,
    start_node,
    start_server,
    statuses,
    wait_output,
)

FRAME = "airsim_node/Drone1"  # the robot's own tf frame


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


def test_after_a_scene_reload_restarts_the_clock_a_goal_in_the_robots_frame_uses_the_new_pose(
    launcher: Rig, ros_master: RosMaster
):
    ports = SimPorts.free()
    start_server(launcher, ports)
    node = start_node(launcher, ports, "--scene", SCENE, node_name="retf")
    pose_topic = f"{ROBOT}/desired_pose"
    watcher = probe(launcher, "pose", "watch", f"{ROBOT}/actual_pose")
    wait_until(lambda: len(stamps(watcher)) > 10, 30, what="actual_pose")
    view = SimView(ports)
    try:
        home = view.position()
        time.sleep(15.0)  # sim time well past tf's 10 s cache before the reload
        first = probe(launcher, "ahead50", "pose", pose_topic, "50", "0", "0", "1", "0", "0", "0", FRAME)
        wait_output(first, "SENT", 20)
        wait_until(lambda: view.position()[0] > home[0] + 40, 10, what="the first goal, 50 m ahead")
        first.stop()
        loads = node.output().count(f"({SCENE}) loaded")
        reload = probe(launcher, "reload", "strings", "/ProjectAirSim/node/retf/load_scene", SCENE)
        wait_until(lambda: node.output().count(f"({SCENE}) loaded") > loads, 30, what="the scene reloaded")
        reload.stop()
        wait_until(lambda: abs(view.position()[0] - home[0]) < 0.1, 10, what="the robot back home")
        time.sleep(2.0)
        second = probe(launcher, "ahead1", "pose", pose_topic, "1", "0", "0", "1", "0", "0", "0", FRAME)
        wait_output(second, "SENT", 20)
        time.sleep(1.0)
        where = view.position()
    finally:
        view.close()
    print(f"home {home}, after a goal 1 m ahead: {where}")
    # the probe publishes its goal three times: each goes 1 m ahead of where the robot is then
    assert home[0] + 0.7 <= where[0] <= home[0] + 3.3, "the goal was computed from the old scene's transform"
    log = node.output()
    assert log.count("TF_OLD_DATA") < 20  # before: about 2,000 a second until the new time passed the old
    assert log.count("tf buffer cleared") >= 1
