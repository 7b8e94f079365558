"""The scene's objects by name: the world file's solids, objects spawned at run time, and their poses.

The scene-level methods of the real server's `WorldSimApi` (Unreal plugin) that name objects: `ListObjects`,
`ListAssets`, `GetObjectPose`, `GetObjectPoses`, `SetObjectPose`, `SpawnObject`, `spawnObjectAtGeo`,
`spawnObjectFromFile`, `spawnObjectFromFileAtGeo`, `DestroyObject`, `DestroyAllSpawnedObjects` and
`createVoxelGrid` (`voxels.py`). Unreal's actors are here
the world's objects, the scene's robots and its env actors; only world objects move, appear and vanish
through these methods (a robot or env actor is moved by its own API).

The world the sensors see changes with them: `LiveWorld` stands for the server's `World` everywhere and
answers from the newest one. Each change builds a new immutable `World` from the objects' poses and
swaps it in with one assignment, so each call (a ray cast, a collision) works on one consistent world;
a reader that makes several calls for one sample (a render, a radar scan, annotations) takes
`world.current` once. A new scene starts again from the world file.
"""

from __future__ import annotations

import logging
import math
import re
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from airsim_mapper.common.geometry import (
    IDENTITY_Q,
    quat_conjugate,
    quat_from_rpy,
    quat_multiply,
    rotate,
    yaw_of,
)
from airsim_mapper.simserver.scene import voxels
from airsim_mapper.simserver.scene.geo import DEFAULT_HOME, geo_to_ned
from airsim_mapper.simserver.wire import messages
from airsim_mapper.simserver.wire.services import Method, ServiceError
from airsim_mapper.simserver.world import gltf
from airsim_mapper.simserver.world.world import World, WorldObject

LOG = logging.getLogger("airsim_mapper.simserver.objects")

# SpawnObject's assets: Unreal's basic shapes, 1 m across before scale
ASSETS = {"Cube": "box", "Sphere": "sphere"}
SPAWNED_COLOR_BGR = (128, 128, 128)
NAN_POSE = (np.full(3, math.nan), IDENTITY_Q)

Pose = tuple[np.ndarray, np.ndarray]
_UNIT_CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
NOT_FOUND = "SetObjectPose failed. No objects of name {} were found in the world."
NOT_MOVABLE = "SetObjectPose failed. Unable to move object {}, check if object state is movable!"


class LiveWorld:
    """The server's world as it is now: every World attribute and method, answered by the newest World."""

    def __init__(self, base: World) -> None:
        self.base = base
        self.current = base

    def __getattr__(self, name: str) -> Any:
        if name in ("base", "current"):  # not set yet (a half-made instance): no recursion
            raise AttributeError(name)
        return getattr(self.current, name)

    def show(self, objects: Sequence[WorldObject]) -> None:
        """Make `objects` the world's solids (the ground and sky stay the world file's)."""
        b = self.base
        self.current = World(objects, b.ground_segmentation_id, b.ground_color_bgr, b.sky_color_bgr, b.source)

    def reset(self) -> None:
        self.current = self.base


@dataclass(frozen=True, eq=False)
class Placed:
    """An object placed in the world: its actor pose, and its shape in the actor's frame (scaled)."""

    name: str
    shape: str
    position: np.ndarray  # the actor's location, world NED
    orientation: np.ndarray  # the actor's rotation (w, x, y, z)
    offset: np.ndarray  # the shape's centre in the actor frame
    size: np.ndarray  # box extents along the actor axes; a sphere's diameter thrice
    segmentation_id: int
    color_bgr: tuple[int, int, int]
    collidable: bool = True
    spawned: bool = False

    @classmethod
    def of(cls, obj: WorldObject) -> Placed:
        """A world file object: its actor sits at its centre, turned by its yaw."""
        return cls(
            obj.name,
            obj.shape,
            np.array(obj.center, dtype=float),
            quat_from_rpy(0.0, 0.0, obj.yaw) if obj.shape == "box" else IDENTITY_Q.copy(),
            np.zeros(3),
            np.array(obj.size, dtype=float),
            obj.segmentation_id,
            obj.color_bgr,
            obj.collidable,
        )

    def solid(self) -> WorldObject:
        """The world's solid: a sphere, or the box yawed like the actor that holds the actor's box turned
        by the rest of its rotation (exactly the box when the actor only yaws)."""
        center = self.position + rotate(self.orientation, self.offset)
        if self.shape == "sphere":
            return WorldObject(
                self.name,
                "sphere",
                center,
                self.size.copy(),
                0.0,
                self.segmentation_id,
                self.color_bgr,
                self.collidable,
            )
        yaw = yaw_of(self.orientation)
        tilt = quat_multiply(quat_conjugate(quat_from_rpy(0.0, 0.0, yaw)), self.orientation)
        extent = np.abs(rotate(tilt, _UNIT_CORNERS * self.size / 2.0)).max(axis=0) * 2.0
        return WorldObject(
            self.name, "box", center, extent, yaw, self.segmentation_id, self.color_bgr, self.collidable
        )


