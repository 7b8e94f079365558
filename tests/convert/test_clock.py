"""Clock messages carry the sim time of any stamped message."""

from __future__ import annotations

import pytest
import rospy

from airsim_mapper.convert.clock import clock
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError


def test_clock_is_the_message_sim_time(roundtrip):
    msg = clock({"time_stamp": 61_000_000_001, "anything": 1}, ConvertContext())
    assert msg.clock == rospy.Time(61, 1)
    assert roundtrip(msg) == msg


def test_clock_ignores_ros_stamping():
    ctx = ConvertContext(stamp="ros", now=lambda: rospy.Time(99, 0))
    assert clock({"time_stamp": 5}, ctx).clock == rospy.Time(0, 5)


def test_clock_without_time_stamp_is_rejected():
    with pytest.raises(ConversionError, match=r"clock: message has no 'time_stamp'"):
        clock({"position": {}}, ConvertContext())
