"""The per-pose messages published as CDR bytes (engine/ros2_cdr.py): cdr_ros2.py's property and
publish-subscribe tests, run by pytest in .venv-ros2 on a ROS_DOMAIN_ID of this test's own."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from ros2kit import ROOT, ros2_env

pytestmark = pytest.mark.live  # runs .venv-ros2's interpreter

CHECKS = Path(__file__).resolve().parent / "cdr_ros2.py"


def test_poses_and_transforms_written_as_cdr_are_rclpys_bytes_and_reach_a_subscriber(
    ros2_python: Path, ros_domain: int
) -> None:
    run = subprocess.run(
        [str(ros2_python), "-m", "pytest", "-q", "-p", "no:cacheprovider", str(CHECKS)],
        env=ros2_env(ros_domain),
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stdout[-5000:] + run.stderr[-2000:]
    summary = run.stdout.strip().splitlines()[-1]
    assert "5 passed" in summary and "skipped" not in summary, summary
