"""The ROS -> simulator runners: `RosToSim` (a ROS topic to a simulator topic, a simulator call with the
command watchdog, or an engine action) and `RosService` (a ROS service answered from a simulator call, on
one robot or on every robot of the scene). Their base and the simulator -> ROS runners are in bridges.py;
runners.py picks one for a spec."""

from __future__ import annotations

import time
from typing import Any

from airsim_mapper.common.logs import ros_logger
from airsim_mapper.convert import catalog, registry
from airsim_mapper.convert.command import require_finite
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.engine.bridges import Bridge, BridgeParts, _accepted, rule_qos
from airsim_mapper.engine.replays import LatchedReplays, connection_header
from airsim_mapper.engine.sim_link import SimLinkError
from airsim_mapper.engine.tf_poses import FrameUnknown
from airsim_mapper.mapping.model import BridgeSpec

__all__ = ["RosService", "RosToSim"]

log = ros_logger("airsim_mapper.bridge")
# A service call waits for the simulator's reply this long past the call's own `timeout_sec` (by then the
# simulator has answered, success or not); a call without one waits SIM_REPLY_S.
REPLY_MARGIN_S = 5.0
SIM_REPLY_S = 30.0


class RosToSim(Bridge):
    """ROS subscriber -> converter -> sim topic publish, sim service call, or an engine action."""

    def __init__(self, spec: BridgeSpec, parts: BridgeParts) -> None:
        super().__init__(spec, parts)
        self.convert = registry.get(spec.converter)
        self.subscriber: Any = None
        self.last_message = 0.0
        self.moving = False  # a command was sent since the last watchdog stop
        # An engine action (load_scene) acts once per message: a latched message replayed on a new
        # connection is ignored.
        self.replays = None
        if self.info.runner == catalog.ACTION:
            self.replays = parts.replays.setdefault(spec.ros, LatchedReplays())

    def start(self) -> None:
        self.subscriber = self.parts.ros.subscriber(
            self.spec.ros,
            self.spec.ros_type,
            self.on_message,
            queue_size=self.spec.options.queue_size,
            **rule_qos(self.spec),
        )

    def on_message(self, ros_msg: Any) -> None:
        if self.replays is not None and self.replays.is_replay(connection_header(ros_msg), _payload(ros_msg)):
            log.info(
                "%s: ignored the latched message %s replayed it on a new connection",
                self.spec.name,
                connection_header(ros_msg).get("callerid", "a publisher"),
            )
            return
        try:
            ros_msg = self._in_target_frame(ros_msg)
        except FrameUnknown as exc:
            self.fail(f"refused a message on {self.spec.ros}, nothing sent: {exc}")
            return
        try:
            params = self.convert(ros_msg, self.ctx)
            require_finite(params)
        except ConversionError as exc:
            self.fail(f"rejected a message on {self.spec.ros}: {exc}")
            return
        except Exception as exc:  # the node never dies from one bad message
            self.failed(f"converting a message on {self.spec.ros} failed", exc)
            return
        spec, runner = self.spec, self.info.runner
        self.last_message = time.monotonic()
        try:
            if runner == catalog.SEND:
                self.parts.sim.publish(spec.sim, params)
                self.stats.messages += 1
            elif runner == catalog.CALL:
                self.moving = spec.options.watchdog_s is not None
                future = self.parts.sim.call_async(spec.sim, params)
                future.add_done_callback(lambda f, p=params: self._on_reply(f, p))
            else:
                self.parts.node_action(self.info.action, params)
                self.stats.messages += 1
        except Exception as exc:  # the node never dies from one bad message
            self.fail(f"could not forward a message on {spec.ros}: {exc}")

    def _in_target_frame(self, ros_msg: Any) -> Any:
        """A stamped goal in another tf frame than the rule's target_frame, transformed into it."""
        target = self.spec.params.get("target_frame")
        header = getattr(ros_msg, "header", None)
        if (
            not target
            or header is None
            or header.frame_id.removeprefix("/") in ("", target.removeprefix("/"))
        ):
            return ros_msg  # a leading slash is ignored, as tf2 does
        return self.parts.ros.transform_pose(ros_msg, target)

    def _on_reply(self, future: Any, params: dict) -> None:
        try:
            result = future.result()
        except SimLinkError as exc:
            self.fail(str(exc))
            return
        except Exception as exc:
            self.fail(f"{self.spec.sim}: {exc}")
            return
        self.stats.messages += 1
        self.after_call(params, result)

    def check_watchdog(self, now: float) -> float | None:
        """Stop the robot when commands stopped arriving for `watchdog_s` seconds. The seconds until this
        watchdog can next be due (a command arriving now is due `watchdog_s` from now), or None without
        a watchdog."""
        timeout = self.spec.options.watchdog_s
        if timeout is None:
            return None
        if not self.moving:
            return timeout
        quiet = now - self.last_message
        if quiet < timeout:
            return timeout - quiet
        self.moving = False
        self.stop_robot(f"no command for {timeout:.1f} s")
        return timeout

    def stop_robot(self, why: str) -> None:
        method = self.spec.params.get("stop_method", "Hover")
        robot_path = self.spec.sim.rsplit("/", 1)[0]
        log.info("%s: %s: sending %s", self.spec.name, why, method)
        self.parts.sim.call_async(f"{robot_path}/{method}", {})

    def stop(self) -> None:
        # The subscriber's callback is a method of this bridge: dropped, the stopped bridge is freed by
        # reference counting (a cycle would outlive it in the frozen heap, engine/process_tuning.py)
        subscriber, self.subscriber = self.subscriber, None
        if subscriber is not None:
            subscriber.unregister()
        if self.moving:
            self.moving = False
            try:
                self.stop_robot("bridge stopping")
            except Exception as exc:
                log.warning("%s: could not stop the robot: %s", self.spec.name, exc)


