"""The node's open-file budget: raised to the hard limit, and a warning for a scene that needs more."""

from __future__ import annotations

import resource
import subprocess
import sys

from airsim_mapper.cli.limits import OWN_FILES, files_needed, shortfall


def test_a_scene_with_more_bridges_than_the_limit_allows_is_named_with_the_numbers():
    assert files_needed(10) == OWN_FILES + 10
    assert shortfall(100, 1024) == ""
    warning = shortfall(1000, 1024)
    assert warning.startswith(
        f"the scene has 1000 bridges: with a ROS peer each, the node needs about "
        f"{OWN_FILES + 1000} open files, and its limit is 1024"
    )
    assert shortfall(10**6, resource.RLIM_INFINITY) == ""


def test_the_soft_limit_is_raised_to_the_hard_one():
    code = (
        "import resource\n"
        "from airsim_mapper.cli.limits import raise_open_files\n"
        "soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)\n"
        "resource.setrlimit(resource.RLIMIT_NOFILE, (256, hard))\n"
        "before, after = raise_open_files()\n"
        "now = resource.getrlimit(resource.RLIMIT_NOFILE)[0]\n"
        "assert before == 256 and after == hard == now, (before, after)\n"
        "print('OK', after)\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0 and run.stdout.startswith("OK"), run.stderr
