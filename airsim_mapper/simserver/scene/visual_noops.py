"""Scene calls that only change how Unreal draws the world, answered as documented no-ops.

Debug plotting, trace lines, weather, time of day, sun, clouds and lights have nothing to act on in the
headless world. Each is accepted with the reply the real server gives on success (true, or the value last
set for the getters) and a warning in the server log, once per method and scene, naming what was ignored,
so that the rest of a script runs. Wind is read back by GetWindVelocity and acts on the kinematics as a
velocity disturbance: an airborne robot with no command running drifts with it (a running command's
controller holds its course, as a position controller would).
"""

from __future__ import annotations

import logging
import math
import threading
from collections.abc import Callable
from typing import Any

from airsim_mapper.simserver.motion.motion import MAX_WIND_MPS
from airsim_mapper.simserver.wire.services import Method, ServiceError

LOG = logging.getLogger("airsim_mapper.simserver")

# method -> required parameters (exactly as the 1.1.0 client sends them)
IGNORED: dict[str, tuple[str, ...]] = {
    "debugPlotArrows": (
        "points_start",
        "points_end",
        "color_rgba",
        "thickness",
        "arrow_size",
        "duration",
        "is_persistent",
    ),
    "debugPlotDashedLine": ("points", "color_rgba", "thickness", "duration", "is_persistent"),
    "debugPlotPoints": ("points", "color_rgba", "size", "duration", "is_persistent"),
    "debugPlotSolidLine": ("points", "color_rgba", "thickness", "duration", "is_persistent"),
    "debugPlotStrings": ("strings", "positions", "scale", "color_rgba", "duration"),
    "debugPlotTransforms": ("poses", "scale", "thickness", "duration", "is_persistent"),
    "debugPlotTransformsWithNames": (
        "poses",
        "names",
        "tf_scale",
        "tf_thickness",
        "text_scale",
        "text_color_rgba",
        "duration",
    ),
    "debugFlushPersistentMarkers": (),
    "SetTraceLine": ("color_rgba", "thickness"),
    "ToggleTrace": (),
    "SimSetWeatherVisualEffectsStatus": ("status",),
    "ResetWeatherEffects": (),
    "SetTimeOfDay": ("status", "datetime", "is_dst", "clock_speed", "update_interval", "move_sun"),
    "SetSunPositionFromDateTime": ("datetime", "format", "is_dst"),
    "SetLightObjectColor": ("object_name", "color_rgb"),
    "SetLightObjectIntensity": ("object_name", "new_intensity"),
    "SetLightObjectRadius": ("object_name", "new_radius"),
}
DEFAULT_TIME_OF_DAY = "2021-01-01 12:00:00"


class VisualSettings:
    """The values the visual setters last stored, so that their getters answer consistently."""

    def __init__(
        self, on_wind: Callable[[list[float]], None] | None = None, wind: list[float] | None = None
    ) -> None:
        self._on_wind = on_wind
        self._lock = threading.Lock()
        self._warned: set[str] = set()
        self.weather: dict[str, float] = {}
        self.sun_intensity = 1.0
        self.cloud_shadow = 0.0
        self.time_of_day = DEFAULT_TIME_OF_DAY
        self.wind = list(wind) if wind is not None else [0.0, 0.0, 0.0]  # the scene's, until set

    def _warn(self, method: str, what: str = "") -> None:
        with self._lock:
            if method in self._warned:
                return
            self._warned.add(method)
        LOG.warning("%s ignored: the headless server has no %s", method, what or "rendering to change")

    def _ignore(self, method: str) -> Callable[[dict[str, Any]], bool]:
        def accept(params: dict[str, Any]) -> bool:
            if method == "SetTimeOfDay" and isinstance(params.get("datetime"), str):
                self.time_of_day = params["datetime"]
            self._warn(method)
            return True

        return accept

    def _set_weather(self, params: dict[str, Any]) -> bool:
        self._warn("SetWeatherVisualEffectsParameter", "weather")
        with self._lock:
            self.weather[str(int(params["param"]))] = float(params["value"])
        return True

    def _set_sun(self, params: dict[str, Any]) -> bool:
        self._warn("SetSunLightIntensity", "sun")
        self.sun_intensity = float(params["intensity"])
        return True

    def _set_clouds(self, params: dict[str, Any]) -> bool:
        self._warn("SetCloudShadowStrength", "clouds")
        self.cloud_shadow = float(params["strength"])
        return True

    def _set_wind(self, params: dict[str, Any]) -> bool:
        self._warn("SetWindVelocity", "aerodynamics: wind only makes idle airborne robots drift")
        wind = [float(params[k]) for k in ("v_x", "v_y", "v_z")]
        if not all(math.isfinite(v) and abs(v) <= MAX_WIND_MPS for v in wind):
            raise ServiceError(
                f"Wind velocity must be finite and within {MAX_WIND_MPS:g} m/s, got {wind}", 2.0
            )
        self.wind = wind
        if self._on_wind is not None:
            self._on_wind(wind)
        return True

    def methods(self, prefix: str) -> list[Method]:
        table = [Method(f"{prefix}/{name}", params, self._ignore(name)) for name, params in IGNORED.items()]
        table += [
            Method(f"{prefix}/SetWeatherVisualEffectsParameter", ("param", "value"), self._set_weather),
            Method(f"{prefix}/GetWeatherVisualEffectsParameter", (), lambda _: dict(self.weather)),
            Method(f"{prefix}/SetSunLightIntensity", ("intensity",), self._set_sun),
            Method(f"{prefix}/GetSunLightIntensity", (), lambda _: self.sun_intensity),
            Method(f"{prefix}/SetCloudShadowStrength", ("strength",), self._set_clouds),
            Method(f"{prefix}/GetCloudShadowStrength", (), lambda _: self.cloud_shadow),
            Method(f"{prefix}/GetSimTimeofDay", (), lambda _: self.time_of_day),
            Method(f"{prefix}/SetWindVelocity", ("v_x", "v_y", "v_z"), self._set_wind),
            Method(f"{prefix}/GetWindVelocity", (), lambda _: list(self.wind)),
        ]
        return table