class RosService(Bridge):
    """A ROS service (std_srvs) whose requests become sim service calls."""

    def __init__(self, spec: BridgeSpec, parts: BridgeParts) -> None:
        super().__init__(spec, parts)
        self.convert = registry.get(spec.converter)
        self.service: Any = None

    def start(self) -> None:
        self.service, self._response = self.parts.ros.service(
            self.spec.ros, self.spec.ros_type, self.on_request, **rule_qos(self.spec)
        )

    def on_request(self, request: Any) -> Any:
        response = self._response()
        try:
            params = self.convert(request, self.ctx)
            require_finite(params)
            if self.info.runner == catalog.SERVE_ALL:
                return self._on_all_robots(response, params)
            started = time.monotonic()
            result = self.parts.sim.call(self.spec.sim, params, timeout=reply_timeout(params, SIM_REPLY_S))
        except (ConversionError, SimLinkError) as exc:
            self.fail(str(exc))
            return _fill(response, False, str(exc))
        except Exception as exc:  # answered as a failure, not as a broken service
            self.failed(f"{self.spec.ros}: the request failed", exc)
            return _fill(response, False, f"{type(exc).__name__}: {exc}")
        self.stats.messages += 1
        self.after_call(params, result)
        if result is None or isinstance(result, bool):
            said = "" if result else refused(self.spec.sim, params, result, time.monotonic() - started)
            return _fill(response, _accepted(result), said)
        return _fill(response, _accepted(result), str(result))

    def _on_all_robots(self, response: Any, params: dict) -> Any:
        """Call `<sim>/<robot>/<params.method>` on every robot of the scene at once; succeed if all do."""
        method = self.spec.params["method"]
        robots = list(self.spec.source.get("robots", []))
        sim = self.parts.sim
        calls = {robot: sim.call_async(f"{self.spec.sim}/{robot}/{method}", params) for robot in robots}
        wait = reply_timeout(params, float(self.spec.params.get("timeout_s", 60.0)))
        failed = []
        for robot, future in calls.items():
            try:
                if future.result(timeout=wait) in (False, None):
                    failed.append(f"{robot}: false")
            except Exception as exc:
                failed.append(f"{robot}: {exc}")
        self.stats.messages += 1
        if failed:
            self.fail(f"{method} failed for " + "; ".join(failed))
        message = "; ".join(failed) or f"{method}: {len(robots)} robots"
        return _fill(response, not failed and bool(robots), message)

    def stop(self) -> None:
        # rospy's service keeps its handler, a method of this bridge, after shutdown: dropped, as above
        service, self.service = self.service, None
        if service is not None:
            service.shutdown()


def _payload(ros_msg: Any) -> Any:
    """A hashable value of a message's fields (for telling a replay from a new message)."""
    try:
        return tuple(repr(getattr(ros_msg, slot)) for slot in ros_msg.__slots__)
    except AttributeError:
        return repr(ros_msg)


def _fill(response: Any, success: bool, message: str) -> Any:
    if hasattr(response, "success"):
        response.success = success
    if hasattr(response, "message"):
        response.message = message
    return response


def refused(sim: str, params: dict, result: bool | None = False, took_s: float = 0.0) -> str:
    """The answer to a call the simulator answered with false (or nothing) and no reason: which method,
    and its own time limit when the call ran that long (a land from high up takes longer than its 60 s and
    stops where it got)."""
    text = f"{sim.rsplit('/', 1)[-1]} returned {'nothing' if result is None else 'false'}"
    limit = params.get("timeout_sec")
    if isinstance(limit, (int, float)) and not isinstance(limit, bool) and 0 < limit <= took_s:
        text += f" after its timeout_sec, {limit:g} s (the robot stays where it got to)"
    return text


def reply_timeout(params: dict, default: float) -> float:
    """How long a service call waits for the simulator: the call's own `timeout_sec` (the simulator gives
    up then and replies false) plus REPLY_MARGIN_S, so a land or move is never cut short on the bridge's
    side while the robot still moves; `default` for a call without one."""
    try:
        limit = float(params.get("timeout_sec"))
    except (TypeError, ValueError):
        return default
    return limit + REPLY_MARGIN_S if 0 < limit < float("inf") else default
