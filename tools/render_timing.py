"""Timing renders of the built-in world: the camera poses a measurement takes in turn, and the median time
of a call."""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable

import numpy as np

from airsim_mapper.common.geometry import quat_from_rpy

# oblique over the blocks, facing a wall at 8 m, straight down at the pad, towards the ball
POSES = (
    (np.array([0.0, 0.0, -4.0]), quat_from_rpy(0.0, -0.2, 0.6)),
    (np.array([20.0, 0.0, -4.0]), quat_from_rpy(0.0, 0.0, 0.0)),
    (np.array([0.0, 0.0, -4.0]), quat_from_rpy(0.0, -math.pi / 2, 0.0)),
    (np.array([14.0, 14.0, -3.5]), quat_from_rpy(0.0, -0.05, math.pi / 4)),
)


def median_ms(
    fn: Callable[[int], object], calls: int, clock: Callable[[], float] = time.perf_counter
) -> float:
    """Median time (ms, by `clock`) of `fn(i)` over `calls` calls, after one warm-up call."""
    fn(0)
    samples = []
    for i in range(calls):
        start = clock()
        fn(i)
        samples.append((clock() - start) * 1e3)
    return statistics.median(samples)
