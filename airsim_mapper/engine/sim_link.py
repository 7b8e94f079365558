"""The simulator side of the engine: one Project AirSim client, shared safely.

- Subscriptions are reference-counted per callback: the bridge adds its own callbacks to the client's
  subscription table and removes only those, so a mission script sharing the client keeps its callbacks;
  the server is told to unsubscribe only when no callback is left on a topic.
- Requests never use the client's shared default request context (unsafe across threads) nor its
  `request_async` (whose error handler disconnects the client): each call gets its own NNG context on one
  asyncio loop owned by this link, so a long motion command never blocks other requests.
- Callbacks run on the client's receive thread; they must only hand messages over (see streams.py).
- Receiving: the client's own receive loop decodes every frame element by element and ends for good on
  the first undecodable frame (or a failing callback). The bridge's loop (`receive`, the same dispatch)
  replaces it whatever the order in which a mission script made `World` and the bridge: a malformed frame,
  or one of a type other than MESSAGE, is dropped, counted in `bad_frames` and reported at most every 5 s;
  a frame over `FrameCounts.max_frame_bytes` is dropped before it is unpacked and counted in
  `oversized_frames` (the engine keeps the counts across reconnects); large frames that only the bridge
  listens to skip msgpack's per-element lists; every other callback gets what the client would give it.
- Liveness: the link notices when a connection drops (an NNG pipe removal on either socket: the server
  died or restarted) and offers a cheap `probe`. A link marked dead answers every call at once with
  SimLinkError instead of waiting on sockets that will never answer (see health.py and Engine's reconnect).
- Closing is bounded: once `begin_close` is called, unsubscribes are only collected, and `close` sends
  them as one request with a timeout, so a frozen simulator cannot hold up a shutdown.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from airsim_mapper.common.logs import RateLimitedLog, ros_logger
from airsim_mapper.engine.errors import EngineError
from airsim_mapper.engine.fast_frames import Buffer, parse_frame_header
from airsim_mapper.engine.health import answered_within
from airsim_mapper.engine.receive import (
    CURRENT_LINK,
    FAST_MIN_BYTES,
    RECEIVE_THREAD,
    close_client,
    receive,
    take_over,
    unknown_topic,
    unpack_message,
)

log = ros_logger("airsim_mapper.sim")

TopicCallback = Callable[[Any, Any], None]
WARN_PERIOD_S = 5.0
MAX_FRAME_MB = 64.0  # default cap on one simulator frame (a 4K BGR image is 25 MB)
MESSAGE_FRAME = 2  # projectairsim.types.FrameType.MESSAGE: the only type a server sends to a client
SETTLE_S = 1.0  # at most this long for cancelled requests to hear back from NNG when the link stops


@dataclass
class FrameCounts:
    """Simulator frames the bridge refused, kept by the engine across reconnects (status, /diagnostics)."""

    max_frame_bytes: int = int(MAX_FRAME_MB * 1024 * 1024)
    bad: int = 0  # undecodable, or of an unknown type
    oversized: int = 0  # over max_frame_bytes, or an image over its pixel bound
    callback_errors: int = 0  # a callback on the receive thread raised (the frame itself was fine)


class SimLinkError(EngineError):
    """A simulator request failed."""


class SimLinkDead(SimLinkError):
    """The link lost its simulator; nothing is sent until the engine reconnects."""

    def __init__(self, what: str) -> None:
        super().__init__(f"{what}: the simulator connection is lost")


class LinkState:
    """A link's connection state, owned here and changed under its own lock (a leaf lock: nothing else is
    taken while it is held). NNG's callback thread drops it, the supervisor kills it, shutdown closes it,
    and every thread that sends asks it first."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._dropped = False  # a connection dropped at least once
        self._dead = False  # every call fails at once; subscriptions are only remembered
        self._closing = False  # unsubscribes are collected for `close`

    def drop(self) -> None:
        with self._lock:
            self._dropped = True

    def kill(self) -> None:
        with self._lock:
            self._dead = True

    def begin_close(self) -> None:
        with self._lock:
            self._closing = True

    @property
    def dead(self) -> bool:
        with self._lock:
            return self._dead

    @property
    def closing(self) -> bool:
        with self._lock:
            return self._closing

    def connected(self) -> bool:
        """Neither dead nor ever dropped, read together."""
        with self._lock:
            return not self._dead and not self._dropped


