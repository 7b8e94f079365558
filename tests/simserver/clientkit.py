"""Helpers for driving the headless server with the real `projectairsim` 1.1.0 client in tests."""

from __future__ import annotations

import asyncio
import functools
import json
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from harness import SIM_CONFIG, RigError


class Inbox:
    """Messages received on one topic by a client subscription (thread-safe)."""

    def __init__(self) -> None:
        self.messages: list[Any] = []
        self.arrivals: list[float] = []
        self._cond = threading.Condition()

    def __call__(self, _topic: Any, message: Any) -> None:
        with self._cond:
            self.messages.append(message)
            self.arrivals.append(time.monotonic())
            self._cond.notify_all()

    def wait_for(
        self, count: int = 1, timeout: float = 5.0, where: Callable[[Any], bool] | None = None
    ) -> list:
        deadline = time.monotonic() + timeout
        with self._cond:
            while True:
                matching = [m for m in self.messages if where is None or where(m)]
                if len(matching) >= count:
                    return matching
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise RigError(f"got {len(matching)} of {count} messages within {timeout} s")
                self._cond.wait(remaining)


def subscribe(client: Any, topic: str) -> Inbox:
    inbox = Inbox()
    client.subscribe(topic, inbox)
    return inbox


def settle(client: Any, fence: str, timeout: float = 5.0) -> None:
    """Return once the server has taken every subscription this client sent so far.

    The client's `subscribe` returns without waiting for the server, and steps go on the services socket,
    so a paused step can reach the server before a subscription sent ahead of it, and a lazy sensor then
    has no subscriber to sample for. The server reads the topics socket in order and answers a
    subscription to a topic with a last value (`fence`: a robot's pose) at once, so that answer arriving
    means the subscriptions before it are in place."""
    subscribe(client, fence).wait_for(1, timeout)


@functools.cache
def _merged_config(scene_file: str, sim_config: Path) -> str:
    from projectairsim.utils import load_scene_config_as_dict

    config, _ = load_scene_config_as_dict(scene_file, sim_config_path=str(sim_config))
    return json.dumps(config)


def scene_config(scene_file: str, sim_config: Path = SIM_CONFIG) -> dict[str, Any]:
    """The merged scene dict the client builds from a scene file in `sim_config` (the project's own configs
    unless told otherwise; parsed once per test run: the client's jsonc parser takes seconds per file)."""
    return json.loads(_merged_config(scene_file, sim_config))


def load_world(client: Any, scene_file: str, sim_config: Path = SIM_CONFIG) -> Any:
    """A World on a freshly (re)loaded scene, through the client's own `World.load_scene`."""
    from projectairsim import World

    world = World(client)
    world.load_scene(scene_config(scene_file, sim_config))
    return world


def run_async(coroutine_factory: Callable[[], Any]) -> Any:
    """Run an async client interaction (the `*_async` drone methods need a running loop)."""
    return asyncio.run(coroutine_factory())


def position(drone: Any) -> list[float]:
    translation = drone.get_ground_truth_pose()["translation"]
    return [translation["x"], translation["y"], translation["z"]]
