"""World files: the JSON or YAML description of a `World` (format in WORLD.md), parsed and checked.

`default_world.json` next to this module is the built-in default world. Every problem is a `WorldError`
naming the file and the offending key.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from airsim_mapper.simserver.errors import SimServerError
from airsim_mapper.simserver.world.world import World, WorldObject

DEFAULT_WORLD_PATH = Path(__file__).parent.parent / "default_world.json"  # simserver/, beside WORLD.md
SHAPES = ("box", "sphere")


class WorldError(SimServerError, ValueError):
    """A world file is malformed; the message names the file and the offending key."""

    def __init__(self, source: str, key: str, problem: str) -> None:
        self.source, self.key, self.problem = source, key, problem
        super().__init__(f"world file {source}: key {key!r}: {problem}")


def _number(value: Any, source: str, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise WorldError(source, key, f"must be a finite number, got {value!r}")
    return float(value)


def _vector(value: Any, source: str, key: str, positive: bool = False) -> np.ndarray:
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise WorldError(source, key, f"must be a list of 3 numbers, got {value!r}")
    vec = np.array([_number(v, source, f"{key}[{i}]") for i, v in enumerate(value)])
    if positive and not (vec > 0).all():
        raise WorldError(source, key, f"must hold 3 positive numbers, got {value!r}")
    return vec


def _color(value: Any, source: str, key: str) -> tuple[int, int, int]:
    ok = isinstance(value, (list, tuple)) and len(value) == 3
    if not ok or not all(isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= 255 for v in value):
        raise WorldError(source, key, f"must be 3 integers 0-255 (blue, green, red), got {value!r}")
    return (value[0], value[1], value[2])


def _seg_id(value: Any, source: str, key: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 255:
        raise WorldError(source, key, f"must be an integer 1-255, got {value!r}")
    return value


def _check_keys(entry: dict, allowed: set[str], source: str, where: str) -> None:
    unknown = sorted(set(entry) - allowed)
    if unknown:
        raise WorldError(
            source, f"{where}.{unknown[0]}", f"unknown key (allowed: {', '.join(sorted(allowed))})"
        )


_OBJECT_KEYS = {
    "name",
    "shape",
    "center",
    "size",
    "radius",
    "yaw-deg",
    "segmentation-id",
    "color-bgr",
    "collidable",
}


def _parse_object(entry: Any, source: str, where: str) -> WorldObject:
    if not isinstance(entry, dict):
        raise WorldError(source, where, f"must be a mapping, got {entry!r}")
    _check_keys(entry, _OBJECT_KEYS, source, where)
    for required in ("name", "shape", "center", "segmentation-id", "color-bgr"):
        if required not in entry:
            raise WorldError(source, f"{where}.{required}", "is required")
    name = entry["name"]
    if not isinstance(name, str) or not name:
        raise WorldError(source, f"{where}.name", f"must be a non-empty string, got {name!r}")
    shape = entry["shape"]
    if shape not in SHAPES:
        raise WorldError(source, f"{where}.shape", f"must be one of {', '.join(SHAPES)}, got {shape!r}")
    center = _vector(entry["center"], source, f"{where}.center")
    if shape == "box":
        if "size" not in entry:
            raise WorldError(source, f"{where}.size", "is required for a box")
        size = _vector(entry["size"], source, f"{where}.size", positive=True)
    else:
        if "radius" not in entry:
            raise WorldError(source, f"{where}.radius", "is required for a sphere")
        radius = _number(entry["radius"], source, f"{where}.radius")
        if radius <= 0:
            raise WorldError(source, f"{where}.radius", f"must be positive, got {radius!r}")
        size = np.full(3, 2.0 * radius)
    yaw = math.radians(_number(entry.get("yaw-deg", 0.0), source, f"{where}.yaw-deg"))
    collidable = entry.get("collidable", True)
    if not isinstance(collidable, bool):
        raise WorldError(source, f"{where}.collidable", f"must be true or false, got {collidable!r}")
    return WorldObject(
        name=name,
        shape=shape,
        center=center,
        size=size,
        yaw=yaw,
        segmentation_id=_seg_id(entry["segmentation-id"], source, f"{where}.segmentation-id"),
        color_bgr=_color(entry["color-bgr"], source, f"{where}.color-bgr"),
        collidable=collidable,
    )


def world_from_dict(data: Any, source: str = "<dict>") -> World:
    """Build a World from the parsed contents of a world file (see WORLD.md)."""
    if not isinstance(data, dict):
        raise WorldError(source, "<top level>", f"must be a mapping, got {type(data).__name__}")
    _check_keys(data, {"version", "ground", "sky", "objects"}, source, "<top level>")
    version = data.get("version", 1)
    if version != 1:
        raise WorldError(source, "version", f"must be 1, got {version!r}")
    ground = data.get("ground", {})
    if not isinstance(ground, dict):
        raise WorldError(source, "ground", f"must be a mapping, got {ground!r}")
    _check_keys(ground, {"segmentation-id", "color-bgr"}, source, "ground")
    sky = data.get("sky", {})
    if not isinstance(sky, dict):
        raise WorldError(source, "sky", f"must be a mapping, got {sky!r}")
    _check_keys(sky, {"color-bgr"}, source, "sky")
    entries = data.get("objects", [])
    if not isinstance(entries, list):
        raise WorldError(source, "objects", f"must be a list, got {entries!r}")
    objects = [_parse_object(e, source, f"objects[{i}]") for i, e in enumerate(entries)]
    ground_id = _seg_id(ground.get("segmentation-id", 1), source, "ground.segmentation-id")
    seen: dict[str, int] = {}
    for i, obj in enumerate(objects):
        if obj.name in seen:
            raise WorldError(
                source, f"objects[{i}].name", f"duplicate name {obj.name!r} (see objects[{seen[obj.name]}])"
            )
        seen[obj.name] = i
        if obj.segmentation_id == ground_id:
            raise WorldError(
                source,
                f"objects[{i}].segmentation-id",
                f"{obj.segmentation_id} is the ground's segmentation id",
            )
    return World(
        objects,
        ground_segmentation_id=ground_id,
        ground_color_bgr=_color(ground.get("color-bgr", [70, 130, 90]), source, "ground.color-bgr"),
        sky_color_bgr=_color(sky.get("color-bgr", [235, 206, 135]), source, "sky.color-bgr"),
        source=source,
    )


def load_world(path: str | os.PathLike | None = None) -> World:
    """Load a world file (.json, or .yaml/.yml); None loads the built-in default world."""
    file = DEFAULT_WORLD_PATH if path is None else Path(path)
    source = str(file)
    try:
        text = file.read_text(encoding="utf-8")
    except OSError as exc:
        raise WorldError(source, "<file>", f"cannot be read ({exc.strerror or exc})") from exc
    try:
        data = yaml.safe_load(text) if file.suffix.lower() in (".yaml", ".yml") else json.loads(text)
    except (json.JSONDecodeError, yaml.YAMLError) as exc:
        raise WorldError(
            source, "<file>", f"is not valid {file.suffix.lstrip('.') or 'JSON'}: {exc}"
        ) from exc
    return world_from_dict(data, source)
