"""Builders of small scene and robot configs for mapping tests (plain dicts, written as JSON), and of
mapping rules (YAML text)."""

from __future__ import annotations

from typing import Any

MINIMAL_ROBOT: dict[str, Any] = {
    "physics-type": "non-physics",
    "links": [{"name": "Frame"}],
    "sensors": [],
}


def camera(sensor_id: str, captures: list[dict[str, Any]], enabled: bool = True) -> dict[str, Any]:
    return {
        "id": sensor_id,
        "type": "camera",
        "enabled": enabled,
        "parent-link": "Frame",
        "capture-interval": 0.05,
        "capture-settings": captures,
        "origin": {"xyz": "0.3 0 0", "rpy-deg": "0 0 0"},
    }


def capture(image_type: int, enabled: bool = True, streaming: bool = False) -> dict[str, Any]:
    return {
        "image-type": image_type,
        "width": 320,
        "height": 240,
        "fov-degrees": 90,
        "capture-enabled": enabled,
        "streaming-enabled": streaming,
        "pixels-as-float": False,
        "compress": False,
    }


def scene_doc(robots: dict[str, str], scene_id: str = "TestScene") -> dict[str, Any]:
    actors = [
        {
            "type": "robot",
            "name": name,
            "origin": {"xyz": "0 0 -4", "rpy-deg": "0 0 0"},
            "robot-config": config,
        }
        for name, config in robots.items()
    ]
    return {"id": scene_id, "actors": actors, "clock": {"type": "steppable"}}


def pose_rule(name: str, ros: str, ros_type: str = "geometry_msgs/PoseStamped") -> str:
    """One pose rule of a mapping's `rules:` list, in block style, ending with its `type` line."""
    return (
        f"  - name: {name}\n    for_each: robot\n    direction: sim_to_ros\n    converter: pose\n"
        f"    sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose\n    ros: {ros}\n    type: {ros_type}\n"
    )
