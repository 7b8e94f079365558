"""One converter catalogue for both flavours: the same simulator frames, converted in .venv (ROS1's genpy
classes) and in .venv-ros2 (ROS 2's rosidl classes), give field-for-field equal messages."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from ros2kit import ROOT, ros2_env

pytestmark = pytest.mark.live  # runs .venv-ros2's interpreter

SCRIPT = Path(__file__).resolve().parent / "convert_frames.py"
# Fields ROS 2's definitions have and ROS1's do not, by message type: the converters leave their defaults.
ROS2_ONLY = {"Range": {"variance": 0.0}}


def converted(python: Path | str, env: dict[str, str] | None = None) -> list[dict]:
    out = subprocess.run(
        [str(python), str(SCRIPT)], env=env, cwd=ROOT, capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def test_the_same_frames_give_field_for_field_equal_ros1_and_ros2_messages(ros2_python: Path) -> None:
    ros1 = converted(sys.executable)
    ros2 = converted(ros2_python, ros2_env(0))
    assert [m["converter"] for m in ros1] == [m["converter"] for m in ros2]
    assert len(ros1) >= 15
    for one, two in zip(ros1, ros2):
        assert one["type"] == two["type"]
        for name, default in ROS2_ONLY.get(two["type"], {}).items():
            assert two["msg"].pop(name) == default
        assert one["msg"] == two["msg"], one["converter"]


def test_ros2_messages_carry_ros2_stamps_and_lower_case_camera_matrices(ros2_python: Path) -> None:
    by_converter = {m["converter"]: m["msg"] for m in converted(ros2_python, ros2_env(0))}
    assert by_converter["pose"]["header"]["stamp"] == {"sec": 12, "nanosec": 345_678_901}
    assert "seq" not in by_converter["pose"]["header"]
    info = by_converter["camera_info"]
    assert len(info["k"]) == 9 and len(info["p"]) == 12 and info["d"] == [0.0] * 5
    assert by_converter["clock"]["clock"] == {"sec": 7, "nanosec": 42}
