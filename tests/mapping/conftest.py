"""Fixtures for mapping tests: small scene directories written into a temporary folder."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from scene_builders import MINIMAL_ROBOT, scene_doc


@pytest.fixture
def write_scene(tmp_path: Path) -> Callable[..., Path]:
    """Write a scene (and robot configs) into tmp_path/sim_config; return that directory."""

    def write(
        robots: dict[str, list[dict[str, Any]]], scene_id: str = "TestScene", name: str = "scene.jsonc"
    ) -> Path:
        root = tmp_path / "sim_config"
        root.mkdir(exist_ok=True)
        configs = {}
        for robot, sensors in robots.items():
            config_name = f"robot_{robot}.jsonc"
            (root / config_name).write_text(json.dumps({**MINIMAL_ROBOT, "sensors": sensors}))
            configs[robot] = config_name
        (root / name).write_text(json.dumps(scene_doc(configs, scene_id)))
        return root

    return write
