"""engine.publish: an image or a point cloud handed over in parts is, on the wire, what rospy's publish
sends, whether the socket takes it at once, in part, or only after others queued before it."""

from __future__ import annotations

import gc
import socket
import threading
import time
import weakref
from typing import Any

import numpy as np
import pytest
import rospy.topics
from rospy.exceptions import ROSException, ROSSerializationException
from rospy.impl.tcpros_base import TCPROSTransport
from rospy.impl.tcpros_pubsub import QueuedConnection, TCPROSPub
from sensor_msgs.msg import CompressedImage, Image, PointCloud2

from airsim_mapper.convert.compressed_image import BufferCompressedImage
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.image import BufferImage
from airsim_mapper.convert.pointcloud import BufferPointCloud2, pointcloud
from airsim_mapper.engine.publish import publish
from airsim_mapper.engine.rospy_internals import PromptQueuedConnection, unsent

TOPIC = "/test_publish/image"
QUEUE = 2


class Publisher:
    """rospy.Publisher's publish over a real `_PublisherImpl` (a `rospy.Publisher` needs a master)."""

    def __init__(self, data_class: type = Image) -> None:
        self.impl = rospy.topics._PublisherImpl(TOPIC, data_class)

    def publish(self, message: Any) -> None:
        self.impl.acquire()
        try:
            self.impl.publish(message)
        finally:
            self.impl.release()


def connect(impl: Any, kind: type = PromptQueuedConnection) -> tuple[Any, socket.socket]:
    """A subscriber's connection on `impl` as the node makes it (a queued connection around a TCPROS
    transport); returns it and the subscriber's end of the socket."""
    ours, theirs = tcp_pair()
    transport = TCPROSTransport(TCPROSPub(TOPIC, impl.data_class), TOPIC)
    transport.set_socket(ours, "test")
    connection = kind(transport, QUEUE)
    impl.add_connection(connection)
    return connection, theirs


def tcp_pair() -> tuple[socket.socket, socket.socket]:
    """Two ends of a loopback TCP connection, as between a publisher and its subscriber; the subscriber's
    receive buffer small, so that a large message cannot be taken at once."""
    with socket.create_server(("127.0.0.1", 0)) as server:
        theirs = socket.socket()
        theirs.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 65536)
        theirs.connect(server.getsockname())
        ours, _ = server.accept()
    ours.setblocking(True)  # as rospy's handshake leaves it, whatever socket.setdefaulttimeout says
    ours.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 65536)
    return ours, theirs


def read(sock: socket.socket, size: int, timeout: float = 10.0) -> bytes:
    sock.settimeout(timeout)
    chunks, left = [], size
    while left:
        chunk = sock.recv(left)
        assert chunk, "the connection closed early"
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


def image(pixels: bytes | memoryview, width: int = 4, height: int = 2) -> BufferImage:
    out = BufferImage(height=height, width=width, encoding="bgr8", step=width * 3, data=memoryview(pixels))
    out.header.frame_id = "Drone1/Cam_optical"
    out.header.stamp.secs, out.header.stamp.nsecs = 12, 345
    return out


def sent_by_both(data_class: type, make: Any, times: int, plain: Any = None) -> tuple[bytes, bytes]:
    """What a subscriber reads of `times` messages from `make`, published through engine.publish and
    through rospy's own publish (of `plain(message)`, when given)."""
    ours, rospys = Publisher(data_class), Publisher(data_class)
    (_, our_end), (_, their_end) = connect(ours.impl), connect(rospys.impl)
    try:
        for _ in range(times):
            publish(ours, make())
            rospys.publish(plain(make()) if plain else make())
        size = ours.impl.message_data_sent
        assert size == rospys.impl.message_data_sent
        return read(our_end, size), read(their_end, size)
    finally:
        ours.impl.close()
        rospys.impl.close()


def test_the_bytes_on_the_wire_are_rospys() -> None:
    pixels = bytes(range(24))
    ours, rospys = sent_by_both(Image, lambda: image(pixels), times=3)
    assert ours == rospys
    assert pixels in ours


def test_a_compressed_image_too() -> None:
    def make() -> BufferCompressedImage:
        out = BufferCompressedImage(format="bgr8; png compressed bgr8", data=memoryview(b"\x89PNG-bytes"))
        out.header.frame_id = "cam"
        return out

    ours, rospys = sent_by_both(CompressedImage, make, times=2)
    assert ours == rospys


