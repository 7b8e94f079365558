"""Spinning lidar: the configured scan pattern ray-cast against the world, points in the sensor frame.

Pattern (every `lidar-type` uses the generic cylindrical pattern): `number-of-channels` lasers spread
evenly from `vertical-fov-upper-deg` (channel 0) down to `vertical-fov-lower-deg`, fired together in
columns. Columns come at `points-per-second / number-of-channels` per second while the head turns at
`horizontal-rotation-frequency` Hz, so consecutive columns are `360 * frequency * channels / pps` degrees
apart. The azimuth is state: each `scan` continues where the previous one stopped, and a fraction of a
column left over is carried to the next scan. Columns outside [`horizontal-fov-start-deg`,
`horizontal-fov-end-deg`] (clockwise from forward, i.e. positive to the right) fire nothing.

Frames: azimuth = atan2(y, x) (positive right), elevation = asin(-z / range) (positive up), sensor frame
FRD. `scan` takes the lidar's own world pose (compose the robot pose with `mount_position` /
`mount_orientation`, the config `origin`). Only returns within `range` are reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from airsim_mapper.common.geometry import parse_origin, quat_to_matrix
from airsim_mapper.simserver.errors import SimServerError
from airsim_mapper.simserver.world.world import World

_DEFAULTS = {
    "number-of-channels": 16,
    "range": 100.0,
    "points-per-second": 100000,
    "horizontal-rotation-frequency": 10.0,
    "horizontal-fov-start-deg": 0.0,
    "horizontal-fov-end-deg": 360.0,
    "vertical-fov-upper-deg": 10.0,
    "vertical-fov-lower-deg": -10.0,
}


class LidarError(SimServerError, ValueError):
    """A lidar sensor config value is invalid; the message names the sensor and the key."""


def _config_number(sensor: dict, key: str, minimum: float | None = None, above: float | None = None) -> float:
    value = sensor.get(key, _DEFAULTS[key])
    sensor_id = sensor.get("id", "<lidar>")
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise LidarError(f"lidar {sensor_id!r}: {key!r} must be a finite number, got {value!r}")
    if above is not None and value <= above:
        raise LidarError(f"lidar {sensor_id!r}: {key!r} must be greater than {above:g}, got {value!r}")
    if minimum is not None and value < minimum:
        raise LidarError(f"lidar {sensor_id!r}: {key!r} must be at least {minimum:g}, got {value!r}")
    return float(value)


@dataclass
class LidarModel:
    sensor_id: str
    channels: int
    range_m: float
    points_per_second: float
    rotation_hz: float
    hfov_start_deg: float
    hfov_end_deg: float
    vfov_upper_deg: float
    vfov_lower_deg: float
    lidar_type: str = "generic_cylindrical"
    report_azimuth_elevation_range: bool = False
    mount_position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    mount_orientation: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0, 0.0, 0.0]))
    azimuth_deg: float = 0.0  # azimuth of the last column fired (state)
    column_carry: float = 0.0  # fraction of a column owed to the next scan (state)

    @classmethod
    def from_config(cls, sensor: dict[str, Any]) -> LidarModel:
        """Build from a robot-config sensor entry (`type: lidar`); absent keys take the defaults."""
        sensor_id = str(sensor.get("id", "<lidar>"))
        channels = sensor.get("number-of-channels", _DEFAULTS["number-of-channels"])
        if isinstance(channels, bool) or not isinstance(channels, int) or channels < 1:
            raise LidarError(
                f"lidar {sensor_id!r}: 'number-of-channels' must be an integer >= 1, got {channels!r}"
            )
        upper = _config_number(sensor, "vertical-fov-upper-deg")
        lower = _config_number(sensor, "vertical-fov-lower-deg")
        if lower > upper:
            raise LidarError(
                f"lidar {sensor_id!r}: 'vertical-fov-lower-deg' ({lower:g}) is above "
                f"'vertical-fov-upper-deg' ({upper:g})"
            )
        start = _config_number(sensor, "horizontal-fov-start-deg")
        end = _config_number(sensor, "horizontal-fov-end-deg")
        if end <= start:
            raise LidarError(
                f"lidar {sensor_id!r}: 'horizontal-fov-end-deg' ({end:g}) must be greater than "
                f"'horizontal-fov-start-deg' ({start:g})"
            )
        position, orientation = parse_origin(sensor.get("origin"))
        return cls(
            sensor_id=sensor_id,
            channels=channels,
            range_m=_config_number(sensor, "range", above=0.0),
            points_per_second=_config_number(sensor, "points-per-second", above=0.0),
            rotation_hz=_config_number(sensor, "horizontal-rotation-frequency", above=0.0),
            hfov_start_deg=start,
            hfov_end_deg=end,
            vfov_upper_deg=upper,
            vfov_lower_deg=lower,
            lidar_type=str(sensor.get("lidar-type", "generic_cylindrical")),
            report_azimuth_elevation_range=bool(sensor.get("report-azimuth-elevation-range", False)),
            mount_position=position,
            mount_orientation=orientation,
            azimuth_deg=start,
        )

    @property
    def elevations_deg(self) -> np.ndarray:
        """Elevation of each channel, channel 0 the uppermost."""
        return np.linspace(self.vfov_upper_deg, self.vfov_lower_deg, self.channels)

    @property
    def column_step_deg(self) -> float:
        """Azimuth between consecutive columns."""
        return 360.0 * self.rotation_hz * self.channels / self.points_per_second

    def _next_columns(self, seconds: float) -> np.ndarray:
        """Azimuths (deg, in [0, 360)) of the columns fired in the next `seconds`; advances the state."""
        owed = self.points_per_second / self.channels * seconds + self.column_carry
        count = math.floor(owed)
        self.column_carry = owed - count
        azimuths = self.azimuth_deg + self.column_step_deg * np.arange(1, count + 1, dtype=np.float64)
        if count:
            self.azimuth_deg = float(azimuths[-1] % 360.0)
        azimuths %= 360.0
        width = self.hfov_end_deg - self.hfov_start_deg
        if width < 360.0:
            inside = (azimuths - self.hfov_start_deg) % 360.0 <= width
            azimuths = azimuths[inside]
        return azimuths

    def scan(
        self, world: World, position: np.ndarray, orientation: np.ndarray, t_start_ns: int, t_end_ns: int
    ) -> dict:
        """Fire the columns due between the two times from the lidar's world pose; returns the clouds."""
        seconds = max(0, int(t_end_ns) - int(t_start_ns)) / 1e9
        azimuth = np.radians(self._next_columns(seconds))
        elevation = np.radians(self.elevations_deg)
        az = np.repeat(azimuth, self.channels)  # column-major: every channel of a column, then the next
        el = np.tile(elevation, azimuth.size)
        laser = np.tile(np.arange(self.channels, dtype=np.int32), azimuth.size)
        cos_el = np.cos(el)
        local = np.stack([cos_el * np.cos(az), cos_el * np.sin(az), -np.sin(el)]).astype(np.float32)
        rotation = quat_to_matrix(np.asarray(orientation, dtype=float)).astype(np.float32)
        origin = np.asarray(position, dtype=np.float32).reshape(3)
        world_dirs = rotation @ local
        hits = world.raycast_columns(origin, world_dirs, self.range_m, unit=True)
        keep = np.nonzero(hits.hit)[0]
        distance = hits.distance[keep]
        points = local[:, keep] * distance
        # intensity: Lambertian return, fading with range
        cos_inc = np.abs((hits.normal.T[:, keep] * world_dirs[:, keep]).sum(axis=0))
        intensity = (cos_inc * (1.0 - 0.5 * distance / self.range_m)).astype(np.float32)
        out = {
            "point_cloud": np.ascontiguousarray(points.T, dtype=np.float32).reshape(-1),
            "intensity_cloud": intensity,
            "segmentation_cloud": hits.segmentation_id[keep].astype(np.int32),
            "laser_index_cloud": laser[keep],
            "azimuth_elevation_range_cloud": np.zeros(0, dtype=np.float32),
        }
        if self.report_azimuth_elevation_range:
            aer = np.stack([az[keep], el[keep], distance]).astype(np.float32)
            out["azimuth_elevation_range_cloud"] = np.ascontiguousarray(aer.T).reshape(-1)
        return out
