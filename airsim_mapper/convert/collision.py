"""sim CollisionInfo -> geometry_msgs/PointStamped: where the robot hit something, in the world frame.

Sim fields (protocol.md §5.3): ``{time_stamp, object_name, segmentation_id, position, impact_point,
normal, penetration_depth}``. The impact point is a world point (NED; ENU with the ENU convention). A
PointStamped is typed, plots in RViz and its arrival is the event; the object name is not carried.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from geometry_msgs.msg import Point, PointStamped

from airsim_mapper.convert import frames, sim_fields
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.stamps import sim_header


@sim_fields.converter("collision")
def collision(msg: Mapping[str, Any], ctx: ConvertContext) -> PointStamped:
    """sim CollisionInfo -> PointStamped of its impact point."""
    point = sim_fields.vector3(msg, "impact_point")
    if ctx.enu:
        point = frames.ned_to_enu(point)
    return PointStamped(header=sim_header(msg, ctx), point=Point(**dict(zip("xyz", map(float, point)))))
