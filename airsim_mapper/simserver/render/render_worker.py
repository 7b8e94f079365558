"""Camera rendering in a child process that runs at a lower CPU priority than the simulation.

In Project AirSim the GPU renders while the CPU simulates. Here both share the CPU, and a render in the
server's own process holds its GIL in many short numpy steps while the simulation thread must publish
poses on time, at the same priority as the ROS nodes downstream. `RenderWorker` renders with
`rendering.render` in a child process at nice +10 (`RENDER_NICE`), in a session and autogroup of its own at
the same nice value (`lower_priority`), so on a busy machine the camera rates drop before the pose rate
does.

The child is `python -m airsim_mapper.simserver.render.render_worker FD NICE BUFFER_FD`: it reads requests
from one end of a socket pair and answers on the same end (pickled by `multiprocessing.connection`). The first
message is the World, and a World sent later (objects moved, spawned or destroyed) replaces it without an
answer; each request is a RenderRequest with the size of the shared image buffer; each answer is a small
dict of the images made (type -> encoding, width, height), or the CameraError it raised. The pixels
themselves go through the shared buffer (a memfd both processes map): the child renders straight into it
at the request's `layout`, and the server packs each image from there into its topics frame (a render's
images are views of the buffer, valid until the next render). Through the socket, a 1280x720 frame of all
seven types (17.5 MB) was pickled, sent, received and unpickled: four copies and about half of the
server's CPU time per frame.

The child renders with `rendering.render`, so with OpenGL by default: its EGL context and llvmpipe's threads
live in the child, at its priority, made on its first render (docs/rendering.md).

It starts on the first render, is replaced if it dies or hangs, and exits when the server closes its end
or dies. In a session of its own it does not receive the signals a terminal or a supervisor sends to
the server's process group; it ignores SIGINT and SIGTERM anyway, so a stopping server never loses its
renderer first. A child that fails before its first answer
(it cannot be started, or cannot import) is reported once, and the server then renders in its own
process.
"""

from __future__ import annotations

import logging
import mmap
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from multiprocessing.connection import Connection
from pathlib import Path

from airsim_mapper.simserver.errors import SimServerError
from airsim_mapper.simserver.render import rendering
from airsim_mapper.simserver.render.camera_model import CameraError, RenderedImage, RenderRequest
from airsim_mapper.simserver.world.world import World

LOG = logging.getLogger("airsim_mapper.simserver.render_worker")

RENDER_NICE = 10  # added to the server's nice value; 0 keeps the worker at the server's priority and session
AUTOGROUP = Path("/proc/self/autogroup")
ANSWER_TIMEOUT_S = 10.0  # a render slower than this counts as a hung worker


class RenderWorkerError(SimServerError, RuntimeError):
    """The render process could not be started or stopped answering."""


class RenderWorker:
    """`rendering.render` of one world, answered by a child process."""

    def __init__(self, world: World, nice: int = RENDER_NICE) -> None:
        self.world = world
        self.nice = int(nice)
        self.starts = 0
        self._lock = threading.Lock()
        self._proc: subprocess.Popen | None = None
        self._conn: Connection | None = None
        self._closed = False
        self._answered = False  # the current child has answered at least once
        self._in_process = False  # set for good when a new child fails before its first answer
        self._sent: World | None = None  # the world the current child renders
        self._buffer_fd: int | None = None  # the shared image buffer (a memfd), made with the first child
        self._buffer: mmap.mmap | None = None
        self._buffer_size = 0

    @property
    def restarts(self) -> int:
        return max(0, self.starts - 1)

    @property
    def pid(self) -> int | None:
        return self._proc.pid if self._proc is not None else None

    def render(self, request: RenderRequest) -> dict[int, RenderedImage]:
        """`rendering.render(world, request)`, answered by the child; the images' data are views of the
        shared buffer, valid until the next render."""
        with self._lock:
            if self._closed:
                raise RenderWorkerError("the render worker is closed")
            if self._in_process:
                return rendering.render(self.world.current, request)
            try:
                conn = self._connection()
                if self._sent is not self.world.current:
                    self._sent = self.world.current
                    conn.send(self._sent)
                buffer = self._shared_buffer(request.nbytes)
                conn.send((request, self._buffer_size))
                if not conn.poll(ANSWER_TIMEOUT_S):
                    raise RenderWorkerError(f"no answer within {ANSWER_TIMEOUT_S:g} s")
                answer = conn.recv()
                if not isinstance(answer, Exception):
                    answer = _images(request, answer, buffer)
            except (OSError, EOFError, RenderWorkerError) as exc:
                reason = str(exc) or type(exc).__name__
                answered, self._answered = self._answered, False
                self._discard()
                if answered:  # it worked before: the next render starts a new one
                    raise RenderWorkerError(f"render worker failed ({reason})") from exc
                LOG.error("the render worker does not start (%s); rendering in the server process", reason)
                self._in_process = True
                return rendering.render(self.world.current, request)
            self._answered = True
        if isinstance(answer, Exception):
            raise answer
        return answer

    def close(self) -> None:
        """Stop the child (it exits on end of file) and wait for it."""
        with self._lock:
            self._closed = True
            self._discard()
            self._buffer = None  # unmapped when the last view of it goes
            if self._buffer_fd is not None:
                os.close(self._buffer_fd)
                self._buffer_fd = None

    def _shared_buffer(self, size: int) -> memoryview:
        """The shared image buffer, grown (never shrunk) to hold `size` bytes (call with the lock held)."""
        assert self._buffer_fd is not None  # made with the child
        if size > self._buffer_size or self._buffer is None:
            self._buffer_size = max(size, self._buffer_size, mmap.PAGESIZE)
            os.ftruncate(self._buffer_fd, self._buffer_size)
            self._buffer = mmap.mmap(self._buffer_fd, self._buffer_size)
        return memoryview(self._buffer)

    # -- the child process

    def _connection(self) -> Connection:
        if self._conn is not None and self._proc is not None and self._proc.poll() is None:
            return self._conn
        if self._proc is not None:
            code = self._proc.poll()
            LOG.warning("render worker %d exited (code %s); starting a new one", self._proc.pid, code)
            self._discard()
        if self._buffer_fd is None:
            self._buffer_fd = os.memfd_create("airsim-mapper-render", 0)
        ours, theirs = socket.socketpair()
        # Blocking on both ends whatever socket.setdefaulttimeout says (rospy sets 60 s): a timeout makes the
        # descriptors non-blocking, and Connection's plain reads then fail with EAGAIN between requests.
        ours.setblocking(True)
        theirs.setblocking(True)
        try:
            self._proc = subprocess.Popen(
                _command(theirs.fileno(), self.nice, self._buffer_fd),
                pass_fds=(theirs.fileno(), self._buffer_fd),
                stdin=subprocess.DEVNULL,
                env=_child_env(),
                start_new_session=self.nice > 0,  # its own autogroup (see `lower_priority`)
            )
        except OSError as exc:
            ours.close()
            raise RenderWorkerError(f"cannot start the render worker: {exc}") from exc
        finally:
            theirs.close()
        self.starts += 1
        self._answered = False
        self._conn = Connection(ours.detach())
        self._sent = self.world.current
        self._conn.send(self._sent)
        return self._conn

    def _discard(self) -> None:
        """Close our end (the child then exits) and reap the child, killing it if it lingers."""
        if self._conn is not None:
            self._conn.close()
            self._conn = None
        proc, self._proc = self._proc, None
        if proc is not None:
            try:
                proc.wait(timeout=2.0)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


