"""The render worker: the same images as an in-process render, from a nicer child that survives faults."""

from __future__ import annotations

import logging
import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest
from harness import wait_until

from airsim_mapper.simserver.render import camera_model, raycast_renderer, render_worker, rendering
from airsim_mapper.simserver.render.camera_model import RenderRequest
from airsim_mapper.simserver.render.render_worker import (
    RENDER_NICE,
    RenderWorker,
    RenderWorkerError,
    set_autogroup_nice,
)
from airsim_mapper.simserver.world.world_file import load_world
from simserver.clientkit import load_world as load_scene

pytestmark = pytest.mark.live  # the render worker is a child process

POSITION = np.array([-8.0, 0.0, -12.0])
ORIENTATION = np.array([0.9914, 0.0, -0.1305, 0.0])


def nice_of(pid: int) -> int:
    return int(Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()[16])


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()[0]
    except FileNotFoundError:
        return False
    return state != "Z"


@pytest.fixture
def worker():
    rw = RenderWorker(load_world())
    yield rw
    rw.close()


def test_the_worker_renders_every_type_byte_for_byte_like_an_in_process_render(worker):
    types = list(camera_model.IMAGE_TYPES)
    got = worker.render(RenderRequest(POSITION, ORIENTATION, 160, 120, 90.0, types, 30.0))
    want = rendering.render(load_world(), RenderRequest(POSITION, ORIENTATION, 160, 120, 90.0, types, 30.0))
    assert sorted(got) == types
    for kind in types:
        assert got[kind] == want[kind], f"image type {kind} differs"


def test_a_default_socket_timeout_does_not_make_the_worker_fail_between_requests():
    import socket

    # rospy sets a 60 s default timeout in every node; sockets made then are non-blocking underneath
    previous = socket.getdefaulttimeout()
    socket.setdefaulttimeout(60.0)
    rw = RenderWorker(load_world())
    try:
        rw.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0]))
        pid = rw.pid
        time.sleep(0.3)  # the child waits for its next request: a non-blocking read would fail here
        assert alive(pid)
        rw.render(
            RenderRequest(POSITION, ORIENTATION, 320, 240, 90.0, list(camera_model.IMAGE_TYPES))
        )  # large answers too
        assert (rw.pid, rw.restarts) == (pid, 0)
    finally:
        socket.setdefaulttimeout(previous)
        rw.close()


def test_the_worker_starts_on_the_first_render_at_a_lower_priority_and_stops_on_close(worker):
    assert worker.pid is None
    worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0]))
    pid = worker.pid
    assert nice_of(pid) == min(19, os.nice(0) + RENDER_NICE)
    worker.close()
    assert not alive(pid)
    with pytest.raises(RenderWorkerError, match="closed"):
        worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0]))


def test_a_bad_request_raises_its_camera_error_and_the_worker_stays_up(worker):
    worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0]))
    pid = worker.pid
    with pytest.raises(camera_model.CameraError, match="image size must be positive"):
        worker.render(RenderRequest(POSITION, ORIENTATION, 0, 24, 90.0, [0]))
    with pytest.raises(camera_model.CameraError, match="unknown image type 9"):
        worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [9]))
    assert worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [1]))[1].encoding == "16FC1"
    assert worker.pid == pid and worker.restarts == 0


def test_a_killed_worker_is_replaced_on_the_next_render_with_a_warning(worker, caplog):
    worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0]))
    first = worker.pid
    os.kill(first, signal.SIGKILL)
    wait_until(lambda: worker._proc.poll() is not None, 5.0, what="the worker to die")
    with caplog.at_level(logging.WARNING, logger=render_worker.LOG.name):
        image = worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0]))[0]
    assert (image.width, image.height, len(image.data)) == (32, 24, 32 * 24 * 3)
    assert worker.pid != first and worker.restarts == 1
    assert f"render worker {first} exited (code -9); starting a new one" in caplog.text


def test_a_hung_worker_is_killed_after_the_answer_timeout_and_then_replaced(worker, monkeypatch):
    worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0]))  # started (slow on a busy machine)
    monkeypatch.setattr(render_worker, "ANSWER_TIMEOUT_S", 0.5)
    hung = worker.pid
    os.kill(hung, signal.SIGSTOP)
    start = time.monotonic()
    with pytest.raises(RenderWorkerError, match=r"no answer within 0\.5 s"):
        worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0]))
    assert time.monotonic() - start < 5.0
    assert not alive(hung)
    assert worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0]))[0].width == 32
    assert worker.pid != hung


def children(pid: int) -> list[int]:
    found = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        text = (task / "children").read_text().split()
        found += [int(c) for c in text]
    return found


