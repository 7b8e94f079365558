"""The rclpy node a bridge runs in: its log handler and its executor thread (the node's and the wrapper's).

`RclpyHandler` hands Python log records to the node's rclpy logger, which prints them and sends them on
/rosout with ROS 2's severities. `Spinner` runs a MultiThreadedExecutor for the node on a thread of its own,
so a mission script's main thread stays its own.
"""

from __future__ import annotations

import logging
import threading
from typing import Any

__all__ = ["ROSOUT_LOGGER", "RclpyHandler", "Spinner", "spin"]

ROSOUT_LOGGER = "rosout"  # the parent of the bridge's loggers (`ros_logger`), the client's forwarded log too
SPIN_S = 0.5  # the executor's wait, between checks that rclpy still runs
EXECUTOR_THREADS = 4


class RclpyHandler(logging.Handler):
    """Hands log records to an rclpy logger: console and /rosout, DEBUG/INFO/WARN/ERROR/FATAL."""

    def __init__(self, logger: Any) -> None:
        super().__init__()
        self._logger = logger

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


def spin(executor: Any, context: Any) -> None:
    """Run the executor until rclpy shuts down. A bridge stopped on a scene change destroys its endpoints
    while the executor may be waiting on them; rclpy then raises InvalidHandle from the wait, and the
    executor carries on with the endpoints that are left."""
    from rclpy.exceptions import InvalidHandle
    from rclpy.executors import ExternalShutdownException, ShutdownException

    while context.ok():
        try:
            executor.spin_once(timeout_sec=SPIN_S)
        except InvalidHandle:
            continue
        except (ExternalShutdownException, ShutdownException):
            return


class Spinner:
    """A node's executor on a thread of its own, and its log records (`rosout.*`) on the node's logger,
    from `start` until `stop`."""

    def __init__(self, node: Any, level: int = logging.INFO) -> None:
        from rclpy.executors import MultiThreadedExecutor

        self.node = node
        self.handler = RclpyHandler(node.get_logger())
        self._level = level
        self.executor = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS, context=node.context)
        self.executor.add_node(node)
        self._thread = threading.Thread(
            target=spin, args=(self.executor, node.context), name="rclpy-executor", daemon=True
        )

    def start(self) -> None:
        rosout = logging.getLogger(ROSOUT_LOGGER)
        rosout.addHandler(self.handler)
        rosout.setLevel(self._level)
        self._thread.start()

    def stop(self, timeout: float = 1.0, keep_log: bool = False) -> None:
        """Stop the executor (the node stays: its owner destroys it) and, unless `keep_log`, take the log
        handler back."""
        if not keep_log:
            logging.getLogger(ROSOUT_LOGGER).removeHandler(self.handler)
        self.executor.shutdown(timeout_sec=timeout)
