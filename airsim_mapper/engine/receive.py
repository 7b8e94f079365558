"""The bridge's receive loop on a client's topics socket, and what goes with it: decoding a frame's body
(numpy fast path for large ones), taking over the thread of a client that started receiving itself, and
closing a client at once. Frames go to the client's current link (`SimLink.dispatch`, sim_link.py), which
this module never imports: the link starts the loop and registers itself on the client."""

from __future__ import annotations

import contextlib
import functools
import threading
import time
from typing import Any

from airsim_mapper.common.logs import ros_logger
from airsim_mapper.common.nng_wait import MessageWait
from airsim_mapper.engine.client_internals import (
    FRAME_READ,
    can_replace_frame_read,
    frame_read_replaced,
    replace_frame_read,
)
from airsim_mapper.engine.fast_frames import Buffer, decode_map

__all__ = [
    "FrameWait",
    "close_client",
    "nng_handles",
    "read_ahead",
    "receive",
    "receive_frame",
    "take_over",
    "unknown_topic",
    "unpack_message",
]

log = ros_logger("airsim_mapper.sim")
FAST_MIN_BYTES = 32768  # smaller bodies are cheaper through msgpack
RECEIVE_THREAD = "sim-receive"
CURRENT_LINK = "_airsim_mapper_link"  # client attribute: the link that frames are dispatched through
TAKE_OVER_WAIT_S = 1.0
READ_AHEAD_FRAMES = 16  # frames NNG may read off the topics socket before the receive loop takes them
WAIT_MS = 100  # the loop's wait for a frame before it looks again whether its client stopped (the client's)


def unpack_message(body: Buffer, fast: bool) -> tuple[Any, bool]:
    """The message of a frame body, and whether it took the fast path.

    With `fast` (only the bridge listens to the topic), a large body is decoded with its float/int arrays
    straight into numpy (fast_frames.decode_map), skipping the per-element Python lists msgpack would
    build (docs/performance.md has the cost), and its large bin values (image pixels) as memoryviews of
    the body, which the image converter publishes without a copy. Everything else, and anything unusual,
    takes msgpack's path, exactly as the client would.
    """
    import msgpack

    if fast and len(body) >= FAST_MIN_BYTES:
        try:
            message = decode_map(body, views=True)
        except Exception:
            message = None
        if message is not None:
            return message, True
    return msgpack.unpackb(body, raw=False), False


def receive(client: Any) -> None:
    """The bridge's receive loop on a client's topics socket, until the client stops or the socket closes.

    Each frame goes to the client's current link (`SimLink.dispatch`): a malformed frame or a failing
    callback is dropped and counted there, and the loop goes on. NNG reads ahead of the loop from its start
    (`read_ahead`), whichever thread runs it. On a pynng socket the loop waits for frames in `FrameWait`.
    """
    import pynng

    sock = client.socket_topics
    read_ahead(sock)
    try:
        read = FrameWait(sock) if isinstance(sock, pynng.Socket) else sock.recv
    except pynng.exceptions.Closed:
        return
    while client.state:
        try:
            packed = read()
        except (pynng.exceptions.Timeout, pynng.exceptions.TryAgain):
            continue
        except pynng.exceptions.Closed:
            return
        except pynng.exceptions.NNGException as exc:
            getattr(client, CURRENT_LINK)._bad_frame(f"receive failed: {exc}")
            continue
        if packed is not None:
            getattr(client, CURRENT_LINK).dispatch(packed)


class FrameWait:
    """The next frame on a pynng socket, or None after WAIT_MS without one: the loop then looks whether its
    client stopped (`state`), as the client's own loop does at its receive timeout. The wait is in the
    kernel (`MessageWait`) and the frame is then taken without blocking."""

    def __init__(self, sock: Any) -> None:
        self.sock = sock
        self.ready = MessageWait(sock)

    def __call__(self) -> memoryview | None:
        if not self.ready(WAIT_MS):
            return None
        return receive_frame(self.sock, block=False)


