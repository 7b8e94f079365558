"""Bridge integration fixtures: one private roscore for the package, the pytest process as a probe node,
and per-module rigs of (headless server + bridge node) subprocesses."""

from __future__ import annotations

import os
import time
from collections.abc import Iterator

import pytest
from bridgeharness import Rig
from harness import Launcher, RosMaster, start_master
from simharness import start_simserver

ROS_KEYS = ("ROS_MASTER_URI", "ROS_HOSTNAME", "ROS_LOG_DIR", "ROS_HOME")


@pytest.fixture(scope="session")
def ros_session(tmp_path_factory) -> Iterator[RosMaster]:
    """A roscore for all bridge tests; this pytest process joins it as the probe node."""
    launcher = Launcher(tmp_path_factory.mktemp("roscore"), dict(os.environ))
    master = start_master(launcher)
    saved = {key: os.environ.get(key) for key in ROS_KEYS}
    os.environ.update({key: master.env[key] for key in ROS_KEYS})
    import rospy

    rospy.init_node("pytest_probe", anonymous=True, disable_signals=True)
    yield master
    rospy.signal_shutdown("tests done")
    launcher.stop_all()
    for key, value in saved.items():
        if value is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = value


@pytest.fixture(scope="module")
def rig_factory(ros_session: RosMaster, tmp_path_factory) -> Iterator[callable]:
    launchers: list[Launcher] = []

    def make() -> Rig:
        launcher = Launcher(tmp_path_factory.mktemp("rig"), dict(ros_session.env))
        launchers.append(launcher)
        return Rig(launcher, start_simserver(launcher), None, "")

    yield make
    for launcher in launchers:
        launcher.stop_all()
        print(launcher.dump_logs())
    time.sleep(0.5)  # let the master drop the stopped node's registrations
