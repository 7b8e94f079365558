"""Fixtures shared by the whole suite."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest
from harness import Launcher, RosMaster, start_master


@pytest.fixture
def launcher(tmp_path: Path) -> Iterator[Launcher]:
    """Starts subprocesses for one test; stops them all (by process group) at teardown."""
    proc_launcher = Launcher(tmp_path, dict(os.environ))
    try:
        yield proc_launcher
    finally:
        proc_launcher.stop_all()
        # Shown by pytest only when the test failed.
        print(proc_launcher.dump_logs())


@pytest.fixture
def ros_master(launcher: Launcher) -> RosMaster:
    """A private roscore on a free port; ROS_* variables point at temporary folders."""
    return start_master(launcher)
