"""The topic hub's last-value cache: offered samples are made only when someone asks, and a subscriber
gets the newest one."""

from __future__ import annotations

import time

import pynng
import pytest
from harness import free_port

from airsim_mapper.simserver.wire import protocol
from airsim_mapper.simserver.wire.topics import TopicHub, TopicInfo

PATH = "/Sim/S/robots/R/sensors/Airspeed/airspeed"


@pytest.fixture
def hub():
    hub = TopicHub("127.0.0.1", free_port())
    hub.start()
    hub.set_table([TopicInfo(PATH, message_type="airspeed")], {})
    sent: list[tuple[str, dict]] = []
    hub._send = lambda path, frame: sent.append((path, protocol.decode_body(frame.body)))  # no socket traffic
    hub.sent = sent
    yield hub
    hub.stop()


class Maker:
    """A sample maker that counts its calls."""

    def __init__(self, stamp: int) -> None:
        self.stamp, self.calls = stamp, 0

    def __call__(self) -> dict:
        self.calls += 1
        return {"time_stamp": self.stamp}


def test_an_offer_nobody_listens_to_is_never_made(hub):
    makers = [Maker(t) for t in range(5)]
    assert [hub.offer(PATH, m) for m in makers] == [False] * 5
    assert [m.calls for m in makers] == [0] * 5 and hub.sent == []


def test_a_new_subscriber_gets_the_newest_offer_made_once(hub):
    older, newest = Maker(1), Maker(2)
    hub.offer(PATH, older)
    hub.offer(PATH, newest)
    hub._subscribe(PATH)
    assert hub.sent == [(PATH, {"time_stamp": 2})]
    assert protocol.decode_body(hub.cached(PATH)) == {"time_stamp": 2}
    assert (older.calls, newest.calls) == (0, 1)  # made for the subscriber, cached from then on


def test_offers_to_a_subscribed_topic_are_made_and_sent_in_order(hub):
    hub._subscribe(PATH)
    assert [hub.offer(PATH, Maker(t)) for t in (5, 6)] == [True, True]
    assert hub.sent == [(PATH, {"time_stamp": 5}), (PATH, {"time_stamp": 6})]


def test_reading_the_cache_makes_an_offered_sample(hub):
    hub.offer(PATH, Maker(7))
    assert protocol.decode_body(hub.cached(PATH)) == {"time_stamp": 7}


def test_a_maker_that_fails_on_subscribe_is_logged_and_the_subscription_stands(hub, caplog):
    def broken() -> dict:
        raise ValueError("no geometry")

    hub.offer(PATH, broken)
    hub._subscribe(PATH)
    assert "could not make the last sample of " + PATH in caplog.text and hub.sent == []
    assert hub.is_subscribed(PATH) and hub.cached(PATH) is None
    hub.offer(PATH, Maker(8))  # the next sample reaches the subscriber
    assert hub.sent == [(PATH, {"time_stamp": 8})]


def test_unknown_topics_are_refused(hub):
    assert hub.offer("/nope", Maker(1)) is False and hub.cached("/nope") is None


def test_an_idle_hub_takes_a_clients_subscription_and_stops_within_its_wait(hub):
    """The hub's receive loop waits for client frames in the kernel (`MessageWait`), not on NNG's timer."""
    with pynng.Pair0(dial=hub.url, send_timeout=5000) as client:
        time.sleep(1.0)  # ten waits without a frame
        client.send(protocol.encode_frame(PATH, b"", protocol.FrameType.SUBSCRIBE))
        deadline = time.monotonic() + 5
        while not hub.is_subscribed(PATH) and time.monotonic() < deadline:
            time.sleep(0.01)
        assert hub.is_subscribed(PATH)
    assert hub._socket.recv_timeout == -1  # no NNG receive timer
    start = time.monotonic()
    hub.stop()
    assert not hub._thread.is_alive() and time.monotonic() - start < 1.5  # one 100 ms wait, a busy host
