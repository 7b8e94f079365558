"""`make demo`'s program end to end, shortened: it starts everything, flies, writes the picture and the bag,
stops what it started and exits 0."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from harness import ROOT, wait_until

from tools.rig import descendants, kill_tree, stat_fields

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


def alive(pid: int) -> bool:
    """The process exists and is not a zombie."""
    try:
        return stat_fields(Path(f"/proc/{pid}/stat").read_text())[0] != "Z"
    except (OSError, IndexError):
        return False


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP], ids=["SIGTERM", "SIGHUP"])
def test_make_demo_ends_everything_it_started_on_a_signal_to_its_process_group(tmp_path, sig):
    env = {**os.environ, "DEMO_SECONDS": "300", "DEMO_OUT": str(tmp_path)}
    log = tmp_path / "make.log"
    with open(log, "wb") as out:
        make = subprocess.Popen(
            ["make", "-s", "demo"],
            cwd=ROOT,
            env=env,
            stdout=out,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            start_new_session=True,
        )
    try:
        wait_until(lambda: "demo: t =" in log.read_text() or make.poll() is not None, 240, "the demo running")
        assert make.poll() is None, log.read_text()[-3000:]
        started = descendants({make.pid})
        names = {Path(f"/proc/{pid}/comm").read_text().strip() for pid in started if alive(pid)}
        assert {"rosmaster", "rosout"} <= names and len(started) >= 6, names  # make, demo, roscore, sim, ...
        os.killpg(make.pid, sig)
        make.wait(timeout=60)
        wait_until(lambda: not any(alive(pid) for pid in started), 60, "everything the demo started ending")
    finally:
        kill_tree({make.pid} | descendants({make.pid}))
    assert f"demo: {signal.Signals(sig).name}: stopping everything it started" in log.read_text()
