"""The bench's receive proxy: heavy frames rewritten to placeholders and resolved, all else byte for byte."""

from __future__ import annotations

import threading
import time
from typing import Any

import msgpack
import numpy as np
import pytest
from framekit import LIDAR_TOPIC, client_decode, image_frame, lidar_frame

from tools.bench.recv_proxy import (
    ExpiredFrameError,
    FastFrames,
    NotConnectedError,
    RecvProxy,
    install,
    placeholder_frame,
)


def everything_heavy(**options: Any) -> FastFrames:
    return FastFrames(lambda topic: True, min_bytes=options.pop("min_bytes", 0), **options)


def through(fast: FastFrames, frame: bytes) -> tuple[str, Any]:
    """A frame through the proxy, the client's own decoding, and resolve: what a bridge handler gets."""
    topic, message = client_decode(fast.rewrite(frame))
    return topic, fast.resolve(message)


def test_a_lidar_frame_through_the_proxy_equals_the_clients_message_with_numpy_arrays():
    frame = lidar_frame()
    expected_topic, expected = client_decode(frame)
    topic, message = through(everything_heavy(), frame)
    assert topic == expected_topic == LIDAR_TOPIC and list(message) == list(expected)
    np.testing.assert_array_equal(message["point_cloud"], np.asarray(expected["point_cloud"], np.float32))


def test_a_body_that_is_not_a_map_passes_through():
    fast = everything_heavy()
    frame = msgpack.packb([2, "/t", msgpack.packb(list(range(100)), use_bin_type=True)], use_bin_type=True)
    assert fast.rewrite(frame) is frame
    assert fast.stats.fallback == 1


def test_a_truncated_body_falls_back_to_the_clients_path():
    fast = everything_heavy()
    good = lidar_frame(points=200)
    body = msgpack.unpackb(good, raw=True)[2]
    frame = msgpack.packb([2, LIDAR_TOPIC, body[:-10]], use_bin_type=True)
    assert fast.rewrite(frame) is frame
    assert fast.stats.fallback == 1


# ------------------------------------------------------------------------------------------ pass-through


def test_small_frames_other_frame_types_and_non_heavy_topics_pass_through_byte_for_byte():
    fast = FastFrames(lambda topic: topic == LIDAR_TOPIC, min_bytes=1024)
    small = msgpack.packb([2, LIDAR_TOPIC, msgpack.packb({"time_stamp": 1})], use_bin_type=True)
    subscribe = msgpack.packb([0, LIDAR_TOPIC, b"x" * 4096], use_bin_type=True)
    other = image_frame("/not/heavy")
    for frame in (small, subscribe, other, b"\x00garbage"):
        assert fast.rewrite(frame) is frame
    assert fast.stats.passthrough == 4
    assert fast.stats.fast == 0


def test_a_predicate_that_raises_means_not_heavy():
    def broken(_topic: str) -> bool:
        raise KeyError("no such topic")

    fast = FastFrames(broken, min_bytes=0)
    frame = lidar_frame(points=100)
    assert fast.rewrite(frame) is frame


# ------------------------------------------------------------------------------------------ side table


def test_resolve_returns_other_messages_unchanged():
    fast = everything_heavy()
    for message in ({"time_stamp": 1}, {"__fast__": "not-an-int"}, [1, 2], None):
        assert fast.resolve(message) is message


def test_a_placeholder_resolves_once_and_then_says_it_expired():
    fast = everything_heavy()
    _, placeholder = client_decode(fast.rewrite(lidar_frame(points=100)))
    assert fast.resolve(placeholder)["time_stamp"] == 1_700_000_000_123_456_789
    with pytest.raises(ExpiredFrameError, match=r"fast frames: frame \d+ expired or was already resolved"):
        fast.resolve(placeholder)
    assert fast.stats.resolved == 1


def test_unresolved_entries_expire_after_their_ttl():
    fast = everything_heavy(ttl_s=0.05)
    _, placeholder = client_decode(fast.rewrite(lidar_frame(points=100)))
    assert fast.pending() == 1
    time.sleep(0.08)
    assert fast.pending() == 0
    assert fast.stats.expired == 1
    with pytest.raises(ExpiredFrameError, match="expired or was already resolved"):
        fast.resolve(placeholder)


def test_at_most_per_topic_entries_wait_for_one_topic():
    fast = everything_heavy(per_topic=2)
    placeholders = [client_decode(fast.rewrite(lidar_frame(points=100, seed=i)))[1] for i in range(5)]
    assert fast.pending() == 2
    assert fast.stats.expired == 3
    with pytest.raises(ExpiredFrameError, match="expired"):
        fast.resolve(placeholders[0])
    assert fast.resolve(placeholders[-1])["point_cloud"].size == 300


