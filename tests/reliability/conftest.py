"""Fixtures shared by the tests of one module: a launcher and a private roscore that live as long as it."""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest
from harness import Launcher, RosMaster, start_master


@pytest.fixture(scope="module")
def module_launcher(tmp_path_factory) -> Iterator[Launcher]:
    launcher = Launcher(tmp_path_factory.mktemp("reliability"), dict(os.environ))
    try:
        yield launcher
    finally:
        launcher.stop_all()
        print(launcher.dump_logs())


@pytest.fixture(scope="module")
def module_master(module_launcher: Launcher) -> RosMaster:
    return start_master(module_launcher)
