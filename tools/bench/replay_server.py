"""The headless server with pre-rendered sensor data, so that the benchmark measures the bridge.

Cameras and lidars still run on the server's own schedule, and every message is still built by
`simserver.messages` and sent by the server's `TopicHub` (protocol-faithful frames, the same sockets and
services); only the ray casting is replaced by a cache. A camera's first frame of each size is rendered
at an eighth of the resolution and scaled up by pixel repetition (ray casting 1080p would take seconds),
a lidar's first rotation is cast once and then replayed, as many returns per scan as its time span
sweeps. Cameras render in the server's own process (`--render-in-process`): a render worker, a child
process, would not have the cache.

    python -m tools.bench.replay_server --topicsport P --servicesport Q
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from airsim_mapper.simserver.cli import main as server_main
from airsim_mapper.simserver.render import camera_model, rendering
from airsim_mapper.simserver.render.camera_model import RenderRequest
from airsim_mapper.simserver.sensors import lidar_model

MAX_RENDER_PIXELS = 320 * 240


def _reduction(width: int, height: int) -> int:
    """The largest factor in 1..8 dividing both sides that brings the render under MAX_RENDER_PIXELS."""
    for factor in range(1, 9):
        if (
            width % factor == 0
            and height % factor == 0
            and (width // factor) * (height // factor) <= MAX_RENDER_PIXELS
        ):
            return factor
    return max(f for f in range(1, 9) if width % f == 0 and height % f == 0)


def _upscale(
    image: camera_model.RenderedImage, factor: int, width: int, height: int
) -> camera_model.RenderedImage:
    channels = 3 if image.encoding == "BGR" else 1
    dtype = np.uint8 if image.encoding == "BGR" else np.dtype("<f2")
    pixels = np.frombuffer(image.data, dtype=dtype).reshape(image.height, image.width, channels)
    big = np.repeat(np.repeat(pixels, factor, axis=0), factor, axis=1)
    return camera_model.RenderedImage(image.encoding, width, height, np.ascontiguousarray(big).tobytes())


def cached_render(real_render: Any) -> Any:
    cache: dict[tuple, dict[int, camera_model.RenderedImage]] = {}

    def render(world: Any, request: RenderRequest) -> dict[int, camera_model.RenderedImage]:
        """`rendering.render`'s signature; the depth scale and range are part of the cache key."""
        r = request
        key = (r.width, r.height, float(r.fov_deg), tuple(r.image_types), r.max_depth_vis, r.max_distance)
        if key not in cache:
            factor = _reduction(r.width, r.height)
            small = real_render(world, replace(r, width=r.width // factor, height=r.height // factor))
            cache[key] = {t: _upscale(img, factor, r.width, r.height) for t, img in small.items()}
        return cache[key]

    return render


def cached_scan(real_scan: Any) -> Any:
    """A lidar's scan from one rotation cast once: each call takes the next returns of that rotation, as
    many as the call's time span sweeps (a physics tick's segment, or several), cycling through it."""
    cache: dict[int, tuple[dict[str, Any], list[int]]] = {}

    def scan(
        self: lidar_model.LidarModel, world: Any, position: Any, orientation: Any, start_ns: int, end_ns: int
    ):
        if id(self) not in cache:
            period = int(1e9 / self.rotation_hz)
            cache[id(self)] = (real_scan(self, world, position, orientation, end_ns - period, end_ns), [0])
        rotation, offset = cache[id(self)]
        returns = rotation["segmentation_cloud"].size
        count = round(returns * max(0, end_ns - start_ns) * self.rotation_hz / 1e9) if returns else 0
        rows = (offset[0] + np.arange(count)) % max(returns, 1)
        offset[0] = (offset[0] + count) % max(returns, 1)
        out = {}
        for key, values in rotation.items():
            width = values.size // returns if returns and values.size else 0
            out[key] = values.reshape(-1, width)[rows].reshape(-1) if width else values
        return out

    return scan


def install_replay() -> None:
    rendering.render = cached_render(rendering.render)
    lidar_model.LidarModel.scan = cached_scan(lidar_model.LidarModel.scan)


def main(argv: Sequence[str] | None = None) -> int:
    """The headless server with the cache installed; it renders in its own process, where the cache is."""
    install_replay()
    args = list(sys.argv[1:] if argv is None else argv)
    return server_main([*args, "--render-in-process"] if "--render-in-process" not in args else args)


if __name__ == "__main__":
    sys.exit(main())
