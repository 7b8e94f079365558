"""Helpers for converter tests: genpy round trips and a context factory."""

from __future__ import annotations

import io
import time
from collections.abc import Callable
from typing import Any

import pytest

from airsim_mapper.convert.context import ConvertContext


def serialize_roundtrip(msg: Any) -> Any:
    """Serialise a ROS message with genpy, deserialise it into a fresh instance, and return that."""
    buffer = io.BytesIO()
    msg.serialize(buffer)
    copy = type(msg)()
    copy.deserialize(buffer.getvalue())
    return copy


@pytest.fixture
def roundtrip():
    return serialize_roundtrip


@pytest.fixture
def enu() -> ConvertContext:
    return ConvertContext(frame_id="map", convention="enu")


@pytest.fixture
def ned() -> ConvertContext:
    return ConvertContext(frame_id="map", convention="ned")


def best_of(runs: int, fn: Callable[[], Any]) -> float:
    """The shortest wall time (s) of `runs` calls: robust against a busy machine."""
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


@pytest.fixture
def timed():
    return best_of
