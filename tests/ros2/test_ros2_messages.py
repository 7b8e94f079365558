"""On ROS 2 the pose messages the converters build field by field equal, and serialise as, those rosidl's
constructors build."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from ros2kit import ROOT, ros2_env

pytestmark = pytest.mark.live  # runs .venv-ros2's interpreter

CHECK = """
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
from rclpy.serialization import serialize_message
from std_msgs.msg import Header

from airsim_mapper.convert import messages

head = messages.header(Time(sec=5, nanosec=7), "map")
built = messages.pose_stamped(head, messages.pose(1, 2.5, -3, 0.5, 0.5, -0.5, 0.5))
given = PoseStamped(
    header=Header(stamp=Time(sec=5, nanosec=7), frame_id="map"),
    pose=Pose(position=Point(x=1.0, y=2.5, z=-3.0), orientation=Quaternion(w=0.5, x=0.5, y=-0.5, z=0.5)),
)
assert built == given, (built, given)
assert serialize_message(built) == serialize_message(given)
assert repr(built) == repr(given)
assert type(built.pose.position.x) is float
print("equal")
"""


def test_pose_messages_built_field_by_field_equal_the_constructors(ros2_python: Path) -> None:
    out = subprocess.run(
        [str(ros2_python), "-c", CHECK], env=ros2_env(0), cwd=ROOT, capture_output=True, text=True, timeout=60
    )
    assert out.returncode == 0 and out.stdout.strip() == "equal", out.stderr
