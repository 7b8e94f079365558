"""The message space `make setup` builds (devel/): a catkin-style space whose setup.bash, sourced once or
twice, lets Debian's own tools find radar_msgs and uuid_msgs and nothing else of the venv."""

from __future__ import annotations

import subprocess

import pytest
from harness import DEVEL_SETUP, ROOT

pytestmark = pytest.mark.live  # runs Debian's rospack and rosmsg

SPACE = ROOT / "devel"


def sourced(command: str, times: int = 1) -> subprocess.CompletedProcess:
    sources = f'source "{DEVEL_SETUP}" && ' * times
    env = {"PATH": "/usr/bin:/bin", "ROS_PACKAGE_PATH": "/opt/other", "PYTHONPATH": "/opt/lib"}
    return subprocess.run(["/bin/bash", "-c", sources + command], env=env, capture_output=True, text=True)


def test_sourcing_twice_extends_each_path_once_and_keeps_what_was_there():
    run = sourced('echo "$ROS_PACKAGE_PATH"; echo "$PYTHONPATH"', times=2)
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines() == [
        f"{SPACE}/share:/opt/other",
        f"{SPACE}/lib/python3/dist-packages:/opt/lib",
    ]


def test_the_system_tools_find_the_packages_and_their_upstream_md5sums():
    run = sourced(
        "rospack find radar_msgs && rosmsg md5 radar_msgs/RadarScan && rosmsg md5 uuid_msgs/UniqueID"
    )
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines()[:2] == [f"{SPACE}/share/radar_msgs", "6dfacef1e665538dbd8e159d5ce7a97a"]


def test_the_space_holds_only_the_two_packages():
    python = SPACE / "lib" / "python3" / "dist-packages"
    assert sorted(p.name for p in python.iterdir()) == ["radar_msgs", "uuid_msgs"]
    assert sorted(p.name for p in (SPACE / "share").iterdir()) == ["radar_msgs", "uuid_msgs"]
