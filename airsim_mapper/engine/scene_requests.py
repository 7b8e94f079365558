"""Scene loads asked for over ROS (the load_scene bridge): a short queue, and one thread that loads them
in turn. A ROS callback never waits for a load; a request beyond the queue's room is refused."""

from __future__ import annotations

import contextlib
import logging
import queue
import threading
from collections.abc import Callable
from typing import Any

from airsim_mapper.common.errors import ConfigError
from airsim_mapper.common.logs import RateLimitedLog, ros_logger, shorten
from airsim_mapper.engine.errors import EngineError

log = ros_logger("airsim_mapper.engine")
MAX_QUEUED_SCENES = 8  # load_scene requests waiting for the scene-loader thread
REFUSALS_LOGGED, REFUSALS_PERIOD_S = 10, 10.0  # at most this many refused loads logged per period
SHOWN_LINE = 300  # characters of an error line a refusal log shows


class SceneRequests:
    """Queued scene loads, run one at a time on the scene-loader thread by `load` (the engine's
    load_scene); `loaded` is told of each load that succeeded."""

    def __init__(self, load: Callable[[str], Any], loaded: Callable[[], None]) -> None:
        self._load = load
        self._loaded = loaded
        self._requests: queue.Queue[str | None] = queue.Queue(MAX_QUEUED_SCENES)
        self._loading: str | None = None  # the scene file being loaded by the scene-loader thread
        self._refusals = RateLimitedLog(log, REFUSALS_PERIOD_S, REFUSALS_LOGGED, logging.ERROR)
        self._running = True
        self._thread = threading.Thread(target=self._loop, name="scene-loader", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        """No more loads: the thread ends after the load it is running (if any)."""
        self._running = False
        with contextlib.suppress(queue.Full):  # a full queue's loader sees _running false after its load
            self._requests.put_nowait(None)

    def request(self, scene_file: str) -> None:
        """Queue a scene load (from a ROS callback). At most MAX_QUEUED_SCENES wait; a request beyond
        that is refused (EngineError) and logged."""
        loading = self._loading
        try:
            self._requests.put_nowait(scene_file)
        except queue.Full:
            self._refusals.warn(
                f"load_scene {shorten(scene_file)!r} refused: {MAX_QUEUED_SCENES} loads are already waiting"
                + (f" behind {shorten(loading)!r}" if loading else "")
            )
            raise EngineError(f"{MAX_QUEUED_SCENES} scene loads are already waiting") from None
        if loading is not None:
            log.info(
                "load_scene %r queued behind %r (%d waiting)",
                shorten(scene_file),
                shorten(loading),
                self._requests.qsize(),
            )

    def _loop(self) -> None:
        while True:
            scene_file = self._requests.get()
            if scene_file is None or not self._running:
                return
            self._loading = scene_file
            try:
                self._load(scene_file)
            except ConfigError as exc:
                report = "\n".join(shorten(line, SHOWN_LINE) for line in str(exc).splitlines())
                self._refusals.warn(
                    f"load_scene {shorten(scene_file)!r} refused; the current scene stays:\n{report}"
                )
            except Exception as exc:
                self._refusals.warn(
                    f"load_scene {shorten(scene_file)!r} failed: {shorten(str(exc), SHOWN_LINE)}"
                )
            else:
                self._loaded()
            finally:
                self._loading = None
