"""redirect_client_log: the client's records reach rosout.projectairsim only as far as its level allows."""

from __future__ import annotations

import logging

import pytest


@pytest.fixture
def captured():
    from projectairsim.utils import projectairsim_log

    from airsim_mapper.wrapper import redirect_client_log

    redirect_client_log()
    target = logging.getLogger("rosout.projectairsim")
    records: list[logging.LogRecord] = []
    handler = logging.Handler()
    handler.emit = records.append
    saved = target.level
    target.addHandler(handler)
    yield projectairsim_log(), target, records
    target.removeHandler(handler)
    target.setLevel(saved)


def test_the_client_logger_honours_the_rosout_logger_level(captured) -> None:
    client_log, target, records = captured
    client_log.setLevel(logging.DEBUG)
    target.setLevel(logging.ERROR)
    client_log.warning("a warning")
    client_log.error("an error")
    assert [r.getMessage() for r in records] == ["an error"]
    target.setLevel(logging.INFO)
    client_log.info("now info")
    assert [r.getMessage() for r in records][-1] == "now info"
