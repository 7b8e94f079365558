"""The shipped mappings, rewritten with `variables` (default) and `extends: default` (enu), expand to exactly
the bridges the standalone files they replaced expanded to (kept in data/), on every shipped scene."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
from harness import ROOT

from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping
from airsim_mapper.mapping.model import BridgeSpec
from airsim_mapper.resources import MAPPINGS_DIR
from airsim_mapper.scene import read_scene

DATA = Path(__file__).resolve().parent / "data"
SIM_CONFIG = ROOT / "sim_config"
SCENES = sorted(path.name for path in SIM_CONFIG.glob("scene_*.jsonc"))


def everything(bridge: BridgeSpec) -> dict:
    """Every field of a bridge, as comparable plain data."""
    fields = {field.name: getattr(bridge, field.name) for field in dataclasses.fields(bridge)}
    return json.loads(json.dumps(fields, default=plain, sort_keys=True))


def plain(value: object) -> object:
    return dataclasses.asdict(value) if dataclasses.is_dataclass(value) else dict(value)


@pytest.mark.parametrize("name", ["default", "enu"])
@pytest.mark.parametrize("scene_file", SCENES)
@pytest.mark.parametrize("namespace", ["", "/sim2"])
def test_the_shipped_mapping_expands_as_its_standalone_predecessor(name, scene_file, namespace):
    scene = read_scene(SIM_CONFIG, scene_file)
    before = expand(load_mapping(DATA / f"{name}_before_extends.yaml"), scene, "projectairsim", namespace)
    after = expand(load_mapping(name), scene, "projectairsim", namespace)
    assert [b.name for b in after] == [b.name for b in before]  # the same bridges in the same order
    assert [everything(b) for b in after] == [everything(b) for b in before]


def test_enu_extends_default_and_is_at_most_a_third_of_its_predecessor():
    enu = (MAPPINGS_DIR / "enu.yaml").read_text()
    assert "\nextends: default\n" in enu
    assert len(enu.splitlines()) * 3 <= len((DATA / "enu_before_extends.yaml").read_text().splitlines())
    assert len(enu) * 3 <= len((DATA / "enu_before_extends.yaml").read_text())
