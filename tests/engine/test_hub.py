"""StreamHub: detaching a bridge's handler really detaches it, and the last one leaves the simulator."""

from __future__ import annotations

import threading

from airsim_mapper.engine.hub import StreamHub


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
        self.seen = threading.Event()

    def handle(self, _message) -> None:
        self.seen.set()


def test_detaching_with_a_fresh_bound_method_detaches_and_the_last_one_unsubscribes() -> None:
    sim = FakeSim()
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
