"""The world the sensors sense: a ground plane with boxes and spheres, and the world file it comes from.

`world` answers ray casts and single-ray queries, `contacts` the overlap of a robot's collision sphere,
`world_file` reads and checks a world file (format in ../WORLD.md), `gltf` reads a model's bounds and
colour. Its face (`__all__`, the modules the rooms above import): `world`, `world_file`, `gltf`.
"""

from __future__ import annotations

__all__ = ["gltf", "world", "world_file"]
