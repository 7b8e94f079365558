"""Services for every robot of the scene at once (`for_each: scene`, converter trigger_all)."""

from __future__ import annotations

from bridgeharness import Stack
from harness import wait_until


def test_land_all_and_takeoff_all_move_every_drone_of_the_scene(rig_factory):
    import rospy
    from geometry_msgs.msg import PoseStamped
    from std_srvs.srv import Trigger

    rig: Stack = rig_factory()
    rig.start_node(
        "--scene",
        "scene_two_drones.jsonc",
        node_name="all_bridge",
        wait_for="/airsim_node/Drone2/actual_pose",
    )
    heights: dict[str, float] = {}
    subs = [
        rospy.Subscriber(
            f"/airsim_node/{robot}/actual_pose",
            PoseStamped,
            lambda m, r=robot: heights.__setitem__(r, m.pose.position.z),
            queue_size=1,
        )
        for robot in ("Drone1", "Drone2")
    ]
    try:
        wait_until(lambda: len(heights) == 2, 20, what="both poses")
        rospy.wait_for_service("/airsim_node/land_all", timeout=20)
        reply = rospy.ServiceProxy("/airsim_node/land_all", Trigger)()
        assert reply.success, reply.message
        assert "2 robots" in reply.message
        wait_until(lambda: all(z > -0.3 for z in heights.values()), 20, what="both drones to land")
        reply = rospy.ServiceProxy("/airsim_node/takeoff_all", Trigger)()
        assert reply.success, reply.message
        # takeoff_all lifts each drone to 3 m above the ground; both settle there
        wait_until(lambda: all(abs(z + 3.0) < 0.1 for z in heights.values()), 20, what="both drones at 3 m")
    finally:
        for sub in subs:
            sub.unregister()
