"""StreamHub: light handlers run inline on the receive thread, and detaching really detaches."""

from __future__ import annotations

import threading

from airsim_mapper.convert.catalog import CONVERTERS, LIGHT, SIM_TO_ROS
from airsim_mapper.engine.hub import StreamHub
from airsim_mapper.engine.streams import Stream


class FakeSim:
    """Records the hub's subscriptions (the part of SimLink the hub uses)."""

    def __init__(self) -> None:
        self.callbacks: dict[str, list] = {}

    def subscribe(self, topic: str, callback) -> None:
        self.callbacks.setdefault(topic, []).append(callback)

    def unsubscribe(self, topic: str, callback) -> None:
        self.callbacks[topic].remove(callback)


class Bridge:
    """Hands out a fresh bound method on every access, as the real bridges do."""

    def __init__(self) -> None:
        self.threads: list[str] = []

    def handle(self, _message) -> None:
        self.threads.append(threading.current_thread().name)


def test_a_stream_of_light_handlers_runs_them_on_the_offering_thread() -> None:
    sim = FakeSim()
    hub = StreamHub(sim, lambda _tf: None)
    pose, odometry = Bridge(), Bridge()
    hub.attach("/pose", pose.handle, light=True)
    hub.attach("/pose", odometry.handle, light=True)
    stream = hub.streams()["/pose"]
    assert stream.inline
    for callback in sim.callbacks["/pose"]:
        callback(None, {"n": 1})
    here = threading.current_thread().name
    assert pose.threads == [here] and odometry.threads == [here]  # done before offer returned
    assert stream.stats.handled == 1
    hub.drop_all()


def test_one_heavy_handler_moves_the_stream_to_its_worker_and_leaving_moves_it_back() -> None:
    sim = FakeSim()
    hub = StreamHub(sim, lambda _tf: None)
    light, heavy = Bridge(), Bridge()
    hub.attach("/t", light.handle, light=True)
    hub.attach("/t", heavy.handle)
    stream = hub.streams()["/t"]
    assert not stream.inline
    sim.callbacks["/t"][0](None, {})
    stream_thread = "stream:/t"
    _wait(lambda: heavy.threads == [stream_thread] and light.threads == [stream_thread])
    hub.detach("/t", heavy.handle)  # a fresh bound method, equal to the attached one
    assert stream.handlers == [light.handle] and stream.inline
    hub.detach("/t", light.handle)
    assert "/t" not in hub.streams() and sim.callbacks["/t"] == []  # unsubscribed from the simulator


def test_inline_and_worker_runs_of_one_stream_never_overlap() -> None:
    inside, overlaps = [0], [0]
    lock = threading.Lock()
    release = threading.Event()

    def handler(message) -> None:
        with lock:
            inside[0] += 1
            overlaps[0] += inside[0] > 1
        if message == "first":
            release.wait(5)
        with lock:
            inside[0] -= 1

    stream = Stream("/t", None, [handler])
    try:
        stream.offer(None, "first")  # to the worker, which blocks in the handler
        _wait(lambda: inside[0] == 1)
        stream.inline = True  # as the hub does when the last heavy handler leaves
        threading.Timer(0.2, release.set).start()
        stream.offer(None, "second")  # inline: waits for the worker's run to finish
        assert overlaps[0] == 0 and release.is_set() and stream.stats.handled == 2
    finally:
        stream.stop()


def test_the_light_converters_exist_and_read_simulator_topics() -> None:
    for name in LIGHT:
        info = CONVERTERS[name]
        assert info.light and info.direction == SIM_TO_ROS and info.sim_kind == "topic"
    assert not any(CONVERTERS[n].light for n in ("image", "camera_info", "pointcloud", "radar_scan"))


def _wait(predicate, timeout: float = 5.0) -> None:
    done = threading.Event()
    for _ in range(int(timeout / 0.01)):
        if predicate():
            return
        done.wait(0.01)
    assert predicate()
