"""The other ways to run the bridge: the two-drone scene, roslaunch, and hello_ros.py (mission script and
bridge sharing one client)."""

from __future__ import annotations

import time

import numpy as np
import pytest
from bridgeharness import published_topics, wait_topic
from harness import ROOT, wait_until


def test_two_drone_scene_bridges_both_robots_and_their_frames(rig_factory):
    import rospy
    import tf2_ros

    rig = rig_factory()
    rig.start_node(
        "--scene",
        "scene_two_drones.jsonc",
        node_name="two_bridge",
        wait_for="/airsim_node/Drone2/FrontCamera/depth_planar_camera/camera_info",
    )
    topics = published_topics()
    for robot in ("Drone1", "Drone2"):
        assert topics[f"/airsim_node/{robot}/actual_pose"] == "geometry_msgs/PoseStamped"
        assert topics[f"/airsim_node/{robot}/FrontCamera/camera_pose"] == "geometry_msgs/PoseStamped"
        for kind in ("scene_camera", "depth_planar_camera"):
            assert topics[f"/airsim_node/{robot}/FrontCamera/{kind}/image"] == "sensor_msgs/Image"
            assert topics[f"/airsim_node/{robot}/FrontCamera/{kind}/camera_info"] == "sensor_msgs/CameraInfo"
    buffer = tf2_ros.Buffer()
    tf2_ros.TransformListener(buffer)
    east = []
    for robot in ("Drone1", "Drone2"):
        tf = buffer.lookup_transform("map", f"airsim_node/{robot}", rospy.Time(0), rospy.Duration(10))
        east.append(tf.transform.translation.y)
    assert east == [-2.5, 2.5]
    line = "no namespace: topics and frames as the mapping names them"  # logged after the bridge table
    wait_until(lambda: line in rig.node.output(), 20, what="the namespace line")
    rig.node.stop()


def test_roslaunch_starts_the_node_and_its_topics_appear(rig_factory):
    rig = rig_factory()
    rig.launcher.start(
        "roslaunch",
        [
            "roslaunch",
            str(ROOT / "launch" / "projectairsim.launch"),
            f"topicsport:={rig.sim.topics_port}",
            f"servicesport:={rig.sim.services_port}",
            "scene:=scene_two_drones.jsonc",
            "nodename:=launched_bridge",
        ],
    )
    wait_topic("/airsim_node/Drone2/actual_pose", timeout=90)
    import rosgraph

    _pubs, subs, _srvs = rosgraph.Master("/probe").getSystemState()
    assert any(t == "/ProjectAirSim/node/launched_bridge/load_scene" for t, _ in subs)
    rig.launcher.stop_all()


def test_hello_ros_flies_to_the_ball_while_the_bridge_publishes(rig_factory):
    import rospy
    from geometry_msgs.msg import PoseStamped
    from sensor_msgs.msg import Image

    rig = rig_factory()
    mission = rig.launcher.python(
        "hello_ros",
        [
            str(ROOT / "scripts" / "hello_ros.py"),
            "--topicsport",
            str(rig.sim.topics_port),
            "--servicesport",
            str(rig.sim.services_port),
            "--nodename",
            "hello",
            "--speed",
            "8",
            "--seconds",
            "60",
        ],
    )
    wait_topic("/airsim_node/Drone1/actual_pose", mission)
    import rosgraph

    # The mission made its World first; the wrapper's own load_scene is there too.
    _pubs, subs, _srvs = rosgraph.Master("/probe").getSystemState()
    assert any(t == "/ProjectAirSim/node/hello/load_scene" for t, _ in subs)
    track: list[np.ndarray] = []
    images: list[float] = []
    subscribers = [
        rospy.Subscriber(
            "/airsim_node/Drone1/actual_pose",
            PoseStamped,
            lambda m: track.append(np.array([m.pose.position.x, m.pose.position.y, m.pose.position.z])),
        ),
        rospy.Subscriber(
            "/airsim_node/Drone1/DownCamera/scene_camera/image",
            Image,
            lambda m: images.append(time.monotonic()),
        ),
    ]
    ball = np.array([20.0, 20.0, -3.0])  # the default world's orange ball

    def near_ball() -> bool:
        if not mission.alive():
            raise AssertionError(mission.output())
        return bool(track) and np.linalg.norm(track[-1] - ball) < 6.0

    try:
        wait_until(near_ball, 45, interval=0.2, what="the drone to reach the ball")
    finally:  # this process is one ROS node for the whole session: leave no subscriber behind
        for subscriber in subscribers:
            subscriber.unregister()
    assert len(images) > 10  # the bridge kept publishing during the mission
    assert mission.alive()
    mission.stop()
    assert mission.popen.returncode == 0, mission.output()
    assert "Traceback" not in mission.output(), mission.output()  # Ctrl-C exits cleanly, pynng included


