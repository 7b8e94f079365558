"""Which scene configs a test runs on: the project's own `sim_config/` always, and Project AirSim's example
configs (`../shared/sim_config`, beside the clone in CI) in addition where they exist.

A test that needs the examples takes the `example_config` fixture, is parametrized with `scenes_of(...)` or
`both_configs()` and the indirect `sim_config` fixture, or has a fixture parametrized with `both_configs()`
that calls `config_dir` (fixtures in tests/conftest.py). Where the examples are absent, all such tests are
skipped through `require_example_config`, and `fold_example_skips` gives their skips one location, so
pytest's summary (`-ra`) shows one line: how many did not run, and why.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import commentjson
import pytest
from harness import EXAMPLE_CONFIG, SIM_CONFIG

PROJECT = "project"
EXAMPLES = "examples"
# the example scenes the compatibility tests cover (a test checks this is all of them)
EXAMPLE_SCENES = (
    "scene_basic_drone.jsonc",
    "scene_drone_sensors.jsonc",
    "scene_lidar_drone.jsonc",
    "scene_radar_tower.jsonc",
    "scene_two_drones_sensors.jsonc",
)
EXAMPLES_ABSENT = (
    "../shared/sim_config not present: compatibility with the Project AirSim example configs not checked"
)


def require_example_config() -> Path:
    """The example config directory; skips the calling test where it is absent."""
    if not EXAMPLE_CONFIG.is_dir():
        pytest.skip(EXAMPLES_ABSENT)
    return EXAMPLE_CONFIG


def config_dir(source: str) -> Path:
    """The directory of a config source, `PROJECT` or `EXAMPLES` (skipping the test where absent)."""
    if source == EXAMPLES:
        return require_example_config()
    if source != PROJECT:
        raise ValueError(f"unknown config source {source!r}")
    return SIM_CONFIG


def scenes_of(project: Iterable[str], examples: Iterable[str] = ()) -> list:
    """`(sim_config, scene_file)` parameters for the project's scenes and then the examples', with ids
    such as `project/scene_basic_drone.jsonc`; use with `indirect=["sim_config"]`."""
    return [
        pytest.param(source, scene, id=f"{source}/{scene}")
        for source, scenes in ((PROJECT, project), (EXAMPLES, examples))
        for scene in sorted(scenes)
    ]


def both_configs() -> list:
    """`sim_config` parameters for a test that runs on the project's configs and on the examples; use with
    `indirect=True`."""
    return [pytest.param(PROJECT, id=PROJECT), pytest.param(EXAMPLES, id=EXAMPLES)]


def robot_sensors(source: str, files: Mapping[str, str]) -> list[dict[str, Any]]:
    """The sensor list of the robot config `files[source]` in that source's directory, parsed as the client
    parses it (commentjson); skips the test where the source is absent."""
    return commentjson.loads((config_dir(source) / files[source]).read_text())["sensors"]


def fold_example_skips(report: pytest.TestReport) -> None:
    """Report a skip for want of the examples at this module rather than at each test (pytest gives a skip
    raised in a fixture the test's location), so that the summary folds them all into one line."""
    longrepr = report.longrepr
    if report.skipped and isinstance(longrepr, tuple) and longrepr[2].endswith(EXAMPLES_ABSENT):
        report.longrepr = (__file__, None, longrepr[2])
