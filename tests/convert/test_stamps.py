"""Sim nanosecond stamps become exact ROS times (genpy's Time on ROS1, builtin_interfaces/Time on ROS 2: this
module runs on both flavours); headers follow the context."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.flavour import ros_time, stamp_parts
from airsim_mapper.convert.stamps import MAX_STAMP_NS, convert_stamp, sim_header


def nanoseconds(stamp: Any) -> int:
    secs, nsecs = stamp_parts(stamp)
    return secs * 1_000_000_000 + nsecs


def test_stamp_splits_into_seconds_and_nanoseconds():
    assert stamp_parts(convert_stamp(12_345_678_901)) == (12, 345_678_901)


def test_large_stamps_keep_every_nanosecond():
    ns = 1_763_771_234_123_456_789  # a Unix-epoch stamp where float seconds would round
    stamp = convert_stamp(ns)
    assert nanoseconds(stamp) == ns
    assert stamp_parts(stamp)[1] == 123_456_789


def test_numpy_integers_are_accepted():
    assert nanoseconds(convert_stamp(np.int64(5))) == 5


@settings(deadline=None)
@given(st.integers(0, MAX_STAMP_NS))
def test_every_representable_stamp_round_trips(ns):
    stamp = convert_stamp(ns)
    assert nanoseconds(stamp) == ns
    assert 0 <= stamp_parts(stamp)[1] < 1_000_000_000


@pytest.mark.parametrize("bad", [1.5, "10", None, True])
def test_non_integer_stamps_are_rejected(bad):
    with pytest.raises(ConversionError, match=r"time_stamp must be integer nanoseconds"):
        convert_stamp(bad)


@pytest.mark.parametrize("bad", [-1, MAX_STAMP_NS + 1])
def test_stamps_outside_ros1_time_are_rejected(bad):
    with pytest.raises(ConversionError, match=f"time_stamp {bad} ns is outside the ROS1 time range"):
        convert_stamp(bad)


def test_header_takes_frame_and_sim_stamp_from_the_context():
    result = sim_header({"time_stamp": 3_000_000_007}, ConvertContext(frame_id="map"))
    assert result.frame_id == "map"
    assert result.stamp == ros_time(3, 7)


def test_header_with_ros_stamp_uses_now_and_ignores_the_sim_stamp():
    ctx = ConvertContext(stamp="ros", now=lambda: ros_time(42, 1))
    assert sim_header({}, ctx).stamp == ros_time(42, 1)


def test_header_without_a_time_stamp_is_rejected():
    with pytest.raises(ConversionError, match=r"message has no 'time_stamp'"):
        sim_header({}, ConvertContext())


def test_header_of_a_non_map_is_rejected():
    with pytest.raises(ConversionError, match=r"message must be a map, got list"):
        sim_header([], ConvertContext())


def test_a_ros_stamp_without_a_clock_is_a_conversion_error():
    with pytest.raises(ConversionError, match="stamp 'ros' needs the node's clock"):
        sim_header({"time_stamp": 7}, ConvertContext(stamp="ros"))