def receive_frame(sock: Any, block: bool = True) -> memoryview:
    """The next frame on a pynng socket, as a view of NNG's own message: not copied. Without `block`, pynng's
    TryAgain when NNG holds no frame.

    `Socket.recv` copies each frame twice (NNG's message into a buffer it allocates, that buffer into a
    Python bytes object). Here the view keeps the message alive and frees it when the last view of it (the
    pixels of an image being published, say) is gone. NNG's blocking receive runs without the GIL.
    """
    ffi, lib, check_err = nng_handles()
    holder = ffi.new("nng_msg **")
    check_err(lib.nng_recvmsg(sock.socket, holder, 0 if block else lib.NNG_FLAG_NONBLOCK))
    msg = holder[0]
    body = ffi.gc(lib.nng_msg_body(msg), lambda _body: lib.nng_msg_free(msg))
    return memoryview(ffi.buffer(body, lib.nng_msg_len(msg)))


def read_ahead(sock: Any) -> None:
    """Let NNG read up to READ_AHEAD_FRAMES frames ahead of the receive loop on a pynng socket.

    With pynng's default (no receive buffer) a Pair0 socket holds one frame in its pipe and reads the next
    only once the loop has taken it, so every frame of a burst (ten robots' poses of one tick) waits for a
    round trip through NNG's threads. With a few frames of buffer NNG reads on while the loop converts and
    publishes, and the loop mostly finds the next frame waiting. The bound keeps what a stalled loop can
    pile up to a few frames (16 1080p images are 100 MB); beyond it the socket pushes back as before.
    """
    import pynng

    if isinstance(sock, pynng.Socket):
        with contextlib.suppress(pynng.exceptions.NNGException):
            sock.recv_buffer_size = READ_AHEAD_FRAMES


@functools.cache
def nng_handles() -> tuple[Any, Any, Any]:
    """pynng's cffi handles, imported once: a `from pynng import ...` per frame cost more than the rest of
    `receive_frame` (pynng is a package, so each such import runs importlib's Python code)."""
    from pynng import ffi, lib
    from pynng.exceptions import check_err

    return ffi, lib, check_err


def take_over(client: Any) -> bool:
    """Make the client's own receive thread run `receive`; True if it was not doing so already.

    The client's loop reads each frame through a private method and then decodes and dispatches it
    itself; `client_internals.replace_frame_read` shadows that method: the thread's next read
    enters `receive` and stays there until the client stops; the frame read before the swap is the
    client's last, and this call waits for the swap. A client without that method (another version)
    keeps its own loop, with a warning.
    """
    if getattr(client.recv_topic_thread, "name", "") == RECEIVE_THREAD or frame_read_replaced(client):
        return False
    if not can_replace_frame_read(client):
        log.warning("this projectairsim client has no %s: its own receive loop stays in use", FRAME_READ)
        replace_frame_read(client, None)  # warns once; a client without the method never reads it
        return False

    entered = threading.Event()

    def read() -> None:
        entered.set()
        receive(client)
        if client.state:  # the socket closed under a live client: the client's loop would spin
            time.sleep(0.1)

    replace_frame_read(client, read)
    # The client's thread reads again within its 100 ms receive timeout; until then a frame would still
    # be the client's to decode, so the bridge subscribes nothing before the swap has happened.
    if not entered.wait(TAKE_OVER_WAIT_S):
        log.warning(
            "the client's receive thread did not pick up the bridge's loop within %g s", TAKE_OVER_WAIT_S
        )
    return True


def unknown_topic(topic: str) -> Any:
    from projectairsim.types import ProjectAirSimTopic

    return ProjectAirSimTopic(topic, "unknown", "unknown", 0)


def close_client(client: Any) -> None:
    """Close a client's sockets at once, without talking to the server; joins its receive thread."""
    client.state = False  # the receive loop ends at its next frame or wait ...
    _close(getattr(client, "socket_topics", None))  # ... or at once, on the closed socket
    thread = getattr(client, "recv_topic_thread", None)
    if thread is not None and thread.is_alive() and thread is not threading.current_thread():
        thread.join(timeout=2)
    _close(getattr(client, "socket_services", None))


def _close(sock: Any) -> None:
    if sock is not None:
        with contextlib.suppress(Exception):
            sock.close()
