"""Commands with finite but absurd values (1e308) never stop the pose stream: the shipped mapping bounds
speeds and positions, and the server refuses motion that would make its state non-finite."""

from __future__ import annotations

import math
import time

from harness import Rig, RosMaster, wait_until

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
    wait_output,
)

HUGE = "1e308"


def test_a_cmd_vel_of_1e308_is_clamped_and_actual_pose_odom_and_tf_keep_flowing(
    launcher: Rig, ros_master: RosMaster
):
    ports = SimPorts.free()
    start_server(launcher, ports)
    node = start_node(launcher, ports, "--scene", SCENE, node_name="bounded")
    status = probe(launcher, "status", "status", "bounded")
    watchers = {
        name: probe(launcher, name, "watch", topic)
        for name, topic in (("pose", f"{ROBOT}/actual_pose"), ("odom", f"{ROBOT}/odom"), ("tf", "/tf"))
    }
    for watcher in watchers.values():
        wait_until(lambda w=watcher: len(stamps(w)) > 5, 40, what=f"{watcher.name} before the command")
    view = SimView(ports)
    view.ready()
    above_the_blocks = {"translation": {"x": 0.0, "y": 0.0, "z": -40.0}, "frame_id": "DEFAULT_ID"}
    above_the_blocks["rotation"] = {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0}
    assert view.call(f"{SIM_ROBOT}/SetPose", pose=above_the_blocks, reset_kinematics=True)
    driver = probe(launcher, "drive", "twist", f"{ROBOT}/cmd_vel", "20", HUGE)
    wait_output(driver, "LAST", 20)
    sent = time.time()
    t0, p0 = time.monotonic(), view.position()
    time.sleep(1.0)
    t1, p1 = time.monotonic(), view.position()
    assert all(math.isfinite(v) for v in p1), p1
    speed = math.dist(p0, p1) / (t1 - t0)
    assert 1.0 < speed < 25.0, (speed, p0, p1)  # clamped to the shipped max_linear_speed
    time.sleep(2.0)
    for name, watcher in watchers.items():
        after = [t for t in stamps(watcher) if t > sent + 1.0]
        assert len(after) > 20, (name, len(after))
    pose = probe(launcher, "teleport", "pose", f"{ROBOT}/desired_pose", HUGE, "0", "-5", "1", "0", "0", "0")
    wait_output(pose, "SENT", 20)
    wait_until(
        lambda: statuses(status)[-1]["bridge_errors"].get("desired_pose[Drone1]", 0) >= 3,
        5,
        what="the out-of-bounds desired_pose counted",
    )
    assert all(abs(v) < 1e4 for v in view.position())
    assert "outside the position box" in node.output()
    view.close()
    assert node.alive()