def cloud(points: int, dense: bool = True) -> BufferPointCloud2:
    xyz = np.arange(3 * points, dtype=np.float32)
    if not dense:
        xyz[1] = np.nan
    sim = {
        "time_stamp": 5,
        "point_cloud": xyz.tobytes(),
        "intensity_cloud": np.ones(points, np.float32).tobytes(),
    }
    return pointcloud(sim, ConvertContext(frame_id="Drone1/lidar1"))


def genpy_cloud(message: BufferPointCloud2) -> PointCloud2:
    """The same cloud as genpy builds it, its points in bytes."""
    return PointCloud2(
        **{**{name: getattr(message, name) for name in PointCloud2.__slots__}, "data": bytes(message.data)}
    )


@pytest.mark.parametrize("dense", [True, False])
def test_a_point_cloud_too_with_the_field_after_its_points(dense: bool) -> None:
    ours, genpys = sent_by_both(PointCloud2, lambda: cloud(5, dense), times=2, plain=genpy_cloud)
    assert ours == genpys
    assert ours.endswith(b"\x01" if dense else b"\x00")


def test_a_cloud_the_socket_takes_in_part_arrives_whole_and_counts_once() -> None:
    """100k points (2 MB) through a small send buffer: the rest, its points and is_dense, goes to the
    writer thread as views."""
    ours, genpys = sent_by_both(PointCloud2, lambda: cloud(100_000), times=2, plain=genpy_cloud)
    assert ours == genpys
    publisher = Publisher(PointCloud2)
    connection, end = connect(publisher.impl)
    taken: list[int] = []
    send_now = connection._send_now
    connection._send_now = lambda parts: taken.append(send_now(parts)) or taken[-1]
    try:
        publish(publisher, cloud(100_000))
        size = publisher.impl.message_data_sent
        assert len(taken) == 1 and 0 < taken[0] < size  # sent in part at once, the rest by the writer
        read(end, size)
        deadline = time.monotonic() + 10
        while connection.stat_num_msg < 1 and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.05)
        assert (connection.stat_num_msg, connection.stat_bytes) == (1, size)
    finally:
        publisher.impl.close()


def test_a_frame_id_of_none_is_sent_as_rospy_sends_it() -> None:
    def make() -> BufferImage:
        out = image(bytes(24))
        out.header.frame_id = None
        return out

    ours, rospys = sent_by_both(Image, make, times=1)
    assert ours == rospys


def test_a_field_that_cannot_be_serialised_raises_as_in_rospy() -> None:
    publisher = Publisher()
    connect(publisher.impl)
    bad = image(bytes(24))
    bad.height = "two"
    with pytest.raises(ROSSerializationException):
        publish(publisher, bad)
    publisher.impl.close()


def test_a_closed_topic_raises_as_in_rospy() -> None:
    publisher = Publisher()
    connect(publisher.impl)
    publisher.impl.close()
    with pytest.raises(ROSException):
        publish(publisher, image(bytes(24)))


def test_sequence_numbers_and_statistics_are_kept() -> None:
    publisher = Publisher()
    connection, end = connect(publisher.impl)
    messages = [image(bytes(24)) for _ in range(3)]
    for message in messages:
        publish(publisher, message)
    assert [m.header.seq for m in messages] == [1, 2, 3]
    assert publisher.impl.seq == 3
    assert len(read(end, publisher.impl.message_data_sent)) == connection.stat_bytes
    assert connection.stat_num_msg == 3
    publisher.impl.close()


class Recording(PromptQueuedConnection):
    """The node's connection, noting the pixels it is handed."""

    def __init__(self, connection: Any, queue_size: int) -> None:
        self.tails: list[memoryview] = []
        super().__init__(connection, queue_size)

    def write_parts(self, parts: tuple[bytes | memoryview, ...]) -> bool:
        self.tails.append(parts[1])
        return super().write_parts(parts)


def test_the_pixels_are_handed_over_where_they_are() -> None:
    publisher = Publisher()
    connection, end = connect(publisher.impl, Recording)
    pixels = bytes(range(24))
    publish(publisher, image(pixels))
    assert [tail.obj for tail in connection.tails] == [pixels]
    assert read(end, publisher.impl.message_data_sent).endswith(pixels)
    publisher.impl.close()


def frame_pixels(n: int) -> bytes:
    return bytes([n]) * (1920 * 1080 * 3)


