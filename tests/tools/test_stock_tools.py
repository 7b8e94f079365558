"""Debian's own ROS tools, run by the system interpreter outside the venv, read every message the bridge
publishes once the message space `make setup` builds (devel/setup.bash) is sourced: radar included. The
node's /rosout records, as rosout logs them, name their calling file, function and line, and none of the
node's or a mission script's first records is lost."""

from __future__ import annotations

import json

import pytest
from harness import DEVEL_SETUP, SIM_CONFIG, Rig, stock_tool, wait_until

pytestmark = pytest.mark.live

RADAR = "/airsim_node/RadarTower1/radar1"


def test_the_stock_tools_read_radar_live_and_from_a_bag(launcher: Rig) -> None:
    assert DEVEL_SETUP.is_file(), "make setup builds devel/"
    launcher.roscore()
    sim = launcher.simserver()
    node = launcher.node(sim.ports, "--scene", "scene_radar_tower.jsonc")
    launcher.wait_topics([f"{RADAR}/radar_detections", f"{RADAR}/radar_tracks"], node)

    shown = stock_tool(launcher, "rosmsg show radar_msgs/RadarTracks && rosmsg md5 radar_msgs/RadarScan")
    assert shown.returncode == 0, shown.stderr
    assert "uuid_msgs/UniqueID uuid" in shown.stdout and "6dfacef1e665538dbd8e159d5ce7a97a" in shown.stdout

    echo = stock_tool(launcher, f"/usr/bin/rostopic echo -n 1 {RADAR}/radar_detections")
    assert echo.returncode == 0, echo.stdout + echo.stderr
    assert 'frame_id: "airsim_node/RadarTower1/radar1"' in echo.stdout and "returns:" in echo.stdout

    bag = launcher.workdir / "radar.bag"
    record = stock_tool(
        launcher,
        f"/usr/bin/rosbag record -q --duration=3 -O {bag} {RADAR}/radar_detections {RADAR}/radar_tracks",
    )
    assert record.returncode == 0, record.stderr
    launcher.stop(node)  # from here on, only the bag publishes radar
    # rosout's own log: every record of the node names the calling file, line and function
    (rosout_log,) = [p for p in launcher.workdir.glob("ros_log/*/rosout.log") if p.parent.name != "latest"]
    records = [line for line in rosout_log.read_text().splitlines() if " /projectairsim [" in line]
    assert records and not [line for line in records if "threading.py" in line], records[:3]
    assert any(" [node.py:" in line and "(main)]" in line for line in records), records[:3]
    # /rosout latches only its last record: those the node logs before rosout connects must not be lost
    assert any("] setting scene = " in line for line in records), records[:3]
    assert any("] bridges:" in line for line in records), records[:3]

    info = stock_tool(launcher, f"/usr/bin/rosbag info {bag}")
    assert "radar_msgs/RadarScan" in info.stdout and "radar_msgs/RadarTracks" in info.stdout, info.stdout
    replay = stock_tool(
        launcher,
        f"/usr/bin/rostopic echo -n 1 {RADAR}/radar_tracks > tracks.txt & echoing=$!; sleep 2; "
        f"/usr/bin/rosbag play -q {bag}; wait $echoing; cat tracks.txt",
        timeout=60,
    )
    assert replay.returncode == 0, replay.stdout + replay.stderr
    assert "tracks:" in replay.stdout and "radar1" in replay.stdout, replay.stdout


MISSION = """
import sys
import rospy
from airsim_mapper.wrapper import ProjectAirSimWrapper

rospy.init_node("quick_mission")
ProjectAirSimWrapper(topicsport=int(sys.argv[1]), servicesport=int(sys.argv[2]), sim_config_path=sys.argv[3],
                     scene="scene_radar_tower.jsonc")
rospy.spin()
"""


def test_a_mission_script_that_makes_the_wrapper_at_once_keeps_its_records_in_rosout_log(
    launcher: Rig,
) -> None:
    launcher.roscore()
    sim = launcher.simserver()
    mission = launcher.python(
        "mission", ["-c", MISSION, str(sim.topics_port), str(sim.services_port), str(SIM_CONFIG)]
    )
    launcher.wait_topics([f"{RADAR}/radar_detections"], mission)
    loaded = "scene_radar_tower.jsonc) loaded:"  # logged after its topics appear
    wait_until(lambda: loaded in mission.output(), 20, what="the scene loaded")

    def records() -> list[str]:
        logs = [p for p in launcher.workdir.glob("ros_log/*/rosout.log") if p.parent.name != "latest"]
        return [line for p in logs for line in p.read_text().splitlines() if " /quick_mission [" in line]

    def has(text: str) -> bool:
        return any(text in line for line in records())

    # /rosout latches only its last record: the wrapper waits for rosout before it (or the client it
    # opens) logs, as the node does; rosout writes each record as it receives it
    wait_until(lambda: has(loaded), 10, what="the loaded record in rosout.log")
    assert has("Connecting to simulation server"), records()[:5]
    launcher.stop(mission)


