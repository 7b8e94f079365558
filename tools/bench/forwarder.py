"""The bare forwarder: the floor the bridge's end-to-end figures are divided by.

The real projectairsim client, its own receive loop and msgpack decoding, and one plain rospy publisher
per topic: each robot's `actual_pose` as a PoseStamped and (with `--camera`) its `Cam/scene_camera` as an
Image on the bridge's topic names, so the same probe measures both. No mapping, no tf, no camera_info,
no diagnostics, no process tuning: what a hand-written ~50-line bridge does with the same frames.

    python -m tools.bench.forwarder --topicsport P --servicesport S --simconfigpath DIR --scene FILE
        [--camera]
"""

from __future__ import annotations

import argparse
import json
import signal
import threading
from pathlib import Path
from typing import Any

IMAGE_ENCODINGS = {"BGR": "bgr8", "RGB": "rgb8", "16FC1": "16FC1", "32FC1": "32FC1"}


def forward_pose(publisher: Any) -> Any:
    from genpy import Time
    from geometry_msgs.msg import PoseStamped

    def callback(_topic: Any, msg: dict) -> None:
        out = PoseStamped()
        out.header.stamp = Time(*divmod(msg["time_stamp"], 1_000_000_000))
        out.header.frame_id = "map"
        p, q = msg["position"], msg["orientation"]
        out.pose.position.x, out.pose.position.y, out.pose.position.z = p["x"], p["y"], p["z"]
        o = out.pose.orientation
        o.w, o.x, o.y, o.z = q["w"], q["x"], q["y"], q["z"]
        publisher.publish(out)

    return callback


def forward_image(publisher: Any, frame_id: str) -> Any:
    from genpy import Time
    from sensor_msgs.msg import Image

    def callback(_topic: Any, msg: dict) -> None:
        encoding = IMAGE_ENCODINGS.get(msg["encoding"], msg["encoding"])
        data = msg["data"]
        out = Image(height=msg["height"], width=msg["width"], encoding=encoding, is_bigendian=0, data=data)
        out.step = len(data) // max(out.height, 1)
        out.header.stamp = Time(*divmod(msg["time_stamp"], 1_000_000_000))
        out.header.frame_id = frame_id
        publisher.publish(out)

    return callback


def scene_arguments(description: str) -> argparse.ArgumentParser:
    """The switches of a bench process that connects to the replay server and loads a scene."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--address", default="127.0.0.1")
    parser.add_argument("--topicsport", type=int, required=True)
    parser.add_argument("--servicesport", type=int, required=True)
    parser.add_argument("--simconfigpath", required=True)
    parser.add_argument("--scene", required=True)
    return parser


def load_scene(args: argparse.Namespace) -> tuple[Any, dict]:
    """The real client, connected, with the scene loaded; and the scene file's contents."""
    from projectairsim import ProjectAirSimClient, World

    scene = json.loads((Path(args.simconfigpath) / args.scene).read_text())
    client = ProjectAirSimClient(args.address, args.topicsport, args.servicesport)
    client.connect()
    World(client, args.scene, sim_config_path=args.simconfigpath.rstrip("/") + "/")
    return client, scene


def main(argv: list[str] | None = None) -> int:
    import rospy
    from geometry_msgs.msg import PoseStamped
    from sensor_msgs.msg import Image

    parser = scene_arguments(__doc__.splitlines()[0])
    parser.add_argument("--camera", action="store_true", help="also forward each robot's scene image")
    args, _ros_args = parser.parse_known_args(argv)
    rospy.init_node("bench_forwarder", disable_signals=True)
    client, scene = load_scene(args)
    publishers = []
    for actor in scene["actors"]:
        robot, sim = actor["name"], f"/Sim/{scene['id']}/robots/{actor['name']}"
        pose = rospy.Publisher(f"/airsim_node/{robot}/actual_pose", PoseStamped, queue_size=1)
        client.subscribe(f"{sim}/actual_pose", forward_pose(pose))
        publishers.append(pose)
        if args.camera:
            image = rospy.Publisher(f"/airsim_node/{robot}/Cam/scene_camera/image", Image, queue_size=1)
            client.subscribe(f"{sim}/sensors/Cam/scene_camera", forward_image(image, f"{robot}/Cam"))
            publishers.append(image)
    stop = threading.Event()
    rospy.on_shutdown(stop.set)
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    stop.wait()
    client.disconnect()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