def test_images_the_socket_takes_in_part_or_queues_arrive_whole_and_in_order() -> None:
    """A small send buffer and a subscriber that reads late: the first image is taken in part (its rest
    goes to the writer thread as a view), the next ones wait in the queue."""
    publisher, reference = Publisher(), Publisher()
    connection, end = connect(publisher.impl)
    _, reference_end = connect(reference.impl)
    for n in (1, 2):
        publish(publisher, image(frame_pixels(n), 1920, 1080))
        reference.publish(image(frame_pixels(n), 1920, 1080))
    assert connection.stat_num_msg < 2  # the socket could not take both at once
    size = reference.impl.message_data_sent
    assert read(end, size) == read(reference_end, size)
    for item in (publisher, reference):
        item.impl.close()


def test_a_queue_full_of_images_drops_the_oldest_whole() -> None:
    publisher = Publisher()
    _, end = connect(publisher.impl)
    for n in range(1, 7):
        publish(publisher, image(frame_pixels(n), 1920, 1080))
    pixels: list[int] = []
    while not pixels or pixels[-1] != 6:
        length = int.from_bytes(read(end, 4), "little")
        pixels.append(read(end, length)[-1])
    assert pixels == sorted(pixels) and pixels[0] == 1  # in order, none cut: the first, then the newest
    assert len(pixels) < 6
    publisher.impl.close()


def test_a_frame_taken_in_part_lives_until_its_rest_is_sent_and_no_longer() -> None:
    publisher = Publisher()
    connection, end = connect(publisher.impl)
    pixels = np.full(1920 * 1080 * 3, 7, dtype=np.uint8)  # the received frame
    alive = weakref.ref(pixels)
    publish(publisher, image(pixels, 1920, 1080))
    del pixels
    gc.collect()
    assert alive() is not None  # the writer thread holds the rest, a view of it
    assert read(end, publisher.impl.message_data_sent).endswith(bytes([7]) * 1000)
    deadline = time.monotonic() + 10
    while (alive() is not None or connection.stat_num_msg < 1) and time.monotonic() < deadline:
        time.sleep(0.01)
    assert connection.stat_num_msg == 1
    assert alive() is None  # not kept until the next message
    publisher.impl.close()


def test_a_broken_connection_is_closed_and_the_others_still_receive() -> None:
    publisher = Publisher()
    broken, broken_end = connect(publisher.impl)
    _, good_end = connect(publisher.impl)
    broken_end.close()
    deadline = time.monotonic() + 10
    while not broken.done and time.monotonic() < deadline:
        publish(publisher, image(bytes(24)))
        time.sleep(0.01)  # the writer thread meets the error; the next publish closes the connection
    assert broken.done
    assert len(read(good_end, publisher.impl.message_data_sent)) == publisher.impl.message_data_sent
    publisher.impl.close()


@pytest.mark.parametrize(
    "case", ["plain message", "latched", "no subscriber", "rospy's connection", "one of rospy's connections"]
)
def test_anything_else_goes_through_rospys_publish(case: str) -> None:
    calls: list[Any] = []
    publisher = Publisher()
    publisher.publish = calls.append  # type: ignore[method-assign]
    message: Any = Image() if case == "plain message" else image(bytes(24))
    publisher.impl.is_latch = case == "latched"
    if case != "no subscriber":
        connect(publisher.impl, QueuedConnection if case == "rospy's connection" else PromptQueuedConnection)
    if case == "one of rospy's connections":
        connect(publisher.impl, QueuedConnection)
    publish(publisher, message)
    assert calls == [message]
    publisher.impl.close()


def test_unsent_is_views_of_what_is_left() -> None:
    head, points, after = b"head", memoryview(b"points"), b"\x01"
    assert [bytes(part) for part in unsent((head, points, after), 2)] == [b"ad", b"points", b"\x01"]
    rest = unsent((head, points, after), 6)
    assert [bytes(part) for part in rest] == [b"ints", b"\x01"] and rest[0].obj is points.obj
    assert [bytes(part) for part in unsent((b"data",), 1)] == [b"ata"]
    assert unsent((head, points), 10) == ()


def test_threads_may_publish_at_once() -> None:
    publisher = Publisher()
    _, end = connect(publisher.impl)
    threads = [
        threading.Thread(target=lambda: [publish(publisher, image(bytes(24))) for _ in range(50)])
        for _ in range(4)
    ]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    data = read(end, publisher.impl.message_data_sent)
    seqs, offset = [], 0
    while offset < len(data):
        length = int.from_bytes(data[offset : offset + 4], "little")
        seqs.append(int.from_bytes(data[offset + 4 : offset + 8], "little"))
        offset += 4 + length
    assert seqs == list(range(1, 201))
    publisher.impl.close()
