"""The headless server: sockets, the current scene, and the simulation, camera and scan threads."""

from __future__ import annotations

import contextlib
import logging
import operator
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from airsim_mapper.common.ports import SERVICES_PORT, TOPICS_PORT
from airsim_mapper.simserver.render.render_worker import RENDER_NICE, RenderWorker, RenderWorkerError
from airsim_mapper.simserver.scene.config import SceneSpec, SceneSpecError, default_scene, parse_scene
from airsim_mapper.simserver.scene.objects import LiveWorld
from airsim_mapper.simserver.session import TRAJECTORY_KEYS, Session, TrajectoryStore
from airsim_mapper.simserver.wire.services import MethodTable, ServiceError, ServiceServer
from airsim_mapper.simserver.wire.topics import TopicHub
from airsim_mapper.simserver.world.world_file import load_world

LOG = logging.getLogger("airsim_mapper.simserver")

DEFAULT_SCENE_PREFIX = "/Sim/SceneBasicDrone"
NEVER_EXPIRES = 0xFFFFFFFFFFFFFFFF
MIN_TICK_S, MAX_TICK_S = 0.001, 0.02  # bounds of the free-running physics tick period (wall seconds)
SENSOR_IDLE_S = 0.005
LOCK_STEP_FLUSH_S = 5.0  # at most this long for a step's frames to leave (each send gives up after 250 ms)


@dataclass(frozen=True)
class SensorLane:
    """A sensor thread: the session's step it runs, and the lock held around each step (a scene swap and a
    lock-step step take it too). Cameras and scans have a lane each, so a slow render never holds back a
    lidar or radar sample."""

    name: str
    step: Callable[[Session], bool]
    lock: threading.Lock = field(default_factory=threading.Lock, compare=False)


@dataclass(frozen=True)
class ServerOptions:
    address: str = "127.0.0.1"  # anything else exposes an unauthenticated control port: say so
    topics_port: int = TOPICS_PORT
    services_port: int = SERVICES_PORT
    world_path: str | None = None
    pose_rate_hz: float = 100.0
    tick_rate_hz: float | None = None  # None: one physics tick per scene clock step-ns (as the real server)
    workers: int = 32
    render_nice: int | None = RENDER_NICE  # None renders in the server's own process


def is_loopback(address: str) -> bool:
    """Whether `address` (a host name or an IP address) is this machine's loopback."""
    import ipaddress

    if address == "localhost":
        return True
    try:
        return ipaddress.ip_address(address).is_loopback
    except ValueError:
        return False


