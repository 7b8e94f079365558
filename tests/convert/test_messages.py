"""The direct message builders give what genpy's constructors give, and the float frame changes what
the array ones give, bit for bit (the pose converter uses them on every message)."""

from __future__ import annotations

import io
from typing import Any

import numpy as np
from genpy import Time
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
from hypothesis import given
from hypothesis import strategies as st
from std_msgs.msg import Header

from airsim_mapper.convert import frames, messages

finite = st.floats(-1e6, 1e6, allow_nan=False)
unit = st.floats(-1.0, 1.0, allow_nan=False)


def serialized(msg: Any) -> bytes:
    buffer = io.BytesIO()
    msg.serialize(buffer)
    return buffer.getvalue()


def every_slot_set(msg: Any) -> None:
    for name in msg.__slots__:  # a generated class's fields (and a Time's secs and nsecs)
        value = getattr(msg, name)  # AttributeError if a builder left it out
        if hasattr(value, "__slots__"):
            every_slot_set(value)


@given(finite, finite, finite, unit, unit, unit, unit, st.integers(0, 2**32 - 1), st.integers(0, 999_999_999))
def test_a_built_pose_stamped_equals_and_serialises_as_the_constructed_one(
    x, y, z, qw, qx, qy, qz, secs, nsecs
):
    built = messages.pose_stamped(
        messages.header(messages.ros_time(secs, nsecs), "map"), messages.pose(x, y, z, qw, qx, qy, qz)
    )
    constructed = PoseStamped(
        header=Header(stamp=Time(secs, nsecs), frame_id="map"),
        pose=Pose(position=Point(x, y, z), orientation=Quaternion(qx, qy, qz, qw)),
    )
    assert built == constructed
    assert serialized(built) == serialized(constructed)
    every_slot_set(built)


@given(finite, finite, finite)
def test_float_ned_to_enu_matches_the_array_version(x, y, z):
    assert list(frames.ned_to_enu_floats((x, y, z))) == frames.ned_to_enu(np.array([x, y, z])).tolist()


@given(unit, unit, unit, unit)
def test_float_attitude_change_matches_the_array_version_bit_for_bit(w, x, y, z):
    q = (w, x, y, z)
    expected = frames.ned_frd_to_enu_flu(np.array(q)).tolist()
    got = list(frames.ned_frd_to_enu_flu_floats(q))
    assert got == expected
    assert got[0] >= 0.0