def _pose(value: Any, what: str = "pose") -> Pose:
    """(position, orientation) of a Pose param; a zero rotation (as the client's examples send) is none."""
    if not isinstance(value, Mapping):
        raise ServiceError(f"Parameter '{what}' must be a pose, got {value!r}", code=2.0)
    try:
        position = messages.parse_vector3(value.get("translation"), f"{what} translation")
        rotation = value.get("rotation")
        if isinstance(rotation, Mapping) and all(rotation.get(k) == 0 for k in "wxyz"):
            return position, IDENTITY_Q.copy()
        return position, messages.parse_quaternion(rotation, f"{what} rotation")
    except messages.MessageError as exc:
        raise ServiceError(str(exc), code=2.0) from exc


def _scale(value: Any) -> np.ndarray:
    ok = isinstance(value, (list, tuple)) and len(value) == 3
    if not ok or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value):
        raise ServiceError(f"Parameter 'scale' must be 3 numbers, got {value!r}", code=2.0)
    scale = np.array(value, dtype=float)
    if not np.all(np.isfinite(scale)) or not np.all(scale > 0):
        raise ServiceError(f"Parameter 'scale' must be 3 positive numbers, got {value!r}", code=2.0)
    return scale


def _regex(params: Mapping[str, Any]) -> re.Pattern[str]:
    try:
        return re.compile(str(params["name"]))
    except re.error as exc:
        raise ServiceError(f"Invalid regex '{params['name']}': {exc}") from exc


def pose_result(pose: Pose) -> dict[str, Any]:
    """A Pose reply: {translation, rotation, frame_id}."""
    return messages.transform(pose[0], pose[1])


