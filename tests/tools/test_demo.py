"""`make demo`'s program end to end, shortened: it starts everything, flies, writes the picture and the bag,
stops what it started and exits 0."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from harness import ROOT

pytestmark = pytest.mark.live  # runs the demo


def test_demo_writes_the_picture_and_a_bag_and_exits_cleanly(tmp_path):
    env = {**os.environ, "DEMO_SECONDS": "8", "DEMO_OUT": str(tmp_path)}
    run = subprocess.run(
        [sys.executable, "-m", "tools.demo"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "/airsim_node/Drone1/actual_pose" in run.stdout
    png = (tmp_path / "demo.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
    from rosbag import Bag

    with Bag(str(tmp_path / "demo.bag")) as bag:
        topics = set(bag.get_type_and_topic_info().topics)
    assert "/airsim_node/Drone1/actual_pose" in topics
    assert "/airsim_node/Drone1/lidar1/lidar" in topics
    # everything it started is gone
    leftovers = subprocess.run(
        ["pgrep", "-f", f"airsim_mapper.simserver.*{tmp_path.name}"], capture_output=True
    )
    assert leftovers.returncode == 1
