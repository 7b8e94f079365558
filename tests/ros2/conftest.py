"""The ROS 2 flavour's fixtures: .venv-ros2's interpreter, and a ROS_DOMAIN_ID of a test's own.

A domain is claimed with an exclusive lock on a file named for it, held for the whole test, so tests of
parallel pytest runs (and workers) on one machine never share a domain; the search starts at a place
taken from the process id. Discovery stays on localhost.
"""

from __future__ import annotations

import fcntl
import os
from collections.abc import Iterator
from pathlib import Path

import pytest
from ros2kit import ROS2_PYTHON

DOMAIN_LOCKS = Path("/tmp/airsim-mapper-ros2-domains")
DOMAINS = range(1, 102)  # Fast DDS's ports fit domains 0-232; 0 is everyone's default


@pytest.fixture(scope="session")
def ros2_python() -> Path:
    """.venv-ros2's interpreter; a clear failure where `make setup` has not built it."""
    if not ROS2_PYTHON.is_file():
        pytest.fail(f"{ROS2_PYTHON} is missing: run `make setup`")
    return ROS2_PYTHON


@pytest.fixture
def ros_domain() -> Iterator[int]:
    """A ROS_DOMAIN_ID no other test on this machine uses while this one runs."""
    DOMAIN_LOCKS.mkdir(exist_ok=True)
    start = os.getpid() % len(DOMAINS)
    for i in range(len(DOMAINS)):
        domain = DOMAINS[(start + i) % len(DOMAINS)]
        handle = (DOMAIN_LOCKS / f"{domain}.lock").open("w")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.close()
            continue
        try:
            yield domain
        finally:
            handle.close()
        return
    pytest.fail(f"every ROS 2 domain in {DOMAINS} is taken")
