"""A receive loop's wait for a message: in the kernel on NNG's receive descriptor, ended by a message within
its time, empty after it, and pynng's Closed once the socket is closed (no loop polls a dead descriptor)."""

from __future__ import annotations

import time

import pynng
import pytest

from airsim_mapper.common.nng_wait import MessageWait


def test_a_wait_is_empty_after_its_time_and_ready_with_a_message(tmp_path):
    address = f"ipc://{tmp_path}/wait"
    with pynng.Pair0(listen=address, send_timeout=5000) as server, pynng.Pair0(dial=address) as sock:
        ready = MessageWait(sock)
        start = time.monotonic()
        assert not ready(20) and time.monotonic() - start >= 0.015
        server.send(b"message")
        assert ready(5000)
        assert ready(0)  # still there until it is received
        assert sock.recv(block=False) == b"message"
        assert not ready(0)


def test_a_wait_on_a_closed_socket_is_pynngs_closed(tmp_path):
    sock = pynng.Pair0(listen=f"ipc://{tmp_path}/closed")
    ready = MessageWait(sock)
    sock.close()
    with pytest.raises(pynng.exceptions.Closed):
        ready(5000)
    with pytest.raises(pynng.exceptions.Closed):
        MessageWait(sock)
