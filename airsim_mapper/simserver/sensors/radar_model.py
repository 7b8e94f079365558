"""Radar: detections and tracks of world objects inside the configured field of view and range.

Beams cover the `fov` box (azimuth x elevation) at the configured resolutions, plus one beam aimed at the
centre of every object inside the field of view (so small far objects are not lost between beams). Each
object seen by a beam gives one detection: its centre beam if that beam reaches it, else its nearest beam.
The ground gives no returns (no clutter model). Conventions (protocol.md §5.7), sensor frame FRD:
azimuth = atan2(y, x) (positive right), elevation = asin(-z / range) (positive up); velocity is the
relative velocity projected on the beam (negative when closing); range is rounded to `range-resolution`
and velocity to `velocity-resolution`. RCS is the object's cross-section seen along the beam (pi r^2 for a
sphere, the projected area for a box) times `rcs-adjust-factor`. A detection inside every bound of any
`masks` entry is suppressed. Objects are static, so the relative velocity is minus the radar's own.

Tracks: one per object currently detected, with an id that stays the same for that object across calls
(ids are never reused), estimates of the object centre in the sensor frame, and acceleration estimated
from the change of the velocity estimate between calls.
`detect` and `track` take the radar's own world pose (compose the robot pose with `mount_position` /
`mount_orientation`, the config `origin`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from airsim_mapper.common.geometry import parse_origin, quat_to_matrix
from airsim_mapper.simserver.errors import SimServerError
from airsim_mapper.simserver.world.world import World

_FOV_DEFAULTS = {
    "azimuth-max": math.pi / 4,
    "azimuth-min": -math.pi / 4,
    "elevation-max": math.pi / 6,
    "elevation-min": -math.pi / 6,
    "azimuth-resolution": 0.0175,
    "elevation-resolution": 0.0175,
}
_DEFAULTS = {
    "range-max": 500.0,
    "range-resolution": 1.0,
    "velocity-max": 100.0,
    "velocity-resolution": 1.0,
    "detection-interval": 0.02,
    "track-interval": 0.2,
    "rcs-adjust-factor": 1.0,
}
_MASK_KEYS = ("azimuth", "elevation", "range", "velocity", "rcs-sqm")


class RadarError(SimServerError, ValueError):
    """A radar sensor config value is invalid; the message names the sensor and the key."""


def _number(value: Any, sensor_id: str, key: str, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise RadarError(f"radar {sensor_id!r}: {key!r} must be a finite number, got {value!r}")
    if positive and value <= 0:
        raise RadarError(f"radar {sensor_id!r}: {key!r} must be positive, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class Mask:
    """An exclusion zone: detections inside every [min, max] bound are dropped."""

    bounds: dict[str, tuple[float, float]]

    def covers(self, values: dict[str, np.ndarray]) -> np.ndarray:
        inside = np.ones(len(values["range"]), dtype=bool)
        for key, (low, high) in self.bounds.items():
            inside &= (values[key] >= low) & (values[key] <= high)
        return inside


@dataclass(frozen=True)
class _Observation:
    """Per detected object (arrays of length M)."""

    objects: np.ndarray  # world object indices
    range: np.ndarray
    azimuth: np.ndarray
    elevation: np.ndarray
    velocity: np.ndarray
    rcs: np.ndarray


@dataclass
class _Track:
    track_id: int
    velocity: np.ndarray
    time_ns: int


@dataclass
class RadarModel:
    sensor_id: str
    azimuth_min: float
    azimuth_max: float
    elevation_min: float
    elevation_max: float
    azimuth_resolution: float
    elevation_resolution: float
    range_max: float
    range_resolution: float
    velocity_max: float
    velocity_resolution: float
    detection_interval: float
    track_interval: float
    rcs_adjust_factor: float
    masks: tuple[Mask, ...] = ()
    mount_position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    mount_orientation: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0, 0.0, 0.0]))
    _tracks: dict[int, _Track] = field(default_factory=dict, repr=False)
    _next_id: int = field(default=1, repr=False)

    @classmethod
    def from_config(cls, sensor: dict[str, Any]) -> RadarModel:
        """Build from a robot-config sensor entry (`type: radar`); absent keys take the defaults."""
        sensor_id = str(sensor.get("id", "<radar>"))
        fov = sensor.get("fov", {})
        if not isinstance(fov, dict):
            raise RadarError(f"radar {sensor_id!r}: 'fov' must be a mapping, got {fov!r}")
        f = {
            k: _number(fov.get(k, v), sensor_id, f"fov.{k}", positive="resolution" in k)
            for k, v in _FOV_DEFAULTS.items()
        }
        for axis in ("azimuth", "elevation"):
            if f[f"{axis}-min"] >= f[f"{axis}-max"]:
                raise RadarError(f"radar {sensor_id!r}: 'fov.{axis}-min' must be below 'fov.{axis}-max'")
        g = {
            k: _number(sensor.get(k, v), sensor_id, k, positive=k != "rcs-adjust-factor")
            for k, v in _DEFAULTS.items()
        }
        masks_cfg = sensor.get("masks", [])
        if not isinstance(masks_cfg, list):
            raise RadarError(f"radar {sensor_id!r}: 'masks' must be a list, got {masks_cfg!r}")
        masks = []
        for i, entry in enumerate(masks_cfg):
            if not isinstance(entry, dict):
                raise RadarError(f"radar {sensor_id!r}: 'masks[{i}]' must be a mapping, got {entry!r}")
            bounds = {}
            for key in _MASK_KEYS:
                lo, hi = f"{key}-min", f"{key}-max"
                low = _number(entry[lo], sensor_id, f"masks[{i}].{lo}") if lo in entry else -math.inf
                high = _number(entry[hi], sensor_id, f"masks[{i}].{hi}") if hi in entry else math.inf
                bounds[key] = (low, high)
            masks.append(Mask(bounds))
        position, orientation = parse_origin(sensor.get("origin"))
        return cls(
            sensor_id=sensor_id,
            azimuth_min=f["azimuth-min"],
            azimuth_max=f["azimuth-max"],
            elevation_min=f["elevation-min"],
            elevation_max=f["elevation-max"],
            azimuth_resolution=f["azimuth-resolution"],
            elevation_resolution=f["elevation-resolution"],
            range_max=g["range-max"],
            range_resolution=g["range-resolution"],
            velocity_max=g["velocity-max"],
            velocity_resolution=g["velocity-resolution"],
            detection_interval=g["detection-interval"],
            track_interval=g["track-interval"],
            rcs_adjust_factor=g["rcs-adjust-factor"],
            masks=tuple(masks),
            mount_position=position,
            mount_orientation=orientation,
        )

    # ------------------------------------------------------------------ beams
    def beam_grid(self) -> tuple[np.ndarray, np.ndarray]:
        """Azimuths and elevations (rad) of the fixed beams covering the field of view."""
        az = np.arange(self.azimuth_min, self.azimuth_max + 1e-9, self.azimuth_resolution)
        el = np.arange(self.elevation_min, self.elevation_max + 1e-9, self.elevation_resolution)
        grid_az, grid_el = np.meshgrid(az, el)
        return grid_az.ravel(), grid_el.ravel()

    def _in_fov(self, azimuth: np.ndarray, elevation: np.ndarray) -> np.ndarray:
        return (
            (azimuth >= self.azimuth_min)
            & (azimuth <= self.azimuth_max)
            & (elevation >= self.elevation_min)
            & (elevation <= self.elevation_max)
        )

    def _observe(self, world: World, position, orientation, velocity_world) -> _Observation:
        rotation = quat_to_matrix(np.asarray(orientation, dtype=float))
        origin = np.asarray(position, dtype=float).reshape(3)
        grid_az, grid_el = self.beam_grid()
        centres = np.array([o.center for o in world.objects], dtype=float).reshape(-1, 3)
        rel = (centres - origin) @ rotation  # object centres in the sensor frame
        dist = np.linalg.norm(rel, axis=1)
        safe = np.where(dist > 0, dist, 1.0)
        centre_az = np.arctan2(rel[:, 1], rel[:, 0])
        centre_el = np.arcsin(np.clip(-rel[:, 2] / safe, -1.0, 1.0))
        aimed = np.nonzero(self._in_fov(centre_az, centre_el) & (dist > 0))[0]
        az = np.concatenate([grid_az, centre_az[aimed]])
        el = np.concatenate([grid_el, centre_el[aimed]])
        local = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), -np.sin(el)])
        hits = world.raycast_columns(
            origin.astype(np.float32), (rotation @ local).astype(np.float32), self.range_max
        )
        obj = hits.object_index
        n_grid = grid_az.size
        # preference: a centre beam that reaches its own object (rank 0), then any beam by distance
        is_own_centre = np.zeros(obj.size, dtype=bool)
        is_own_centre[n_grid:] = obj[n_grid:] == aimed
        valid = np.nonzero(obj >= 0)[0]
        if valid.size == 0:
            return _Observation(*(np.zeros(0) for _ in range(6)))
        order = valid[np.lexsort((hits.distance[valid], ~is_own_centre[valid], obj[valid]))]
        objects, first = np.unique(obj[order], return_index=True)
        beams = order[first]
        velocity = -(np.asarray(velocity_world, dtype=float) @ (rotation @ local[:, beams]))  # static objects
        rcs = self._cross_sections(world, objects, (rotation @ local[:, beams]).T) * self.rcs_adjust_factor
        return _Observation(objects, hits.distance[beams].astype(float), az[beams], el[beams], velocity, rcs)

    @staticmethod
    def _cross_sections(world: World, objects: np.ndarray, beams_world: np.ndarray) -> np.ndarray:
        """Geometric cross-section (m^2) of each object seen along its beam."""
        areas = np.empty(objects.size)
        for slot, (i, beam) in enumerate(zip(objects, beams_world)):
            o = world.objects[int(i)]
            if o.shape == "sphere":
                areas[slot] = math.pi * (o.size[0] / 2.0) ** 2
                continue
            c, s = math.cos(o.yaw), math.sin(o.yaw)
            local = np.array([c * beam[0] + s * beam[1], -s * beam[0] + c * beam[1], beam[2]])
            sx, sy, sz = o.size
            areas[slot] = sy * sz * abs(local[0]) + sx * sz * abs(local[1]) + sx * sy * abs(local[2])
        return areas

    def _quantise(self, value: np.ndarray, step: float) -> np.ndarray:
        return np.round(value / step) * step

    def _accepted(self, seen: _Observation) -> np.ndarray:
        values = {
            "azimuth": seen.azimuth,
            "elevation": seen.elevation,
            "range": seen.range,
            "velocity": seen.velocity,
            "rcs-sqm": seen.rcs,
        }
        keep = np.abs(seen.velocity) <= self.velocity_max
        for mask in self.masks:
            keep &= ~mask.covers(values)
        return keep

    # ------------------------------------------------------------------ outputs
    def detect(self, world: World, position, orientation, velocity_world, t_ns: int) -> list[dict]:
        """Detections (protocol.md §5.7) of the objects the radar sees now."""
        seen = self._observe(world, position, orientation, velocity_world)
        keep = self._accepted(seen)
        ranges = self._quantise(seen.range[keep], self.range_resolution)
        velocities = self._quantise(seen.velocity[keep], self.velocity_resolution)
        return [
            {
                "range": float(r),
                "azimuth": float(a),
                "elevation": float(e),
                "velocity": float(v),
                "rcs_sqm": float(c),
            }
            for r, a, e, v, c in zip(
                ranges, seen.azimuth[keep], seen.elevation[keep], velocities, seen.rcs[keep]
            )
        ]

    def track(self, world: World, position, orientation, velocity_world, t_ns: int) -> list[dict]:
        """Tracks (protocol.md §5.7) of the objects detected now; ids are stable per object."""
        seen = self._observe(world, position, orientation, velocity_world)
        keep = self._accepted(seen)
        rotation = quat_to_matrix(np.asarray(orientation, dtype=float))
        origin = np.asarray(position, dtype=float).reshape(3)
        sensor_velocity = -(np.asarray(velocity_world, dtype=float) @ rotation)  # static object, sensor frame
        objects = seen.objects[keep].astype(int)
        centres = np.array([world.objects[i].center for i in objects], dtype=float).reshape(-1, 3)
        positions = (centres - origin) @ rotation
        tracks = []
        for i, pos, rcs in zip(objects, positions, seen.rcs[keep]):
            state = self._tracks.get(i)
            if state is None:
                state = self._tracks[i] = _Track(self._next_id, sensor_velocity.copy(), int(t_ns))
                self._next_id += 1
                accel = np.zeros(3)
            else:
                dt = (int(t_ns) - state.time_ns) / 1e9
                accel = (sensor_velocity - state.velocity) / dt if dt > 0 else np.zeros(3)
                state.velocity, state.time_ns = sensor_velocity.copy(), int(t_ns)
            rng = float(np.linalg.norm(pos))
            tracks.append(
                {
                    "id": state.track_id,
                    "azimuth_est": float(math.atan2(pos[1], pos[0])),
                    "elevation_est": float(math.asin(max(-1.0, min(1.0, -pos[2] / rng)))) if rng > 0 else 0.0,
                    "range_est": rng,
                    "position_est": _vector(pos),
                    "velocity_est": _vector(sensor_velocity),
                    "accel_est": _vector(accel),
                    "rcs_sqm": float(rcs),
                }
            )
        return tracks


def _vector(v: np.ndarray) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1]), "z": float(v[2])}
