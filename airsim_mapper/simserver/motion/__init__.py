"""Motion: a robot's kinematic body and the commands that move it (no aerodynamics, no sockets).

`motion` is the body, its state (`Kinematic`) and the tick that applies a command; `motion_commands` the
commands of multirotors and rovers. Both are its face (`__all__`).
"""

from __future__ import annotations

__all__ = ["motion", "motion_commands"]
