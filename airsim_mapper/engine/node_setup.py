"""What an engine is made with, besides its client and mapping: its node's names and its way to the
simulator."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from airsim_mapper.engine.sim_link import FrameCounts, SimLink
from airsim_mapper.engine.validated_world import load_validated_world
from airsim_mapper.mapping.scene import Scene


@dataclass(frozen=True)
class NodeNames:
    """The names an engine's bridges are expanded with and its reports go by."""

    node: str  # the mapping's <node_name>
    namespace: str = ""  # where the mapping's names go
    ros: str = ""  # the node's ROS name (its status topic's, diagnostics'); `node` when empty


@dataclass(frozen=True)
class SimAccess:
    """How an engine reaches the simulator: the scene configurations, how a scene is loaded into a client,
    how a link is made on one, and (only when the engine may replace its client) how a client is made."""

    config_path: str | Path
    load_world: Callable[[Any, Scene, str], Any] = load_validated_world
    client_factory: Callable[[], Any] | None = None
    link: Callable[[Any, FrameCounts], SimLink] = SimLink
