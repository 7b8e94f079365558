"""Live reload's controller without ROS: a fake engine records what is applied; the watcher polls files."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest
from harness import wait_until

from airsim_mapper.engine.diagnostics import ERROR, OK, mapping_status
from airsim_mapper.engine.mapping_reload import MappingReloader, stamp
from airsim_mapper.mapping.diff import BridgeDiff
from airsim_mapper.mapping.errors import MappingError
from airsim_mapper.mapping.loader import load_mapping

GOOD = "version: 1\nextends: {base}\nrules:\n  - {{name: imu, rate_limit_hz: {rate}}}\n"


class FakeEngine:
    def __init__(self, fail: Exception | None = None) -> None:
        self.applied: list = []
        self.fail = fail
        self.mapping_report: dict = {}
        self.published = 0

    def apply_mapping(self, mapping):
        if self.fail:
            raise self.fail
        self.applied.append(mapping)
        return BridgeDiff((), (), ("imu[R/I]",), ("pose[R]",))

    def report_mapping(self, report: dict) -> None:
        self.mapping_report = report

    def publish_status(self) -> None:
        self.published += 1


@pytest.fixture
def files(tmp_path: Path):
    base = tmp_path / "base.yaml"
    base.write_text((Path(load_mapping("default").source)).read_text())
    child = tmp_path / "child.yaml"
    child.write_text(GOOD.format(base="./base.yaml", rate=5.0))
    return base, child


def test_a_valid_edit_is_applied_and_reported(files):
    _, child = files
    engine = FakeEngine()
    reloader = MappingReloader(engine, str(child), load_mapping(child))
    assert engine.mapping_report["state"] == "loaded"
    child.write_text(GOOD.format(base="./base.yaml", rate=7.0))
    outcome = reloader.reload()
    assert outcome.applied and outcome.message == "applied: 0 added, 0 removed, 1 changed, 1 unchanged"
    imu = next(rule for rule in engine.applied[0].rules if rule.name == "imu")
    assert imu.options.rate_limit_hz == 7.0
    assert engine.mapping_report | {"file": ""} == {
        "file": "",
        "state": "applied",
        "reloads": 1,
        "rejections": 0,
        "errors": [],
        "last_change": "0 added, 0 removed, 1 changed, 1 unchanged",
    }
    assert engine.published == 1


def test_an_invalid_edit_is_rejected_with_its_located_errors_and_nothing_is_applied(files):
    _, child = files
    engine = FakeEngine()
    reloader = MappingReloader(engine, str(child), load_mapping(child))
    child.write_text("version: 1\nextends: ./base.yaml\nrules:\n  - {name: imu, converter: imuu}\n")
    outcome = reloader.reload()
    expected = f"{child}:4:28: rule 'imu': unknown converter 'imuu' (did you mean 'imu'?)"
    assert not outcome.applied and outcome.errors == (expected,)
    assert engine.applied == []
    report = engine.mapping_report
    assert (report["state"], report["rejections"], report["errors"]) == ("rejected", 1, [expected])
    status = mapping_status(report, "bridge: ")
    assert (status["name"], status["level"]) == ("bridge: mapping", ERROR)
    assert status["message"] == f"edit rejected, bridges unchanged: {expected}"
    assert status["values"]["error_1"] == expected


def test_a_mapping_that_does_not_expand_over_the_scene_is_rejected_too(files):
    _, child = files
    engine = FakeEngine(fail=MappingError.single(str(child), "bridge x: ROS name collides", 3, 1))
    outcome = MappingReloader(engine, str(child), load_mapping(child)).reload()
    assert not outcome.applied and outcome.errors == (f"{child}:3:1: bridge x: ROS name collides",)
    assert mapping_status(engine.mapping_report, "")["level"] == ERROR


def test_a_deleted_file_is_rejected_and_a_good_report_is_ok(files):
    _, child = files
    engine = FakeEngine()
    reloader = MappingReloader(engine, str(child), load_mapping(child))
    assert mapping_status(engine.mapping_report, "")["level"] == OK
    child.unlink()
    outcome = reloader.reload()
    assert not outcome.applied and "cannot read the mapping file" in outcome.errors[0]


def test_the_watcher_reloads_on_a_change_of_the_file_or_of_its_base(files):
    base, child = files
    engine = FakeEngine()
    reloader = MappingReloader(engine, str(child), load_mapping(child), period_s=0.05)
    assert reloader.files == (str(child), str(base))
    assert not reloader.changed()
    reloader.start()
    try:
        child.write_text(GOOD.format(base="./base.yaml", rate=9.0))
        wait_until(lambda: len(engine.applied) == 1, 5, what="a reload after the edit")
        base.write_text(base.read_text() + "\n# edited\n")
        wait_until(lambda: len(engine.applied) == 2, 5, what="a reload after the base's edit")
        time.sleep(0.3)
        assert len(engine.applied) == 2  # one reload a change
    finally:
        reloader.stop()


def test_stamp_changes_with_content_and_is_none_for_a_missing_file(tmp_path):
    path = tmp_path / "m.yaml"
    assert stamp(str(path)) is None
    path.write_text("a")
    first = stamp(str(path))
    path.write_text("ab")
    os.utime(path, ns=(1, 1))
    assert stamp(str(path)) != first


def test_the_node_watches_unless_told_not_to():
    from airsim_mapper.cli.node import parse_args

    assert parse_args([]).no_watch is False
    assert parse_args(["--no-watch"]).no_watch is True
