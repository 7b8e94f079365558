"""On ROS 2 the messages the converters build without rosidl's constructors (poses field by field, byte
arrays filled in place) equal, and serialise as, those the constructors build."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from ros2kit import ROOT, ros2_env

pytestmark = pytest.mark.live  # runs .venv-ros2's interpreter

CHECK = """
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
from rclpy.serialization import deserialize_message, serialize_message
from std_msgs.msg import Header

from airsim_mapper.convert import messages

head = messages.header(Time(sec=5, nanosec=7), "map")
built = messages.pose_stamped(head, messages.pose(1, 2.5, -3, 0.5, 0.5, -0.5, 0.5))
given = PoseStamped(
    header=Header(stamp=Time(sec=5, nanosec=7), frame_id="map"),
    pose=Pose(position=Point(x=1.0, y=2.5, z=-3.0), orientation=Quaternion(w=0.5, x=0.5, y=-0.5, z=0.5)),
)
assert built == given, (built, given)
assert deserialize_message(serialize_message(built), PoseStamped) == given  # padding bytes are not set
assert repr(built) == repr(given)
assert type(built.pose.position.x) is float
print("equal")
"""


def test_pose_messages_built_field_by_field_equal_the_constructors(ros2_python: Path) -> None:
    out = subprocess.run(
        [str(ros2_python), "-c", CHECK], env=ros2_env(0), cwd=ROOT, capture_output=True, text=True, timeout=60
    )
    assert out.returncode == 0 and out.stdout.strip() == "equal", out.stderr


BUFFER_CHECK = """
import array

import numpy as np
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import Image, PointCloud2

from airsim_mapper.convert.buffer_data import ros2_buffer_message

pixels = bytearray(range(256)) * 3 * 4
for data in (bytes(pixels), pixels, memoryview(pixels), np.frombuffer(bytes(pixels), np.uint8), list(pixels)):
    built = ros2_buffer_message(Image)(height=4, width=64, encoding="rgb8", step=192, data=data)
    given = Image(height=4, width=64, encoding="rgb8", step=192, data=bytes(pixels))
    assert built == given and deserialize_message(serialize_message(built), Image) == given
    assert type(built.data) is array.array and built.data.typecode == "B"
floats = np.arange(6, dtype=np.float32)
cloud = ros2_buffer_message(PointCloud2)(height=1, width=6, point_step=4, data=memoryview(floats))
assert cloud.data.tobytes() == floats.tobytes()
assert ros2_buffer_message(Image)(height=1).data == array.array("B")
print("equal")
"""


def test_buffer_messages_hold_the_bytes_as_rclpy_would_from_any_buffer(ros2_python: Path) -> None:
    out = subprocess.run(
        [str(ros2_python), "-c", BUFFER_CHECK],
        env=ros2_env(0),
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 0 and out.stdout.strip() == "equal", out.stderr
