"""1080p on ROS 2 reaches a user's subscriber: the node brings Fast DDS a shared-memory segment that holds
its frames (common/dds_profile.py), and leaves a user's own profile alone.

A best-effort rclpy subscriber with nothing configured (no profile, rclpy's sensor-data QoS) reads a 30 Hz
1080p camera of the bench's replay server through the node. Fast DDS's default 512 KB segment let 0.3-2
frames a second through; the threshold, 10 Hz, holds on a loaded 2-core machine and fails at that rate.
"""

from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

import pytest
from harness import Rig, SimPorts, wait_until
from ros2kit import ROOT, ros2_env

from tools.bench.scenes import CameraSetup, image_topic, write_scene

pytestmark = pytest.mark.live  # starts a server, the node and a subscriber

NODE = ROOT / ".venv-ros2" / "bin" / "airsim-mapper-node"
RATE = Path(__file__).resolve().parent / "rate_ros2.py"
MIN_HZ = 10.0
COUNT_S = 3.0
SHIPPED_SEGMENT = 32 * 1024 * 1024
USER_SEGMENT = 2 * 1024 * 1024
PROFILE_LINE = re.compile(r"Fast DDS profile: (.*)")
USER_PROFILE = f"""<?xml version="1.0" encoding="UTF-8"?>
<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <transport_descriptors>
    <transport_descriptor><transport_id>shm</transport_id><type>SHM</type>
      <segment_size>{USER_SEGMENT}</segment_size></transport_descriptor>
    <transport_descriptor><transport_id>udp</transport_id><type>UDPv4</type></transport_descriptor>
  </transport_descriptors>
  <participant profile_name="users" is_default_profile="true">
    <rtps><userTransports><transport_id>shm</transport_id><transport_id>udp</transport_id></userTransports>
      <useBuiltinTransports>false</useBuiltinTransports></rtps>
  </participant>
</profiles>
"""


def profile_said(node) -> str:
    found = PROFILE_LINE.search(node.output())
    return found.group(1) if found else ""


def largest_shm_segment(pid: int) -> int:
    """The size of the largest Fast DDS shared-memory file the process maps (its own segment)."""
    sizes, current = [0], ""
    for line in Path(f"/proc/{pid}/smaps").read_text().splitlines():
        if "/dev/shm/fastdds_" in line and not line.endswith("_el"):
            current = line
        elif line.startswith("Size:") and current:
            sizes.append(int(line.split()[1]) * 1024)
            current = ""
        elif not line[:1].isupper():
            current = ""
    return max(sizes)


def test_a_default_best_effort_subscriber_receives_a_1080p_camera_at_30_hz(
    launcher: Rig, ros2_python: Path, ros_domain: int, tmp_path: Path
) -> None:
    config = tmp_path / "sim_config"
    scene = write_scene(config, "hd", 1, CameraSetup(1920, 1080, 1 / 30))
    ports = SimPorts.free()
    server = launcher.python(
        "replay_server", ["-m", "tools.bench.replay_server", "--address", "127.0.0.1", *ports.args()]
    )
    launcher.wait_ports(server, (ports.topics, ports.services))
    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}
    argv = [str(NODE), *ports.args(), "--simconfigpath", str(config), "--scene", scene]
    node = launcher.start("node_ros2", argv)

    out = subprocess.run(
        [str(ros2_python), str(RATE), image_topic(1), str(COUNT_S), "60"],
        env=ros2_env(ros_domain),
        capture_output=True,
        text=True,
        timeout=90,
    )
    assert out.returncode == 0, out.stderr
    heard = json.loads(out.stdout.strip().splitlines()[-1])
    assert heard["size"] == [1920, 1080, 1920 * 1080 * 3], node.output()[-3000:]
    assert heard["hz"] >= MIN_HZ, f"{heard}; node log:\n{node.output()[-3000:]}"
    assert profile_said(node).startswith("airsim-mapper's")
    assert largest_shm_segment(node.pid) >= SHIPPED_SEGMENT


def test_a_users_own_profile_is_left_alone(launcher: Rig, ros_domain: int, tmp_path: Path) -> None:
    mine = tmp_path / "mine.xml"
    mine.write_text(USER_PROFILE)
    ports = SimPorts.free()  # no simulator: the node's participant is there while it waits to connect
    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}
    argv = [str(NODE), *ports.args(), "--simconfigpath", str(ROOT / "sim_config")]
    # alone in its domain: a node maps the segments of the peers it reads from too
    node = launcher.start("node_users", argv, env={"FASTDDS_DEFAULT_PROFILES_FILE": str(mine)})
    wait_until(
        lambda: node.check_alive() or (profile_said(node) and largest_shm_segment(node.pid)),
        60,
        "the node's participant",
    )
    assert profile_said(node) == f"the user's (FASTDDS_DEFAULT_PROFILES_FILE={mine})"
    assert USER_SEGMENT <= largest_shm_segment(node.pid) < SHIPPED_SEGMENT
