"""StreamHub: detaching a bridge's handler really detaches it, and the last one leaves the simulator."""

from __future__ import annotations

import threading

from airsim_mapper.engine.hub import StreamHub


class RecordingLink:
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
        self.seen = threading.Event()

    def handle(self, _message) -> None:
        self.seen.set()


def test_detaching_with_a_fresh_bound_method_detaches_and_the_last_one_unsubscribes() -> None:
    sim = RecordingLink()
    hub = StreamHub(sim, lambda _tf: None)
    first, second = Bridge(), Bridge()
    hub.attach("/t", first.handle)
    hub.attach("/t", second.handle)
    assert len(sim.callbacks["/t"]) == 1  # one simulator subscription per topic
    stream = hub.streams()["/t"]
    sim.callbacks["/t"][0](None, {})
    assert first.seen.wait(5) and second.seen.wait(5)
    hub.detach("/t", second.handle)  # a new bound method object, equal to the attached one
    assert stream.handlers == [first.handle]
    hub.detach("/t", first.handle)
    assert "/t" not in hub.streams() and sim.callbacks["/t"] == []  # unsubscribed from the simulator


class SlowUnsubscribeSim(RecordingLink):
    """A simulator whose unsubscribe service call is in flight until released, as over a slow link."""

    def __init__(self) -> None:
        super().__init__()
        self.in_flight, self.release = threading.Event(), threading.Event()
        self.order: list[str] = []

    def subscribe(self, topic: str, callback) -> None:
        self.order.append("subscribe")
        super().subscribe(topic, callback)

    def unsubscribe(self, topic: str, callback) -> None:
        self.in_flight.set()
        assert self.release.wait(5)
        self.order.append("unsubscribe")
        super().unsubscribe(topic, callback)


def test_an_attach_waits_for_an_unsubscribe_in_flight_so_the_server_sees_them_in_order() -> None:
    """Subscribe (a topics frame) must not overtake unsubscribe (a service call) for the same topic:
    the server would apply the unsubscribe last and the new bridge would never get a message."""
    sim = SlowUnsubscribeSim()
    hub = StreamHub(sim, lambda _tf: None)
    image, info = Bridge(), Bridge()
    hub.attach("/cam", image.handle)
    leaving = threading.Thread(target=hub.detach, args=("/cam", image.handle))
    leaving.start()
    assert sim.in_flight.wait(5)
    coming = threading.Thread(target=hub.attach, args=("/cam", info.handle))
    coming.start()
    coming.join(0.2)
    assert coming.is_alive() and sim.order == ["subscribe"]  # held back while the unsubscribe is out
    hub.attach("/other", image.handle)  # other topics are not held up
    sim.release.set()
    leaving.join(5)
    coming.join(5)
    assert sim.order == ["subscribe", "subscribe", "unsubscribe", "subscribe"]  # /cam, /other, /cam, /cam
    assert hub.streams()["/cam"].handlers == [info.handle] and len(sim.callbacks["/cam"]) == 1


def test_every_streams_stamps_reach_the_time_watch_and_a_new_session_forgets_the_newest() -> None:
    sim, seen = RecordingLink(), []
    hub = StreamHub(sim, lambda _tf: None, on_stamp=lambda stamp, _now, _topic: seen.append(stamp))
    bridges = [Bridge(), Bridge()]
    hub.attach("/a", bridges[0].handle)
    hub.attach("/b", bridges[1].handle)
    for topic, stamps in (("/a", (50, 60)), ("/b", (55, 65))):
        for stamp in stamps:
            sim.callbacks[topic][0](None, {"time_stamp": stamp})
    assert seen == [60, 65] and hub.sim_now() == 65
    hub.forget_stamps()  # the stale filter of a lazy bridge attaching now waits for no old time
    assert hub.sim_now() == 0
    for bridge in bridges:
        hub.detach("/a" if bridge is bridges[0] else "/b", bridge.handle)
