"""CPU per pose message through the bridges a robot's actual_pose feeds, in one process (no ROS master).

The default mapping's bridges for one robot of the bench's scene (one camera) are built on fake links; each
pose message runs every handler the pose stream runs when nobody subscribes to the lazy topics, and what
the worker does with their transforms, with every message serialised as rospy would before sending it.
CPU time of the process (`time.process_time`), so other work on the host barely moves it. Compared with
the previous default: camera frames per pose (`tf: {static: false}`, parent map) and camera_pose eager.

    python -m tools.bench.pose_path [--messages 20000]
"""

from __future__ import annotations

import argparse
import io
import tempfile
import time
from pathlib import Path
from typing import Any

from tools.bench import scenes

PREVIOUS = """version: 1
extends: default
rules:
  - name: camera_pose
    lazy: false
  - name: camera_tf
    tf: {parent: <frame_prefix>map, child: <robot_parts>/<camera_name>/<image_type>, static: false}
    lazy: false
  - name: camera_optical_tf
    tf: {parent: <frame_prefix>map, child: <image_frame>, static: false}
    lazy: false
"""


class SerialisingPublisher:
    """A publisher that serialises each message (rospy's cost before the socket) and counts it."""

    def __init__(self) -> None:
        self.count = 0
        self.buffer = io.BytesIO()

    def publish(self, msg: Any) -> None:
        self.buffer.seek(0)
        msg.serialize(self.buffer)
        self.count += 1

    def get_num_connections(self) -> int:
        return 0

    def unregister(self) -> None:
        pass


def run(mapping: str, messages: int) -> dict[str, float]:
    from tf2_msgs.msg import TFMessage

    from airsim_mapper.engine.bridges import BridgeParts, SimToRos
    from airsim_mapper.engine.mounts import CameraMounts
    from airsim_mapper.engine.runners import build
    from airsim_mapper.mapping.expand import expand
    from airsim_mapper.mapping.loader import load_mapping
    from airsim_mapper.mapping.scene import read_scene

    folder = Path(tempfile.mkdtemp(prefix="pose_path_"))
    scene_file = scenes.write_scene(folder, "pose", 1, scenes.CameraSetup(320, 240, 0.1, (0,)))
    scene = read_scene(str(folder), scene_file)
    if mapping == "previous":
        (folder / "previous.yaml").write_text(PREVIOUS)
        mapping = str(folder / "previous.yaml")
    specs = expand(load_mapping(mapping), scene, "bench", "")
    pose_topic = next(s.sim for s in specs if s.name.startswith("actual_pose["))

    class Ros:
        def __init__(self) -> None:
            self.tf = SerialisingPublisher()
            self.static: dict = {}

        def publisher(self, name: str, ros_type: str, **_kwargs: Any) -> SerialisingPublisher:
            return SerialisingPublisher()

        def now(self) -> Any:
            import genpy

            return genpy.Time(1, 0)

        def tf_wanted(self) -> bool:
            return True  # the transforms are built and serialised, as with a /tf subscriber

        def send_tf(self, transforms: list) -> None:
            self.tf.publish(TFMessage(transforms))

        def set_static_tf(self, transform: Any) -> None:
            self.static[transform.child_frame_id] = transform

        def remove_static_tf(self, child: str) -> None:
            self.static.pop(child, None)

    class Hub:
        def __init__(self) -> None:
            self.handlers: dict[str, list] = {}

        def attach(self, topic: str, handler: Any, inline: bool = False) -> None:
            self.handlers.setdefault(topic, []).append(handler)

        def detach(self, topic: str, handler: Any) -> None:
            self.handlers[topic].remove(handler)

        def sim_now(self) -> int:
            return 0

    ros, hub = Ros(), Hub()
    services = BridgeParts(None, hub, ros, CameraMounts(), lambda *_: None)  # type: ignore[arg-type]
    for spec in specs:
        if spec.direction == "sim_to_ros":
            bridge = build(spec, services)
            bridge.start()
    handlers = hub.handlers.get(pose_topic, [])
    message = {
        "time_stamp": 0,
        "position": {"x": 1.0, "y": 2.0, "z": -3.0},
        "orientation": {"w": 0.9, "x": 0.1, "y": 0.3, "z": 0.3},
    }
    started = time.process_time()
    for i in range(messages):
        message["time_stamp"] = 1_000_000_000 + i * 10_000_000
        transforms: list = []
        for handler in handlers:
            transforms.extend(handler(message) or ())
        if transforms:
            ros.send_tf(transforms)
    cpu = time.process_time() - started
    kinds = sorted({type(h.__self__).__name__ + ":" + h.__self__.spec.name.split("[")[0] for h in handlers})
    assert all(isinstance(h.__self__, SimToRos) for h in handlers)
    return {"us_per_pose": cpu / messages * 1e6, "handlers": len(handlers), "kinds": kinds}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--messages", type=int, default=20000)
    args = parser.parse_args(argv)
    for mapping in ("previous", "default"):
        result = run(mapping, args.messages)
        print(
            f"{mapping:8s} {result['us_per_pose']:7.1f} us per pose, "
            f"{result['handlers']} handlers: {result['kinds']}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