FAST = (
    "actual_pose",
    "IMU1/imu",
    "GPS/gps",
    "Airspeed/airspeed",
    "Barometer/barometer",
    "Magnetometer/magnetometer",
    "DistanceSensor/distance",
    "Battery/battery",
    "Chase/camera_pose",
)
CAMERA = "/airsim_node/Drone1/Chase/scene_camera"
FIRSTS = """
import json, sys
import rosbag
first, stamps = {}, {}
for topic, message, t in rosbag.Bag(sys.argv[1]).read_messages():
    first.setdefault(topic, t.to_sec())
    if topic.startswith(sys.argv[2]):
        stamps.setdefault(topic, []).append(message.header.stamp.to_nsec())
print(json.dumps({"first": first, "stamps": stamps}))
"""


def connections_queued(rig: Rig, topic: str, count: int = 12) -> int:
    """How many of `count` TCP connections opened at once to the node publishing `topic` get through while
    the node reads the first one's header (it never comes), each given 0.5 s."""
    import contextlib
    import socket
    import xmlrpc.client

    master = xmlrpc.client.ServerProxy(rig.env["ROS_MASTER_URI"])
    _, _, (publishers, _, _) = master.getSystemState("/probe")
    (node,) = next(nodes for name, nodes in publishers if name == topic)
    _, _, node_uri = master.lookupNode("/probe", node)
    _, _, (_, host, port) = xmlrpc.client.ServerProxy(node_uri).requestTopic("/probe", topic, [["TCPROS"]])
    opened: list[socket.socket] = []
    try:
        for _ in range(count):
            with contextlib.suppress(OSError):
                opened.append(socket.create_connection((host, port), timeout=0.5))
        return len(opened)
    finally:
        for sock in opened:
            sock.close()


def test_a_bag_of_many_topics_starts_every_topic_at_once(launcher: Rig) -> None:
    """`rosbag record` of fourteen topics connects to the node fourteen times within milliseconds: each
    topic starts with the others, and each image with its camera_info (rospy's TCPROS port queued 5 new
    connections, and those beyond started 1 s late, when their clients tried again)."""
    launcher.roscore()
    sim = launcher.simserver()
    node = launcher.node(sim.ports, "--scene", "scene_drone_sensors.jsonc")
    topics = [f"/airsim_node/Drone1/{name}" for name in FAST] + ["/clock", "/tf", "/tf_static"]
    topics += [f"{CAMERA}/image", f"{CAMERA}/camera_info"]
    launcher.wait_topics(topics, node)
    assert connections_queued(launcher, topics[0]) == 12  # with rospy's backlog of 5: 7
    bag = launcher.workdir / "many.bag"
    record = stock_tool(launcher, f"/usr/bin/rosbag record -q --duration=3 -O {bag} {' '.join(topics)}")
    assert record.returncode == 0, record.stderr
    (launcher.workdir / "firsts.py").write_text(FIRSTS)
    read = stock_tool(launcher, f"/usr/bin/python3 firsts.py {bag} {CAMERA}")
    assert read.returncode == 0, read.stderr
    first, stamps = json.loads(read.stdout).values()
    assert set(first) == set(topics)
    start = min(t for topic, t in first.items() if not topic.startswith(CAMERA))  # lazy: it starts later
    late = {t: round(first[t] - start, 3) for t in topics if first[t] - start > 0.8 and CAMERA not in t}
    assert not late, f"topics whose first message came late (s): {late}"
    # the camera's image and camera_info start together (neither connection waits for the other); a
    # busy host may drop one of either later (queue_size 1), so only the start is compared
    images, infos = set(stamps[f"{CAMERA}/image"]), set(stamps[f"{CAMERA}/camera_info"])
    assert len(images & infos) > 10
    paired = min(images & infos)
    assert not [stamp for stamp in images ^ infos if stamp < paired], sorted(images ^ infos)[:5]


def test_rosmsg_and_rossrv_show_every_type_the_bridge_publishes_or_serves(launcher: Rig) -> None:
    """Each type of the shipped mappings' rules and of the node's own topics, through Debian's rosmsg or
    rossrv: they need a package's msg/ (or srv/) and its package.xml, from separate Debian packages."""
    from airsim_mapper.common.ros_types import ros_type_kind
    from airsim_mapper.mapping.loader import load_mapping

    own = {"diagnostic_msgs/DiagnosticArray", "tf2_msgs/TFMessage", "rosgraph_msgs/Clock", "std_msgs/String"}
    ros_types = own | {r.ros_type for m in ("default", "enu") for r in load_mapping(m).rules if r.ros_type}
    commands = [
        f"{'rosmsg' if ros_type_kind(t) == 'topic' else 'rossrv'} show {t}" for t in sorted(ros_types)
    ]
    script = " && ".join(f"/usr/bin/{command} > /dev/null" for command in commands)
    launcher.roscore()  # the shell a user runs them in has a master
    shown = stock_tool(launcher, script, timeout=120)
    assert shown.returncode == 0, shown.stderr
    assert len(commands) > 20
