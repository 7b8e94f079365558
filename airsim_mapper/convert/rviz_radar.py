"""radar_msgs/RadarScan -> visualization_msgs/MarkerArray, because RViz has no radar display.

Each scan becomes one SPHERE_LIST marker in the scan's own frame (the radar sensor frame), one sphere per
return, coloured by amplitude (weakest yellow, strongest red). A scan without returns becomes a DELETE of
that marker, so old detections do not linger.

The position of a return follows the bridge's radar convention (see `airsim_mapper/convert/radar.py`):

- ``frd`` (`mappings/default.yaml`): azimuth positive to the right, elevation positive up, z down:
  ``(r cos(el) cos(az), r cos(el) sin(az), -r sin(el))``;
- ``flu`` (`mappings/enu.yaml`): azimuth positive to the left, elevation positive up, z up:
  ``(r cos(el) cos(az), r cos(el) sin(az), r sin(el))``.
"""

from __future__ import annotations

import operator
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from airsim_mapper.convert.errors import ConvertError

CONVENTIONS = ("frd", "flu")
RETURN_FIELDS = ("range", "azimuth", "elevation", "doppler_velocity", "amplitude")
WEAK_RGBA = (1.0, 0.9, 0.1, 1.0)  # yellow
STRONG_RGBA = (1.0, 0.1, 0.1, 1.0)  # red


class RadarMarkerError(ConvertError, ValueError):
    """A scan or an option cannot be turned into markers."""


@dataclass(frozen=True)
class MarkerStyle:
    """How the detections look in RViz."""

    namespace: str = "radar_detections"
    marker_id: int = 0
    diameter_m: float = 1.0
    lifetime_s: float = 1.0


def return_points(
    ranges: Sequence[float] | np.ndarray,
    azimuths: Sequence[float] | np.ndarray,
    elevations: Sequence[float] | np.ndarray,
    convention: str = "frd",
) -> np.ndarray:
    """(N, 3) Cartesian points in the radar frame of N (range, azimuth, elevation) returns (m, rad)."""
    if convention not in CONVENTIONS:
        raise RadarMarkerError(f"unknown radar convention {convention!r} (expected one of {CONVENTIONS})")
    rng = np.asarray(ranges, dtype=float)
    az = np.asarray(azimuths, dtype=float)
    el = np.asarray(elevations, dtype=float)
    if not rng.shape == az.shape == el.shape or rng.ndim != 1:
        raise RadarMarkerError("range, azimuth and elevation must be 1-D arrays of one length")
    horizontal = rng * np.cos(el)
    up = rng * np.sin(el)
    return np.column_stack(
        [horizontal * np.cos(az), horizontal * np.sin(az), -up if convention == "frd" else up]
    )


def amplitude_colors(amplitudes: Sequence[float] | np.ndarray) -> np.ndarray:
    """(N, 4) RGBA in [0, 1]: a linear ramp from WEAK_RGBA (lowest amplitude of the scan) to STRONG_RGBA."""
    amp = np.nan_to_num(np.asarray(amplitudes, dtype=float), nan=0.0, posinf=0.0, neginf=0.0)
    if not amp.size:
        return np.zeros((0, 4))
    span = float(amp.max() - amp.min())
    weight = (amp - amp.min()) / span if span > 0 else np.ones_like(amp)
    weak, strong = np.asarray(WEAK_RGBA), np.asarray(STRONG_RGBA)
    return weak + weight[:, None] * (strong - weak)


def scan_table(scan: Any) -> np.ndarray:
    """(N, 5) array of a RadarScan's returns: range, azimuth, elevation, doppler_velocity, amplitude."""
    getter = operator.attrgetter(*RETURN_FIELDS)
    return np.array([getter(r) for r in scan.returns], dtype=float).reshape(-1, len(RETURN_FIELDS))


def scan_markers(scan: Any, convention: str = "frd", style: MarkerStyle | None = None) -> Any:
    """A visualization_msgs/MarkerArray with one SPHERE_LIST marker of the scan's returns (returns with a
    non-finite range, azimuth or elevation are left out)."""
    from geometry_msgs.msg import Point
    from std_msgs.msg import ColorRGBA
    from visualization_msgs.msg import Marker, MarkerArray

    from airsim_mapper.convert.flavour import duration

    style = style or MarkerStyle()
    table = scan_table(scan)
    table = table[np.isfinite(table[:, :3]).all(axis=1)]
    marker = Marker(header=scan.header, ns=style.namespace, id=style.marker_id)
    if not len(table):
        marker.action = Marker.DELETE
        return MarkerArray(markers=[marker])
    xyz = return_points(table[:, 0], table[:, 1], table[:, 2], convention)
    marker.type = Marker.SPHERE_LIST
    marker.action = Marker.ADD
    marker.pose.orientation.w = 1.0
    marker.scale.x = marker.scale.y = marker.scale.z = style.diameter_m
    marker.color = ColorRGBA(**dict(zip("rgba", map(float, WEAK_RGBA))))
    marker.lifetime = duration(style.lifetime_s)
    marker.points = [Point(x=x, y=y, z=z) for x, y, z in xyz.tolist()]
    marker.colors = [ColorRGBA(r=r, g=g, b=b, a=a) for r, g, b, a in amplitude_colors(table[:, 4]).tolist()]
    return MarkerArray(markers=[marker])
