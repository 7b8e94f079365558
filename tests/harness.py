"""Test harness: the project's one process rig (tools/rig.py) and the paths the tests read.

Tests that start processes get a `Rig` from the fixtures in conftest.py: a real ROS master, the headless
server and nodes run with the venv's interpreter, each in a session of its own, so teardown stops each one
and everything it started.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from tools.rig import (
    Child,
    Rig,
    RigError,
    RosMaster,
    SimPorts,
    SimServer,
    free_port,
    port_open,
    wait_until,
)

ROOT = Path(__file__).resolve().parent.parent
# The project's own scenes and robot configs: every test may rely on them.
SIM_CONFIG = ROOT / "sim_config"
# Project AirSim's example configs, beside the clone only where CI puts them. The tests that check
# compatibility with them skip where they are absent (tests/simconfigs.py, and the `example_config` and
# `sim_config` fixtures in tests/conftest.py).
SHARED = ROOT.parent / "shared"
EXAMPLE_CONFIG = SHARED / "sim_config"
VENV_BIN = Path(sys.executable).parent
# The message space `make setup` builds: sourced, Debian's own tools read radar_msgs and uuid_msgs.
DEVEL_SETUP = ROOT / "devel" / "setup.bash"


def stock_tool(rig: Rig, command: str, setup: Path = DEVEL_SETUP, timeout: float = 30.0):
    """`command` in bash after sourcing `setup`, in a plain environment (the master's address, ROS's
    folders and the system's PATH, none of the venv's or the rig's search paths), in the rig's workdir:
    what a user's shell runs Debian's rostopic, rosbag and rosmsg in."""
    env = {
        "PATH": "/usr/bin:/bin",
        "HOME": os.environ.get("HOME", "/root"),
        **{k: rig.env[k] for k in ("ROS_MASTER_URI", "ROS_HOSTNAME", "ROS_LOG_DIR", "ROS_HOME")},
    }
    return subprocess.run(
        ["/bin/bash", "-c", f'source "{setup}" && {command}'],
        env=env,
        cwd=rig.workdir,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


__all__ = [
    "DEVEL_SETUP",
    "EXAMPLE_CONFIG",
    "ROOT",
    "SIM_CONFIG",
    "VENV_BIN",
    "Child",
    "Rig",
    "RigError",
    "RosMaster",
    "SimPorts",
    "SimServer",
    "free_port",
    "port_open",
    "stock_tool",
    "wait_until",
]
