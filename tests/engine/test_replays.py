"""LatchedReplays: a latched message re-sent on a new connection is a replay; a new message is not."""

from __future__ import annotations

from airsim_mapper.engine.replays import LatchedReplays


def header(caller: str = "/rostopic_1", latching: str = "1") -> dict[str, str]:
    """A fresh connection's header, as rospy makes one dict per connection."""
    return {"callerid": caller, "latching": latching, "topic": "/load_scene"}


def test_a_latched_message_replayed_on_a_new_connection_is_a_replay() -> None:
    replays = LatchedReplays()
    assert not replays.is_replay(header(), "a.jsonc")
    assert replays.is_replay(header(), "a.jsonc")  # the subscriber re-connected: the same message again
    assert replays.is_replay(header(), "a.jsonc")
    assert replays.replays == 2


def test_new_messages_are_not_replays() -> None:
    replays = LatchedReplays()
    first = header()
    assert not replays.is_replay(first, "a.jsonc")
    assert not replays.is_replay(first, "a.jsonc")  # published again on the same connection, on purpose
    assert not replays.is_replay(header(), "b.jsonc")  # a new payload on a new connection
    assert not replays.is_replay(header("/rostopic_2"), "b.jsonc")  # another publisher (a second pub -1)
    assert not replays.is_replay(header(latching="0"), "b.jsonc")  # not latched: never replayed
    assert not replays.is_replay(None, "b.jsonc")  # made in-process, no connection
    assert replays.replays == 0


def test_publishers_are_remembered_up_to_the_limit() -> None:
    replays = LatchedReplays(size=2)
    for caller in ("/a", "/b", "/c"):
        replays.is_replay(header(caller), "x")
    assert not replays.is_replay(header("/a"), "x")  # forgotten: acted on again rather than lost
    assert replays.is_replay(header("/c"), "x")
