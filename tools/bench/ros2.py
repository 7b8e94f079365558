"""Where the bench's ROS 2 processes run: .venv-ros2's interpreter and node, on a ROS_DOMAIN_ID of the
bench's own, without ROS1's Python path.

A domain is claimed as `tests/ros2` claims one (an exclusive lock on a file named for it, in the same
folder), so a bench and a test run on one machine never share a domain. Discovery stays on localhost.
"""

from __future__ import annotations

import fcntl
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

ROOT = Path(__file__).resolve().parent.parent.parent
ROS2_PYTHON = ROOT / ".venv-ros2" / "bin" / "python"
ROS2_NODE = ROOT / ".venv-ros2" / "bin" / "airsim-mapper-node"  # the node as users start it
DOMAIN_LOCKS = Path("/tmp/airsim-mapper-ros2-domains")  # the bench's and tests/ros2's
DOMAINS = range(1, 102)  # Fast DDS's ports fit domains 0-232; 0 is everyone's default


class Ros2Unavailable(RuntimeError):
    """The ROS 2 rows cannot run: no .venv-ros2, or every domain is taken."""


@dataclass
class Domain:
    """A ROS_DOMAIN_ID held by this process until `release`."""

    number: int
    lock: TextIO

    def release(self) -> None:
        self.lock.close()


def claim_domain(locks: Path = DOMAIN_LOCKS, domains: range = DOMAINS) -> Domain:
    """The first domain no other process on this machine holds, searched from a place taken from the pid."""
    if not ROS2_PYTHON.is_file():
        raise Ros2Unavailable(f"{ROS2_PYTHON} is missing: run `make setup`")
    locks.mkdir(exist_ok=True)
    start = os.getpid() % len(domains)
    for i in range(len(domains)):
        number = domains[(start + i) % len(domains)]
        handle = (locks / f"{number}.lock").open("w")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.close()
            continue
        return Domain(number, handle)
    raise Ros2Unavailable(f"every ROS 2 domain in {domains} is taken")


def environment(domain: int) -> dict[str, str]:
    """What a ROS 2 process gets over the bench's environment: no ROS1 Python path (an empty PYTHONPATH is
    none), its domain, localhost discovery, Fast DDS."""
    return {
        "PYTHONPATH": "",
        "ROS_DOMAIN_ID": str(domain),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
    }


def interpreter() -> list[str]:
    """The command that runs .venv-ros2's Python as the bench runs its own (unbuffered, faulthandler on)."""
    return [str(ROS2_PYTHON), "-u", "-X", "faulthandler"]
