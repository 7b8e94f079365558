"""The rclpy node a bridge runs in: its log handler and its executor thread (the node's and the wrapper's).

`log_to` hands the bridge's Python log records (`rosout.*`, the client's forwarded ones among them) to a
node's rclpy logger, which prints them and sends them on /rosout with ROS 2's severities. `Spinner` runs a
MultiThreadedExecutor for the node on a thread of its own, so a mission script's main thread stays its own.
"""

from __future__ import annotations

import logging
import threading
from typing import Any

from airsim_mapper.common.logs import ros_logger

__all__ = ["ROSOUT_LOGGER", "RclpyHandler", "Spinner", "log_to", "spin"]

ROSOUT_LOGGER = "rosout"  # the parent of the bridge's loggers (`ros_logger`), the client's forwarded log too
# The executor's longest wait. Nothing waits for it to end: stop() wakes the executor, rclpy's shutdown wakes
# it (the executor's on_shutdown), and a node that adds or removes an endpoint wakes it; each wake costs a
# rebuild of the wait set, so a long one spares the idle node's CPU.
SPIN_S = 5.0
EXECUTOR_THREADS = 4
log = ros_logger("airsim_mapper.node")


class RclpyHandler(logging.Handler):
    """Hands log records to an rclpy logger: console and /rosout, DEBUG/INFO/WARN/ERROR/FATAL."""

    def __init__(self, logger: Any) -> None:
        super().__init__()
        self._logger = logger
        self.logger_name: str = logger.name

    def emit(self, record: logging.LogRecord) -> None:
        # rclpy ties a severity to each calling line: one call per severity
        try:
            text, level, logger = self.format(record), record.levelno, self._logger
            if level >= logging.CRITICAL:
                logger.fatal(text)
            elif level >= logging.ERROR:
                logger.error(text)
            elif level >= logging.WARNING:
                logger.warning(text)
            elif level >= logging.INFO:
                logger.info(text)
            else:
                logger.debug(text)
        except Exception:  # a log record must never break the code that logged it
            self.handleError(record)


def log_to(node: Any, level: int = logging.INFO) -> RclpyHandler:
    """From now on the `rosout.*` records at `level` and above go to `node`'s logger (and to no other
    node's: one handler at a time); the handler, for `logging.getLogger(ROSOUT_LOGGER).removeHandler`."""
    rosout = logging.getLogger(ROSOUT_LOGGER)
    name = node.get_logger().name
    for handler in list(rosout.handlers):
        if isinstance(handler, RclpyHandler):
            if handler.logger_name == name:
                return handler
            rosout.removeHandler(handler)
    handler = RclpyHandler(node.get_logger())
    rosout.addHandler(handler)
    rosout.setLevel(level)
    return handler


def spin(executor: Any, context: Any, stop: threading.Event | None = None) -> None:
    """Run the executor until rclpy shuts down (or `stop` is set). A bridge stopped on a scene change
    destroys its endpoints while the executor may be waiting on them; rclpy then raises InvalidHandle from
    the wait, and the executor carries on with the endpoints that are left. rclpy re-raises a callback's
    exception from a later wait: it is logged and the node keeps serving its other callbacks (uncaught, it
    would end this thread, and with it every subscriber, service and lazy stream of the node)."""
    from rclpy.exceptions import InvalidHandle
    from rclpy.executors import ExternalShutdownException, ShutdownException

    stop = stop or threading.Event()
    while context.ok() and not stop.is_set():
        try:
            executor.spin_once(timeout_sec=SPIN_S)
        except InvalidHandle:
            continue
        except (ExternalShutdownException, ShutdownException):
            return
        except Exception:
            log.exception("a ROS 2 callback failed; the node carries on")


class Spinner:
    """A node's executor on a thread of its own, from `start` until `stop`."""

    def __init__(self, node: Any) -> None:
        from rclpy.executors import MultiThreadedExecutor

        self.node = node
        self.executor = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS, context=node.context)
        self.executor.add_node(node)
        self._stop = threading.Event()
        self._thread = threading.Thread(
            target=spin, args=(self.executor, node.context, self._stop), name="rclpy-executor", daemon=True
        )

    def start(self) -> None:
        self._thread.start()

    def stop(self, timeout: float = 1.0) -> None:
        """Stop the executor; the node stays (its owner destroys it)."""
        self._stop.set()  # the spin loop ends first: a shut-down executor refuses the callbacks it finds
        self.executor.wake()  # its wait ends now, not after SPIN_S
        if self._thread.is_alive():
            self._thread.join(timeout=timeout)
        self.executor.shutdown(timeout_sec=timeout)
