"""The projectairsim World the engine loads a scene with: the scene exactly as `read_scene` validated it."""

from __future__ import annotations

import copy
import functools
from pathlib import Path
from typing import Any

from airsim_mapper.mapping.scene import Scene

__all__ = ["load_validated_world", "validated_world_class"]


def load_validated_world(client: Any, scene: Scene, sim_config_path: str) -> Any:
    """A projectairsim World on `scene` as it was validated (`Scene.config`): no file is read again."""
    return validated_world_class()(client, scene, sim_config_path)


@functools.cache
def validated_world_class() -> type:
    """The World subclass `load_validated_world` uses (made on first use: projectairsim is imported
    lazily)."""
    from projectairsim import World

    class ValidatedWorld(World):
        """World.__init__ of projectairsim 1.1.0 step for step, except that the scene dict is the one
        read_scene validated instead of whatever the file holds now (it may have been edited, or replaced
        by a symlink out of the config directory, since)."""

        def __init__(self, client: Any, scene: Scene, sim_config_path: str) -> None:
            self.client = client
            self.sim_config_path = sim_config_path.rstrip("/") + "/"
            self.sim_instance_idx = -1
            self.parent_topic = "/Sim/SceneBasicDrone"
            self.sim_config = None
            self.home_geo_point = None
            self.scene_config_path = str(Path(scene.config_dir) / scene.file)
            self.robot_config_paths: list[str] = []
            self.envactor_config_paths: list[str] = []
            self.load_scene(copy.deepcopy(dict(scene.config)), delay_after_load_sec=0)
            zeros = [0, 0]
            self.import_ned_trajectory("null_trajectory", [0, 1], zeros, zeros, zeros, zeros, zeros, zeros)

    return ValidatedWorld
