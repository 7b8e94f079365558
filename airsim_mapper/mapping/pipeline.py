"""Mapping file + scene -> concrete bridges, in one call (what the node and validate-mapping both use)."""

from __future__ import annotations

from pathlib import Path

from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping
from airsim_mapper.mapping.model import BridgeSpec, Mapping
from airsim_mapper.scene import Scene, read_scene


def load_and_expand(
    mapping_path: str | Path,
    scene_file: str,
    simconfigpath: str | Path,
    node_name: str,
    namespace: str = "",
) -> tuple[Mapping, Scene, tuple[BridgeSpec, ...]]:
    """Load the mapping, read the scene, expand; raise MappingError or SceneConfigError (both ConfigError)."""
    mapping = load_mapping(mapping_path)
    scene = read_scene(simconfigpath, scene_file)
    return mapping, scene, expand(mapping, scene, node_name, namespace)
