"""The simulator side of the engine: one Project AirSim client, shared safely.

- Subscriptions are reference-counted per callback: the bridge adds its own callbacks to the client's
  subscription table and removes only those, so a mission script sharing the client keeps its callbacks;
  the server is told to unsubscribe only when no callback is left on a topic.
- Requests never use the client's shared default request context (unsafe across threads) nor its
  `request_async` (whose error handler disconnects the client): each call gets its own NNG context on one
  asyncio loop owned by this link, so a long motion command never blocks other requests.
- Callbacks run on the client's receive thread; they must only hand messages over (see streams.py).
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import logging
import threading
from collections.abc import Callable
from typing import Any

log = logging.getLogger("rosout.airsim_mapper.sim")

TopicCallback = Callable[[Any, Any], None]


class SimLinkError(RuntimeError):
    """A simulator request failed."""


class SimLink:
    """Reference-counted topic subscriptions and concurrent service calls on a shared client."""

    def __init__(self, client: Any) -> None:
        self.client = client
        self._lock = threading.RLock()
        self._ours: dict[str, list[TopicCallback]] = {}
        self._loop = asyncio.new_event_loop()
        self._loop_thread = threading.Thread(target=self._run_loop, name="sim-requests", daemon=True)
        self._loop_thread.start()

    # --- topics -----------------------------------------------------------------------------
    def subscribe(self, topic: str, callback: TopicCallback) -> None:
        """Add a callback for a sim topic; the client sends SUBSCRIBE (and the server its cached value)."""
        with self._lock:
            self._ours.setdefault(topic, []).append(callback)
            self.client.subscribe(topic, callback)

    def unsubscribe(self, topic: str, callback: TopicCallback) -> None:
        """Remove one of our callbacks; unsubscribe on the server only when nobody else listens."""
        with self._lock:
            ours = self._ours.get(topic, [])
            if callback in ours:
                ours.remove(callback)
            if not ours:
                self._ours.pop(topic, None)
            entry = self.client.subs.get(topic)
            if entry is None:
                return
            callbacks = entry["callbacks"]
            # Replace the list rather than mutate it: the receive thread may be iterating the old one.
            entry["callbacks"] = [cb for cb in callbacks if cb is not callback]
            if entry["callbacks"]:
                return
        try:
            self.call(
                "/Sim/Unsubscribe",
                {"topic_paths": [topic]},
                timeout=10.0,
            )
        except SimLinkError as exc:
            log.warning("unsubscribe %s: %s", topic, exc)
        with self._lock:
            entry = self.client.subs.get(topic)
            if entry is not None and not entry["callbacks"]:
                self.client.subs.pop(topic, None)

    def resubscribe_all(self) -> None:
        """Re-send SUBSCRIBE for every topic we hold callbacks for (after the server dropped them)."""
        with self._lock:
            for topic, callbacks in self._ours.items():
                entry = self.client.subs.setdefault(topic, {"reliability": 1.0, "callbacks": []})
                missing = [cb for cb in callbacks if cb not in entry["callbacks"]]
                entry["callbacks"] = entry["callbacks"] + missing
                self.client.try_send(_subscribe_frame(topic))

    def forget_all(self) -> None:
        """Drop our bookkeeping after the client's subscriptions were cleared (scene load)."""
        with self._lock:
            self._ours.clear()

    def publish(self, topic: str, message: dict) -> None:
        self.client.publish(topic, message)

    # --- services ---------------------------------------------------------------------------
    def call_async(self, method: str, params: dict) -> concurrent.futures.Future:
        """Send a request on its own NNG context; the future resolves with the decoded result."""
        return asyncio.run_coroutine_threadsafe(self._request(method, params), self._loop)

    def call(self, method: str, params: dict, timeout: float = 30.0) -> Any:
        future = self.call_async(method, params)
        try:
            return future.result(timeout=timeout)
        except concurrent.futures.TimeoutError as exc:
            future.cancel()
            raise SimLinkError(f"{method}: no reply within {timeout:.0f} s") from exc

    async def _request(self, method: str, params: dict) -> Any:
        request = {"method": method, "params": params, "version": 1.0}
        packed = self.client.preprocess_request(request)
        socket = self.client.socket_services
        if socket is None:
            raise SimLinkError(f"{method}: not connected to the simulator")
        ctx = socket.new_context()
        try:
            await ctx.asend(packed)
            reply = await ctx.arecv_msg()
            try:
                return self.client.postprocess_response(reply)
            except RuntimeError as exc:  # the client's form of a server error reply
                raise SimLinkError(f"{method}: {exc}") from exc
        except SimLinkError:
            raise
        except Exception as exc:
            raise SimLinkError(f"{method}: {type(exc).__name__}: {exc}") from exc
        finally:
            ctx.close()

    def _run_loop(self) -> None:
        asyncio.set_event_loop(self._loop)
        self._loop.run_forever()

    def close(self) -> None:
        """Remove every callback of ours from the client, then stop the request loop."""
        with self._lock:
            topics = list(self._ours.items())
        for topic, callbacks in topics:
            for cb in list(callbacks):
                self.unsubscribe(topic, cb)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._loop_thread.join(timeout=5)


def _subscribe_frame(topic: str) -> bytes:
    import msgpack

    return msgpack.packb([0, topic, ""], use_bin_type=True)