class SimLink:
    """Reference-counted topic subscriptions and concurrent service calls on a shared client."""

    def __init__(self, client: Any, counts: FrameCounts | None = None) -> None:
        self.client = client
        self.counts = counts or FrameCounts()
        self._lock = threading.RLock()
        self._encode_lock = threading.Lock()  # the client's request numbering (`_encode`)
        self._ours: dict[str, list[TopicCallback]] = {}
        self._loop = asyncio.new_event_loop()
        self._loop_thread = threading.Thread(target=self._run_loop, name="sim-requests", daemon=True)
        self._loop_thread.start()
        self.connection = LinkState()  # dropped, dead, closing: one lock of its own
        self._pending: set[str] = set()  # topics to unsubscribe when closing
        self._watched = [
            sock
            for sock in (getattr(client, "socket_topics", None), getattr(client, "socket_services", None))
            if sock is not None
        ]
        for sock in self._watched:
            sock.add_post_pipe_remove_cb(self._on_pipe_removed)
        self.fast_frames = 0  # frames decoded on the fast path
        self._warn = RateLimitedLog(
            log, WARN_PERIOD_S
        ).warn  # dropped frames, with a count of those held back
        self.ensure_receiver()

    # --- receiving --------------------------------------------------------------------------
    def ensure_receiver(self) -> bool:
        """Make the bridge's receive loop the client's, whoever started receiving; True if it started.

        The loop dispatches through the client's current link (this one from now on). With no receive
        thread yet, it gets its own thread, which the client then keeps using. A thread the client started
        itself (a mission script that made `World` first) is taken over: its per-frame read is replaced, so
        that thread runs this loop instead of the client's, which would decode every frame element by
        element and stop for good on the first undecodable one.
        """
        client = self.client
        if self.dead or client.socket_topics is None:
            return False
        setattr(client, CURRENT_LINK, self)
        thread = getattr(client, "recv_topic_thread", None)
        if thread is not None and thread.is_alive():
            return take_over(client)
        if thread is not None and not client.state:
            return False  # disconnected on purpose
        client.recv_topic_thread = threading.Thread(target=receive, args=(client,), name=RECEIVE_THREAD)
        client.recv_topic_thread.daemon = True
        client.recv_topic_thread.start()
        if thread is not None:
            self._bad_frame("the client's receive loop had stopped; receiving again")
        return True

    def dispatch(self, packed: Buffer) -> None:
        """One frame off the topics socket: decode it and hand the message to the topic's callbacks."""
        import msgpack

        client = self.client
        if len(packed) > self.counts.max_frame_bytes:
            self.counts.oversized += 1
            self._warn(
                f"a {len(packed) / 1048576:.1f} MB frame dropped: over the "
                f"{self.counts.max_frame_bytes / 1048576:g} MB limit (--max-frame-mb)"
            )
            return
        try:
            # The header parser keeps a large body where it was received; a small frame is cheaper whole
            # through msgpack's C decoder.
            header = parse_frame_header(packed) if len(packed) >= FAST_MIN_BYTES else None
            if header is None:  # small, or any other framing: msgpack's path, as the client reads it
                frame = msgpack.unpackb(packed, raw=True)
                frame_type, topic, body = frame[0], frame[1].decode("utf-8"), frame[2]
            else:  # the body stays where it was received: no copy
                frame_type, topic = header.frame_type, header.topic
                body = memoryview(packed)[header.body_start : header.body_end]
            if frame_type != MESSAGE_FRAME:
                self._bad_frame(f"frame of unknown type {frame_type!r} dropped (only MESSAGE is expected)")
                return
            entry = client.subs.get(topic)
            if entry is None:
                return
            message = self._decode(topic, entry, body)
        except Exception as exc:
            self._bad_frame(f"undecodable frame dropped ({type(exc).__name__}: {exc})")
            return
        info = client.topics.get(topic) or unknown_topic(topic)
        for callback in entry["callbacks"]:
            try:
                callback(info, message)
            except Exception as exc:  # not a bad frame: the callback's own bug, told with its traceback
                self.counts.callback_errors += 1
                self._warn(f"{topic}: a callback failed: {type(exc).__name__}: {exc}", exc)

    def _decode(self, topic: str, entry: dict, body: Buffer) -> Any:
        message, fast = unpack_message(body, self._only_ours(topic, entry["callbacks"]))
        self.fast_frames += fast
        return message

    def _only_ours(self, topic: str, callbacks: list) -> bool:
        ours = self._ours.get(topic, ())
        return bool(callbacks) and all(cb in ours for cb in callbacks)

    @property
    def bad_frames(self) -> int:
        return self.counts.bad

    def _bad_frame(self, message: str) -> None:
        self.counts.bad += 1
        self._warn(message)

    # --- liveness ---------------------------------------------------------------------------
    def _on_pipe_removed(self, _pipe: Any) -> None:
        """NNG callback thread: the server closed a connection (died, restarted, or dropped us)."""
        self.connection.drop()

    @property
    def dead(self) -> bool:
        """Marked dead: every call fails at once (see LinkState)."""
        return self.connection.dead

    def connected(self) -> bool:
        """The topics connection never dropped since this link was made."""
        return self.connection.connected()

    def probe(self, timeout: float) -> bool:
        """One cheap request, on the calling thread: did the server answer within `timeout` seconds?"""
        return not self.dead and answered_within(self.client, timeout, self._encode)

    def _encode(self, request: dict) -> bytes:
        """The client's bytes for `request`. The client numbers requests from a generator, which two
        threads must not advance at once: the request loop and the health probe both encode here."""
        with self._encode_lock:
            return self.client.preprocess_request(request)

    def mark_dead(self) -> None:
        """From now on every call fails at once; subscriptions are only remembered."""
        self.connection.kill()

    # --- topics -----------------------------------------------------------------------------
    def subscribe(self, topic: str, callback: TopicCallback) -> None:
        """Add a callback for a sim topic; the client sends SUBSCRIBE (and the server its cached value)."""
        with self._lock:
            self._ours.setdefault(topic, []).append(callback)
            if not self.dead:
                self.client.subscribe(topic, callback)

    def _forget(self, topic: str, callback: TopicCallback) -> bool:
        """Remove one of our callbacks locally; True when the server should be told to unsubscribe."""
        with self._lock:
            ours = self._ours.get(topic, [])
            if callback in ours:
                ours.remove(callback)
            if not ours:
                self._ours.pop(topic, None)
            if self.dead:
                return False
            entry = self.client.subs.get(topic)
            if entry is None:
                return False
            callbacks = entry["callbacks"]
            # Replace the list rather than mutate it: the receive thread may be iterating the old one.
            # `!=`, not `is not`: every access to a bound method (stream.offer) makes a new object.
            entry["callbacks"] = [cb for cb in callbacks if cb != callback]
            if entry["callbacks"]:
                return False
            if self.connection.closing:
                self._pending.add(topic)
                return False
            return True

    def unsubscribe(self, topic: str, callback: TopicCallback) -> None:
        """Remove one of our callbacks; unsubscribe on the server only when nobody else listens."""
        if not self._forget(topic, callback):
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

    def forget_all(self) -> None:
        """Drop our bookkeeping after the client's subscriptions were cleared (scene load)."""
        with self._lock:
            self._ours.clear()

    def publish(self, topic: str, message: dict) -> None:
        if self.dead:
            raise SimLinkDead(topic)
        self.client.publish(topic, message)

    # --- services ---------------------------------------------------------------------------
    def call_async(self, method: str, params: dict) -> concurrent.futures.Future:
        """Send a request on its own NNG context; the future resolves with the decoded result."""
        if not self.dead:
            coroutine = self._request(method, params)
            try:
                return asyncio.run_coroutine_threadsafe(coroutine, self._loop)
            except RuntimeError:  # the loop was stopped and closed (the link is closed)
                coroutine.close()
        failed: concurrent.futures.Future = concurrent.futures.Future()
        failed.set_exception(SimLinkDead(method))
        return failed

    def call(self, method: str, params: dict, timeout: float = 30.0) -> Any:
        future = self.call_async(method, params)
        try:
            return future.result(timeout=timeout)
        except concurrent.futures.TimeoutError as exc:
            future.cancel()
            raise SimLinkError(f"{method}: no reply within {timeout:.3g} s") from exc

    async def _request(self, method: str, params: dict) -> Any:
        packed = self._encode({"method": method, "params": params, "version": 1.0})
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
        try:
            self._loop.run_forever()
            self._settle()
        finally:
            self._loop.close()  # its selector and wake-up pipe go now, not whenever the collector runs

    def _settle(self) -> None:
        """Cancel the requests still waiting (a frozen simulator answers none) and run the loop until NNG's
        completions of them arrive: one arriving after the loop closed would raise on NNG's thread, and a
        request left pending would be finalised with its NNG context still open."""
        waiting = asyncio.all_tasks(self._loop)
        for task in waiting:
            task.cancel()
        if waiting:
            self._loop.run_until_complete(asyncio.wait(waiting, timeout=SETTLE_S))

    def stop_loop(self) -> None:
        """Stop the request loop thread (pending requests are abandoned)."""
        for sock in self._watched:
            with contextlib.suppress(ValueError):
                sock.remove_post_pipe_remove_cb(self._on_pipe_removed)
        with contextlib.suppress(RuntimeError):  # already stopped and closed
            self._loop.call_soon_threadsafe(self._loop.stop)
        if threading.current_thread() is not self._loop_thread:
            self._loop_thread.join(timeout=5)

    def abandon(self) -> None:
        """The simulator is gone: fail every call from now on, close the client's sockets, stop the loop.

        The client is closed without the usual unsubscribe request (nobody would answer it), and before a
        restarted server can be re-dialled by NNG: its single topics connection belongs to the new client.
        """
        self.mark_dead()
        close_client(self.client)
        self.stop_loop()

    def begin_close(self) -> None:
        """From now on unsubscribes are collected for `close` instead of sent one by one."""
        self.connection.begin_close()

    def close(self, timeout: float = 10.0, client_topics: bool = False) -> bool:
        """Remove every callback of ours from the client, tell the server in one request (waiting at most
        `timeout` s), then stop the request loop. With `client_topics` every topic the client holds is
        unsubscribed (the link's owner closes the client next). False if the server did not answer."""
        self.begin_close()
        with self._lock:
            topics = [(topic, list(callbacks)) for topic, callbacks in self._ours.items()]
        for topic, callbacks in topics:
            for cb in callbacks:
                self._forget(topic, cb)
        with self._lock:
            pending, self._pending = set(self._pending), set()
            if client_topics and not self.dead:
                pending |= set(self.client.subs)
        answered = not self.dead
        if pending and not self.dead:
            try:
                self.call("/Sim/Unsubscribe", {"topic_paths": sorted(pending)}, timeout=timeout)
            except SimLinkError as exc:
                log.warning("unsubscribing %d topics at close: %s", len(pending), exc)
                answered = False
            with self._lock:
                for topic in pending:
                    entry = self.client.subs.get(topic)
                    if entry is not None and (client_topics or not entry["callbacks"]):
                        self.client.subs.pop(topic, None)
        self.stop_loop()
        return answered
