"""A scene: its configuration, its frame on the earth, its topics, clock, objects and scene-level calls.

`config` parses the scene `/Sim/LoadScene` sends, `geo` converts geo points to the scene's NED frame and
back, `topic_table` lists the topics the scene registers, `sim_clock` keeps its time, `objects` its objects
by name (with `voxels` for voxel grids), `env_actors` moves its environment actors, and `visual_noops`
answers the calls that only change how Unreal draws. All of these are its face (`__all__`).
"""

from __future__ import annotations

__all__ = ["config", "env_actors", "geo", "objects", "sim_clock", "topic_table", "visual_noops"]
