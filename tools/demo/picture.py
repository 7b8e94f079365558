"""The demo's picture: the camera's image types in a grid, a lidar bird's-eye view and the flown track."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from airsim_mapper.common.image_types import DOCUMENTED_IMAGE_TYPES

IMAGE_TYPES = tuple(DOCUMENTED_IMAGE_TYPES.values())  # the default mapping's <image_type> names


def image_array(msg: Any) -> np.ndarray:
    """A displayable RGB (or float) array of a sensor_msgs/Image."""
    if msg.encoding == "32FC1":
        depth = np.frombuffer(msg.data, dtype="<f4").reshape(msg.height, msg.width)
        return np.where(np.isfinite(depth), depth, np.nan)
    channels = {"bgr8": 3, "rgb8": 3, "mono8": 1}.get(msg.encoding, 3)
    pixels = np.frombuffer(msg.data, dtype=np.uint8).reshape(msg.height, msg.width, channels)
    return pixels[..., ::-1] if msg.encoding == "bgr8" else pixels.squeeze()


def cloud_xy(msg: Any) -> np.ndarray:
    """(N, 2) x, y of a PointCloud2 with float32 x, y fields."""
    offsets = {f.name: f.offset for f in msg.fields}
    raw = np.frombuffer(msg.data, dtype=np.uint8).reshape(-1, msg.point_step)
    x = raw[:, offsets["x"] : offsets["x"] + 4].copy().view("<f4").ravel()
    y = raw[:, offsets["y"] : offsets["y"] + 4].copy().view("<f4").ravel()
    return np.stack([x, y], axis=1)


def draw(path: Path, latest: Mapping[str, Any], track: np.ndarray, robot: str, camera: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 3, figsize=(14, 11))
    for ax, kind in zip(axes.flat[:7], IMAGE_TYPES):
        msg = latest.get(f"/airsim_node/{robot}/{camera}/{kind}/image")
        ax.set_title(kind, fontsize=10)
        ax.axis("off")
        if msg is None:
            ax.text(0.5, 0.5, "no image", ha="center", va="center")
            continue
        pixels = image_array(msg)
        ax.imshow(pixels, cmap="viridis" if pixels.ndim == 2 else None)
    lidar = next((m for t, m in latest.items() if t.endswith("/lidar")), None)
    ax = axes.flat[7]
    ax.set_title("lidar, bird's-eye view (sensor frame, m)", fontsize=10)
    if lidar is not None:
        xy = cloud_xy(lidar)
        ax.scatter(xy[:, 1], xy[:, 0], s=0.3, c=np.hypot(xy[:, 0], xy[:, 1]), cmap="plasma")
        ax.set_xlabel("y (right)")
        ax.set_ylabel("x (forward)")
        ax.set_aspect("equal")
    ax = axes.flat[8]
    ax.set_title(f"{robot} track (NED, m)", fontsize=10)
    ax.plot(track[:, 1], track[:, 0], "-", lw=1.5)
    ax.plot(track[-1, 1], track[-1, 0], "o")
    ax.set_xlabel("east")
    ax.set_ylabel("north")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    fig.suptitle("airsim-mapper demo: headless Project AirSim server -> bridge -> ROS", fontsize=13)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
