"""The bridge's log on an rclpy node's logger (engine/ros2_node.py): each Python level becomes its ROS 2
severity, one node's handler at a time takes the `rosout.*` records, the client's forwarded ones among them.
A recording stand-in plays rclpy's logger (its name and one method per severity)."""

from __future__ import annotations

import logging

import pytest

from airsim_mapper.engine.ros2_node import ROSOUT_LOGGER, RclpyHandler, log_to


class RecordingLogger:
    """rclpy's logger as the handler uses it: a name, and debug/info/warning/error/fatal."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.calls: list[tuple[str, str]] = []

    def __getattr__(self, severity: str):
        if severity not in ("debug", "info", "warning", "error", "fatal"):
            raise AttributeError(severity)
        return lambda text: self.calls.append((severity, text))


class StandInNode:
    def __init__(self, name: str) -> None:
        self.logger = RecordingLogger(name)

    def get_logger(self) -> RecordingLogger:
        return self.logger


@pytest.fixture
def rosout():
    """The `rosout` logger, its handlers and level restored after the test."""
    logger = logging.getLogger(ROSOUT_LOGGER)
    handlers, level = list(logger.handlers), logger.level
    yield logger
    logger.handlers[:] = handlers
    logger.setLevel(level)


@pytest.mark.parametrize(
    ("level", "severity"),
    [
        (logging.DEBUG, "debug"),
        (logging.INFO, "info"),
        (logging.WARNING, "warning"),
        (logging.ERROR, "error"),
        (logging.CRITICAL, "fatal"),
    ],
)
def test_each_python_level_becomes_its_ros2_severity(level: int, severity: str) -> None:
    logger = RecordingLogger("projectairsim")
    handler = RclpyHandler(logger)
    handler.handle(logging.LogRecord("rosout.x", level, __file__, 1, "the %s line", ("one",), None))
    assert logger.calls == [(severity, "the one line")]


def test_a_failing_rclpy_logger_does_not_break_the_code_that_logged(capsys) -> None:
    class Broken(RecordingLogger):
        def __getattr__(self, severity: str):
            raise RuntimeError("rclpy is shut down")

    handler = RclpyHandler(Broken("n"))
    handler.handle(logging.LogRecord("rosout.x", logging.INFO, __file__, 1, "text", (), None))
    assert "rclpy is shut down" in capsys.readouterr().err  # logging's own report, nothing raised


def test_log_to_hands_the_rosout_records_and_the_clients_to_one_node_at_a_time(rosout) -> None:
    first, second = StandInNode("first"), StandInNode("sim1.second")
    handler = log_to(first)
    assert log_to(first) is handler  # once per node
    logging.getLogger("rosout.airsim_mapper.engine").info("bridged")
    logging.getLogger("rosout.airsim_mapper.engine").debug("below the level")
    log_to(second)
    logging.getLogger("rosout.projectairsim").warning("Unable to unsubscribe from all topics.")
    assert first.logger.calls == [("info", "bridged")]
    assert second.logger.calls == [("warning", "Unable to unsubscribe from all topics.")]
    (current,) = [h for h in rosout.handlers if isinstance(h, RclpyHandler)]
    assert current is not handler and current.logger_name == "sim1.second"
