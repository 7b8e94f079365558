"""The bridge's /rosout records name their caller, though rospy makes every later logger its own class."""

from __future__ import annotations

import inspect
import logging

from airsim_mapper.logs import ros_logger


def test_a_record_names_the_calling_file_function_and_line_where_rospy_set_the_logger_class(caplog):
    import rosgraph.roslogging  # what `import rospy` does: every logger made from now on is a RospyLogger

    assert type(logging.getLogger("rosout.airsim_mapper.test_plain")) is rosgraph.roslogging.RospyLogger
    logger = ros_logger("airsim_mapper.test_caller")

    def emitter() -> int:
        logger.warning("hello")
        return inspect.currentframe().f_lineno - 1

    with caplog.at_level(logging.INFO, logger=logger.name):
        line = emitter()
    (record,) = caplog.records
    assert (record.filename, record.funcName, record.lineno) == ("test_ros_logger.py", "emitter", line)
