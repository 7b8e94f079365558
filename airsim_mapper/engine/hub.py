"""One Stream per subscribed simulator topic, shared by every bridge that reads it."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from airsim_mapper.engine.sim_link import SimLink
from airsim_mapper.engine.streams import Handler, Stream


class StreamHub:
    """Attaches bridge handlers to topic streams; subscribes on the first, unsubscribes after the last.

    Subscribing is a frame on the topics socket and unsubscribing a service call, so the server may see
    them out of order: a bridge attaching while another's unsubscribe of the same topic is in flight would
    be left unsubscribed (an image bridge detaching as its camera_info bridge attaches). Each topic's
    subscription changes therefore go one at a time: an attach waits for the unsubscribe's reply.
    """

    def __init__(
        self,
        sim: SimLink,
        on_transforms: Callable[[list], None],
        on_stamp: Callable[[int, float, str], object] | None = None,
    ) -> None:
        self._sim = sim
        self._on_transforms = on_transforms
        self._on_stamp = on_stamp  # every stream's stamps (the time watch)
        self._streams: dict[str, Stream] = {}
        self._lock = threading.Lock()
        self._topic_locks: dict[str, threading.Lock] = {}  # one per topic ever attached: a bounded set

    def _in_order(self, topic: str) -> threading.Lock:
        """The lock that orders `topic`'s subscription changes."""
        with self._lock:
            return self._topic_locks.setdefault(topic, threading.Lock())

    def attach(self, topic: str, handler: Handler, inline: bool = False) -> None:
        """Feed `topic`'s messages to `handler`; `inline` if it is light enough for the receive thread
        (streams.py)."""
        with self._in_order(topic):
            with self._lock:
                stream = self._streams.get(topic)
                if stream is not None:
                    stream.add_handler(handler, inline)
                    return
                stream = Stream(topic, self._on_transforms, [handler], on_stamp=self._on_stamp, inline=inline)
                self._streams[topic] = stream
                sim = self._sim
            sim.subscribe(topic, stream.offer)

    def detach(self, topic: str, handler: Handler) -> None:
        with self._in_order(topic):
            with self._lock:
                stream = self._streams.get(topic)
                if stream is None:
                    return
                if stream.remove_handler(handler):
                    return
                del self._streams[topic]
                sim = self._sim
            sim.unsubscribe(topic, stream.offer)  # the reply comes before this topic's next subscribe
        stream.stop()

    def sim_now(self) -> int:
        """The simulator's time as far as the streams know it: the newest time_stamp (ns) seen on any
        (0 before any)."""
        return max((s.stats.newest_stamp for s in self.streams().values()), default=0)

    def newest_arrival(self) -> float:
        """When the newest message arrived on any stream (time.monotonic(); 0 before any)."""
        return max((s.stats.last_receive for s in self.streams().values()), default=0.0)

    def forget_stamps(self) -> None:
        """A new simulator session: the old session's newest stamps no longer say what is stale. Called
        from the receive thread, so it takes no lock (`rebind` holds the hub's while it subscribes)."""
        for stream in list(self._streams.values()):
            stream.stats.newest_stamp = 0

    def streams(self) -> dict[str, Stream]:
        with self._lock:
            return dict(self._streams)

    def statistics(self) -> dict[str, dict[str, Any]]:
        """Every stream's counts, the age of its newest frame and its peaks since the previous call."""
        now = time.monotonic()
        return {
            topic: {
                "received": s.stats.received,
                "dropped": s.stats.dropped,
                "handled": s.stats.handled,
                "errors": s.stats.errors,
                "age_s": round(now - s.stats.last_receive, 3) if s.stats.last_receive else None,
                **s.stats.take_peaks(),
            }
            for topic, s in self.streams().items()
        }

    def rebind(self, sim: SimLink) -> None:
        """Move every stream to a new sim link (after a reconnect): same streams, subscribed anew."""
        with self._lock:
            self._sim = sim
            for topic, stream in self._streams.items():
                sim.subscribe(topic, stream.offer)

    def drop_all(self) -> None:
        """Forget every stream without telling the server (its subscriptions are already gone)."""
        with self._lock:
            streams, self._streams = list(self._streams.values()), {}
        for stream in streams:
            stream.stop()
