"""The one place that touches a private part of the Project AirSim client (pinned: projectairsim 1.1.0).

The client's receive thread reads each topic frame through its name-mangled `__recv_topic_frame` and then
decodes and dispatches it itself. The bridge's receive loop takes that thread over (`receive.take_over`)
by shadowing the method with an instance attribute of the same name, so that one thread, not two, reads
the topics socket. `missing_internals` says what of this is gone in the installed client.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = [
    "FRAME_READ",
    "PINNED",
    "can_replace_frame_read",
    "frame_read_replaced",
    "missing_internals",
    "replace_frame_read",
]

PINNED = "projectairsim 1.1.0"
FRAME_READ = "_ProjectAirSimClient__recv_topic_frame"  # the client's per-frame read (name-mangled)


def can_replace_frame_read(client: Any) -> bool:
    """Whether `client`'s class reads its frames through the method the bridge shadows."""
    return callable(getattr(type(client), FRAME_READ, None))


def frame_read_replaced(client: Any) -> bool:
    """Whether `replace_frame_read` was called on `client` already."""
    return FRAME_READ in vars(client)


def replace_frame_read(client: Any, read: Callable[[], None] | None) -> None:
    """Make `client`'s receive thread call `read` for its next frame instead of its own read (None marks a
    client whose read cannot be replaced, so that it is looked at once)."""
    vars(client)[FRAME_READ] = read


def missing_internals() -> list[str]:
    """The private names of the installed client this module relies on that are gone."""
    from projectairsim import ProjectAirSimClient

    if callable(getattr(ProjectAirSimClient, FRAME_READ, None)):
        return []
    return [f"ProjectAirSimClient.{FRAME_READ}"]
