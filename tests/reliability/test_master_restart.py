"""A restarted ROS master: the node registers its topics again, so new peers find them."""

from __future__ import annotations

import time

import pytest
from harness import Rig, RosMaster, free_port, wait_until

from reliability.relkit import (
    ROBOT,
    SCENE,
    SimPorts,
    SimView,
    node_registrations,
    probe,
    restart_master,
    stamps,
    start_namespaced_master,
    start_node,
    start_server,
    unshare_available,
    wait_output,
)
from tools.rig import master_pid, ros_environment


def test_after_a_master_restart_new_subscribers_get_actual_pose_and_new_publishers_drive_the_robot(
    launcher: Rig, ros_master: RosMaster
):
    ports = SimPorts.free()
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


@pytest.mark.skipif(not unshare_available(), reason="needs root and unshare --pid (a fresh PID namespace)")
def test_a_master_restarted_in_a_fresh_pid_namespace_with_the_same_pid_gets_every_registration_back(
    launcher: Rig, tmp_path
):
    """In a container every rosmaster has the same pid: the node must notice the restart all the same."""
    port = free_port()
    env = ros_environment(launcher.env, tmp_path, port)
    launcher.env = env
    master_uri = env["ROS_MASTER_URI"]

    master = start_namespaced_master(launcher, port, env)
    wait_until(lambda: master_pid(master_uri) is not None, 30, what="the namespaced master")
    first_pid = master_pid(master_uri)
    ports = SimPorts.free()
    start_server(launcher, ports)
    node = start_node(launcher, ports, "--scene", SCENE, node_name="contained")
    wait_output(node, f"({SCENE}) loaded", 60)
    wait_until(lambda: node_registrations(master_uri, "/contained")[0] > 30, 20, what="the node's publishers")
    time.sleep(1.0)  # lazily made publishers (tf) settle
    before = node_registrations(master_uri, "/contained")
    mark = len(node.output())
    master.stop()
    restarted = time.monotonic()
    start_namespaced_master(launcher, port, env)
    wait_until(lambda: master_pid(master_uri) is not None, 30, what="the restarted namespaced master")
    assert (
        master_pid(master_uri) == first_pid
    )  # the situation of the bug: a pid check cannot see this restart
    wait_output(node, "registered again", 15, start=mark)
    wait_until(
        lambda: node_registrations(master_uri, "/contained") == before,
        10,
        what=f"the node's {before} registrations with the new master",
    )
    took = time.monotonic() - restarted
    after = probe(launcher, "after", "watch", f"{ROBOT}/actual_pose")
    wait_until(lambda: len(stamps(after)) > 5, 20, what="actual_pose from a subscriber of the new master")
    print(f"re-registered {before} (publishers, subscribers, services) {took:.1f} s after the restart")
    assert node.alive()
