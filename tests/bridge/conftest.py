"""Bridge integration fixtures: one private roscore for the package, the pytest process as a probe node,
and rigs of (headless server + bridge node) subprocesses, per test or per module."""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator

import pytest
from bridgeharness import Stack
from harness import Rig, RosMaster

ROS_KEYS = ("ROS_MASTER_URI", "ROS_HOSTNAME", "ROS_LOG_DIR", "ROS_HOME")


@pytest.fixture(scope="session")
def ros_session(tmp_path_factory) -> Iterator[RosMaster]:
    """A roscore for all bridge tests; this pytest process joins it as the probe node."""
    launcher = Rig(tmp_path_factory.mktemp("roscore"), dict(os.environ))
    master = launcher.roscore()
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


def _stacks(ros_session: RosMaster, tmp_path_factory) -> Iterator[Callable[[], Stack]]:
    """A factory of stacks; everything they started is stopped, and its logs printed, at the end."""
    launchers: list[Rig] = []

    def make() -> Stack:
        launcher = Rig(tmp_path_factory.mktemp("rig"), dict(ros_session.env))
        launchers.append(launcher)
        return Stack(launcher, launcher.simserver(), None, "")

    yield make
    for launcher in launchers:
        launcher.stop_all()
        print(launcher.dump_logs())
    time.sleep(0.5)  # let the master drop the stopped node's registrations


@pytest.fixture
def rig_factory(ros_session: RosMaster, tmp_path_factory) -> Iterator[Callable[[], Stack]]:
    """Stacks of one test, stopped at its end even when it fails: a node left running would serve the
    next test's topics (the same names on the same master) and hold its simulator's topics channel."""
    yield from _stacks(ros_session, tmp_path_factory)


@pytest.fixture(scope="module")
def module_rig_factory(ros_session: RosMaster, tmp_path_factory) -> Iterator[Callable[[], Stack]]:
    """Stacks shared by the tests of a module (its `rig` fixture), stopped at the module's end."""
    yield from _stacks(ros_session, tmp_path_factory)
