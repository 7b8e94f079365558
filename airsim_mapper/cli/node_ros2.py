"""projectairsim_node on ROS 2: the same switches and mapping as on ROS1, over one rclpy node.

Each setting that is a private parameter on ROS1 is a ROS 2 parameter of the node (`--ros-args -p
scene:=...`); the command line wins. `--ros-args -r __ns:=/sim1` and `__node:=` name the node; the
mapping's names resolve below its namespace. The node's log records and the client's go to rclpy's
logger (the console and /rosout). `-p use_sim_time:=true` puts the node's clock, and so every stamp it
takes from it, on /clock. SIGINT or SIGTERM stops the node within --shutdown-timeout seconds.
"""

from __future__ import annotations

import logging
import signal
import sys
import time
from collections.abc import Callable
from functools import partial
from typing import Any

from airsim_mapper.cli.settings import SETTINGS, SettingError, given_settings, resolve_settings, values
from airsim_mapper.cli.startup import Stopper, connect
from airsim_mapper.common.dds_profile import use_shipped_profile
from airsim_mapper.common.errors import ConfigError
from airsim_mapper.common.logs import ros_logger

log = ros_logger("airsim_mapper.node")
DEFAULT_NODE_NAME = "projectairsim"
STOP_CHECK_S = 1.0


def overridden(node: Any) -> dict[str, Any]:
    """The ROS 2 parameters given on the command line (`-p name:=value`), by setting name."""
    return {
        s.name: node.get_parameter(s.name).value
        for s in SETTINGS
        if node.has_parameter(s.name) and node.get_parameter(s.name).value not in (None, "")
    }


def main(argv: list[str], stop: Stopper, parse_args: Callable[[list[str]], Any], config_problem: Any) -> int:
    """The node on ROS 2 (`stop` is the node's signal handler, already installed; `parse_args` and
    `config_problem` are the ROS1 node's, shared)."""
    import rclpy
    from rclpy.signals import SignalHandlerOptions
    from rclpy.utilities import remove_ros_args

    from airsim_mapper.engine import Diagnostics, close_client
    from airsim_mapper.engine.ros2_node import ROSOUT_LOGGER, Spinner, log_to
    from airsim_mapper.mapping.names import resolve_namespace
    from airsim_mapper.wrapper import redirect_client_log

    args = parse_args(remove_ros_args(argv)[1:])
    stop.timeout = args.shutdown_timeout
    profile = use_shipped_profile()  # before rclpy makes its participant
    rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node(
        args.nodename or DEFAULT_NODE_NAME, automatically_declare_parameters_from_overrides=True
    )
    handler = log_to(node)
    log.info(profile)
    redirect_client_log()
    spinner = Spinner(node)
    spinner.start()
    stop.at_once = False
    engine = diagnostics = reloader = None
    try:
        given = given_settings(args)
        from_parameters = overridden(node)
        try:
            resolved = resolve_settings(given, lambda name: _lookup(from_parameters, name))
        except SettingError as exc:
            print(str(exc), file=sys.stderr)
            return 1
        for name, setting in resolved.items():
            log.info("setting %s = %r (%s)", name, setting.value, setting.source)
        settings = values(resolved)
        ros_name = node.get_fully_qualified_name()
        namespace = resolve_namespace(settings["namespace"], node.get_namespace())
        prepared, problem = config_problem(
            settings, node.get_name(), namespace, None, node.get_namespace(), ros=2
        )
        if problem:
            print(problem, file=sys.stderr)
            return 1
        engine, failure = start_engine(node, args, settings, prepared, ros_name, lambda: bool(stop))
        if failure:
            print(failure, file=sys.stderr)
            return 1
        if engine is not None:
            diagnostics = Diagnostics(engine, ros_name)
            diagnostics.start()
            reloader = serve_reload(engine, settings["mapping"], prepared.mapping, watch=not args.no_watch)
        while not stop:
            stop.wait(STOP_CHECK_S)
        log.info("stopping (%s)", signal.Signals(stop.signals[0]).name)
        return 0
    finally:
        if reloader is not None:
            reloader.stop()
        if diagnostics is not None:
            diagnostics.stop()
        if engine is not None:
            engine.shutdown(max(0.5, args.shutdown_timeout - 1.5), client_topics=True)
            close_client(engine.client)
        logging.getLogger(ROSOUT_LOGGER).removeHandler(handler)
        spinner.stop()
        node.destroy_node()
        rclpy.try_shutdown()


def serve_reload(engine: Any, spec: str, mapping: Any, watch: bool) -> Any:
    """Live reload: the `~/reload_mapping` service (std_srvs/Trigger) and, with `watch`, the file watcher."""
    from airsim_mapper.engine import MappingReloader

    reloader = MappingReloader(engine, spec, mapping)

    def on_request(_request: Any) -> Any:
        outcome = reloader.reload("~reload_mapping")
        return response(success=outcome.ok, message=outcome.message)

    _service, response = engine.ros.service("~/reload_mapping", "std_srvs/Trigger", on_request)
    if watch:
        reloader.start()
        log.info("watching %s for changes (--no-watch turns this off)", ", ".join(reloader.files))
    return reloader


def _lookup(given: dict[str, Any], name: str) -> Any:
    key = name.removeprefix("~")
    if key not in given:
        raise KeyError(name)
    return given[key]


def start_engine(
    node: Any, args: Any, settings: dict[str, Any], prepared: Any, ros_name: str, stopping: Any
) -> tuple[Any, str]:
    """Connect, make the engine on a ROS 2 link, start its node bridges and load the start scene; (engine,
    what went wrong or "")."""
    from airsim_mapper.common.tuning import keep_frame_buffers
    from airsim_mapper.engine import (
        Engine,
        FrameCounts,
        NodeNames,
        SimAccess,
        SimSilent,
        WaitingStatus,
        open_client,
    )
    from airsim_mapper.engine.ros2_link import Ros2Link

    keep_frame_buffers()
    address, topicsport, servicesport = (settings[k] for k in ("address", "topicsport", "servicesport"))
    ros = Ros2Link(node)
    waiting = WaitingStatus(ros_name, ros.publisher)
    try:
        client = connect(address, topicsport, servicesport, stopping, on_wait=waiting.publish)
    except SimSilent as exc:
        return None, str(exc)
    finally:
        waiting.close()
    if client is None:
        return None, ""
    engine = Engine(
        client,
        prepared.mapping,
        NodeNames(prepared.node_name, prepared.namespace, ros_name),
        SimAccess(
            settings["simconfigpath"], client_factory=partial(open_client, address, topicsport, servicesport)
        ),
        ros=ros,
        frame_counts=FrameCounts(max_frame_bytes=int(args.max_frame_mb * 1024 * 1024)),
        tune=True,
    )
    engine.start()
    engine.start_node_bridges()
    if prepared.scene is not None:
        started = time.monotonic()
        try:
            engine.load_scene(prepared.scene, prepared.specs)
        except ConfigError as exc:
            return engine, str(exc)
        except Exception as exc:
            return (
                engine,
                f"{settings['scene']}: the simulator could not load it: {type(exc).__name__}: {exc}",
            )
        log.info("scene %s bridged in %.1f s", settings["scene"], time.monotonic() - started)
    return engine, ""
