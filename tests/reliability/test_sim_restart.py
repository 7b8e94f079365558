"""The node outlives its simulator: it waits for it, notices it die, and comes back with every bridge."""

from __future__ import annotations

import signal
import statistics
import time
from pathlib import Path

from harness import Rig, RosMaster, wait_until

from reliability.relkit import (
    PROJECT_SIM_CONFIG as SIM_CONFIG,
)
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
    task_and_fd_counts,
    wait_output,
)

CYCLES = 10


def first_after(times: list[float], t0: float) -> float | None:
    return next((t for t in times if t > t0), None)


def test_node_waits_for_a_simulator_that_is_not_running_yet_and_bridges_once_it_appears(
    launcher: Rig, ros_master: RosMaster
):
    ports = SimPorts.free()
    node = start_node(launcher, ports, "--scene", SCENE, node_name="early")
    wait_output(node, "waiting for it: attempt 3", 20)
    assert "Traceback" not in node.output()
    status = probe(launcher, "status", "status", "early")  # the wait is seen over ROS, too
    wait_until(lambda: bool(statuses(status)), 20, what="a status while the simulator is absent")
    waiting = statuses(status)[-1]
    assert waiting["state"] == "connecting" and waiting["attempts"] >= 3, waiting
    assert "nothing listens on port" in waiting["reason"], waiting
    watcher = probe(launcher, "pose", "watch", f"{ROBOT}/actual_pose")
    wait_output(watcher, "READY", 20)
    start_server(launcher, ports)
    up = time.time()
    wait_output(node, f"({SCENE}) loaded", 10)
    # The node's own log stamp (wall clock) of the moment its bridges were running.
    line = next(x for x in node.output().splitlines() if f"({SCENE}) loaded" in x)
    bridged = float(line.split("]")[1].strip(" ["))
    assert bridged - up < 5.0
    assert "answered" in node.output() and "waiting for it: attempt 1, next in 0.2 s" in node.output()
    assert node.output().count("Connecting to simulation server") == 1  # one line per retry, not two
    wait_until(lambda: first_after(stamps(watcher), up) is not None, 30, what="actual_pose after the start")
    wait_until(lambda: statuses(status)[-1]["state"] == "connected", 10, what="the status connected")


def test_ten_simulator_restarts_each_recover_within_five_seconds_and_leak_no_threads_or_sockets(
    launcher: Rig, ros_master: RosMaster
):
    ports = SimPorts.free()
    server = start_server(launcher, ports)
    node = start_node(launcher, ports, "--scene", SCENE, node_name="phoenix")
    watcher = probe(launcher, "pose", "watch", f"{ROBOT}/actual_pose")
    status = probe(launcher, "status", "status", "phoenix")
    wait_until(lambda: len(stamps(watcher)) > 10, 30, what="actual_pose before the first restart")
    view = SimView(ports)
    view.ready()
    driver = probe(launcher, "drive", "twist", f"{ROBOT}/cmd_vel", "10", "2.0")
    wait_output(driver, "LAST", 20)  # the robot is moving: each command lasts 3 s
    assert view.still(0.1) > 0.1
    view.close()
    baseline = task_and_fd_counts(node.popen.pid)
    detections, recoveries, counts = [], [], []
    for cycle in range(CYCLES):
        server.stop(signal.SIGKILL)
        killed = time.time()
        wait_until(
            lambda c=cycle: any(s["state"] == "stale" and s["sim_losses"] == c + 1 for s in statuses(status)),
            5,
            interval=0.02,
            what=f"cycle {cycle}: the status to say stale",
        )
        detections.append(time.time() - killed)
        server = start_server(launcher, ports, wait=False)
        wait_until(
            lambda k=killed: first_after(stamps(watcher), k + 0.3) is not None,
            15,
            interval=0.02,
            what=f"cycle {cycle}: actual_pose after the restart",
        )
        recoveries.append(first_after(stamps(watcher), killed + 0.3) - killed)
        wait_until(
            lambda: statuses(status)[-1]["state"] == "connected", 5, what="the status to say connected"
        )
        if cycle == 0:  # a robot driven when the simulator died: its command does not survive the restart
            view = SimView(ports)
            assert view.still(0.5) < 1e-3
            view.close()
        time.sleep(0.3)
        counts.append(task_and_fd_counts(node.popen.pid))
    print(f"detection s: {detections}\nrecovery s: {recoveries}\nthreads/fds: {baseline} -> {counts}")
    assert max(detections) < 2.0
    assert max(recoveries) < 5.0, recoveries
    threads, fds = zip(*counts, strict=True)
    assert max(threads) <= baseline[0] + 2 and threads[-1] <= threads[1] + 1
    assert max(fds) <= baseline[1] + 4 and fds[-1] <= fds[1] + 2
    last = statuses(status)[-1]
    assert last["reconnects"] == CYCLES and last["scene"] == SCENE
    assert node.output().count("Connecting to simulation server") == 1  # the reconnects log their own lines
    assert node.alive()
    print(f"median recovery {statistics.median(recoveries):.2f} s")


def test_a_client_owned_by_the_mission_script_is_reported_stale_and_never_replaced_behind_its_back(
    launcher: Rig, ros_master: RosMaster
):
    ports = SimPorts.free()
    server = start_server(launcher, ports)
    script = Path(__file__).resolve().parent / "user_client_node.py"
    owner = launcher.python(
        "owner", [str(script), str(ports.topics), str(ports.services), str(SIM_CONFIG), SCENE]
    )
    status = probe(launcher, "status", "status", "owner")
    wait_output(owner, "BRIDGED", 30)
    wait_until(lambda: statuses(status) and statuses(status)[-1]["scene"] == SCENE, 20, what="the status")
    server.stop(signal.SIGKILL)
    wait_until(lambda: statuses(status)[-1]["state"] == "stale", 2.0, interval=0.02, what="stale")
    start_server(launcher, ports)
    time.sleep(3.0)
    last = statuses(status)[-1]
    assert last["state"] == "stale" and last["reconnects"] == 0
    assert last["reason"] == "the simulator closed the connection"
    assert "the mission script owns the client" in owner.output()
    assert owner.alive()


def test_after_a_restart_lazy_streams_flow_at_once_whatever_the_old_simulator_had_run(
    launcher: Rig, ros_master: RosMaster
):
    ports = SimPorts.free()
    server = start_server(launcher, ports)
    node = start_node(launcher, ports, "--scene", SCENE, node_name="lazyback")
    imu = probe(launcher, "imu", "watch", f"{ROBOT}/IMU1/imu")  # subscribed across the restart
    wait_until(lambda: len(stamps(imu)) > 10, 30, what="IMU before the restart")
    time.sleep(40.0)  # the old simulator's clock runs well ahead of what the new one reaches in the test
    server.stop(signal.SIGKILL)
    killed = time.time()
    start_server(launcher, ports)
    wait_output(node, "simulator back", 20)
    back = time.time()
    image = probe(launcher, "image", "watch", f"{ROBOT}/Chase/scene_camera/image")  # subscribed afterwards
    wait_until(lambda: first_after(stamps(imu), back) is not None, 10, what="IMU after the restart")
    # a restarted server's first images take seconds on a busy machine; before, the node also dropped
    # every image stamped before the old simulator's time, here 40 s
    wait_until(lambda: stamps(image), 25, what="a camera image after the restart")
    print(
        f"after the restart: IMU {first_after(stamps(imu), killed) - killed:.2f} s, "
        f"first image {stamps(image)[0] - back:.2f} s after the node was back"
    )
    assert node.alive()
