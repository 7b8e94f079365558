"""The ROS 2 flavour's fixtures: .venv-ros2's interpreter, and a ROS_DOMAIN_ID of a test's own.

A domain is claimed with an exclusive lock on a file named for it, held for the whole test, so tests of
parallel pytest runs (and workers) on one machine never share a domain; the search starts at a place
taken from the process id. Discovery stays on localhost.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from ros2kit import ROS2_PYTHON

from tools.bench.ros2 import Ros2Unavailable, claim_domain


@pytest.fixture(scope="session")
def ros2_python() -> Path:
    """.venv-ros2's interpreter; a clear failure where `make setup` has not built it."""
    if not ROS2_PYTHON.is_file():
        pytest.fail(f"{ROS2_PYTHON} is missing: run `make setup`")
    return ROS2_PYTHON


@pytest.fixture
def ros_domain() -> Iterator[int]:
    """A ROS_DOMAIN_ID no other test or bench on this machine uses while this one runs."""
    try:
        domain = claim_domain()
    except Ros2Unavailable as e:
        pytest.fail(str(e))
    try:
        yield domain.number
    finally:
        domain.release()
