"""Geo points and the scene's local NED frame: a flat earth around the scene's home point."""

from __future__ import annotations

import math

import numpy as np

DEFAULT_HOME = (47.641468, -122.140165, 122.0)  # latitude, longitude, altitude of a scene without a home
EARTH_RADIUS_M = 6378137.0


def geo_to_ned(geo: tuple[float, float, float], home: tuple[float, float, float]) -> np.ndarray:
    """Flat-earth NED offset of a geo point (lat, lon, alt) from the home point."""
    lat0 = math.radians(home[0])
    north = math.radians(geo[0] - home[0]) * EARTH_RADIUS_M
    east = math.radians(geo[1] - home[1]) * EARTH_RADIUS_M * math.cos(lat0)
    return np.array([north, east, home[2] - geo[2]])


def ned_to_geo(ned: np.ndarray, home: tuple[float, float, float]) -> tuple[float, float, float]:
    lat0 = math.radians(home[0])
    lat = home[0] + math.degrees(float(ned[0]) / EARTH_RADIUS_M)
    lon = home[1] + math.degrees(float(ned[1]) / (EARTH_RADIUS_M * max(math.cos(lat0), 1e-9)))
    return lat, lon, home[2] - float(ned[2])
