"""Sim time stamps (int64 nanoseconds) to ROS time, and header construction."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from std_msgs.msg import Header

from airsim_mapper.convert import messages
from airsim_mapper.convert.context import STAMP_ROS, ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.flavour import Time

NS_PER_S = 1_000_000_000
MAX_STAMP_NS = (2**32) * NS_PER_S - 1  # ROS1 time seconds are uint32


def convert_stamp(time_stamp_ns: Any) -> Time:
    """Exact split of integer nanoseconds into a ROS time (no float rounding)."""
    if isinstance(time_stamp_ns, (bool, np.bool_)) or not isinstance(time_stamp_ns, (int, np.integer)):
        raise ConversionError(f"time_stamp must be integer nanoseconds, got {time_stamp_ns!r}")
    ns = int(time_stamp_ns)
    if ns < 0 or ns > MAX_STAMP_NS:
        raise ConversionError(f"time_stamp {ns} ns is outside the ROS1 time range [0, {MAX_STAMP_NS}]")
    secs, nsecs = divmod(ns, NS_PER_S)
    return messages.ros_time(secs, nsecs)


def sim_stamp(msg: Mapping[str, Any]) -> Time:
    """The ROS time of a sim message's ``time_stamp``."""
    if not isinstance(msg, Mapping):
        raise ConversionError(f"message must be a map, got {type(msg).__name__}")
    if "time_stamp" not in msg:
        raise ConversionError("message has no 'time_stamp'")
    return convert_stamp(msg["time_stamp"])


def sim_header(msg: Mapping[str, Any], ctx: ConvertContext) -> Header:
    """A fresh std_msgs/Header with the context's frame id and the sim (or ROS) stamp."""
    if ctx.stamp == STAMP_ROS:
        if ctx.now is None:
            raise ConversionError("stamp 'ros' needs the node's clock, and this context has none")
        stamp = ctx.now()
    else:
        stamp = sim_stamp(msg)
    return messages.header(stamp, ctx.frame_id)
