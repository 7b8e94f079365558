"""/diagnostics: one DiagnosticStatus per bridge (rate, drops, stamp age, errors) and one for the simulator
connection, published once a second. Names are the bridges' names, the same ones validate-mapping prints."""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from typing import Any

from airsim_mapper.common.logs import ros_logger
from airsim_mapper.convert import catalog
from airsim_mapper.engine.bridges import Bridge, SimToRos

log = ros_logger("airsim_mapper.diagnostics")
OK, WARN, ERROR = 0, 1, 2
STALE_AFTER_S = 3.0


@dataclass
class _Seen:
    messages: int = 0
    errors: int = 0
    time: float = 0.0


def bridge_status(bridge: Bridge, seen: _Seen, now: float, drops: int, prefix: str) -> dict[str, Any]:
    """A plain-value status of one bridge since the last report (pure, for testing)."""
    stats = bridge.stats
    dt = max(now - seen.time, 1e-6) if seen.time else 0.0
    rate = (stats.messages - seen.messages) / dt if dt else 0.0
    new_errors = stats.errors - seen.errors
    attached = getattr(bridge, "_attached", None)
    age = now - stats.last_time if stats.last_time else None
    info = catalog.find(bridge.spec.converter)
    if new_errors:
        level, message = ERROR, f"{new_errors} errors: {stats.last_error}"
    elif attached and info is not None and info.events:  # quiet until something happens
        level, message = OK, "no event yet" if age is None else f"last event {age:.1f} s ago"
    elif attached and (age is None or age > STALE_AFTER_S):
        level, message = WARN, "no data from the simulator" if age is None else f"stale for {age:.1f} s"
    elif attached is False and isinstance(bridge, SimToRos):
        level, message = OK, "idle (no subscribers)"
    else:
        level, message = OK, "ok"
    spec = bridge.spec
    values = {
        "direction": spec.direction,
        "sim": spec.sim or "",
        "ros": spec.ros or "",
        "rate_hz": f"{rate:.2f}",
        "messages": str(stats.messages),
        "errors": str(stats.errors),
        "drops": str(drops),
        "stale_dropped": str(stats.stale_dropped),  # the simulator's cached frames at subscription
        "clamped": str(stats.clamped),  # commands changed to keep them within their limits
        "last_message_age_s": "" if age is None else f"{age:.3f}",
    }
    return {"name": f"{prefix}{spec.name}", "level": level, "message": message, "values": values}


def mapping_status(report: dict[str, Any], prefix: str) -> dict[str, Any]:
    """The mapping's status: ERROR with the located errors while the last reload stands rejected, and with
    the bridges it could not start while the last one stands applied with some of them refused."""
    rejected = report["state"] == "rejected"
    errors = report.get("errors") or []
    message = report["state"]
    if errors:
        message = f"edit rejected, bridges unchanged: {errors[0]}" if rejected else f"applied; {errors[0]}"
    values = {
        "file": report["file"],
        "state": report["state"],
        "reloads": str(report["reloads"]),
        "rejections": str(report["rejections"]),
        "last_change": report.get("last_change", ""),
        **{f"error_{index + 1}": line for index, line in enumerate(errors)},
    }
    return {
        "name": f"{prefix}mapping",
        "level": ERROR if errors or rejected else OK,
        "message": message,
        "values": values,
    }


def refused_status(name: str, why: str, prefix: str) -> dict[str, Any]:
    """A bridge that could not start (ROS refused it): ERROR, with the reason."""
    return {"name": f"{prefix}{name}", "level": ERROR, "message": f"could not start: {why}", "values": {}}


class Diagnostics:
    """Publishes the engine's bridge statistics on /diagnostics from `start` until stopped, through the
    engine's ROS link (either flavour)."""

    def __init__(self, engine: Any, node_name: str, period_s: float = 1.0) -> None:
        self.engine = engine
        self.prefix = f"{node_name.strip('/')}: "
        self.period_s = period_s
        self.publisher = engine.ros.publisher("/diagnostics", "diagnostic_msgs/DiagnosticArray", queue_size=1)
        self._seen: dict[str, _Seen] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="diagnostics", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def statuses(self, now: float) -> list[dict[str, Any]]:
        streams = self.engine.hub.streams()
        out = [self.connection_status(now)]
        report = getattr(self.engine, "mapping_report", None)
        if report:
            out.append(mapping_status(report, self.prefix))
        bridges = list(self.engine.bridges.items())
        for name, bridge in bridges:
            topic = getattr(bridge, "topic", None)
            drops = streams[topic].stats.dropped if topic in streams else 0
            seen = self._seen.get(name, _Seen())
            out.append(bridge_status(bridge, seen, now, drops, self.prefix))
        self._note(bridges, now)
        refused = getattr(self.engine, "refused_bridges", dict)()
        out += [refused_status(name, why, self.prefix) for name, why in refused.items()]
        return out

    def _note(self, bridges: list[tuple[str, Bridge]], now: float) -> None:
        """Each bridge's counts now: the next report's rates start here."""
        self._seen = {name: _Seen(b.stats.messages, b.stats.errors, now) for name, b in bridges}

    def connection_status(self, now: float | None = None) -> dict[str, Any]:
        """The simulator entry: ERROR while not connected; WARN while connected with a reason (topic frames
        arrive, requests go unanswered) and for a while after sim time went back."""
        now = time.monotonic() if now is None else now
        state = getattr(self.engine, "state", "connected")
        reason = getattr(self.engine, "reason", "")
        scene = self.engine.scene
        counts = getattr(self.engine, "frame_counts", None)
        sim_time = getattr(self.engine, "sim_time", None)
        jumped = sim_time.recent(now) if sim_time is not None else ""
        level, message = OK, state if not reason else f"{state}: {reason}"
        if state != "connected":
            level = ERROR
        elif reason or jumped:
            level = WARN
            if jumped:
                message = f"{message}; {jumped}"
        return {
            "name": f"{self.prefix}simulator",
            "level": level,
            "message": message,
            "values": {
                "state": state,
                "scene": scene.name if scene else "",
                "scene_file": scene.file if scene else "",
                "bridges": str(len(self.engine.bridges)),
                **{
                    key: str(getattr(counts, attr, 0))
                    for key, attr in (("bad_frames", "bad"), ("oversized_frames", "oversized"))
                },
                "sim_time_jumps_back": str(getattr(sim_time, "jumps_back", 0)),
            },
        }

    def publish(self) -> None:
        """One report; while nobody subscribes, only the counts its rates start from (rospy would drop
        the message, and with thousands of bridges building it took a tenth of a core)."""
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

        if self.publisher.get_num_connections() == 0:
            self._note(list(self.engine.bridges.items()), time.monotonic())
            return
        array = DiagnosticArray()
        array.header.stamp = self.engine.ros.now()
        for status in self.statuses(time.monotonic()):
            array.status.append(
                DiagnosticStatus(
                    level=status["level"],
                    name=status["name"],
                    message=status["message"],
                    hardware_id="projectairsim",
                    values=[KeyValue(key=k, value=v) for k, v in status["values"].items()],
                )
            )
        self.publisher.publish(array)

    def _run(self) -> None:
        while not self._stop.wait(self.period_s):
            try:
                self.publish()
            except Exception as exc:  # never take the node down for a report
                log.warning("diagnostics: %s", exc)

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2)
        self.publisher.unregister()
