"""Scene configuration as the server receives it from `/Sim/LoadScene` (one merged JSON document).

`parse_scene` validates what the server needs and returns immutable specs (`SceneSpec`, its robots, their
sensors and capture settings, the clock, the environment actors and the wind).
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from airsim_mapper.common.geometry import IDENTITY_Q, OriginError, parse_origin
from airsim_mapper.common.image_types import SIM_IMAGE_LEAVES
from airsim_mapper.simserver.errors import SimServerError
from airsim_mapper.simserver.motion.motion import DEFAULT_MASS_KG, MAX_WIND_MPS
from airsim_mapper.simserver.render.annotations import AnnotationError, AnnotationSettings
from airsim_mapper.simserver.render.camera_model import DEFAULT_MAX_DEPTH_VIS
from airsim_mapper.simserver.scene.env_actors import ENV_ACTOR_TYPES, EnvActorSpec, actor_script
from airsim_mapper.simserver.scene.geo import DEFAULT_HOME, geo_to_ned

IMAGE_TYPE_NAMES = SIM_IMAGE_LEAVES

SENSOR_LEAVES = {
    "imu": ("imu_kinematics", "imu", 100),
    "gps": ("gps", "", 100),
    "barometer": ("barometer", "barometer", 100),
    "magnetometer": ("magnetometer", "magnetometer", 100),
    "distance-sensor": ("distance_sensor", "distance-sensor", 60),
    "battery": ("battery", "", 100),
    "airspeed": ("airspeed", "", 100),
    "lidar": ("lidar", "lidar", 60),
}
SENSOR_TYPES = frozenset({"camera", "radar", *SENSOR_LEAVES})
CLOCK_TYPES = frozenset({"steppable", "real-time"})


class SceneSpecError(SimServerError, ValueError):
    """The scene configuration cannot be loaded; the message says what is wrong."""


@dataclass(frozen=True)
class CaptureSpec:
    image_type: int
    width: int
    height: int
    fov_deg: float
    capture_enabled: bool
    streaming_enabled: bool
    max_depth_m: float = DEFAULT_MAX_DEPTH_VIS  # depth vis: metres that map to white (max-depth-meters)
    compress: bool = True  # PNG for the non-depth types (the real server's default is true)
    pixels_as_float: bool = False  # see image_encoding: never changes what the 1.1.0 client decodes


@dataclass(frozen=True)
class SensorSpec:
    id: str
    type: str
    config: Mapping[str, Any]
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    orientation: np.ndarray = field(default_factory=lambda: IDENTITY_Q.copy())
    captures: tuple[CaptureSpec, ...] = ()
    capture_interval: float = 5.0
    annotation: AnnotationSettings | None = None  # a camera's annotation-settings, when on

    def enabled_captures(self) -> tuple[CaptureSpec, ...]:
        return tuple(c for c in self.captures if c.capture_enabled)


@dataclass(frozen=True)
class RobotSpec:
    name: str
    position: np.ndarray
    orientation: np.ndarray
    config: Mapping[str, Any]
    sensors: tuple[SensorSpec, ...]

    @property
    def controller_type(self) -> str | None:
        controller = self.config.get("controller")
        return str(controller.get("type", "")) if isinstance(controller, Mapping) else None

    @property
    def rover(self) -> bool:
        """A ground robot driven by the simple-drive controller (SetRoverControls, MoveByHeading)."""
        return self.controller_type == "simple-drive-api"

    @functools.cached_property
    def multirotor(self) -> bool:
        """Read every physics tick: parsed from the config once."""
        return self.controller_type is not None and not self.rover

    @property
    def physics_type(self) -> str:
        return str(self.config.get("physics-type", "fast-physics"))

    @property
    def mass_kg(self) -> float:
        """The sum of the links' `inertial.mass` (checked by the parser); DEFAULT_MASS_KG if none is given."""
        links = self.config.get("links", []) or []
        masses = [
            float(link["inertial"]["mass"])
            for link in links
            if isinstance(link, Mapping)
            and isinstance(link.get("inertial"), Mapping)
            and "mass" in link["inertial"]
        ]
        return sum(masses) if masses else DEFAULT_MASS_KG

    def actuator_ids(self) -> list[str]:
        actuators = self.config.get("actuators", []) or []
        return [str(a["name"]) for a in actuators if isinstance(a, Mapping) and "name" in a]


