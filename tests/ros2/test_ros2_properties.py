"""The converters' property tests on ROS 2's messages: the flavour-neutral ones of tests/convert (every
catalogue entry's damaged examples, stamps, frame changes), run by pytest in .venv-ros2, where the
converters build rosidl messages and rclpy serialises them. tests/convert runs them on ROS1 in .venv."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from ros2kit import ROOT, ros2_env

pytestmark = pytest.mark.live  # runs .venv-ros2's interpreter

PROPERTIES = (
    "tests/convert/test_properties.py",
    "tests/convert/test_stamps.py",
    "tests/convert/test_frames.py",
)


def test_the_converters_property_tests_pass_on_ros2_messages(ros2_python: Path) -> None:
    run = subprocess.run(
        [str(ros2_python), "-m", "pytest", "-q", "-p", "no:cacheprovider", *PROPERTIES],
        env=ros2_env(0),
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stdout[-5000:] + run.stderr[-2000:]
    summary = run.stdout.strip().splitlines()[-1]
    assert " passed" in summary and "skipped" not in summary and "deselected" not in summary, summary