class SceneObjects:
    """The objects of one scene; `actors()` gives the pose of every robot and env actor by name; `home` is
    the scene's home geo point (latitude, longitude, altitude) for the spawns at geo points."""

    def __init__(
        self,
        world: LiveWorld,
        actors: Callable[[], dict[str, Pose]],
        home: tuple[float, float, float] = DEFAULT_HOME,
    ) -> None:
        self.world = world
        self.actors = actors
        self.home = home
        self._lock = threading.Lock()
        self._placed = {o.name: Placed.of(o) for o in world.base.objects}
        world.reset()

    def _show(self) -> None:
        """Swap in the world of the objects as they are now (called with the lock held)."""
        self.world.show([p.solid() for p in self._placed.values()])

    def names(self) -> list[str]:
        return [*self._placed, *self.actors()]

    # -- reading

    def list_objects(self, params: Mapping[str, Any]) -> list[str]:
        pattern = _regex(params)
        with self._lock:
            names = self.names()
        return [n for n in names if pattern.fullmatch(n)]

    @staticmethod
    def list_assets(params: Mapping[str, Any]) -> list[str]:
        pattern = _regex(params)
        return [a for a in ASSETS if pattern.fullmatch(a)]

    def pose_of(self, name: str) -> Pose:
        """An object's, robot's or env actor's pose; NaN translation for an unknown name (the real reply)."""
        with self._lock:
            placed = self._placed.get(name)
        if placed is not None:
            return placed.position.copy(), placed.orientation.copy()
        return self.actors().get(name, NAN_POSE)

    def get_pose(self, params: Mapping[str, Any]) -> dict[str, Any]:
        return pose_result(self.pose_of(str(params["object_name"])))

    def get_poses(self, params: Mapping[str, Any]) -> list[dict[str, Any]]:
        names = params["object_names"]
        if not isinstance(names, list):
            raise ServiceError(f"Parameter 'object_names' must be a list of names, got {names!r}", code=2.0)
        return [pose_result(self.pose_of(str(n))) for n in names]

    # -- changing

    def set_pose(self, params: Mapping[str, Any]) -> bool:
        name = str(params["object_name"])
        position, orientation = _pose(params["pose"])
        with self._lock:
            placed = self._placed.get(name)
            if placed is None:
                raise ServiceError((NOT_MOVABLE if name in self.actors() else NOT_FOUND).format(name))
            self._placed[name] = replace(placed, position=position, orientation=orientation)
            self._show()
        return True

    def _unique_name(self, name: str) -> str:
        """The real `getUniqueName`: a name any actor's name contains gets the largest number ending such a
        name, plus one, appended ("Box" beside "Box" and "Box3" becomes "Box4")."""
        matching = [n for n in self.names() if name in n]
        if not matching:
            return name
        numbers = [int(m.group()) for m in (re.search(r"\d+$", n) for n in matching) if m]
        return f"{name}{max(numbers, default=0) + 1}"

    def _free_segmentation_id(self) -> int:
        used = {p.segmentation_id for p in self._placed.values()} | {self.world.base.ground_segmentation_id}
        return next((i for i in range(1, 256) if i not in used), 255)

    def _at_geo(self, params: Mapping[str, Any]) -> dict[str, Any]:
        """The params of a spawn at a geo point with the pose it stands for (NED from the home point)."""
        geo = [params[k] for k in ("latitude", "longitude", "altitude")]
        rotation = params["rotation"]
        numbers = [*geo, *(rotation if isinstance(rotation, list) else [None])]
        if any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in numbers) or len(numbers) != 7:
            raise ServiceError(
                f"latitude, longitude, altitude must be numbers and rotation [w, x, y, z], got {numbers!r}",
                code=2.0,
            )
        north, east, down = geo_to_ned(tuple(float(v) for v in geo), self.home)  # type: ignore[arg-type]
        pose = {
            "translation": {"x": north, "y": east, "z": down},
            "rotation": dict(zip("wxyz", (float(v) for v in rotation))),
        }
        return {**params, "pose": pose}

    def spawn_asset_at_geo(self, params: Mapping[str, Any]) -> str:
        return self.spawn_asset(self._at_geo(params))

    def spawn_from_file_at_geo(self, params: Mapping[str, Any]) -> str:
        return self.spawn_from_file(self._at_geo(params))

    def _spawn(self, params: Mapping[str, Any], shape: str, minimum, maximum, color) -> str:
        position, orientation = _pose(params["pose"])
        scale = _scale(params["scale"])
        low, high = np.asarray(minimum, float) * scale, np.asarray(maximum, float) * scale
        # a non-uniformly scaled sphere becomes the sphere around it
        size = np.full(3, float(np.max(high - low))) if shape == "sphere" else high - low
        with self._lock:
            name = self._unique_name(str(params["object_name"]))
            self._placed[name] = Placed(
                name,
                shape,
                position,
                orientation,
                (low + high) / 2.0,
                size,
                self._free_segmentation_id(),
                color,
                spawned=True,
            )
            self._show()
        return name

    def spawn_asset(self, params: Mapping[str, Any]) -> str:
        asset = str(params["asset_path"])
        shape = ASSETS.get(asset)
        if shape is None:
            raise ServiceError(f"There were no objects with name {asset} found in the Registry")
        return self._spawn(params, shape, (-0.5, -0.5, -0.5), (0.5, 0.5, 0.5), SPAWNED_COLOR_BGR)

    def spawn_from_file(self, params: Mapping[str, Any]) -> str:
        """`spawnObjectFromFile`: a glTF model, kept as its bounding box. Bytes that are not a glTF model
        spawn nothing and return the name asked for, as the real server does when Assimp cannot read them."""
        data = params["byte_array"]
        if isinstance(data, list) and all(isinstance(b, int) and 0 <= b < 256 for b in data):
            data = bytes(data)
        file_format = str(params["file_format"]).lower()
        try:
            if not isinstance(data, (bytes, bytearray)):
                raise gltf.GltfError(f"byte_array must be bytes, got {type(data).__name__}")
            if file_format not in ("gltf", "glb"):
                raise gltf.GltfError(f"file format {file_format!r} is not glTF")
            bounds = gltf.model_bounds(bytes(data))
        except gltf.GltfError as exc:
            LOG.warning("spawnObjectFromFile %s: nothing spawned: %s", params["object_name"], exc)
            return str(params["object_name"])
        return self._spawn(params, "box", bounds.minimum, bounds.maximum, bounds.color_bgr)

    def destroy(self, params: Mapping[str, Any]) -> bool:
        name = str(params["object_name"])
        with self._lock:
            if self._placed.pop(name, None) is None:
                LOG.warning("DestroyObject failed. No objects of name %s were found in the world.", name)
                return False
            self._show()
        return True

    def destroy_spawned(self, _: Mapping[str, Any]) -> bool:
        with self._lock:
            self._placed = {n: p for n, p in self._placed.items() if not p.spawned}
            self._show()
        return True

    def voxel_grid(self, params: Mapping[str, Any]) -> list[bool]:
        return voxels.create_voxel_grid(self.world.current, params)

    def methods(self, prefix: str) -> list[Method]:
        spawn = ("object_name", "pose", "scale", "enable_physics")
        geo = ("object_name", "latitude", "longitude", "altitude", "rotation", "scale", "enable_physics")
        from_file = ("file_format", "byte_array", "is_binary")
        return [
            Method(f"{prefix}/ListObjects", ("name",), self.list_objects),
            Method(f"{prefix}/ListAssets", ("name",), self.list_assets),
            Method(f"{prefix}/GetObjectPose", ("object_name",), self.get_pose),
            Method(f"{prefix}/GetObjectPoses", ("object_names",), self.get_poses),
            Method(f"{prefix}/SetObjectPose", ("object_name", "pose", "teleport"), self.set_pose),
            Method(f"{prefix}/SpawnObject", ("asset_path", *spawn), self.spawn_asset),
            Method(f"{prefix}/spawnObjectAtGeo", ("asset_path", *geo), self.spawn_asset_at_geo),
            Method(f"{prefix}/spawnObjectFromFile", (*from_file, *spawn), self.spawn_from_file),
            Method(f"{prefix}/spawnObjectFromFileAtGeo", (*from_file, *geo), self.spawn_from_file_at_geo),
            Method(f"{prefix}/DestroyObject", ("object_name",), self.destroy),
            Method(f"{prefix}/DestroyAllSpawnedObjects", (), self.destroy_spawned),
            Method(f"{prefix}/createVoxelGrid", voxels.VOXEL_GRID_PARAMS, self.voxel_grid),
        ]
