"""The health probe's request: the real client's envelope on an NNG context of its own, answered or given
up within its timeout, leaving the socket's own timeouts alone."""

from __future__ import annotations

import threading
import time

import pynng
import pytest
from projectairsim import ProjectAirSimClient

from airsim_mapper.engine.health import PROBE_METHOD, answered_within
from airsim_mapper.simserver.wire.protocol import decode_request, encode_result


def client_of(address: str) -> ProjectAirSimClient:
    client = ProjectAirSimClient("127.0.0.1", 0, 0)
    client.request_id = client.request_id_generator()  # what connect() sets up besides the sockets
    client.socket_services = pynng.Req0(dial=address, recv_timeout=300000)
    return client


@pytest.mark.parametrize("answers", [True, False])
def test_the_probe_is_answered_or_given_up_within_its_timeout(tmp_path, answers):
    address, methods = f"ipc://{tmp_path}/services", []
    with pynng.Rep0(listen=address, recv_timeout=5000) as server:
        client = client_of(address)

        def serve() -> None:
            request = decode_request(server.recv())
            methods.append(request.method)
            if answers:
                server.send(encode_result(request.id, "hash"))

        thread = threading.Thread(target=serve, daemon=True)
        thread.start()
        start = time.monotonic()
        try:
            assert answered_within(client, 0.5) is answers
            assert time.monotonic() - start < 2.0
            assert methods == [PROBE_METHOD]
            assert client.socket_services.recv_timeout == 300000  # the client's own, left alone
        finally:
            thread.join(5)
            client.socket_services.close()


def test_a_client_without_a_services_socket_is_not_answered():
    client = ProjectAirSimClient("127.0.0.1", 0, 0)
    assert answered_within(client, 0.1) is False


def test_the_probe_encodes_with_the_encoder_it_is_given(tmp_path):
    """A link passes its own encoder, which numbers requests under its lock (SimLink._encode)."""
    address, encoded = f"ipc://{tmp_path}/services", []
    with pynng.Rep0(listen=address, recv_timeout=5000) as server:
        client = client_of(address)

        def encode(request: dict) -> bytes:
            encoded.append(request["method"])
            return client.preprocess_request(request)

        def serve() -> None:
            request = decode_request(server.recv())
            server.send(encode_result(request.id, "hash"))

        thread = threading.Thread(target=serve, daemon=True)
        thread.start()
        try:
            assert answered_within(client, 2.0, encode) is True
            assert encoded == [PROBE_METHOD]
        finally:
            thread.join(5)
            client.socket_services.close()
