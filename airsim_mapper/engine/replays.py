"""Latched replays: tell a latched message that a publisher sends again on a new connection from a new one.

A latched publisher hands its last message to every subscriber that connects, so a subscriber that is
re-created (or re-registered after a master restart, or reconnected) receives the message it already acted
on. For a command such as load_scene that must not act twice. rospy gives each received message its
connection's header (`msg._connection_header`, one dict per connection) with the publisher's `callerid` and
`latching` flag: the first message on a new latched connection that repeats the last message from that
publisher is a replay. A new message (another payload, or the same one published again on the same
connection, or by another publisher such as a second `rostopic pub -1`) is not.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Hashable, Mapping
from typing import Any

MAX_PUBLISHERS = 64  # publishers remembered (least recently heard from forgotten first)


class LatchedReplays:
    """Remembers, per publisher, the connection and payload of its last message."""

    def __init__(self, size: int = MAX_PUBLISHERS) -> None:
        self.size = size
        self.replays = 0  # messages recognised as replays
        self._last: OrderedDict[str, tuple[Any, Hashable]] = OrderedDict()
        self._lock = threading.Lock()

    def is_replay(self, header: Mapping[str, str] | None, payload: Hashable) -> bool:
        """True for a latched message re-sent on a new connection; records the message either way."""
        if not header or header.get("latching") != "1":
            return False
        caller = header.get("callerid", "")
        with self._lock:
            seen = self._last.pop(caller, None)
            self._last[caller] = (header, payload)
            while len(self._last) > self.size:
                self._last.popitem(last=False)
        replay = seen is not None and seen[0] is not header and seen[1] == payload
        self.replays += replay
        return replay


def connection_header(message: Any) -> Mapping[str, str] | None:
    """The header of the connection rospy received `message` on (None for a message made in-process)."""
    return getattr(message, "_connection_header", None)
