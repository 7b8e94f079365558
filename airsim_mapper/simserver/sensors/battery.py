"""A battery's mutable state and its service methods, as the real server's `Battery` sensor has them.

The real sensor (core_sim/src/sensors/battery.cpp) integrates `remaining -= dt * drain_rate` each physics
update and registers five methods next to its topic: `GetBatteryStatus` (the topic's message),
`SetBatteryRemaining(desired_battery_remaining)` (percent 0-100, else false), `GetBatteryDrainRate`,
`SetBatteryDrainRate(desired_drain_rate)` (>= 0, and not in rotor-power mode, else false) and
`SetBatteryHealthStatus(battery_health_indicator)` (false makes the charge state UNHEALTHY until set true).
Here the charge is integrated over sim time whenever the state is read, so it does not depend on how
often anyone looks.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from airsim_mapper.simserver.sensors.instrument_models import (
    BATTERY_CRITICAL,
    BATTERY_LOW,
    BATTERY_OK,
    InstrumentError,
    _number,
)

BATTERY_UNHEALTHY = "BATTERY_CHARGE_STATE_UNHEALTHY"
ROTOR_POWER_MODE = "rotor-power-discharge-mode"


@dataclass
class BatteryState:
    """Charge (capacity units), drain rate (units/s) and health of one battery sensor; thread-safe."""

    capacity: float
    remaining: float
    drain_rate: float
    rotor_power: bool = False
    healthy: bool = True
    updated_ns: int = 0
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    @classmethod
    def from_config(cls, cfg: Mapping[str, Any], start_ns: int) -> BatteryState:
        capacity = _number(cfg, "total-battery-capacity", 100.0)
        if capacity <= 0:
            raise InstrumentError(
                f"sensor {cfg.get('id', '<sensor>')!r}: 'total-battery-capacity' must be positive"
            )
        return cls(
            capacity=capacity,
            remaining=_number(cfg, "battery-capacity-on-start", capacity),
            drain_rate=_number(cfg, "battery-drain-rate-on-start", 0.02),
            rotor_power=cfg.get("battery-mode") == ROTOR_POWER_MODE,
            updated_ns=start_ns,
        )

    def _advance(self, now_ns: int) -> None:
        dt = max(0, now_ns - self.updated_ns) / 1e9
        self.remaining = max(0.0, self.remaining - dt * self.drain_rate)
        self.updated_ns = max(self.updated_ns, now_ns)

    def message(self, now_ns: int) -> dict[str, Any]:
        """The battery topic's message (and GetBatteryStatus's reply) at `now_ns`."""
        with self._lock:
            self._advance(now_ns)
            percent = 100.0 * self.remaining / self.capacity
            if not self.healthy:
                state = BATTERY_UNHEALTHY
            else:
                state = BATTERY_CRITICAL if percent < 5.0 else BATTERY_LOW if percent < 20.0 else BATTERY_OK
            seconds = self.remaining / self.drain_rate if self.drain_rate > 0 else 0.0
            return {
                "time_stamp": int(now_ns),
                "battery_pct_remaining": percent,
                "estimated_time_remaining": int(seconds),
                "battery_charge_state": state,
            }

    def set_remaining(self, percent: float, now_ns: int) -> bool:
        if not (isinstance(percent, (int, float)) and 0.0 <= percent <= 100.0):
            return False
        with self._lock:
            self._advance(now_ns)
            self.remaining = percent / 100.0 * self.capacity
        return True

    def set_drain_rate(self, rate: float, now_ns: int) -> bool:
        if not (isinstance(rate, (int, float)) and math.isfinite(rate) and rate >= 0.0) or self.rotor_power:
            return False
        with self._lock:
            self._advance(now_ns)
            self.drain_rate = float(rate)
        return True

    def set_healthy(self, healthy: bool) -> bool:
        with self._lock:
            self.healthy = bool(healthy)
        return True
