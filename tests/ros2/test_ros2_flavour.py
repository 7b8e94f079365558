"""The node's `--ros 1|2`: the flavour asked for or the importable one, and an error naming `make setup`
when it cannot be had."""

from __future__ import annotations

import subprocess

import pytest
from ros2kit import ROOT, ROS2_PYTHON

from airsim_mapper.cli.errors import FlavourError
from airsim_mapper.cli.flavour import choose, requested


@pytest.mark.parametrize(
    ("argv", "expected"),
    [([], None), (["--ros", "2"], "2"), (["--ros=1"], "1"), (["--scene", "x", "--ros", "1", "--ros=2"], "2")],
)
def test_the_last_ros_switch_is_the_one_asked_for(argv, expected):
    assert requested(argv) == expected


def test_unasked_the_importable_flavour_runs_ros1_first():
    assert choose(None, lambda name: True) == "1"
    assert choose(None, lambda name: name == "rclpy") == "2"


def test_a_flavour_asked_for_whose_library_is_missing_names_make_setup():
    missing_rclpy = r"ROS 2: rclpy is not importable .*`make setup` builds \.venv-ros2\)"
    with pytest.raises(FlavourError, match=missing_rclpy):
        choose("2", lambda name: name == "rospy")
    with pytest.raises(FlavourError, match=r"ROS1: rospy is not importable .*`make setup` builds \.venv\)"):
        choose(None, lambda name: False)


@pytest.mark.live
@pytest.mark.parametrize(
    ("python", "argv", "message"),
    [
        (ROOT / ".venv" / "bin" / "python", ["--ros", "2"], "ROS 2: rclpy is not importable"),
        (ROS2_PYTHON, ["--ros", "1"], "ROS1: rospy is not importable"),
    ],
)
def test_the_node_refuses_a_flavour_it_cannot_run_before_it_starts(python, argv, message):
    run = subprocess.run(
        [str(python.parent / "airsim-mapper-node"), *argv], capture_output=True, text=True, timeout=60
    )
    assert run.returncode == 1
    assert run.stderr.startswith("airsim-mapper-node: ") and message in run.stderr
