"""sim RadarDetection -> radar_msgs/RadarScan and sim RadarTrack -> radar_msgs/RadarTracks.

Values are in the radar's own frame. The simulator's azimuth is positive to the right (FRD); with the ENU
convention (FLU sensor frame, REP-103) its sign is flipped and track vectors have y and z negated.
Elevation is positive up in both.

- amplitude: ``10*log10(rcs_sqm)`` dB, with rcs below RCS_FLOOR_SQM (including 0 and negatives) clamped
  to the floor, i.e. at most AMPLITUDE_FLOOR_DB = -100 dB, never a math error.
- track uuid: 16 bytes, the first 8 zero, the last 8 the sim's integer id as big-endian two's complement
  int64 (reversible: ``int.from_bytes(uuid[8:], "big", signed=True)``).
- track covariances: a nominal diagonal (upper-triangle order xx, xy, xz, yy, yz, zz) of
  NOMINAL_VARIANCES, overridable per rule by params ``position_variance``, ``velocity_variance``,
  ``acceleration_variance``; size and its covariance are zero; classification NO_CLASSIFICATION.
"""

from __future__ import annotations

import operator
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from geometry_msgs.msg import Point, Vector3
from radar_msgs.msg import RadarReturn, RadarScan, RadarTrack, RadarTracks

from airsim_mapper.convert import frames, sim_fields
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.flavour import ROS2
from airsim_mapper.convert.stamps import sim_header

if ROS2:  # a track's id is unique_identifier_msgs/UUID, a uint8[16] that takes a list of ints
    from unique_identifier_msgs.msg import UUID as UniqueID

    def _uuid_bytes(raw: bytes) -> Any:
        return list(raw)
else:
    from uuid_msgs.msg import UniqueID

    def _uuid_bytes(raw: bytes) -> Any:
        return raw


RCS_FLOOR_SQM = 1e-10
AMPLITUDE_FLOOR_DB = -100.0
NOMINAL_VARIANCES = {"position": 1.0, "velocity": 0.25, "acceleration": 1.0}  # m², (m/s)², (m/s²)²
DETECTION_KEYS = ("range", "azimuth", "elevation", "velocity", "rcs_sqm")
_INT64 = (-(2**63), 2**63 - 1)


def _table(items: Any, keys: Sequence[str], where: str) -> np.ndarray:
    """An (N, len(keys)) float array of the named fields of a list of maps, checked finite."""
    if not isinstance(items, (list, tuple)):
        raise ConversionError(f"{where} must be a list, got {type(items).__name__}")
    getter = operator.itemgetter(*keys)
    try:
        rows = [getter(item) for item in items]
    except KeyError as exc:
        raise ConversionError(f"{where}: an entry has no {exc.args[0]!r}") from exc
    except TypeError as exc:
        raise ConversionError(f"{where}: entries must be maps") from exc
    try:
        table = np.array(rows, dtype=float).reshape(len(rows), len(keys))
    except (TypeError, ValueError) as exc:
        raise ConversionError(f"{where}: fields {', '.join(keys)} must be numbers") from exc
    if not np.isfinite(table).all():
        raise ConversionError(f"{where}: fields {', '.join(keys)} must be finite")
    return table


def amplitude_db(rcs_sqm: np.ndarray) -> np.ndarray:
    """Radar cross-section (m²) in dBsm, floored at AMPLITUDE_FLOOR_DB."""
    return 10.0 * np.log10(np.maximum(np.asarray(rcs_sqm, dtype=float), RCS_FLOOR_SQM))


@sim_fields.converter("radar_scan")
def radar_scan(msg: Mapping[str, Any], ctx: ConvertContext) -> RadarScan:
    """sim RadarDetection message -> RadarScan."""
    table = _table(sim_fields.field(msg, "radar_detections", "radar"), DETECTION_KEYS, "radar_detections")
    rng, azimuth, elevation, velocity, rcs = table.T
    if ctx.enu:
        azimuth = -azimuth
    amplitude = amplitude_db(rcs)
    rows = np.column_stack([rng, azimuth, elevation, velocity, amplitude]).tolist()
    returns = [
        RadarReturn(range=r, azimuth=a, elevation=e, doppler_velocity=v, amplitude=amp)
        for r, a, e, v, amp in rows
    ]
    return RadarScan(header=sim_header(msg, ctx), returns=returns)


def track_uuid(track_id: Any) -> UniqueID:
    """16-byte uuid of a sim track id: 8 zero bytes, then the id as big-endian signed int64."""
    value = sim_fields.integer(track_id, "radar_tracks: id")
    if not _INT64[0] <= value <= _INT64[1]:
        raise ConversionError(f"radar_tracks: id {value} does not fit in 64 bits")
    return UniqueID(uuid=_uuid_bytes(bytes(8) + value.to_bytes(8, "big", signed=True)))


def _vectors(tracks: list[Any], key: str) -> np.ndarray:
    maps = []
    for track in tracks:
        value = sim_fields.field(track, key, "radar_tracks entry")
        maps.append(sim_fields.as_map(value, f"radar_tracks: {key}"))
    return _table(maps, ("x", "y", "z"), f"radar_tracks: {key}")


def _diagonal(variance: float) -> list[float]:
    return [variance, 0.0, 0.0, variance, 0.0, variance]


@sim_fields.converter("radar_tracks")
def radar_tracks(msg: Mapping[str, Any], ctx: ConvertContext) -> RadarTracks:
    """sim RadarTrack message -> RadarTracks."""
    tracks = sim_fields.field(msg, "radar_tracks", "radar")
    if not isinstance(tracks, (list, tuple)):
        raise ConversionError(f"radar_tracks must be a list, got {type(tracks).__name__}")
    tracks = list(tracks)
    ids = [track_uuid(sim_fields.field(t, "id", "radar_tracks entry")) for t in tracks]
    vectors = [_vectors(tracks, key) for key in ("position_est", "velocity_est", "accel_est")]
    if ctx.enu:
        vectors = [frames.frd_to_flu(v) for v in vectors]
    positions, velocities, accels = (v.tolist() for v in vectors)
    variances = {
        name: sim_fields.number(ctx.params.get(f"{name}_variance", default), f"{name}_variance")
        for name, default in NOMINAL_VARIANCES.items()
    }
    out = [
        RadarTrack(
            uuid=uid,
            position=Point(x=p[0], y=p[1], z=p[2]),
            velocity=Vector3(x=v[0], y=v[1], z=v[2]),
            acceleration=Vector3(x=a[0], y=a[1], z=a[2]),
            size=Vector3(x=0.0, y=0.0, z=0.0),
            classification=RadarTrack.NO_CLASSIFICATION,
            position_covariance=_diagonal(variances["position"]),
            velocity_covariance=_diagonal(variances["velocity"]),
            acceleration_covariance=_diagonal(variances["acceleration"]),
            size_covariance=[0.0] * 6,
        )
        for uid, p, v, a in zip(ids, positions, velocities, accels)
    ]
    return RadarTracks(header=sim_header(msg, ctx), tracks=out)
