"""The node's topic connection watch (`ConnectionPoll`) finds a connection whose peer has gone, as
rospy's epoll does: a publisher that comes back at the same node URI must be connected again."""

from __future__ import annotations

import socket
from collections.abc import Iterator
from contextlib import contextmanager

import pytest
import rospy.topics
from std_msgs.msg import Empty

from airsim_mapper.engine.rospy_internals import ConnectionPoll


@contextmanager
def tcp_pair() -> Iterator[tuple[socket.socket, socket.socket]]:
    with socket.create_server(("127.0.0.1", 0)) as server:
        near = socket.create_connection(server.getsockname())
        far, _ = server.accept()
    with near, far:
        yield near, far


class Connection:
    """What rospy's topic asks of a connection: its socket, its endpoint and a cleanup callback."""

    def __init__(self, sock: socket.socket, endpoint_id: str) -> None:
        self.sock, self.endpoint_id, self.cleanup_cb = sock, endpoint_id, None

    def fileno(self) -> int:
        return self.sock.fileno()

    def set_cleanup_callback(self, callback) -> None:
        self.cleanup_cb = callback

    def close(self) -> None:
        pass


def test_a_peer_that_closed_is_reported_although_no_hang_up_is():
    with tcp_pair() as (near, far):
        poll = ConnectionPoll()
        poll.add_fd(near.fileno())
        assert list(poll.error_iter()) == []
        far.close()  # a FIN: POLLRDHUP on `near`, no POLLHUP until `near` closes too
        assert list(poll.error_iter()) == [near.fileno()]
        poll.remove_fd(near.fileno())
        assert list(poll.error_iter()) == []


def test_a_live_peer_is_not_reported_while_data_waits():
    with tcp_pair() as (near, far):
        poll = ConnectionPoll()
        poll.add_fd(near.fileno())
        far.sendall(b"x" * 100)
        assert list(poll.error_iter()) == []


@pytest.fixture
def topic(monkeypatch: pytest.MonkeyPatch) -> rospy.topics._TopicImpl:
    monkeypatch.setattr(rospy.topics, "Poller", ConnectionPoll)
    impl = rospy.topics._TopicImpl("/poll_check", Empty)
    yield impl
    impl.connections = []


def test_rospy_drops_the_gone_connection_before_it_connects_the_new_publisher(topic):
    """rospy runs `check_all` on every publisher update, then connects each URI it has no connection to."""
    uri = "http://test-host:40000/"
    with tcp_pair() as (near, far):
        topic.add_connection(Connection(near, uri))
        assert topic.has_connection(uri)
        far.close()  # the publisher unregistered; the same node registers it again at once
        topic.check()
        assert not topic.has_connection(uri)


def test_threads_may_poll_at_once_as_rospy_does():
    """rospy polls from its registration thread and, under the topic's lock, when a connection is added."""
    import threading

    errors: list[BaseException] = []
    with tcp_pair() as (near, far):
        poll = ConnectionPoll()
        poll.add_fd(near.fileno())
        far.close()

        def hammer() -> None:
            try:
                for _ in range(20000):
                    assert list(poll.error_iter()) == [near.fileno()]
            except BaseException as exc:  # a concurrent poll() raised
                errors.append(exc)

        threads = [threading.Thread(target=hammer) for _ in range(4)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
    assert errors == []
