"""The bare rclpy forwarder: the floor the ROS 2 bridge's end-to-end figures are divided by (the twin of
forwarder.py, run by .venv-ros2's Python).

The real projectairsim client, its own receive loop and msgpack decoding, and one plain rclpy publisher per
topic: each robot's `actual_pose` as a PoseStamped and (with `--camera`) its `Cam/scene_camera` as an Image
on the bridge's topic names, with the QoS the bridge offers them (the default mapping latches the pose:
reliable, transient-local, depth 1; images `sensor_data`), so the same probe reads both. No mapping, no tf,
no camera_info, no diagnostics, no executor, no process tuning; Fast DDS's profile is the node's
(`common/dds_profile.py`).

    python -m tools.bench.forwarder_ros2 --topicsport P --servicesport S --simconfigpath DIR --scene FILE
        [--camera]
"""

from __future__ import annotations

import signal
import threading
from typing import Any

from airsim_mapper.common.dds_profile import use_shipped_profile
from tools.bench.forwarder import IMAGE_ENCODINGS, load_scene, scene_arguments

NANOSECONDS = 1_000_000_000


def forward_pose(publisher: Any) -> Any:
    from geometry_msgs.msg import PoseStamped

    def callback(_topic: Any, msg: dict) -> None:
        out = PoseStamped()
        out.header.stamp.sec, out.header.stamp.nanosec = divmod(msg["time_stamp"], NANOSECONDS)
        out.header.frame_id = "map"
        p, q = msg["position"], msg["orientation"]
        out.pose.position.x, out.pose.position.y, out.pose.position.z = p["x"], p["y"], p["z"]
        o = out.pose.orientation
        o.w, o.x, o.y, o.z = q["w"], q["x"], q["y"], q["z"]
        publisher.publish(out)

    return callback


def forward_image(publisher: Any, frame_id: str) -> Any:
    from sensor_msgs.msg import Image

    def callback(_topic: Any, msg: dict) -> None:
        data = msg["data"]
        out = Image(height=msg["height"], width=msg["width"], is_bigendian=0, data=bytes(data))
        out.encoding = IMAGE_ENCODINGS.get(msg["encoding"], msg["encoding"])
        out.step = len(data) // max(out.height, 1)
        out.header.stamp.sec, out.header.stamp.nanosec = divmod(msg["time_stamp"], NANOSECONDS)
        out.header.frame_id = frame_id
        publisher.publish(out)

    return callback


def main(argv: list[str] | None = None) -> int:
    import rclpy
    from geometry_msgs.msg import PoseStamped
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import Image

    parser = scene_arguments(__doc__.splitlines()[0])
    parser.add_argument("--camera", action="store_true", help="also forward each robot's scene image")
    args = parser.parse_args(argv)
    use_shipped_profile()  # the node's Fast DDS profile: the floor carries the same frames the same way
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node("bench_forwarder")
    latched = QoSProfile(
        depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
    )
    client, scene = load_scene(args)
    for actor in scene["actors"]:
        robot, sim = actor["name"], f"/Sim/{scene['id']}/robots/{actor['name']}"
        pose = node.create_publisher(PoseStamped, f"/airsim_node/{robot}/actual_pose", latched)
        client.subscribe(f"{sim}/actual_pose", forward_pose(pose))
        if args.camera:
            topic = f"/airsim_node/{robot}/Cam/scene_camera/image"
            image = node.create_publisher(Image, topic, qos_profile_sensor_data)
            client.subscribe(f"{sim}/sensors/Cam/scene_camera", forward_image(image, f"{robot}/Cam"))
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    stop.wait()
    client.disconnect()
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
