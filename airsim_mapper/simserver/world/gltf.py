"""The bounds and colour of a glTF 2.0 model (`.gltf` JSON or `.glb` binary), from its bytes.

`spawnObjectFromFile` places a glTF model in the world. This server keeps its bounding box: the box
around every mesh primitive's POSITION bounds, carried through the node hierarchy of the default scene.
The real server imports the file with Assimp (left-handed, metres to centimetres) and turns glTF's +Y up
into Unreal's +Z up (Unreal plugin `AssimpToProcMesh.cpp`), which makes glTF (x, y, z) Unreal (x, z, y):
in the actor's NED frame that is north = x, east = z, down = -y.

Only the JSON is read: POSITION accessors must carry `min` and `max`, as the glTF 2.0 specification
requires, so buffers (embedded or external) are never needed.
"""

from __future__ import annotations

import json
import struct
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from airsim_mapper.simserver.errors import SimServerError

GLB_MAGIC = b"glTF"
GLB_JSON_CHUNK = 0x4E4F534A
DEFAULT_COLOR_BGR = (200, 200, 200)  # glTF's default material is white; a light grey keeps shading visible


class GltfError(SimServerError, ValueError):
    """The bytes are not a glTF 2.0 model this server can take the bounds of."""


@dataclass(frozen=True)
class ModelBounds:
    """The model's box in its actor frame (NED axes, metres, unscaled) and its base colour."""

    minimum: np.ndarray
    maximum: np.ndarray
    color_bgr: tuple[int, int, int]


def read_document(data: bytes) -> dict[str, Any]:
    """The glTF JSON document of `.gltf` text or a `.glb` container."""
    if data[:4] == GLB_MAGIC:
        if len(data) < 20:
            raise GltfError("the GLB file is shorter than its header")
        _, _, length = struct.unpack_from("<4sII", data, 0)
        chunk_length, chunk_type = struct.unpack_from("<II", data, 12)
        if chunk_type != GLB_JSON_CHUNK or 20 + chunk_length > min(length, len(data)):
            raise GltfError("the GLB file does not start with a complete JSON chunk")
        text = data[20 : 20 + chunk_length]
    else:
        text = data
    try:
        document = json.loads(bytes(text).decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise GltfError(f"not glTF JSON: {exc}") from exc
    asset = document.get("asset") if isinstance(document, Mapping) else None
    if not isinstance(asset, Mapping) or not str(asset.get("version", "")).startswith("2"):
        raise GltfError("not a glTF 2.0 document (asset.version must be 2.x)")
    return dict(document)


def _node_matrix(node: Mapping[str, Any]) -> np.ndarray:
    if "matrix" in node:
        return np.array(node["matrix"], dtype=float).reshape(4, 4).T  # glTF matrices are column-major
    x, y, z, w = (float(v) for v in node.get("rotation", (0.0, 0.0, 0.0, 1.0)))
    rotation = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    matrix = np.eye(4)
    matrix[:3, :3] = rotation * np.array(node.get("scale", (1.0, 1.0, 1.0)), dtype=float)
    matrix[:3, 3] = np.array(node.get("translation", (0.0, 0.0, 0.0)), dtype=float)
    return matrix


def _corners(minimum: np.ndarray, maximum: np.ndarray) -> np.ndarray:
    """(8, 4) homogeneous corners of a box."""
    pick = np.array([[(c >> a) & 1 for a in range(3)] for c in range(8)], dtype=bool)
    return np.hstack([np.where(pick, maximum, minimum), np.ones((8, 1))])


def _linear_to_srgb8(value: float) -> int:
    v = min(max(float(value), 0.0), 1.0)
    v = 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055
    return round(v * 255)


def model_bounds(data: bytes) -> ModelBounds:
    """The box around the model's meshes in the actor's NED frame, and its first material's colour."""
    doc = read_document(bytes(data))
    try:
        nodes, meshes, accessors = doc.get("nodes", []), doc.get("meshes", []), doc.get("accessors", [])
        scenes = doc.get("scenes", [])
        if scenes:
            roots = list(scenes[int(doc.get("scene", 0))].get("nodes", []))
        else:
            children = {c for n in nodes for c in n.get("children", [])}
            roots = [i for i in range(len(nodes)) if i not in children]
        points: list[np.ndarray] = []
        primitives: list[Mapping[str, Any]] = []
        stack = [(int(i), np.eye(4)) for i in roots]
        seen = 0
        while stack:
            index, parent = stack.pop()
            seen += 1
            if seen > 100_000:
                raise GltfError("the node hierarchy has a cycle")
            node = nodes[index]
            matrix = parent @ _node_matrix(node)
            stack.extend((int(c), matrix) for c in node.get("children", []))
            if "mesh" not in node:
                continue
            for primitive in meshes[int(node["mesh"])].get("primitives", []):
                accessor = accessors[int(primitive["attributes"]["POSITION"])]
                if "min" not in accessor or "max" not in accessor:
                    raise GltfError("a POSITION accessor has no min and max")
                box = _corners(np.array(accessor["min"][:3], float), np.array(accessor["max"][:3], float))
                points.append((box @ matrix.T)[:, :3])
                primitives.append(primitive)
    except GltfError:
        raise
    except (LookupError, TypeError, ValueError) as exc:
        raise GltfError(f"malformed glTF document: {exc!r}") from exc
    if not points:
        raise GltfError("the default scene has no mesh")
    gltf = np.vstack(points)
    if not np.all(np.isfinite(gltf)):
        raise GltfError("the mesh bounds are not finite")
    ned = np.stack([gltf[:, 0], gltf[:, 2], -gltf[:, 1]], axis=1)
    return ModelBounds(ned.min(axis=0), ned.max(axis=0), _color(doc, primitives))


def _color(doc: Mapping[str, Any], primitives: list[Mapping[str, Any]]) -> tuple[int, int, int]:
    materials = doc.get("materials", [])
    for primitive in primitives:
        if "material" in primitive:
            try:
                factor = materials[int(primitive["material"])]["pbrMetallicRoughness"]["baseColorFactor"]
                r, g, b = (_linear_to_srgb8(c) for c in factor[:3])
            except (LookupError, TypeError, ValueError):
                continue
            return (b, g, r)
    return DEFAULT_COLOR_BGR
