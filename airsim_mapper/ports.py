"""Project AirSim's default ports, written once: the node, the wrapper, the headless server and the scripts
take them from here, and a test checks the launch files' defaults against them. A leaf module."""

from __future__ import annotations

__all__ = ["SERVICES_PORT", "TOPICS_PORT"]

TOPICS_PORT = 8989  # pub-sub (the client's Pair0 topics socket)
SERVICES_PORT = 8990  # requests (the client's Req0 services socket)
