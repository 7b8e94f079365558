"""The ROS 2 flavour's test kit: .venv-ros2's interpreter and the environment of a process in it."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
ROS2_PYTHON = ROOT / ".venv-ros2" / "bin" / "python"
PEER = Path(__file__).resolve().parent / "peer_ros2.py"
SHELL_PREFIXES = ("ROS_", "AMENT_", "RMW_", "FASTDDS_", "FASTRTPS_")  # a shell's ROS and DDS settings


def ros2_env(domain: int) -> dict[str, str]:
    """The environment of a process in .venv-ros2: no ROS1 paths and no Fast DDS settings of the shell, its
    own domain, localhost discovery."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(SHELL_PREFIXES)}
    env.pop("PYTHONPATH", None)
    env.update(ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    env["RMW_IMPLEMENTATION"] = "rmw_fastrtps_cpp"
    return env


def start_peer(python: Path, domain: int, *args: str) -> subprocess.Popen:
    """peer_ros2.py in .venv-ros2, its output captured."""
    return subprocess.Popen(
        [str(python), str(PEER), *args],
        env=ros2_env(domain),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