class SimServer:
    """Owns both channels and the running scene; `start`, then `stop` (joins every thread)."""

    def __init__(self, options: ServerOptions) -> None:
        self.options = options
        self.world = LiveWorld(load_world(options.world_path))  # objects move, appear and vanish at run time
        nice = options.render_nice
        self.render_worker = RenderWorker(self.world, nice) if nice is not None else None
        self.table = MethodTable()
        self.hub = TopicHub(options.address, options.topics_port)
        self.services = ServiceServer(self.table, options.address, options.services_port, options.workers)
        self._scene_lock = threading.Lock()
        # held by each loop around one step of the current session, and by a scene swap (all of them)
        self._sim_step_lock = threading.Lock()
        self._lanes = (
            SensorLane("cameras", operator.methodcaller("camera_tick")),
            SensorLane("scans", operator.methodcaller("scan_tick")),
        )
        self._stopping = threading.Event()
        self._default_trajectories = TrajectoryStore()
        self.session: Session | None = None
        self._session_methods: list[str] = []
        self._register_sim_methods()
        self._activate(self._session(default_scene()))
        self._threads = [
            threading.Thread(target=self._sim_loop, name="sim", daemon=True),
            *(
                threading.Thread(target=self._sensor_loop, args=(lane,), name=lane.name, daemon=True)
                for lane in self._lanes
            ),
        ]

    # -- lifecycle

    def start(self) -> None:
        self.hub.start()
        self.services.start()
        for thread in self._threads:
            thread.start()
        LOG.info("serving topics on %s and services on %s", self.hub.url, self.services.url)
        if not is_loopback(self.options.address):
            LOG.warning(
                "listening on %s: anyone who can reach it can drive, reset and reload this simulator "
                "(the protocol has no authentication); use --address 127.0.0.1 to keep it local",
                self.options.address,
            )

    def stop(self) -> None:
        self._stopping.set()
        if self.session is not None:
            self.session.stop()
        for thread in self._threads:
            thread.join(timeout=5.0)
        self.services.stop()
        self.hub.stop()
        if self.render_worker is not None:
            self.render_worker.close()

    # -- scenes

    def _register_sim_methods(self) -> None:
        self.table.register("/Sim/LoadScene", ("scene_config",), self._load_scene)
        self.table.register("/Sim/Unsubscribe", ("topic_paths",), self._unsubscribe)
        self.table.register("/Sim/SetInteractiveFeature", ("feature_id", "enable"), self._interactive_feature)
        self.table.register("/Sim/GetBuildCommitHash", (), lambda _: "airsim-mapper-simserver")
        self.table.register("/Sim/GetAuthorizationTokenPublicKey", (), lambda _: "")
        self.table.register(
            "/Sim/SetAuthorizationToken", ("token_encrypted_base64",), lambda _: NEVER_EXPIRES
        )
        self.table.register(
            f"{DEFAULT_SCENE_PREFIX}/ImportNEDTrajectory",
            ("traj_name", *TRAJECTORY_KEYS),
            self._default_import,
        )

    def _default_import(self, params: dict[str, Any]) -> bool:
        session = self.session
        if session is not None and session.spec.prefix == DEFAULT_SCENE_PREFIX:
            return session.trajectories.import_ned(params)
        return self._default_trajectories.import_ned(params)

    def _session(self, spec: SceneSpec) -> Session:
        render = self.render_worker.render if self.render_worker is not None else None
        return Session(spec, self.world, self.hub, render)

    def _activate(self, session: Session) -> None:
        """Swap in a new scene: methods, topic table (with `/$topics` cached) and initial publications.

        The swap waits for a simulation or sensor step of the old scene in progress (a render can take a
        while), so that nothing the old scene publishes lands in the new table: a scene reloaded with the same
        id has the same topic paths, and an old frame would become the new scene's cached value.
        """
        with contextlib.ExitStack() as held:
            for lock in (self._sim_step_lock, *(lane.lock for lane in self._lanes)):
                held.enter_context(lock)
            old = self.session
            if old is not None:
                old.stop()
            methods = [
                m for m in session.methods() if m.name != f"{DEFAULT_SCENE_PREFIX}/ImportNEDTrajectory"
            ]
            self.table.replace_group(self._session_methods, methods)
            self._session_methods = [m.name for m in methods]
            self.hub.set_table(session.topics(), session.topic_handlers())
            self.session = session
            session.start()
        LOG.info("scene %s loaded (%d robots)", session.spec.id, len(session.robots))

    def _load_scene(self, params: dict[str, Any]) -> str:
        text = params["scene_config"]
        if not isinstance(text, (str, bytes)):
            raise ServiceError(f"scene_config must be a JSON string, got {type(text).__name__}")
        try:
            spec = parse_scene(text)
        except SceneSpecError as exc:
            raise ServiceError(f"Invalid scene config: {exc}") from exc
        with self._scene_lock:
            self._activate(self._session(spec))
        return spec.id

    def _unsubscribe(self, params: dict[str, Any]) -> bool:
        paths = params["topic_paths"]
        if isinstance(paths, str):
            paths = [paths]
        if not isinstance(paths, list):
            raise ServiceError(f"topic_paths must be a list of topic paths, got {paths!r}")
        return self.hub.unsubscribe(str(p) for p in paths)

    @staticmethod
    def _interactive_feature(params: dict[str, Any]) -> bool:
        return params["feature_id"] == "viewport_camera"

    # -- threads

    def _tick_period_s(self, session: Session | None) -> float:
        """Wall seconds between free-running physics ticks: the scene's step-ns (1-20 ms), unless fixed."""
        if self.options.tick_rate_hz:
            return 1.0 / self.options.tick_rate_hz
        step_ns = session.spec.clock.step_ns if session is not None else 3_000_000
        return min(max(step_ns / 1e9, MIN_TICK_S), MAX_TICK_S)

    def _sim_loop(self) -> None:
        pose_period = 1.0 / self.options.pose_rate_hz
        next_tick = time.monotonic()
        next_pose = next_tick
        while not self._stopping.is_set():
            session = self.session
            if session is not None and session.clock.stepping():
                self._lock_step(session)
                next_tick = time.monotonic()
                continue
            now = time.monotonic()
            publish_pose = now >= next_pose
            if publish_pose:
                next_pose = max(next_pose + pose_period, now - pose_period)
            try:
                with self._sim_step_lock:
                    session = self.session
                    if session is not None:
                        session.tick(publish_pose)
            except Exception:
                LOG.exception("simulation tick failed")
            next_tick += self._tick_period_s(session)
            delay = next_tick - time.monotonic()
            if delay > 0:
                self._stopping.wait(delay)
            else:
                next_tick = time.monotonic()

    def _lock_step(self, session: Session) -> None:
        """One step of a lock-step continue: motion, pose and instruments, then every sensor sample due at
        the step's time (rendered here, before the clock may move on), then the step counts as done."""
        try:
            with self._sim_step_lock:
                if self.session is not session:
                    return
                session.clock.begin_step()
                session.tick(True)
            for lane in self._lanes:
                with lane.lock:
                    if self.session is session:
                        lane.step(session)
            # the step's frames go out before its reply: queued, the next step's image would replace an
            # unsent one (the outbox keeps the newest large frame per topic) while the client was slow
            self.hub.flush(LOCK_STEP_FLUSH_S)
        except Exception:
            LOG.exception("lock-step tick failed")
        finally:
            session.clock.finish_step()

    def _sensor_loop(self, lane: SensorLane) -> None:
        while not self._stopping.is_set():
            worked = False
            try:
                with lane.lock:
                    session = self.session
                    if session is not None:
                        worked = lane.step(session)
            except RenderWorkerError as exc:  # the worker is replaced on the next capture
                LOG.warning("sensor step failed: %s", exc)
                self._stopping.wait(0.1)
            except Exception:
                LOG.exception("sensor step failed")
                self._stopping.wait(0.1)
            if not worked:  # nothing due: look again after a physics tick (at most 5 ms)
                self._stopping.wait(min(SENSOR_IDLE_S, self._tick_period_s(self.session)))
