"""Any stamped sim message -> rosgraph_msgs/Clock at its sim time."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rosgraph_msgs.msg import Clock

from airsim_mapper.convert import sim_fields
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.stamps import sim_stamp


@sim_fields.converter("clock")
def clock(msg: Mapping[str, Any], ctx: ConvertContext) -> Clock:
    """Clock at the message's ``time_stamp`` (always sim time, whatever ctx.stamp says)."""
    return Clock(clock=sim_stamp(msg))
