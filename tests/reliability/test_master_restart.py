"""A restarted ROS master: the node registers its topics again, so new peers find them."""

from __future__ import annotations

from harness import Launcher, RosMaster, wait_until

from reliability.relkit import (
    ROBOT,
    SCENE,
    Ports,
    SimView,
    probe,
    restart_master,
    stamps,
    start_node,
    start_server,
    wait_output,
)


def test_after_a_master_restart_new_subscribers_get_actual_pose_and_new_publishers_drive_the_robot(
    launcher: Launcher, ros_master: RosMaster
):
    ports = Ports.free()
    start_server(launcher, ports)
    node = start_node(launcher, ports, "--scene", SCENE, node_name="survivor")
    before = probe(launcher, "before", "watch", f"{ROBOT}/actual_pose")
    wait_until(lambda: len(stamps(before)) > 5, 30, what="actual_pose before the restart")
    before.stop()
    mark = len(node.output())
    restart_master(launcher, ros_master)
    wait_output(node, "registered again", 10, start=mark)
    after = probe(launcher, "after", "watch", f"{ROBOT}/actual_pose")
    wait_until(lambda: len(stamps(after)) > 5, 20, what="actual_pose from a subscriber of the new master")
    view = SimView(ports)
    view.ready()
    start = view.position()
    driver = probe(launcher, "drive", "twist", f"{ROBOT}/cmd_vel", "10", "2.0")
    wait_output(driver, "LAST", 20)
    moved = view.still(0.0)
    assert abs(view.position()[0] - start[0]) > 0.5, (start, view.position(), moved)
    view.close()
    assert node.alive()
