"""A simulator that holds its ports but never answers: the node says so and exits 1 after about 10 s
(no NNG abort at exit), and a signal still stops it at once while it waits."""

from __future__ import annotations

import signal
import socket
import threading
import time
from collections.abc import Iterator

import pynng
import pytest
from harness import Rig, RosMaster

from reliability.relkit import SCENE, SimPorts, start_node, wait_output

SILENT = "accepted the connection but did not answer within 10 s"


class SilentTcp:
    """Plain TCP listeners that accept every connection and never send a byte (no NNG handshake)."""

    def __init__(self, ports: SimPorts) -> None:
        self.listeners = []
        self.accepted: list[socket.socket] = []
        for port in (ports.topics, ports.services):
            listener = socket.create_server(("127.0.0.1", port))
            self.listeners.append(listener)
            threading.Thread(target=self._accept, args=(listener,), daemon=True).start()

    def _accept(self, listener: socket.socket) -> None:
        while True:
            try:
                self.accepted.append(listener.accept()[0])
            except OSError:
                return

    def close(self) -> None:
        for sock in [*self.listeners, *self.accepted]:
            sock.close()


class SilentNng:
    """NNG sockets of the right kinds that take every request and never reply."""

    def __init__(self, ports: SimPorts) -> None:
        self.sockets = [
            pynng.Pair0(listen=f"tcp://127.0.0.1:{ports.topics}"),
            pynng.Rep0(listen=f"tcp://127.0.0.1:{ports.services}"),
        ]

    def close(self) -> None:
        for sock in self.sockets:
            sock.close()


@pytest.fixture(params=[SilentTcp, SilentNng], ids=["tcp", "nng"])
def silent(request) -> Iterator[SimPorts]:
    ports = SimPorts.free()
    server = request.param(ports)
    yield ports
    server.close()


def test_a_silent_simulator_ends_the_node_with_status_1_and_a_clear_message(
    launcher: Rig, ros_master: RosMaster, silent: SimPorts
):
    start = time.monotonic()
    node = start_node(launcher, silent, "--scene", SCENE)
    status = node.wait(40)
    took = time.monotonic() - start
    log = node.output()
    assert status == 1, log
    assert f"simulator at 127.0.0.1:{silent.topics}/{silent.services} {SILENT}" in log
    assert "Traceback" not in log and "panic" not in log
    assert took < 30, took


def test_a_signal_stops_the_node_at_once_while_it_waits_for_a_silent_simulator(
    launcher: Rig, ros_master: RosMaster
):
    ports = SimPorts.free()
    server = SilentNng(ports)
    try:
        node = start_node(launcher, ports, "--scene", SCENE)
        wait_output(node, "Connecting to simulation server", 30)
        time.sleep(1.0)  # inside the first-answer wait
        sent = time.monotonic()
        node.popen.send_signal(signal.SIGINT)
        status = node.wait(10)
        assert time.monotonic() - sent < 3
        assert status == 0, node.output()
    finally:
        server.close()
