"""ProjectAirSimWrapper: the bridge as an object a mission script embeds (the public API that the Project
AirSim ROS bridge documentation describes), on ROS1 and on ROS 2.

The flavour is the one the converters build messages for (`convert.flavour`): ROS1 where genpy is
importable (`.venv`), ROS 2 where only rclpy is (`.venv-ros2`), as the node chooses without `--ros`.
On ROS1, call `rospy.init_node` first. On ROS 2, call `rclpy.init` first and pass the script's node
(`node=`), or the wrapper makes one named `node_name` (default "projectairsim", with the shipped Fast DDS
profile unless the user chose one: `common/dds_profile.py`); either way the wrapper spins it with an
executor on a thread of its own, sends the bridge's and the client's log to its logger (console and
/rosout), and shuts down with rclpy's context.

Without a scene the wrapper runs the node's own bridges (load_scene) and waits for one. The wrapper either
creates its own client (kept in `projectairsim_client` and disconnected at ROS shutdown) or takes one (then
never disconnects it: the script does, and until then the client's receive thread keeps the process alive,
as it does without the bridge). After a mission script loads a scene itself with `World(...)`, it calls
`update_topics(world)` so the bridges follow. The README's example shows the whole pattern
(`disable_signals=True`, so that Ctrl-C also stops a running mission); `scripts/hello_ros2.py` is its ROS 2
twin.

Reliability: a wrapper that made its client (or was given a `client_factory`) reconnects by itself when
the simulator restarts and reloads the last scene; with a client supplied by the mission script it only
reports "stale" on `/airsim_mapper/<node>/status`. On ROS1 a restarted ROS master is noticed and the
node's topics and services are registered with it again (engine/reregister.py).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

from airsim_mapper.common.dds_profile import use_shipped_profile
from airsim_mapper.common.errors import AirsimMapperError
from airsim_mapper.common.logs import caller_logger, ros_logger, wait_for_rosout
from airsim_mapper.common.ports import SERVICES_PORT, TOPICS_PORT
from airsim_mapper.common.resources import DEFAULT_MAPPING
from airsim_mapper.common.tuning import keep_frame_buffers
from airsim_mapper.convert.flavour import ROS2
from airsim_mapper.engine import (
    MAX_FRAME_MB,
    SHUTDOWN_TIMEOUT_S,
    Diagnostics,
    Engine,
    FrameCounts,
    NodeNames,
    SimAccess,
    close_client,
    open_client,
)
from airsim_mapper.mapping.diff import BridgeDiff
from airsim_mapper.mapping.loader import load_mapping
from airsim_mapper.mapping.model import BridgeSpec, MappingDoc
from airsim_mapper.mapping.names import resolve_namespace
from airsim_mapper.mapping.scene import Scene, scene_from_config

log = ros_logger("airsim_mapper")
DEFAULT_NODE_NAME = "projectairsim"  # the node a ROS 2 wrapper makes when it is given none


class WrapperError(AirsimMapperError, RuntimeError):
    """The wrapper cannot do what was asked (the message says why)."""


def redirect_client_log(node: Any = None) -> None:
    """Send the projectairsim client's log records to `rosout.projectairsim` (console and /rosout), as far
    as that logger's level lets them through. On ROS 2 give the script's rclpy node: the `rosout.*` records
    go to its logger from now on (call this before the client connects, so its first lines get there)."""
    from projectairsim.utils import projectairsim_log

    if node is not None:
        from airsim_mapper.engine.ros2_node import log_to

        log_to(node)

    client_log = caller_logger(projectairsim_log())  # its records name their caller on /rosout too
    if any(getattr(f, "airsim_mapper", False) for f in client_log.filters):
        return

    target = ros_logger("projectairsim")

    def _redirect(record: logging.LogRecord) -> bool:
        if target.isEnabledFor(record.levelno):  # handle() alone would ignore the logger's level
            target.handle(record)
        return False

    _redirect.airsim_mapper = True  # type: ignore[attr-defined]
    client_log.addFilter(_redirect)


class Ros1Node:
    """The wrapper's ROS1 side: the process's rospy node (`rospy.init_node` first), the engine's default ROS
    link, and the watch that registers the node again with a restarted master."""

    def __init__(self) -> None:
        import rospy

        wait_for_rosout()  # so that what the wrapper and its client log first reaches rosout.log (logs.py)
        self.name, self.namespace = rospy.get_name(), rospy.get_namespace()
        self.link: Any = None  # the engine makes ROS1's
        self._watch: Any = None

    def start(self, on_shutdown: Callable[[], None]) -> None:
        import rospy

        from airsim_mapper.engine import MasterWatch

        self._watch = MasterWatch()
        self._watch.start()
        rospy.on_shutdown(on_shutdown)

    def stop(self) -> None:
        """Before the bridges stop: no registering them again."""
        if self._watch is not None:
            self._watch.stop()

    def close(self) -> None:
        """After the bridges stopped: rospy's node is the script's."""


class Ros2Node:
    """The wrapper's ROS 2 side: an rclpy node (the script's, else one made here and destroyed at the end)
    spun by an executor thread of its own, its logger taking the bridge's and the client's records."""

    def __init__(self, node: Any, node_name: str | None) -> None:
        import rclpy

        from airsim_mapper.engine.ros2_link import Ros2Link
        from airsim_mapper.engine.ros2_node import Spinner, log_to

        self._made = node is None
        profile = use_shipped_profile() if node is None else ""  # a script's node has its participant
        self.node = rclpy.create_node(node_name or DEFAULT_NODE_NAME) if node is None else node
        self.name, self.namespace = self.node.get_fully_qualified_name(), self.node.get_namespace()
        self.link = Ros2Link(self.node)
        self._log = log_to(self.node)
        if profile:
            log.info(profile)
        self._spinner = Spinner(self.node)
        self._spinner.start()

    def start(self, on_shutdown: Callable[[], None]) -> None:
        self.node.context.on_shutdown(on_shutdown)

    def stop(self) -> None:
        """Before the bridges stop: the node spins on, so that what they log still reaches /rosout."""

    def close(self) -> None:
        """After the bridges stopped: the executor, and the node and its log if the node was made here. A
        script's node keeps the log (what the script and its client log later still reach it)."""
        from airsim_mapper.engine.ros2_node import ROSOUT_LOGGER

        self._spinner.stop()
        if self._made:
            logging.getLogger(ROSOUT_LOGGER).removeHandler(self._log)
            self.node.destroy_node()