@dataclass(frozen=True)
class ClockSpec:
    type: str = "steppable"
    step_ns: int = 3_000_000
    pause_on_start: bool = False


@dataclass(frozen=True)
class SceneSpec:
    id: str
    robots: tuple[RobotSpec, ...]
    clock: ClockSpec
    home_geo: tuple[float, float, float]
    env_actors: tuple[EnvActorSpec, ...] = ()
    wind: tuple[float, float, float] = (0.0, 0.0, 0.0)  # world NED m/s, the scene's `wind.velocity`

    @property
    def prefix(self) -> str:
        return f"/Sim/{self.id}"

    def robot_prefix(self, robot: str) -> str:
        return f"{self.prefix}/robots/{robot}"

    def sensor_prefix(self, robot: str, sensor: str) -> str:
        return f"{self.prefix}/robots/{robot}/sensors/{sensor}"


def default_scene() -> SceneSpec:
    """The scene served before any load: `SceneBasicDrone` with one sensorless drone at 4 m."""
    robot = RobotSpec(
        "Drone1",
        np.array([0.0, 0.0, -4.0]),
        IDENTITY_Q.copy(),
        {"controller": {"type": "simple-flight-api"}},
        (),
    )
    return SceneSpec("SceneBasicDrone", (robot,), ClockSpec(), DEFAULT_HOME)


# ---------------------------------------------------------------------------------------------- parsing


def _require(mapping: Mapping[str, Any], key: str, where: str) -> Any:
    if key not in mapping:
        raise SceneSpecError(f"{where} has no '{key}'")
    return mapping[key]


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SceneSpecError(f"{where} must be a finite number, got {value!r}")
    return float(value)


