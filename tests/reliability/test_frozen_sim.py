"""A frozen simulator (SIGSTOP): the node can still be stopped at once, and a short stall resets nothing."""

from __future__ import annotations

import json
import math
import signal
import time

from harness import Child, Rig, RosMaster, wait_until

from reliability.relkit import (
    ROBOT,
    SCENE,
    SIM_ROBOT,
    SimPorts,
    SimView,
    probe,
    stamps,
    start_node,
    start_server,
    statuses,
)

SHUTDOWN_DEADLINE_S = 5.0
STALL_S = 4.5
LAZY_TOPICS = (
    f"{ROBOT}/DownCamera/scene_camera/image",
    f"{ROBOT}/DownCamera/depth_camera/image",
    f"{ROBOT}/lidar1/lidar",
    f"{ROBOT}/radar1/radar_detections",
    f"{ROBOT}/IMU1/imu",
)


def bridged_node(launcher: Rig, name: str) -> tuple[Child, Child]:
    """A server and a node on the sensors scene with several lazy streams subscribed (each needs an
    unsubscribe request at shutdown)."""
    ports = SimPorts.free()
    server = start_server(launcher, ports)
    node = start_node(launcher, ports, "--scene", SCENE, node_name=name)
    for index, topic in enumerate(LAZY_TOPICS):
        watcher = probe(launcher, f"lazy{index}", "watch", topic)
        wait_until(lambda w=watcher: len(stamps(w)) > 0, 60, what=f"{topic} flowing")
    return server, node


def test_sigint_stops_the_node_within_its_deadline_while_the_simulator_is_frozen(
    launcher: Rig, ros_master: RosMaster
):
    server, node = bridged_node(launcher, "frozen")
    server.popen.send_signal(signal.SIGSTOP)
    try:
        time.sleep(0.3)
        started = time.monotonic()
        node.popen.send_signal(signal.SIGINT)
        code = node.wait(SHUTDOWN_DEADLINE_S + 5.0)
        took = time.monotonic() - started
    finally:
        server.popen.send_signal(signal.SIGCONT)
    print(f"stopped in {took:.2f} s with the simulator frozen")
    assert took < SHUTDOWN_DEADLINE_S + 1.0, took
    assert code == 0
    assert "Traceback" not in node.output()
    assert "stopping (SIGINT)" in node.output()  # what stopped it is in its log


def test_a_second_sigint_ends_the_node_at_once(launcher: Rig, ros_master: RosMaster):
    server, node = bridged_node(launcher, "impatient")
    server.popen.send_signal(signal.SIGSTOP)
    try:
        time.sleep(0.3)
        node.popen.send_signal(signal.SIGINT)
        time.sleep(0.3)
        second = time.monotonic()
        node.popen.send_signal(signal.SIGINT)
        node.wait(10.0)
        took = time.monotonic() - second
    finally:
        server.popen.send_signal(signal.SIGCONT)
    assert took < 1.0, took
    assert "second signal" in node.output()


def test_a_short_stall_neither_reloads_the_scene_nor_silences_status_and_diagnostics(
    launcher: Rig, ros_master: RosMaster
):
    ports = SimPorts.free()
    server = start_server(launcher, ports)
    node = start_node(launcher, ports, "--scene", SCENE, node_name="patient")
    status = probe(launcher, "status", "status", "patient")
    diagnostics = probe(launcher, "diagnostics", "watch", "/diagnostics")
    pose = probe(launcher, "pose", "watch", f"{ROBOT}/actual_pose")
    wait_until(lambda: len(stamps(pose)) > 5, 40, what="actual_pose")
    view = SimView(ports)
    away = {"translation": {"x": 7.0, "y": -3.0, "z": -6.0}, "frame_id": "DEFAULT_ID"}
    away["rotation"] = {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0}
    assert view.call(f"{SIM_ROBOT}/SetPose", pose=away, reset_kinematics=True)
    mark = len(node.output())
    server.popen.send_signal(signal.SIGSTOP)
    stopped = time.time()
    time.sleep(STALL_S)
    server.popen.send_signal(signal.SIGCONT)
    resumed = time.time()
    wait_until(lambda: any(t > resumed + 1.0 for t in stamps(pose)), 20, what="actual_pose after the stall")
    time.sleep(2.0)
    assert math.dist(view.position(), (7.0, -3.0, -6.0)) < 1e-6  # not teleported back to the start
    view.close()
    reports = statuses(status)
    last = reports[-1]
    assert last["state"] == "connected" and last["reconnects"] == 0, json.dumps(last)
    assert "simulator back" not in node.output()[mark:] and "answers again" in node.output()[mark:]
    for name, times in (("status", stamps(status, "STATUST")), ("diagnostics", stamps(diagnostics))):
        during = [t for t in times if stopped - 1.0 <= t <= resumed + 1.0]
        gaps = [b - a for a, b in zip(during, during[1:])]
        assert during and max(gaps, default=0.0) < 2.0, (name, gaps)
        assert during[0] < stopped + 1.5 and during[-1] > resumed - 1.5, (name, during, stopped, resumed)
    assert node.alive()
