"""Fixtures shared by the whole suite, and the `live` marker for every test that starts processes."""

from __future__ import annotations

import os
import signal
from collections.abc import Generator, Iterator
from pathlib import Path

import pytest
from harness import Rig, RosMaster
from simconfigs import PROJECT, config_dir, fold_example_skips, require_example_config

# Started as a background job of a non-interactive shell, the suite inherits SIGINT ignored, and so would
# every process it starts (an ignored signal stays ignored across exec): the tests that stop a node or a
# mission script with Ctrl-C need it delivered, so the suite takes Python's own handler back.
signal.signal(signal.SIGINT, signal.default_int_handler)

# The fixtures that start real processes; a test that uses one, directly or through another fixture, is
# `live` (`make check` leaves it out). Tests that start processes some other way carry the marker themselves.
PROCESS_FIXTURES = frozenset({"launcher", "module_launcher", "shared_simserver", "ros_session"})


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        if PROCESS_FIXTURES & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.live)


@pytest.fixture
def launcher(tmp_path: Path) -> Iterator[Rig]:
    """The process rig of one test; stops everything it started at teardown."""
    rig = Rig(tmp_path, dict(os.environ))
    try:
        yield rig
    finally:
        rig.stop_all()
        print(rig.dump_logs())  # shown by pytest only when the test failed


@pytest.fixture
def ros_master(launcher: Rig) -> RosMaster:
    """A private roscore on a free port; ROS_* variables point at temporary folders."""
    return launcher.roscore()


@pytest.fixture
def example_config() -> Path:
    """Project AirSim's example sim_config directory; a test that takes it is skipped where it is absent."""
    return require_example_config()


@pytest.fixture
def sim_config(request: pytest.FixtureRequest) -> Path:
    """The config directory a test is parametrized with (indirectly, see `simconfigs.scenes_of`): the
    project's own, or Project AirSim's examples (skipped where absent). Unparametrized: the project's."""
    return config_dir(getattr(request, "param", PROJECT))


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo
) -> Generator[None, pytest.TestReport, pytest.TestReport]:
    """Skips for want of Project AirSim's example configs show as one line in the summary."""
    report = yield
    fold_example_skips(report)
    return report
