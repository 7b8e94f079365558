"""The engine: runs the bridges of a mapping for the current scene, and follows scene changes.

Data flows one way: scene + mapping --expand--> BridgeSpecs --build--> runners wired to the sim link and
the ROS link. A scene change tears the scene's runners down and builds the new scene's; bridges that do
not depend on the scene (load_scene itself) keep running.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from airsim_mapper.engine.bridges import Bridge, RosToSim, Services, StreamingImage, build
from airsim_mapper.engine.hub import StreamHub
from airsim_mapper.engine.ros_link import TfBroadcaster
from airsim_mapper.engine.sim_link import SimLink
from airsim_mapper.mapping.errors import ConfigError
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.model import BridgeSpec, Mapping
from airsim_mapper.scene import Scene, read_scene

log = logging.getLogger("rosout.airsim_mapper.engine")
WATCHDOG_PERIOD_S = 0.05


class Engine:
    """Owns the runners of one node: builds them from specs, reloads them on scene changes."""

    def __init__(
        self,
        client: Any,
        mapping: Mapping,
        sim_config_path: str | Path,
        node_name: str,
        namespace: str = "",
        load_world: Callable[[Any, str, str], Any] | None = None,
    ) -> None:
        self.client = client
        self.mapping = mapping
        self.sim_config_path = str(sim_config_path)
        self.node_name = node_name
        self.namespace = namespace
        self.sim = SimLink(client)
        self.tf = TfBroadcaster()
        self.hub = StreamHub(self.sim, self.tf.send)
        self.shared: dict[Any, Any] = {}
        self.services = Services(self.sim, self.hub, self.tf, self.shared, self._node_action)
        self.bridges: dict[str, Bridge] = {}
        self.scene: Scene | None = None
        self.world: Any = None
        self._load_world = load_world or _load_world
        self._lock = threading.RLock()
        self._scene_requests: queue.Queue[str | None] = queue.Queue()
        self._running = True
        self._threads = [
            threading.Thread(target=self._watchdog_loop, name="watchdog", daemon=True),
            threading.Thread(target=self._scene_loop, name="scene-loader", daemon=True),
        ]
        for thread in self._threads:
            thread.start()

    # --- building ---------------------------------------------------------------------------
    def specs_for(self, scene: Scene) -> tuple[BridgeSpec, ...]:
        return expand(self.mapping, scene, self.node_name, self.namespace)

    def apply(self, scene: Scene) -> tuple[BridgeSpec, ...]:
        """Run exactly the bridges of `scene`: stop the old scene's, start the new ones."""
        specs = self.specs_for(scene)
        with self._lock:
            self._stop_scene_bridges(keep={s.name: s for s in specs})
            self.scene = scene
            self.shared.clear()
            streaming: list[StreamingImage] = [
                b for b in self.bridges.values() if isinstance(b, StreamingImage)
            ]
            for spec in specs:
                if spec.name in self.bridges:
                    continue
                bridge = build(spec, self.services, streaming)
                bridge.start()
                self.bridges[spec.name] = bridge
        return specs

    def _stop_scene_bridges(self, keep: dict[str, BridgeSpec]) -> None:
        """Stop every bridge except scene-independent ones whose spec is unchanged."""
        for name, bridge in list(self.bridges.items()):
            spec = keep.get(name)
            if spec is not None and spec == bridge.spec and _scene_independent(spec):
                continue
            try:
                bridge.stop()
            except Exception:
                log.exception("stopping %s failed", name)
            del self.bridges[name]

    # --- scenes -----------------------------------------------------------------------------
    def load_scene(self, scene_file: str) -> Scene:
        """Validate, load into the simulator, and re-bridge. On any error the current scene stays."""
        scene = read_scene(self.sim_config_path, scene_file)  # path and config checks first
        self.specs_for(scene)  # the mapping must expand for it before anything is torn down
        with self._lock:
            self._stop_scene_bridges(keep={})
            self.hub.drop_all()
            self.sim.forget_all()
            try:
                self.world = self._load_world(self.client, scene_file, self.sim_config_path)
            except Exception:
                if self.scene is not None:
                    log.error("loading %s failed; restoring the bridges of %s", scene_file, self.scene.file)
                    self.apply(self.scene)
                raise
            self.apply(scene)
        log.info("scene %s (%s) loaded: %d bridges", scene.name, scene_file, len(self.bridges))
        return scene

    def adopt(self, scene: Scene, world: Any = None) -> None:
        """A mission script loaded `scene` itself: its load cleared every subscription, so re-bridge."""
        with self._lock:
            self._stop_scene_bridges(keep={})
            self.hub.drop_all()
            self.sim.forget_all()
            self.world = world
            self.apply(scene)

    def request_scene(self, scene_file: str) -> None:
        """Queue a scene load (from a ROS callback); it runs on the scene-loader thread."""
        self._scene_requests.put(scene_file)

    def _scene_loop(self) -> None:
        while True:
            scene_file = self._scene_requests.get()
            if scene_file is None:
                return
            try:
                self.load_scene(scene_file)
            except ConfigError as exc:
                log.error("load_scene %r refused; the current scene stays:\n%s", scene_file, exc)
            except Exception as exc:
                log.error("load_scene %r failed: %s", scene_file, exc)

    def _node_action(self, spec: BridgeSpec, params: dict) -> None:
        if spec.converter == "load_scene":
            self.request_scene(params["scene"])
        else:
            raise ValueError(f"{spec.name}: converter {spec.converter!r} has no engine action")

    # --- watchdog and shutdown --------------------------------------------------------------
    def _watchdog_loop(self) -> None:
        while self._running:
            now = time.monotonic()
            for bridge in list(self.bridges.values()):
                if isinstance(bridge, RosToSim):
                    try:
                        bridge.check_watchdog(now)
                    except Exception:
                        log.exception("watchdog of %s failed", bridge.spec.name)
            time.sleep(WATCHDOG_PERIOD_S)

    def shutdown(self) -> None:
        """Stop every bridge (robots with a running velocity command are stopped) and the link."""
        self._running = False
        self._scene_requests.put(None)
        with self._lock:
            for name, bridge in list(self.bridges.items()):
                try:
                    bridge.stop()
                except Exception:
                    log.exception("stopping %s failed", name)
            self.bridges.clear()
        time.sleep(0.1)  # let the last stop commands leave
        self.sim.close()
        self.hub.drop_all()


def _scene_independent(spec: BridgeSpec) -> bool:
    return "scene_name" not in spec.variables


def _load_world(client: Any, scene_file: str, sim_config_path: str) -> Any:
    from projectairsim import World

    return World(client, scene_file, sim_config_path=sim_config_path.rstrip("/") + "/")
