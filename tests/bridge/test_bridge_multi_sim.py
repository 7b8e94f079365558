"""Many simulators, one ROS graph: two headless servers, two bridge nodes with --namespace, one master."""

from __future__ import annotations

import numpy as np
from bridgeharness import published_topics
from harness import wait_until


def test_two_simulators_share_one_master_without_name_collisions(rig_factory):
    import rospy
    import tf2_ros
    from geometry_msgs.msg import PoseStamped

    first, second = rig_factory(), rig_factory()
    first.start_node(
        "--scene",
        "scene_drone_sensors.jsonc",
        "--namespace",
        "sim1",
        node_name="bridge_sim1",
        wait_for="/sim1/airsim_node/Drone1/actual_pose",
    )
    second.start_node(
        "--scene",
        "scene_two_drones.jsonc",
        "--namespace",
        "sim2",
        node_name="bridge_sim2",
        wait_for="/sim2/airsim_node/Drone2/actual_pose",
    )
    expected = [
        "/sim1/airsim_node/Drone1/lidar1/lidar",
        "/sim2/airsim_node/Drone1/FrontCamera/scene_camera/image",
    ]
    wait_until(lambda: all(t in published_topics() for t in expected), 30, what="both nodes' topics")
    import rosgraph

    pubs, _subs, _srvs = rosgraph.Master("/probe").getSystemState()
    ours = {t for t, nodes in pubs if {"/bridge_sim1", "/bridge_sim2"} & set(nodes)}
    assert {t for t in ours if t.startswith("/sim1/")} and {t for t in ours if t.startswith("/sim2/")}
    # nothing of either node is left un-namespaced (only the node-private status and /diagnostics, tf)
    assert {t for t in ours if not t.startswith(("/sim1/", "/sim2/"))} <= {
        "/tf",
        "/tf_static",
        "/diagnostics",
        "/rosout",
        "/airsim_mapper/bridge_sim1/status",
        "/airsim_mapper/bridge_sim2/status",
    }
    # The same robot name in both simulators, each with its own pose and frames.
    poses = {
        ns: rospy.wait_for_message(f"/{ns}/airsim_node/Drone1/actual_pose", PoseStamped, timeout=20)
        for ns in ("sim1", "sim2")
    }
    assert poses["sim1"].header.frame_id == "sim1/map"
    assert poses["sim2"].header.frame_id == "sim2/map"
    assert poses["sim1"].pose.position.y == 0.0 and poses["sim2"].pose.position.y == -2.5
    buffer = tf2_ros.Buffer()
    tf2_ros.TransformListener(buffer)
    for ns, east in (("sim1", 0.0), ("sim2", -2.5)):
        tf = buffer.lookup_transform(
            f"{ns}/map", f"{ns}/airsim_node/Drone1", rospy.Time(0), rospy.Duration(10)
        )
        assert np.isclose(tf.transform.translation.y, east)
    # Commands reach only their own simulator.
    pub = rospy.Publisher("/sim2/airsim_node/Drone1/desired_pose", PoseStamped, queue_size=1)
    wait_until(lambda: pub.get_num_connections() > 0, 20, what="the sim2 bridge to subscribe")
    target = PoseStamped()
    target.pose.position.x, target.pose.position.z, target.pose.orientation.w = 5.0, -6.0, 1.0
    pub.publish(target)

    def moved() -> bool:
        p = rospy.wait_for_message(
            "/sim2/airsim_node/Drone1/actual_pose", PoseStamped, timeout=10
        ).pose.position
        return abs(p.x - 5.0) < 0.05

    wait_until(moved, 15, what="sim2's Drone1 to teleport")
    p1 = rospy.wait_for_message("/sim1/airsim_node/Drone1/actual_pose", PoseStamped, timeout=10).pose.position
    assert abs(p1.x) < 0.05 and abs(p1.z + 4.0) < 0.05
    pub.unregister()
