"""One robot of a loaded scene: its runtime (body, sensor streams, ticks, collisions) and service methods.

`robots` is the runtime; `robot_services` assembles a robot's service methods from its own and those of
`camera_services` and `motion_services`, whose parameters `robot_params` checks. Its face (`__all__`, the
modules the top of the server imports): `robot_services`, `robots`.
"""

from __future__ import annotations

__all__ = ["robot_services", "robots"]
