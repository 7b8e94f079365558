"""Fixtures for the simulator server tests: a server per test, or one per module for read-mostly tests."""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest
from harness import Rig, SimServer


@pytest.fixture
def simserver(launcher: Rig) -> SimServer:
    """A fresh headless server on free ports, stopped at teardown."""
    return launcher.simserver()


@pytest.fixture(scope="module")
def shared_simserver(tmp_path_factory: pytest.TempPathFactory) -> Iterator[SimServer]:
    """One server for a whole test module (each test loads its own scene)."""
    launcher = Rig(tmp_path_factory.mktemp("simserver"), dict(os.environ))
    try:
        yield launcher.simserver()
    finally:
        launcher.stop_all()
        print(launcher.dump_logs())


@pytest.fixture
def client(shared_simserver: SimServer):
    """A connected 1.1.0 client on the module's server, disconnected at teardown."""
    client = shared_simserver.client()
    yield client
    client.disconnect()
