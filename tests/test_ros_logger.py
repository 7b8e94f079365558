"""The bridge's /rosout records name their caller, though rospy makes every later logger its own class."""

from __future__ import annotations

import inspect
import logging

from airsim_mapper.common.logs import ros_logger


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


def test_a_process_waits_for_rosout_once_so_the_node_s_own_wrapper_does_not_wait_again(monkeypatch):
    """The node waits before it makes its wrapper, which would wait again (up to 2 s when rosout never
    connects) without the once-per-process rule."""
    import threading
    import time

    import rosgraph
    from rospy.impl import rosout

    from airsim_mapper.common import logs

    class Unconnected:
        def get_num_connections(self) -> int:
            return 0

    class Master:
        calls = 0

        def __init__(self, _caller: str) -> None:
            pass

        def getSystemState(self):
            Master.calls += 1
            return [], [["/rosout", ["/rosout"]]], []

    monkeypatch.setattr(rosout, "_rosout_pub", Unconnected())
    monkeypatch.setattr(rosgraph, "Master", Master)
    monkeypatch.setattr(logs, "_ROSOUT_WAITED", threading.Event(), raising=False)
    assert logs.wait_for_rosout(timeout=0.2) is False  # waited the whole timeout: rosout never came
    start = time.monotonic()
    assert logs.wait_for_rosout(timeout=5.0) is False
    assert time.monotonic() - start < 0.1 and Master.calls == 1