def _command(fd: int, nice: int, buffer_fd: int) -> list[str]:
    return [sys.executable, "-m", __name__, str(fd), str(nice), str(buffer_fd)]


def _images(
    request: RenderRequest, made: dict[int, tuple[str, int, int]], buffer: memoryview
) -> dict[int, RenderedImage]:
    """The images the child wrote into the shared buffer, as views of it: valid until the next render."""
    layout = request.layout()
    out = {}
    for kind, (encoding, width, height) in made.items():
        _, offset, size = layout[kind]
        out[kind] = RenderedImage(encoding, width, height, buffer[offset : offset + size])
    return out


def _child_env() -> dict[str, str]:
    """This environment with the directory holding this package first on PYTHONPATH (a checkout works)."""
    env = dict(os.environ)
    root = str(Path(__file__).resolve().parents[3])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH", "")) if p)
    return env


def lower_priority(nice: int, autogroup: Path = AUTOGROUP) -> int:
    """Add `nice` to this process's nice value, and give its autogroup the result; returns the result.

    With autogroup scheduling (`kernel.sched_autogroup_enabled`, on by default) the kernel first shares
    the CPU between sessions, and a task's nice value only ranks it within its own session. A worker at
    nice +10 in the server's session still took its whole session's share from every other session, and
    nice-0 processes elsewhere waited for their CPU while it ran (docs/reliability.md has the scheduler
    trace). The worker therefore runs in a session of its own (the server starts it with a new session when
    `nice` > 0), and sets that session's autogroup to its nice value, so it yields to every process on the
    machine. Without autogroup support the file is missing and the task's nice value does the same job.
    """
    result = os.nice(nice)
    if nice > 0 and autogroup.exists() and not set_autogroup_nice(autogroup, result):
        LOG.warning(
            "render worker: could not set its autogroup to nice %d; it may slow other processes", result
        )
    return result


def set_autogroup_nice(path: Path, nice: int, attempts: int = 20, pause_s: float = 0.1) -> bool:
    """Write `nice` to an autogroup file; False if it could not be done.

    Without CAP_SYS_ADMIN the kernel allows one autogroup write per 100 ms on the whole machine and
    answers the next with EAGAIN, so a busy moment (two servers starting) is waited out.
    """
    for _ in range(attempts):
        try:
            path.write_text(f"{nice}\n")
            return True
        except BlockingIOError:
            time.sleep(pause_s)
        except OSError:  # a nice value below 0 without the privilege for it
            return False
    return False


def serve(conn: Connection, nice: int, buffer_fd: int) -> None:
    """The child's loop: the world first, then one answer per request until end of file (a new world
    replaces the old one, unanswered)."""
    lower_priority(nice)
    world: World = conn.recv()
    mapped: tuple[int, memoryview] | None = None  # the shared buffer's size and view, as last mapped
    while True:
        try:
            message = conn.recv()
        except EOFError:
            return
        if isinstance(message, World):
            world = message
            continue
        request, size = message
        try:
            if mapped is None or mapped[0] != size:
                mapped = (size, memoryview(mmap.mmap(buffer_fd, size)))
            images = rendering.render(world, request, mapped[1])
            answer: object = {k: (image.encoding, image.width, image.height) for k, image in images.items()}
            del images  # views of the buffer
        except CameraError as exc:
            answer = exc
        except Exception as exc:  # a bug in the renderer: the server logs it, the worker stays up
            answer = RenderWorkerError(f"render failed: {exc!r}")
        conn.send(answer)


def main(argv: Sequence[str]) -> int:
    from airsim_mapper.common.tuning import limit_blas_threads

    # a signal meant for the server (its group, when nice is 0) must not stop us first: the server finishes
    # its render and then closes our end
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    limit_blas_threads(1)
    serve(Connection(int(argv[0])), int(argv[1]), int(argv[2]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
