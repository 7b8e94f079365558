"""A tiny misbehaving simulator for tests: Pair0 + Rep0 sockets that serve one scene, then feed each
subscribed topic a cycle of frames, good and malformed, at a fixed rate.

It speaks the wire protocol through the project's own codec (airsim_mapper.simserver.wire.protocol); only the
content of the frames is wrong, never the real server.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence

import msgpack
import pynng

from airsim_mapper.simserver.wire.protocol import (
    FrameType,
    decode_frame,
    decode_request,
    encode_frame,
    encode_result,
)

TOPICS = "/$topics"


class FakeSimServer:
    """Serve `scene_id`; every subscribed topic in `feeds` gets its frames in a cycle every `period` s."""

    def __init__(
        self,
        address: str,
        topics_port: int,
        services_port: int,
        scene_id: str,
        feeds: dict[str, Sequence[bytes]],
    ) -> None:
        self.scene_id = scene_id
        self.feeds = feeds
        self.subscribed: set[str] = set()
        self.sent = 0
        self.methods: list[str] = []
        self._stop = threading.Event()
        self.pair = pynng.Pair0(listen=f"tcp://{address}:{topics_port}", recv_timeout=50, send_timeout=500)
        self.rep = pynng.Rep0(listen=f"tcp://{address}:{services_port}", recv_timeout=50)
        self._threads = [
            threading.Thread(target=self._serve_requests, daemon=True),
            threading.Thread(target=self._serve_topics, daemon=True),
            threading.Thread(target=self._feed, daemon=True),
        ]
        for thread in self._threads:
            thread.start()

    def _reply(self, method: str) -> object:
        if method == "/Sim/LoadScene":
            return self.scene_id
        if method == "/Sim/GetBuildCommitHash":
            return "fakesim"
        return True

    def _serve_requests(self) -> None:
        while not self._stop.is_set():
            try:
                raw = self.rep.recv()
            except pynng.exceptions.Timeout:
                continue
            except pynng.exceptions.Closed:
                return
            request = decode_request(raw)
            self.methods.append(request.method)
            self.rep.send(encode_result(request.id, self._reply(request.method)))

    def _serve_topics(self) -> None:
        while not self._stop.is_set():
            try:
                frame = decode_frame(self.pair.recv())
            except pynng.exceptions.Timeout:
                continue
            except pynng.exceptions.Closed:
                return
            if frame.type == FrameType.SUBSCRIBE:
                self.subscribed.add(frame.topic)
                if frame.topic == TOPICS:
                    rows = [
                        {"path": t, "type": "published", "message_type": "", "frequency": 50}
                        for t in self.feeds
                    ]
                    self.pair.send(encode_frame(TOPICS, msgpack.packb(rows, use_bin_type=True)))
            elif frame.type == FrameType.UNSUBSCRIBE:
                self.subscribed.discard(frame.topic)

    def _feed(self, period: float = 0.02) -> None:
        step = 0
        while not self._stop.wait(period):
            for topic, frames in self.feeds.items():
                if topic in self.subscribed and frames:
                    try:
                        self.pair.send(frames[step % len(frames)])
                        self.sent += 1
                    except pynng.exceptions.NNGException:
                        pass
            step += 1

    def close(self) -> None:
        self._stop.set()
        for thread in self._threads:
            thread.join(timeout=2)
        self.pair.close()
        self.rep.close()


def message_frame(topic: str, message: object) -> bytes:
    return encode_frame(topic, msgpack.packb(message, use_bin_type=True))