def test_concurrent_rewrites_and_resolves_lose_nothing():
    fast = everything_heavy(per_topic=10_000, ttl_s=60.0)
    frame = lidar_frame(points=100)
    placeholders: list[Any] = []
    lock = threading.Lock()

    def produce() -> None:
        for _ in range(200):
            _, placeholder = client_decode(fast.rewrite(frame))
            with lock:
                placeholders.append(placeholder)

    threads = [threading.Thread(target=produce) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    keys = {p["__fast__"] for p in placeholders}
    assert len(keys) == 800
    resolved = [fast.resolve(p) for p in placeholders]
    assert all(r["point_cloud"].size == 300 for r in resolved)
    assert fast.pending() == 0


def test_the_placeholder_frame_is_a_message_frame_the_client_accepts():
    topic, message = client_decode(placeholder_frame("/a/b", 42))
    assert (topic, message) == ("/a/b", {"__fast__": 42})


# ------------------------------------------------------------------------------------------ installation


class FakeSocket:
    """Stands in for a pynng socket in these unit tests (the real client is exercised below)."""

    def __init__(self, frames: list[bytes]) -> None:
        self.frames = list(frames)
        self.recv_timeout = 0
        self.sent: list[bytes] = []

    def recv(self) -> bytes:
        return self.frames.pop(0)

    def send(self, data: bytes) -> None:
        self.sent.append(data)


class FakeClient:
    def __init__(self, socket: Any) -> None:
        self.socket_topics = socket


def test_install_wraps_the_topics_socket_and_forwards_everything_but_recv():
    frame = lidar_frame(points=100)
    real = FakeSocket([frame])
    client = FakeClient(real)
    fast = install(client, lambda topic: True, min_bytes=0)
    assert isinstance(client.socket_topics, RecvProxy)
    client.socket_topics.recv_timeout = 100
    client.socket_topics.send(b"subscribe")
    assert (real.recv_timeout, real.sent) == (100, [b"subscribe"])
    _, placeholder = client_decode(client.socket_topics.recv())
    assert fast.resolve(placeholder)["point_cloud"].dtype == np.float32


def test_install_is_idempotent_and_uninstall_restores_the_real_socket():
    real = FakeSocket([])
    client = FakeClient(real)
    first = install(client, lambda topic: True)
    assert install(client, lambda topic: False) is first
    first.uninstall()
    assert client.socket_topics is real
    first.uninstall()
    assert client.socket_topics is real


def test_install_on_an_unconnected_client_says_to_connect_first():
    with pytest.raises(NotConnectedError, match=r"no topics socket; call client.connect\(\) first"):
        install(FakeClient(None), lambda topic: True)


# ------------------------------------------------------------------------------------------ real client


@pytest.mark.live
def test_the_real_client_delivers_fast_lidar_and_identical_images_through_the_proxy(launcher):
    from simserver.clientkit import Inbox, load_world

    client = launcher.simserver().client()
    try:
        load_world(client, "scene_drone_sensors.jsonc")
        prefix = "/Sim/SceneDroneSensors/robots/Drone1"
        lidar_topic, image_topic = (
            f"{prefix}/sensors/lidar1/lidar",
            f"{prefix}/sensors/DownCamera/scene_camera",
        )
        fast = install(client, lambda topic: topic in (lidar_topic, image_topic))
        lidar, images, poses = Inbox(), Inbox(), Inbox()
        # resolve on the receive thread, in the callback, as the engine's stream slots do
        client.subscribe(lidar_topic, lambda t, m: lidar(t, fast.resolve(m)))
        client.subscribe(image_topic, lambda t, m: images(t, fast.resolve(m)))
        client.subscribe(f"{prefix}/actual_pose", poses)
        scan = lidar.wait_for(1, timeout=10.0)[0]
        fast_image = images.wait_for(1, timeout=10.0)[0]
        assert isinstance(scan["point_cloud"], np.ndarray) and scan["point_cloud"].dtype == np.float32
        assert scan["point_cloud"].size == 3 * len(scan["laser_index_cloud"]) > 0
        assert "__fast__" not in poses.wait_for(1, timeout=5.0)[0]  # small topics are untouched
        assert isinstance(fast_image["data"], bytes)
        fast.uninstall()
        plain = Inbox()
        client.subscribe(image_topic, plain)  # a second callback, seeing only frames read after uninstall
        plain_image = plain.wait_for(1, timeout=10.0, where=lambda m: "__fast__" not in m)[0]
        assert fast_image.keys() == plain_image.keys()
        assert fast_image["data"] == plain_image["data"]  # the drone is at rest: the same picture
        assert fast.stats.fast >= 2
    finally:
        client.disconnect()
