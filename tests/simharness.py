"""Start the headless simulator server (`python -m airsim_mapper.simserver`) for a test.

`start_simserver(launcher, *extra_args)` picks free ports, starts the server through the test's
`launcher` (so teardown always stops it) and returns once both ports accept TCP connections.
"""

from __future__ import annotations

import socket
from dataclasses import dataclass

from harness import SIM_CONFIG, HarnessError, Launcher, Process, free_port, wait_until

ADDRESS = "127.0.0.1"


@dataclass(frozen=True)
class SimServer:
    """A running simulator server: where to reach it and its process."""

    address: str
    topics_port: int
    services_port: int
    process: Process

    def client(self):
        """A connected `projectairsim` 1.1.0 client (the caller disconnects it)."""
        from projectairsim import ProjectAirSimClient

        client = ProjectAirSimClient(self.address, self.topics_port, self.services_port)
        client.connect()
        return client


def port_open(address: str, port: int) -> bool:
    with socket.socket() as sock:
        sock.settimeout(0.2)
        return sock.connect_ex((address, port)) == 0


def start_simserver(launcher: Launcher, *extra_args: str, timeout: float = 30.0) -> SimServer:
    """Run the server on free loopback ports; wait until both of its ports accept connections."""
    topics_port, services_port = free_port(), free_port()
    while services_port == topics_port:
        services_port = free_port()
    argv = [
        "-m",
        "airsim_mapper.simserver",
        "--address",
        ADDRESS,
        "--topicsport",
        str(topics_port),
        "--servicesport",
        str(services_port),
        *extra_args,
    ]
    process = launcher.python("simserver", argv)

    def up() -> bool:
        if not process.alive():
            raise HarnessError(f"simserver exited early:\n{process.output()}")
        return port_open(ADDRESS, topics_port) and port_open(ADDRESS, services_port)

    wait_until(up, timeout, what=f"simserver on ports {topics_port}/{services_port}")
    return SimServer(ADDRESS, topics_port, services_port, process)


__all__ = ["SIM_CONFIG", "SimServer", "port_open", "start_simserver"]