class ProjectAirSimWrapper:
    """Runs the bridge for a mapping on a Project AirSim client, in the calling ROS node.

    The wrapper fixes glibc's malloc thresholds, so that image frames are not returned to the kernel and
    faulted back in on every frame (`tuning.keep_frame_buffers`; AIRSIM_MAPPER_NO_TUNING=1 leaves them),
    and lets the node's TCPROS port queue 128 new connections, not 5 (`rospy_internals.widen_accept_backlog`).
    Beyond that it changes nothing process-wide unless asked: with `tune_process=True` (what the node does)
    it limits numpy's OpenBLAS to one thread, lowers the interpreter's switch interval to 0.5 ms, makes
    every rospy publisher of the process send on the publishing thread when the socket takes the message
    at once, watches rospy's connections without an open file per topic, and freezes the heap after each
    scene change (`gc.freeze`); engine/process_tuning.py explains why.
    """

    def __init__(
        self,
        client: Any = None,
        *,
        address: str = "127.0.0.1",
        topicsport: int = TOPICS_PORT,
        servicesport: int = SERVICES_PORT,
        sim_config_path: str | Path = "sim_config/",
        mapping: MappingDoc | str | Path = DEFAULT_MAPPING,
        scene: str | None = None,
        node_name: str | None = None,
        namespace: str = "",
        disconnect_on_shutdown: bool | None = None,
        client_factory: Callable[[], Any] | None = None,
        shutdown_timeout: float = SHUTDOWN_TIMEOUT_S,
        tune_process: bool = False,
        max_frame_mb: float = MAX_FRAME_MB,
        node: Any = None,
    ) -> None:
        keep_frame_buffers()  # process-wide, from the first frame the bridge receives (tuning.py)
        redirect_client_log()
        self.ros_node = Ros2Node(node, node_name) if ROS2 else Ros1Node()
        self.shutdown_timeout = shutdown_timeout
        self.mapping = mapping if isinstance(mapping, MappingDoc) else load_mapping(mapping)
        self._owns_client = client is None if disconnect_on_shutdown is None else disconnect_on_shutdown
        if client is None:
            client_factory = client_factory or partial(open_client, address, topicsport, servicesport)
            try:
                client = client_factory()
            except BaseException:
                self.ros_node.close()
                raise
        self.sim_config_path = str(sim_config_path)
        # The status topic and diagnostics go by the ROS node's full name, unique on the master (so that
        # /sim1/projectairsim and /sim2/projectairsim differ); the mapping's <node_name> is its last part.
        ros_name = self.ros_node.name
        name = node_name if node_name is not None else ros_name.rsplit("/", 1)[-1]
        # As a ROS name: "sim1" below the node's namespace (ROS_NAMESPACE, <group ns>, __ns:=); "/sim1" as is
        namespace = resolve_namespace(namespace, self.ros_node.namespace)
        self.namespace = namespace
        self.engine = Engine(
            client,
            self.mapping,
            NodeNames(name, namespace, ros_name),
            SimAccess(self.sim_config_path, client_factory=client_factory),
            ros=self.ros_node.link,
            frame_counts=FrameCounts(max_frame_bytes=int(max_frame_mb * 1024 * 1024)),
            tune=tune_process,
        )
        self.engine.start()
        self.diagnostics = Diagnostics(self.engine, ros_name)
        self.diagnostics.start()
        self._closed = False
        self.ros_node.start(self.shutdown)
        self.engine.start_node_bridges()  # load_scene is there before (and without) any scene
        if scene:
            self.engine.load_scene(scene)

    @property
    def projectairsim_client(self) -> Any:
        """The client in use (a new one after the wrapper reconnected to a restarted simulator)."""
        return self.engine.client

    @property
    def bridges(self) -> list[Any]:
        return list(self.engine.bridge_specs())

    @property
    def scene(self) -> Scene | None:
        return self.engine.scene

    def load_scene(self, scene_file: str | Scene, specs: tuple[BridgeSpec, ...] | None = None) -> Scene:
        """Load a scene file from `sim_config_path` into the simulator and bridge it (or a Scene already
        read, with its bridges already expanded for this node: see Engine.load_scene)."""
        return self.engine.load_scene(scene_file, specs)

    def apply_mapping(self, mapping: MappingDoc | str | Path) -> BridgeDiff:
        """Run another mapping (a MappingDoc, a file or a shipped mapping's name) from now on, restarting only
        the bridges whose expansion changed; returns the difference (added, removed, changed). An invalid
        mapping raises MappingError and changes nothing."""
        mapping = mapping if isinstance(mapping, MappingDoc) else load_mapping(mapping)
        diff = self.engine.apply_mapping(mapping)
        self.mapping = mapping
        return diff

    def update_topics(self, world: Any = None) -> None:
        """Re-bridge after a mission script loaded a scene with `World(...)` on the shared client.

        Pass that World; without it the wrapper re-bridges the scene it knows, if the simulator's topic
        catalogue still belongs to it.
        """
        if world is not None:
            config = world.get_configuration()
            if not config:
                raise WrapperError(
                    "update_topics: the World has no scene configuration (built without a scene)"
                )
            scene_file = Path(getattr(world, "scene_config_path", "") or "").name
            scene = scene_from_config(config, scene_file, self.sim_config_path)
        else:
            scene = self.engine.scene
            if scene is None or not any(
                p.startswith(f"/Sim/{scene.name}/") for p in self.projectairsim_client.topics
            ):
                raise WrapperError("update_topics: pass the World the mission script loaded")
        self.engine.adopt(scene, world)

    def shutdown(self) -> None:
        if self._closed:
            return
        self._closed = True
        self.ros_node.stop()
        self.diagnostics.stop()
        # Within the engine's shutdown budget whatever the simulator does: an owned client's subscriptions
        # are unsubscribed with the engine's own in one bounded request, then its sockets are closed (the
        # client's disconnect() would wait up to 300 s for a frozen simulator's reply).
        self.engine.shutdown(self.shutdown_timeout, client_topics=self._owns_client)
        if self._owns_client:
            close_client(self.engine.client)
        self.ros_node.close()
