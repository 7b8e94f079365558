"""Fixtures shared by the tests of one module: a launcher and a private roscore that live as long as it."""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest
from harness import Rig, RosMaster


@pytest.fixture(scope="module")
def module_launcher(tmp_path_factory) -> Iterator[Rig]:
    launcher = Rig(tmp_path_factory.mktemp("reliability"), dict(os.environ))
    try:
        yield launcher
    finally:
        launcher.stop_all()
        print(launcher.dump_logs())


@pytest.fixture(scope="module")
def module_master(module_launcher: Rig) -> RosMaster:
    return module_launcher.roscore()
