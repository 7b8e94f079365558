"""The live engine: runs expanded bridges between the simulator client and ROS.

Its face, the names the layers above use: the `Engine` and what it is made with (`NodeNames`, `SimAccess`,
`FrameCounts`), connecting to a simulator (`open_client`, `close_client`, `Backoff`, `retry_quietly` and
their errors), what the wrapper and the node add around an engine (`Diagnostics`, `MasterWatch`,
`MappingReloader`, `WaitingStatus`), the limits they default to, and the modules `ros2_link` (the ROS link
on ROS 2, which the ROS 2 node imports) and `ros2_node` (the rclpy node's executor thread and log handler,
the ROS 2 node's and wrapper's). Everything else is the engine's own.

Each name is imported from its module on first use, so that importing one (the node's start-up imports
`open_client` before ROS is up) does not import rospy and the rest of the engine with it.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from airsim_mapper.engine.core import SHUTDOWN_TIMEOUT_S, Engine
    from airsim_mapper.engine.diagnostics import Diagnostics
    from airsim_mapper.engine.errors import EngineError, InternalsChanged
    from airsim_mapper.engine.health import Backoff, SimSilent, SimUnreachable, open_client, retry_quietly
    from airsim_mapper.engine.mapping_reload import MappingReloader
    from airsim_mapper.engine.node_setup import NodeNames, SimAccess
    from airsim_mapper.engine.reregister import MasterWatch
    from airsim_mapper.engine.sim_link import MAX_FRAME_MB, FrameCounts, close_client
    from airsim_mapper.engine.status import WaitingStatus

__all__ = [
    "MAX_FRAME_MB",
    "SHUTDOWN_TIMEOUT_S",
    "Backoff",
    "Diagnostics",
    "Engine",
    "EngineError",
    "FrameCounts",
    "InternalsChanged",
    "MappingReloader",
    "MasterWatch",
    "NodeNames",
    "SimAccess",
    "SimSilent",
    "SimUnreachable",
    "WaitingStatus",
    "close_client",
    "open_client",
    "retry_quietly",
    "ros2_link",
    "ros2_node",
]

_HOMES = {
    "core": ("SHUTDOWN_TIMEOUT_S", "Engine"),
    "diagnostics": ("Diagnostics",),
    "errors": ("EngineError", "InternalsChanged"),
    "health": ("Backoff", "SimSilent", "SimUnreachable", "open_client", "retry_quietly"),
    "mapping_reload": ("MappingReloader",),
    "node_setup": ("NodeNames", "SimAccess"),
    "reregister": ("MasterWatch",),
    "sim_link": ("MAX_FRAME_MB", "FrameCounts", "close_client"),
    "status": ("WaitingStatus",),
}
_HOME_OF = {name: module for module, names in _HOMES.items() for name in names}


def __getattr__(name: str) -> Any:
    """A public name, imported from its module on first use."""
    module = _HOME_OF.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)
