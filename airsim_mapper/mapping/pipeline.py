"""Mapping file + scene -> concrete bridges (what the node, validate-mapping and the tools all use).

`prepare` is the one implementation: it loads the mapping and, with a scene, reads it and expands the
mapping over it for a node name and namespace. Given what an earlier call prepared (`known`), it reuses
what still holds: the same files are not read again, and the same names are not expanded again (the node
prepares once before it connects, to refuse a bad mapping early, and again with its final ROS name).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping
from airsim_mapper.mapping.model import BridgeSpec, MappingDoc
from airsim_mapper.mapping.names import resolve_namespace
from airsim_mapper.mapping.scene import Scene, read_scene

__all__ = ["Prepared", "load_and_expand", "prepare"]


@dataclass(frozen=True)
class Prepared:
    """A mapping, and the scene as read and the mapping expanded over it for a node name and namespace."""

    sources: tuple[str, str, str]  # (mapping, scene file, sim config directory) it was made from
    node_name: str
    namespace: str
    mapping: MappingDoc
    scene: Scene | None = None
    specs: tuple[BridgeSpec, ...] | None = None
    node_namespace: str = ""  # the node's ROS namespace, where its relative names resolve
    ros: int = 1  # the ROS whose name rules the bridges' names were checked against


def prepare(
    mapping_path: str | Path,
    scene_file: str,
    simconfigpath: str | Path,
    node_name: str,
    namespace: str = "",
    known: Prepared | None = None,
    node_namespace: str = "",
    ros: int = 1,
) -> Prepared:
    """Load the mapping and, with a scene file, read the scene and expand the mapping over it (its names
    checked against the rules of ROS `ros` too); raise
    MappingError or SceneConfigError (both ConfigError), or OSError. What `known` holds for the same
    sources (and names) is reused, not read (or expanded) again."""
    sources = (str(mapping_path), scene_file, str(simconfigpath))
    same = known is not None and known.sources == sources
    mapping = known.mapping if same else load_mapping(mapping_path)
    names = (node_name, namespace, resolve_namespace(node_namespace or "/"))  # "/a/" as "/a", "/" as ""
    if not scene_file:
        return Prepared(sources, node_name, namespace, mapping, node_namespace=names[2], ros=ros)
    scene = known.scene if same else read_scene(simconfigpath, scene_file)
    if same and (known.node_name, known.namespace, known.node_namespace, known.ros) == (*names, ros):
        specs = known.specs
    else:
        specs = expand(mapping, scene, *names, ros=ros)
    return Prepared(sources, node_name, namespace, mapping, scene, specs, names[2], ros)


def load_and_expand(
    mapping_path: str | Path,
    scene_file: str,
    simconfigpath: str | Path,
    node_name: str,
    namespace: str = "",
    ros: int = 1,
) -> tuple[MappingDoc, Scene, tuple[BridgeSpec, ...]]:
    """Load the mapping, read the scene, expand (its names checked for ROS `ros`); raise MappingError or
    SceneConfigError (both ConfigError)."""
    if not scene_file:
        read_scene(simconfigpath, scene_file)  # refuses the empty name as it refuses any other
    prepared = prepare(mapping_path, scene_file, simconfigpath, node_name, namespace, ros=ros)
    return prepared.mapping, prepared.scene, prepared.specs  # type: ignore[return-value]
