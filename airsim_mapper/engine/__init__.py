"""The live engine: runs expanded bridges between the simulator client and ROS.

Its face (`__all__`, the modules the layers above import): `engine` (Engine), `sim_link` (the client link
and its frame counts), `health` (connecting), `diagnostics`, `reregister`, `mapping_reload` and `status`
(what the wrapper and the node add around an engine). Everything else is the engine's own.
"""

from __future__ import annotations

__all__ = ["diagnostics", "engine", "health", "mapping_reload", "reregister", "sim_link", "status"]