def unexpected_tracebacks(output: str) -> list[str]:
    """Tracebacks in a log that pass through this project's code (airsim_mapper or the script).

    The client logs its own abandoned requests at disconnect (pynng ConnectionReset in
    postprocess_response_async_with_callback, Context.__del__ on closed sockets); those are the
    library's, not ours, and do not count."""
    blocks = output.split("Traceback (most recent call last):")[1:]
    return [block[:300] for block in blocks if "airsim_mapper" in block or "hello_ros.py" in block]


# What the README's mission snippet leaves to the reader: its imports, the client's ports, and a mission,
# which ends at once or runs until it is stopped.
README_MISSION_PREAMBLE = """
import asyncio, functools, sys
import rospy
from projectairsim import Drone, ProjectAirSimClient, World
from airsim_mapper.wrapper import ProjectAirSimWrapper

ProjectAirSimClient = functools.partial(ProjectAirSimClient, "127.0.0.1", int(sys.argv[1]), int(sys.argv[2]))


async def mission(drone):
    drone.enable_api_control()
    drone.arm()
    print("mission started", flush=True)
    await asyncio.sleep(float(sys.argv[3]))
    print("mission done", flush=True)
"""


def readme_mission_snippet() -> str:
    """The Python block of the README's "A mission script and the bridge on one client"."""
    section = (
        (ROOT / "README.md").read_text().split("### A mission script and the bridge on one client", 1)[1]
    )
    return section.split("```python\n", 1)[1].split("```", 1)[0]


@pytest.mark.parametrize("mission_s", [0.0, 3600.0], ids=["after_the_mission", "during_the_mission"])
def test_the_readmes_mission_script_ends_on_one_ctrl_c(rig_factory, tmp_path, mission_s):
    """The snippet as written, run from the checkout (its sim_config/): World first, then the wrapper on the
    same client. The bridge publishes during the mission and after it, and one Ctrl-C ends the process
    cleanly whether the mission is running or done (the client's receive thread, which runs the bridge's
    loop, keeps a process alive until the client disconnects)."""
    import rospy
    from geometry_msgs.msg import PoseStamped

    rig = rig_factory()
    script = tmp_path / "readme_mission.py"
    script.write_text(README_MISSION_PREAMBLE + readme_mission_snippet())
    args = [str(script), str(rig.sim.topics_port), str(rig.sim.services_port), str(mission_s)]
    mission = rig.launcher.python("readme_mission", args, cwd=ROOT)
    wait_topic("/airsim_node/Drone1/actual_pose", mission)
    wait_until(lambda: "mission started" in mission.output(), 30, what="the mission")
    if not mission_s:
        wait_until(lambda: "mission done" in mission.output(), 30, what="the end of the mission")
    rospy.wait_for_message("/airsim_node/Drone1/actual_pose", PoseStamped, timeout=10)  # bridging
    assert mission.stop(timeout=20) == 0, mission.output()
    assert "Disconnected." in mission.output() and "Traceback" not in mission.output(), mission.output()
    assert ("mission done" in mission.output()) == (not mission_s)
