"""The converter catalogue chooses each converter's runner; the engine has one for every choice."""

from __future__ import annotations

import ast
from pathlib import Path

from airsim_mapper.convert import catalog
from airsim_mapper.engine import bridges, runners

ENGINE = Path(bridges.__file__).resolve().parent


def test_every_runner_after_hook_and_action_the_catalogue_names_exists():
    assert set(runners.RUNNERS) == set(catalog.RUNNERS)
    assert set(bridges.AFTER_HOOKS) == set(catalog.AFTER_HOOKS)
    for info in catalog.CONVERTERS.values():
        assert info.runner in catalog.RUNNERS, info.name
        assert info.after is None or info.after in catalog.AFTER_HOOKS, info.name
        assert (info.action is not None) == (info.runner == catalog.ACTION), info.name
        assert info.action is None or info.action in catalog.ACTIONS, info.name


def test_service_runners_serve_only_service_types_and_topic_runners_only_message_types():
    for info in catalog.CONVERTERS.values():
        serves = info.runner in (catalog.SERVE, catalog.SERVE_ALL)
        assert serves == all(t.startswith("std_srvs/") for t in info.ros_types), info.name


def test_no_engine_condition_names_a_converter():
    """Adding a converter touches the catalogue and its module only: the engine never tests a name."""
    names = set(catalog.CONVERTERS)
    found = []
    for path in ENGINE.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Compare):
                for side in (node.left, *node.comparators):
                    if isinstance(side, ast.Constant) and side.value in names:
                        found.append(f"{path.name}:{node.lineno}: {side.value}")
    assert not found, found
