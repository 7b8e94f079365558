"""Scene and robot configs of the end-to-end benchmark, written as JSON (valid jsonc) into a work folder.

Every scene uses the real-time clock, so message stamps are Unix time and the probe's latency (receive
time - stamp) spans server -> bridge -> subscriber.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

LIDAR_POINTS_PER_SCAN = 100_000
LIDAR_HZ = 20.0


@dataclass(frozen=True)
class CameraSetup:
    width: int
    height: int
    interval_s: float
    image_types: tuple[int, ...] = (0,)


def robot_config(camera: CameraSetup | None, lidar: bool) -> dict[str, Any]:
    sensors: list[dict[str, Any]] = []
    if camera is not None:
        sensors.append(
            {
                "id": "Cam",
                "type": "camera",
                "enabled": True,
                "parent-link": "Frame",
                "capture-interval": camera.interval_s,
                "origin": {"xyz": "0.3 0.0 0.0", "rpy-deg": "0 -10 0"},
                "capture-settings": [
                    {
                        "image-type": image_type,
                        "width": camera.width,
                        "height": camera.height,
                        "fov-degrees": 90,
                        "capture-enabled": True,
                        "pixels-as-float": image_type in (1, 2),
                        "compress": False,
                    }
                    for image_type in camera.image_types
                ],
            }
        )
    if lidar:
        sensors.append(
            {
                "id": "lidar1",
                "type": "lidar",
                "enabled": True,
                "parent-link": "Frame",
                "lidar-type": "generic_cylindrical",
                "number-of-channels": 16,
                "range": 200.0,
                "points-per-second": int(LIDAR_POINTS_PER_SCAN * LIDAR_HZ),
                "horizontal-rotation-frequency": LIDAR_HZ,
                "report-frequency": LIDAR_HZ,  # one report per rotation (else one per physics tick)
                "horizontal-fov-start-deg": 0.0,
                "horizontal-fov-end-deg": 360.0,
                "vertical-fov-upper-deg": -5.0,
                "vertical-fov-lower-deg": -45.0,
                "origin": {"xyz": "0 0 -0.2", "rpy-deg": "0 0 0"},
            }
        )
    return {
        "physics-type": "fast-physics",
        "links": [{"name": "Frame"}],
        "controller": {
            "id": "Flight_Controller",
            "type": "simple-flight-api",
            "airframe-setup": "quadrotor-x",
            "simple-flight-api-settings": {"actuator-order": []},
        },
        "sensors": sensors,
    }


def write_scene(
    folder: Path, name: str, drones: int, camera: CameraSetup | None = None, lidar: bool = False
) -> str:
    """Write `scene_<name>.jsonc` (+ its robot config) into `folder`; returns the scene file name."""
    folder.mkdir(parents=True, exist_ok=True)
    robot_file = f"robot_{name}.jsonc"
    (folder / robot_file).write_text(json.dumps(robot_config(camera, lidar), indent=1))
    scene_file = f"scene_{name}.jsonc"
    (folder / scene_file).write_text(json.dumps(scene_config(name, drones, robot_file), indent=1))
    return scene_file


def scene_config(name: str, drones: int, robot: str | dict[str, Any]) -> dict[str, Any]:
    """The scene of `drones` drones in a row; `robot` is their robot config's file name, or the config
    itself inlined (as the client sends a scene to LoadScene)."""
    return {
        "id": f"Bench{name.title().replace('_', '')}",
        "actors": [
            {
                "type": "robot",
                "name": f"Drone{i + 1}",
                "origin": {"xyz": f"0.0 {3.0 * i:.1f} -3.0", "rpy-deg": "0 0 0"},
                "robot-config": robot,
            }
            for i in range(drones)
        ],
        "clock": {"type": "real-time"},
        "home-geo-point": {"latitude": 47.641468, "longitude": -122.140165, "altitude": 122.0},
    }


def pose_topic(drone: int) -> str:
    return f"/airsim_node/Drone{drone}/actual_pose"


def image_topic(drone: int, image_type: str = "scene_camera") -> str:
    return f"/airsim_node/Drone{drone}/Cam/{image_type}/image"


def lidar_topic(drone: int) -> str:
    return f"/airsim_node/Drone{drone}/lidar1/lidar"


# The default mapping's rules that every pose message feeds, per camera.
CAMERA_FRAME_RULES = ("camera_pose", "camera_tf", "camera_optical_tf")


def write_mapping_without_camera_frames(config_dir: Path) -> Path:
    """A mapping file: the default one without the per-camera frames that every pose message feeds."""
    path = Path(config_dir) / "without_camera_frames.yaml"
    path.write_text(f"version: 1\nextends: default\nremove: [{', '.join(CAMERA_FRAME_RULES)}]\n")
    return path
