"""Test harness: the project's one process rig (tools/rig.py) and the paths the tests read.

Tests that start processes get a `Rig` from the fixtures in conftest.py: a real ROS master, the headless
server and nodes run with the venv's interpreter, each in a session of its own, so teardown stops each one
and everything it started.
"""

from __future__ import annotations

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

__all__ = [
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
    "wait_until",
]
