"""Project AirSim's default ports, written once: the node, the wrapper, the headless server and the scripts
take them from here, and a test checks the launch files' defaults against them. A leaf module."""

from __future__ import annotations

from typing import Any

__all__ = ["SERVICES_PORT", "TOPICS_PORT", "accepts_connections", "port"]

TOPICS_PORT = 8989  # pub-sub (the client's Pair0 topics socket)
SERVICES_PORT = 8990  # requests (the client's Req0 services socket)


def port(value: Any) -> int:
    """A TCP port number, 1-65535, as a switch or a parameter gives it: a ValueError otherwise (argparse
    then says "invalid port value", the node "is not a valid port")."""
    number = int(value)
    if not 1 <= number <= 65535:
        raise ValueError(f"{value!r} is not a port (1-65535)")
    return number


def accepts_connections(host: str, number: int, timeout: float) -> bool:
    """Whether something at `host` accepts a TCP connection on port `number` within `timeout` seconds."""
    import socket

    try:
        socket.create_connection((host, number), timeout=timeout).close()
    except OSError:
        return False
    return True
