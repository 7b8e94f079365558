"""Goals in another frame on ROS 2 (no tf2_ros): the ROS 2 link moves a pose through the transforms the node
itself sent, there and back, and refuses frames outside its tree."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest
from ros2kit import ROOT, ros2_env

pytestmark = pytest.mark.live  # runs .venv-ros2's interpreter

SCRIPT = """
import json, math
from geometry_msgs.msg import PoseStamped, TransformStamped
from airsim_mapper.engine.ros2_link import OwnFrames
from airsim_mapper.engine.tf_poses import FrameUnknown, moved_pose

def tf(parent, child, xyz, q):
    t = TransformStamped()
    t.header.frame_id, t.child_frame_id = parent, child
    r, p = t.transform.rotation, t.transform.translation
    p.x, p.y, p.z = xyz
    r.w, r.x, r.y, r.z = q
    return t

h = math.sqrt(0.5)
frames = OwnFrames()
frames.add([tf("map", "drone", (1.0, 2.0, 3.0), (h, 0.0, 0.0, h))])
frames.add([tf("drone", "cam", (0.5, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))])
goal = PoseStamped()
goal.header.frame_id, goal.pose.position.x, goal.pose.orientation.w = "cam", 1.0, 1.0
there = moved_pose(goal, frames.transform("map", "cam"))
back = moved_pose(there, frames.transform("cam", "map"))
try:
    frames.transform("map", "elsewhere/frame")
    refused = ""
except FrameUnknown as exc:
    refused = str(exc)
p, q, b = there.pose.position, there.pose.orientation, back.pose.position
print(json.dumps({"frame": there.header.frame_id, "there": [p.x, p.y, p.z], "q": [q.w, q.x, q.y, q.z],
                  "back": [b.x, b.y, b.z], "refused": refused}))
"""


def test_a_goal_moves_through_the_nodes_own_frames_and_back(ros2_python: Path) -> None:
    out = subprocess.run(
        [str(ros2_python), "-c", SCRIPT],
        env=ros2_env(0),
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    assert result["frame"] == "map"
    assert result["there"] == pytest.approx([1.0, 3.5, 3.0])  # (1.5, 0, 0) in the drone, turned 90 degrees
    assert result["q"] == pytest.approx([2**-0.5, 0.0, 0.0, 2**-0.5])
    assert result["back"] == pytest.approx([1.0, 0.0, 0.0], abs=1e-12)
    assert "'elsewhere/frame' cannot be transformed into 'map'" in result["refused"]