def _origin(origin: Any, where: str, home: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    if origin is None:
        return np.zeros(3), IDENTITY_Q.copy()
    if not isinstance(origin, Mapping):
        raise SceneSpecError(f"{where} origin must be an object, got {origin!r}")
    try:
        if "geo-point" in origin:
            parts = str(origin["geo-point"]).split()
            if len(parts) != 3:
                raise SceneSpecError(f"{where} origin 'geo-point' must hold three numbers")
            position = geo_to_ned(tuple(float(p) for p in parts), home)  # type: ignore[arg-type]
            _, orientation = parse_origin({k: v for k, v in origin.items() if k != "geo-point"})
            return position, orientation
        return parse_origin(origin)
    except (OriginError, ValueError) as exc:
        if isinstance(exc, SceneSpecError):
            raise
        raise SceneSpecError(f"{where}: {exc}") from exc


def _captures(sensor: Mapping[str, Any], where: str) -> tuple[CaptureSpec, ...]:
    settings = sensor.get("capture-settings", [])
    if not isinstance(settings, list):
        raise SceneSpecError(f"{where} 'capture-settings' must be a list")
    captures = []
    for item in settings:
        if not isinstance(item, Mapping):
            raise SceneSpecError(f"{where} capture setting must be an object, got {item!r}")
        image_type = item.get("image-type")
        if (
            isinstance(image_type, bool)
            or not isinstance(image_type, int)
            or image_type not in IMAGE_TYPE_NAMES
        ):
            raise SceneSpecError(f"{where} has an invalid 'image-type' {image_type!r} (expected 0..6)")
        here = f"{where} image-type {image_type}"
        width = int(_number(item.get("width", 256), f"{here} 'width'"))
        height = int(_number(item.get("height", 144), f"{here} 'height'"))
        if width <= 0 or height <= 0:
            raise SceneSpecError(f"{here} must have a positive width and height, got {width}x{height}")
        fov = _number(item.get("fov-degrees", 90.0), f"{here} 'fov-degrees'")
        if not 0.0 < fov < 180.0:
            raise SceneSpecError(f"{here} 'fov-degrees' must be in (0, 180), got {fov}")
        max_depth = _number(item.get("max-depth-meters", DEFAULT_MAX_DEPTH_VIS), f"{here} 'max-depth-meters'")
        if max_depth <= 0.0:
            raise SceneSpecError(f"{here} 'max-depth-meters' must be positive, got {max_depth}")
        captures.append(
            CaptureSpec(
                image_type,
                width,
                height,
                fov,
                bool(item.get("capture-enabled", False)),
                bool(item.get("streaming-enabled", False)),
                max_depth,
                bool(item.get("compress", True)),
                bool(item.get("pixels-as-float", False)),
            )
        )
    return tuple(captures)


def _sensor(sensor: Any, where: str, home: tuple[float, float, float]) -> SensorSpec | None:
    if not isinstance(sensor, Mapping):
        raise SceneSpecError(f"{where} sensor must be an object, got {sensor!r}")
    sensor_id = _require(sensor, "id", f"{where} sensor")
    sensor_type = _require(sensor, "type", f"{where} sensor '{sensor_id}'")
    here = f"{where} sensor '{sensor_id}'"
    if sensor_type not in SENSOR_TYPES:
        raise SceneSpecError(f"{here} has unknown type '{sensor_type}'")
    if not sensor.get("enabled", False):
        return None
    position, orientation = _origin(sensor.get("origin"), here, home)
    captures = _captures(sensor, here) if sensor_type == "camera" else ()
    if "report-frequency" in sensor:
        frequency = _number(sensor["report-frequency"], f"{here} 'report-frequency'")
        if frequency < 0:
            raise SceneSpecError(f"{here} 'report-frequency' must be at least 0, got {frequency:g}")
    interval = _number(sensor.get("capture-interval", 5.0), f"{here} 'capture-interval'")
    if interval <= 0:
        raise SceneSpecError(f"{here} 'capture-interval' must be positive, got {interval}")
    annotation = None
    if sensor_type == "camera":
        try:
            annotation = AnnotationSettings.from_config(sensor)
        except AnnotationError as exc:
            raise SceneSpecError(f"{here}: {exc}") from exc
    return SensorSpec(
        str(sensor_id), sensor_type, sensor, position, orientation, captures, interval, annotation
    )


def _robot(actor: Mapping[str, Any], index: int, home: tuple[float, float, float]) -> RobotSpec:
    name = _require(actor, "name", f"actor #{index}")
    if not isinstance(name, str) or not name:
        raise SceneSpecError(f"actor #{index} 'name' must be a non-empty string")
    where = f"robot '{name}'"
    config = _require(actor, "robot-config", where)
    if not isinstance(config, Mapping):
        raise SceneSpecError(
            f"{where} 'robot-config' must be the inlined robot config object, got {type(config).__name__} "
            "(the client inlines robot files before LoadScene)"
        )
    position, orientation = _origin(_require(actor, "origin", where), where, home)
    sensors_cfg = config.get("sensors", [])
    if not isinstance(sensors_cfg, list):
        raise SceneSpecError(f"{where} 'sensors' must be a list")
    sensors = [s for s in (_sensor(item, where, home) for item in sensors_cfg) if s is not None]
    ids = [s.id for s in sensors]
    duplicates = sorted({i for i in ids if ids.count(i) > 1})
    if duplicates:
        raise SceneSpecError(f"{where} has duplicate sensor ids: {', '.join(duplicates)}")
    links = config.get("links", []) or []
    for i, link in enumerate(links if isinstance(links, list) else []):
        inertial = link.get("inertial") if isinstance(link, Mapping) else None
        if isinstance(inertial, Mapping) and "mass" in inertial:
            mass = _number(inertial["mass"], f"{where} links[{i}] 'inertial.mass'")
            if mass <= 0:
                raise SceneSpecError(f"{where} links[{i}] 'inertial.mass' must be positive, got {mass:g}")
    return RobotSpec(name, position, orientation, config, tuple(sensors))


def _clock(clock: Any) -> ClockSpec:
    if clock is None:
        return ClockSpec()
    if not isinstance(clock, Mapping):
        raise SceneSpecError(f"scene 'clock' must be an object, got {clock!r}")
    kind = clock.get("type", "steppable")
    if kind not in CLOCK_TYPES:
        raise SceneSpecError(f"scene clock type '{kind}' is not supported (expected steppable or real-time)")
    step_ns = int(_number(clock.get("step-ns", 3_000_000), "scene clock 'step-ns'"))
    if step_ns <= 0:
        raise SceneSpecError(f"scene clock 'step-ns' must be positive, got {step_ns}")
    return ClockSpec(kind, step_ns, bool(clock.get("pause-on-start", False)))


def _home(home: Any) -> tuple[float, float, float]:
    if not home:
        return DEFAULT_HOME
    if not isinstance(home, Mapping):
        raise SceneSpecError(f"scene 'home-geo-point' must be an object, got {home!r}")
    return tuple(  # type: ignore[return-value]
        _number(home.get(key, default), f"scene home-geo-point '{key}'")
        for key, default in zip(("latitude", "longitude", "altitude"), DEFAULT_HOME)
    )


def parse_scene(text: str | bytes) -> SceneSpec:
    """Validate the scene JSON sent with `/Sim/LoadScene`; raises SceneSpecError naming the problem."""
    try:
        config = json.loads(text)
    except (ValueError, TypeError) as exc:
        raise SceneSpecError(f"scene_config is not valid JSON: {exc}") from exc
    if not isinstance(config, Mapping):
        raise SceneSpecError(f"scene_config must be a JSON object, got {type(config).__name__}")
    scene_id = _require(config, "id", "scene config")
    if not isinstance(scene_id, str) or not scene_id or "/" in scene_id:
        raise SceneSpecError(f"scene 'id' must be a non-empty string without '/', got {scene_id!r}")
    actors = config.get("actors", [])
    if not isinstance(actors, list):
        raise SceneSpecError("scene 'actors' must be a list")
    home = _home(config.get("home-geo-point"))
    robots = []
    for index, actor in enumerate(actors):
        if not isinstance(actor, Mapping):
            raise SceneSpecError(f"actor #{index} must be an object")
        if actor.get("type") == "robot":
            robots.append(_robot(actor, index, home))
    names = [r.name for r in robots]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise SceneSpecError(f"scene has duplicate robot names: {', '.join(duplicates)}")
    env_actors = config.get("environment-actors", []) or []
    if not isinstance(env_actors, list):
        raise SceneSpecError("scene 'environment-actors' must be a list")
    envs = tuple(_env_actor(a, i, home) for i, a in enumerate(env_actors))
    wind = _wind(config.get("wind"))
    return SceneSpec(scene_id, tuple(robots), _clock(config.get("clock")), home, envs, wind)


def _wind(wind: Any) -> tuple[float, float, float]:
    """The scene's `wind` {"velocity": "x y z"} (m/s, world NED); calm without one."""
    if wind is None:
        return (0.0, 0.0, 0.0)
    if not isinstance(wind, Mapping):
        raise SceneSpecError(f"scene 'wind' must be an object, got {wind!r}")
    text = wind.get("velocity", "0 0 0")
    parts = text.split() if isinstance(text, str) else []
    try:
        velocity = tuple(float(p) for p in parts)
    except ValueError:
        velocity = ()
    if len(velocity) != 3 or not all(math.isfinite(v) and abs(v) <= MAX_WIND_MPS for v in velocity):
        raise SceneSpecError(
            f"scene wind 'velocity' must be three numbers within {MAX_WIND_MPS:g} m/s, got {text!r}"
        )
    return velocity  # type: ignore[return-value]


def _env_actor(actor: Any, index: int, home: tuple[float, float, float]) -> EnvActorSpec:
    if not isinstance(actor, Mapping) or actor.get("type") not in ENV_ACTOR_TYPES:
        raise SceneSpecError(
            f"environment actor #{index} must be an object of type {', '.join(ENV_ACTOR_TYPES)}"
        )
    name = _require(actor, "name", f"environment actor #{index}")
    position, orientation = _origin(actor.get("origin"), f"environment actor '{name}'", home)
    config = actor.get("env-actor-config", {})
    links = config.get("links", []) if isinstance(config, Mapping) else []
    names = tuple(str(link["name"]) for link in links if isinstance(link, Mapping) and "name" in link)
    script = actor_script(config, f"environment actor '{name}'", SceneSpecError)
    return EnvActorSpec(str(name), position, orientation, names, script)
