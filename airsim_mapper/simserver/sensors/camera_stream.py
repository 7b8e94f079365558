"""A robot's camera stream: it renders on the camera thread while someone subscribes or GetImages waits.

Each capture renders the wanted image types of one size and field of view in one request (through the
render worker in the server, which a busy machine slows first), encodes them as the real server does and
publishes them on their topics; GetImages waits for a capture at or after its own sim time.
"""

from __future__ import annotations

import functools
import logging
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from airsim_mapper.simserver.motion.motion import Body
from airsim_mapper.simserver.render import annotations, camera_model, image_encoding, rendering
from airsim_mapper.simserver.render.camera_model import RenderedImage, RenderRequest
from airsim_mapper.simserver.scene.config import IMAGE_TYPE_NAMES, SensorSpec
from airsim_mapper.simserver.scene.topic_table import info_topic_path
from airsim_mapper.simserver.sensors.sensor_streams import Schedule, mount_pose
from airsim_mapper.simserver.wire import messages, protocol
from airsim_mapper.simserver.wire.services import ServiceError
from airsim_mapper.simserver.wire.topics import TopicHub
from airsim_mapper.simserver.world.world import World

LOG = logging.getLogger("airsim_mapper.simserver.camera_stream")
GET_IMAGES_TIMEOUT_S = 5.0
Render = Callable[[RenderRequest], dict[int, RenderedImage]]  # rendering.render of one world