@pytest.mark.parametrize("in_process", [False, True])
def test_the_server_renders_in_a_nicer_child_unless_told_to_render_in_process(launcher, in_process):
    from projectairsim import Drone

    server = launcher.simserver(*(["--render-in-process"] if in_process else []))
    client = server.client()
    try:
        world = load_scene(client, "scene_basic_drone.jsonc")
        images = Drone(client, world, "Drone1").get_images("DownCamera", [0, 2])
        assert set(images) == {0, 2}
        kids = children(server.process.popen.pid)
        if in_process:
            assert kids == []
        else:
            assert len(kids) == 1
            nice = min(19, nice_of(server.process.popen.pid) + RENDER_NICE)
            assert nice_of(kids[0]) == nice
            # its own session, so its nice value also holds against other sessions (autogroup scheduling)
            assert os.getsid(kids[0]) == kids[0] != os.getsid(server.process.popen.pid)
            if Path("/proc/self/autogroup").exists():
                group = Path(f"/proc/{kids[0]}/autogroup").read_text().split()
                assert group[0] != Path(f"/proc/{server.process.popen.pid}/autogroup").read_text().split()[0]
                assert group[1:] == ["nice", str(nice)]
            assert (
                b"airsim_mapper.simserver.render.render_worker"
                in Path(f"/proc/{kids[0]}/cmdline").read_bytes()
            )
    finally:
        client.disconnect()
    if not in_process:  # SIGTERM to the server: it stops, and its renderer exits on end of file
        server.process.popen.send_signal(signal.SIGTERM)
        assert server.process.popen.wait(timeout=10.0) == 0
        wait_until(lambda: not alive(kids[0]), 5.0, what="the render worker to exit after its server")
        assert "sensor step failed" not in server.process.output()


def test_a_worker_that_cannot_start_is_reported_once_and_the_server_renders_in_process(
    worker, monkeypatch, caplog
):
    monkeypatch.setattr(render_worker, "_command", lambda fd, nice, buffer_fd: ["/bin/false"])
    with caplog.at_level(logging.ERROR, logger=render_worker.LOG.name):
        first = worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0, 3]))
        second = worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0, 3]))
    want = rendering.render(load_world(), RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0, 3]))
    assert first == want and second == want
    assert caplog.text.count("the render worker does not start") == 1
    assert worker.starts == 1 and worker.pid is None


def test_a_replacement_that_cannot_start_falls_back_to_rendering_in_process(worker, monkeypatch, caplog):
    worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0]))
    first = worker.pid
    monkeypatch.setattr(render_worker, "_command", lambda fd, nice, buffer_fd: ["/bin/false"])
    os.kill(first, signal.SIGKILL)
    wait_until(lambda: worker._proc.poll() is not None, 5.0, what="the worker to die")
    with caplog.at_level(logging.WARNING, logger=render_worker.LOG.name):
        image = worker.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [3]))[3]
    assert image == rendering.render(load_world(), RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [3]))[3]
    assert "the render worker does not start" in caplog.text and worker.starts == 2


class FlakyAutogroup:
    """An autogroup file that answers EAGAIN `busy` times (the kernel's limit for unprivileged writers)."""

    def __init__(self, busy: int, error: OSError | None = None) -> None:
        self.busy, self.error, self.written = busy, error, []

    def write_text(self, text: str) -> None:
        if self.error is not None:
            raise self.error
        if self.busy:
            self.busy -= 1
            raise BlockingIOError(11, "Resource temporarily unavailable")
        self.written.append(text)


def test_the_autogroup_write_waits_out_the_kernels_rate_limit_and_reports_a_refusal():
    flaky = FlakyAutogroup(busy=3)
    assert set_autogroup_nice(flaky, 10, pause_s=0.0) and flaky.written == ["10\n"]
    assert not set_autogroup_nice(FlakyAutogroup(busy=99), 10, attempts=5, pause_s=0.0)
    assert not set_autogroup_nice(FlakyAutogroup(0, PermissionError(1, "Operation not permitted")), -5)


def test_a_worker_at_the_servers_priority_stays_in_the_servers_session():
    rw = RenderWorker(load_world(), nice=0)
    try:
        rw.render(RenderRequest(POSITION, ORIENTATION, 32, 24, 90.0, [0]))
        assert os.getsid(rw.pid) == os.getsid(0)
        assert nice_of(rw.pid) == nice_of(os.getpid())
    finally:
        rw.close()


@pytest.mark.parametrize("renderer", ["gl", "raycast"])
def test_the_server_renders_with_gl_in_its_worker_unless_told_to_ray_cast(launcher, renderer):
    from projectairsim import Drone

    server = launcher.simserver(*(["--renderer", "raycast"] if renderer == "raycast" else []))
    client = server.client()
    try:
        world = load_scene(client, "scene_basic_drone.jsonc")
        assert set(Drone(client, world, "Drone1").get_images("DownCamera", [0, 2])) == {0, 2}
        (kid,) = children(server.process.popen.pid)
        maps = Path(f"/proc/{kid}/maps").read_text()
        assert ("libEGL" in maps) == (renderer == "gl")
    finally:
        client.disconnect()


def test_a_worker_without_opengl_ray_casts_and_says_so_once(monkeypatch, capfd):
    monkeypatch.setenv("AIRSIM_MAPPER_GL_BACKEND", "no-such-backend")  # the child cannot make a context
    monkeypatch.setenv(rendering.RENDERER_ENV, "gl")
    rw = RenderWorker(load_world())
    try:
        types = list(camera_model.IMAGE_TYPES)
        got = [rw.render(RenderRequest(POSITION, ORIENTATION, 64, 48, 90.0, types, 30.0)) for _ in range(2)]
        want = raycast_renderer.render_raycast(
            load_world(), RenderRequest(POSITION, ORIENTATION, 64, 48, 90.0, types, 30.0)
        )
        assert got[0] == want and got[1] == want
        assert rw.restarts == 0
    finally:
        rw.close()
    said = capfd.readouterr().err  # the child's log goes to the server's stderr
    assert said.count("rendering with the numpy ray caster") == 1, said
