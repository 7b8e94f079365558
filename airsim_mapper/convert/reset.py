"""Service request -> the robot's SetPose params that put it back at its scene origin, at rest."""

from __future__ import annotations

from typing import Any

from airsim_mapper.common.geometry import OriginError, parse_origin
from airsim_mapper.convert import sim_fields
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError

POSE_FRAME_ID = "DEFAULT_ID"


@sim_fields.converter("reset_pose")
def reset_pose(msg: Any, ctx: ConvertContext) -> dict[str, Any]:
    """Any request -> {pose: the actor's origin (NED), reset_kinematics: True} for .../SetPose."""
    if "origin" not in ctx.source:
        raise ConversionError("reset_pose: the robot's scene entry has no 'origin'")
    try:
        position, q = parse_origin(ctx.source["origin"])
    except (OriginError, TypeError, AttributeError) as exc:
        raise ConversionError(f"reset_pose: origin: {exc}") from None
    return {
        "pose": {
            "translation": {"x": float(position[0]), "y": float(position[1]), "z": float(position[2])},
            "rotation": {"w": float(q[0]), "x": float(q[1]), "y": float(q[2]), "z": float(q[3])},
            "frame_id": POSE_FRAME_ID,
        },
        "reset_kinematics": True,
    }