class CameraStream:
    """One camera: renders the capture-enabled types that are subscribed or requested by GetImages.

    `render` draws a RenderRequest (a RenderWorker's, in the server); None renders in this process.
    """

    def __init__(
        self,
        sensor: SensorSpec,
        prefix: str,
        body: Body,
        world: World,
        hub: TopicHub,
        render: Render | None = None,
    ) -> None:
        self.sensor = sensor
        self.prefix = prefix
        self.body = body
        self.world = world
        self.hub = hub
        self.render: Render = render or functools.partial(rendering.render, world)
        self.captures = {c.image_type: c for c in sensor.enabled_captures()}
        for image_type, capture in self.captures.items():
            problem = image_encoding.unsupported_combination(
                image_type, capture.compress, capture.pixels_as_float
            )
            if problem:
                LOG.warning("camera %s image-type %d: %s", prefix, image_type, problem)
        self.fov = {t: c.fov_deg for t, c in self.captures.items()}
        self.offset_position = np.array(sensor.position, dtype=float)
        self.offset_orientation = np.array(sensor.orientation, dtype=float)
        gimbal = sensor.config.get("gimbal")
        self.gimbal = dict(gimbal) if isinstance(gimbal, dict) else None
        self.schedule = Schedule(int(sensor.capture_interval * 1e9))
        self._cond = threading.Condition()
        self._requests: dict[int, int] = {}  # image type -> number of waiting GetImages calls
        self._request_time_ns = -1
        self._latest: dict[int, protocol.TopicFrame] = {}  # the latest capture of each type, packed
        self._latest_ns = -1

    def topic(self, image_type: int) -> str:
        return f"{self.prefix}/{IMAGE_TYPE_NAMES[image_type]}"

    def publish_infos(self) -> None:
        """CameraInfo once at scene start (cached), on each `_info` topic.

        Type 5 has none: the real server names its info topic like the image topic, so `..._info` never
        exists, and an image topic carries only images (the client decodes everything on it as one).
        """
        for image_type, capture in self.captures.items():
            path = info_topic_path(self.prefix, image_type)
            if path != self.topic(image_type):
                info = camera_model.camera_info_message(capture.width, capture.height, capture.fov_deg)
                self.hub.publish(path, info)

    def set_pose(self, position: np.ndarray, orientation: np.ndarray) -> None:
        with self._cond:
            self.offset_position, self.offset_orientation = position, orientation

    def reset_pose(self) -> None:
        self.set_pose(
            np.array(self.sensor.position, dtype=float), np.array(self.sensor.orientation, dtype=float)
        )

    def world_pose(self) -> tuple[np.ndarray, np.ndarray]:
        with self._cond:
            offset = (self.offset_position.copy(), self.offset_orientation.copy())
        return mount_pose(self.body.snapshot(), *offset, self.gimbal)

    def _wanted(self) -> list[int]:
        with self._cond:
            requested = {t for t, n in self._requests.items() if n > 0}
        return sorted(t for t in self.captures if self.hub.is_subscribed(self.topic(t)) or t in requested)

    def step(self, now_ns: int) -> bool:
        """Capture if due and wanted; True if it rendered."""
        with self._cond:
            urgent = self._request_time_ns > self._latest_ns
        if not (self.schedule.due(now_ns) or urgent):
            return False
        wanted = self._wanted()
        if not wanted:
            return False
        self.capture(now_ns, wanted)
        return True

    def capture(self, now_ns: int, image_types: list[int]) -> None:
        position, orientation = self.world_pose()
        groups: dict[tuple[int, int, float], list[int]] = {}
        for image_type in image_types:
            capture = self.captures[image_type]
            groups.setdefault((capture.width, capture.height, self.fov[image_type]), []).append(image_type)
        latest: dict[int, protocol.TopicFrame] = {}
        boxes = self.annotations(position, orientation)
        for (width, height, fov), types in groups.items():
            vis = self.captures.get(camera_model.DEPTH_VIS)
            max_depth = vis.max_depth_m if vis else camera_model.DEFAULT_MAX_DEPTH_VIS
            rendered = self.render(RenderRequest(position, orientation, width, height, fov, types, max_depth))
            for image_type, img in rendered.items():
                setting = self.captures[image_type]
                wire = image_encoding.wire_image(
                    image_type,
                    img.encoding,
                    img.data,
                    img.width,
                    img.height,
                    setting.compress,
                    setting.pixels_as_float,
                )
                message = messages.image(
                    now_ns, wire.encoding, img.width, img.height, wire.data, position, orientation, boxes
                )
                path = self.topic(image_type)
                # packed now, with the one copy of the pixels: a render worker's are views of its buffer
                latest[image_type] = frame = protocol.message_frame(path, message)
                if self.hub.is_subscribed(path):
                    self.hub.publish(path, frame)
        with self._cond:
            self._latest.update(latest)
            self._latest_ns = now_ns
            self._cond.notify_all()

    def annotations(self, position: np.ndarray, orientation: np.ndarray) -> list[dict[str, Any]]:
        """The capture's bounding boxes (annotation-settings), in the scene capture's image geometry."""
        settings = self.sensor.annotation
        if settings is None:
            return []
        scene = next((c for c in self.sensor.captures if c.image_type == camera_model.SCENE), None)
        width, height = (scene.width, scene.height) if scene else annotations.DEFAULT_SIZE
        fov = self.fov.get(camera_model.SCENE, scene.fov_deg if scene else annotations.DEFAULT_FOV_DEG)
        return annotations.annotate(self.world.current, settings, position, orientation, width, height, fov)

    def get_images(self, image_types: list[int], now_ns: Callable[[], int]) -> dict[str, Any]:
        """GetImages: wait for a capture at or after the request's sim time; JSON form (data as a list)."""
        types = [int(t) for t in image_types if int(t) in self.captures]
        if not types:
            return {}
        t_request = now_ns()
        deadline = time.monotonic() + GET_IMAGES_TIMEOUT_S
        with self._cond:
            for t in types:
                self._requests[t] = self._requests.get(t, 0) + 1
            self._request_time_ns = max(self._request_time_ns, t_request)
            try:
                while not (self._latest_ns >= t_request and all(t in self._latest for t in types)):
                    remaining = deadline - time.monotonic()
                    if remaining <= 0:
                        raise ServiceError("GetImages() Timeout waiting for new captured_images.")
                    self._cond.wait(remaining)
                    if self._latest_ns >= t_request and not all(t in self._latest for t in types):
                        self._request_time_ns = max(self._request_time_ns, self._latest_ns + 1)
                frames = {str(t): self._latest[t] for t in types}
            finally:
                for t in types:
                    self._requests[t] -= 1
        result = {key: protocol.decode_body(frame.body) for key, frame in frames.items()}
        for entry in result.values():
            entry["data"] = protocol.uint8_list(entry["data"])
        return result
