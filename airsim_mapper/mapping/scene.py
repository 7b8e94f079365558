"""Read a scene and its robot configs exactly as the simulator will receive them.

The merging and the JSON-schema validation are the client's own (`projectairsim.utils.
load_scene_config_as_dict`, protocol.md 6.1); this module wraps it so that files outside the config directory
are refused and every failure is a SceneConfigError naming the file, and it lists the scene's robots,
sensors and capture settings as plain frozen values. `Scene.config` is the merged dict the engine sends to
the simulator.
"""

from __future__ import annotations

import contextlib
import difflib
import json
import logging
import threading
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from functools import cache
from pathlib import Path, PurePath
from typing import Any

from airsim_mapper.common.files import ConfigFileError, read_config_text
from airsim_mapper.mapping.errors import MappingError

_CLIENT_READS = threading.Lock()  # guards every patch of the client's module state (see _client_patched)
SCENE_SCHEMA = "schema/scene_config_schema.jsonc"
ROBOT_SCHEMA = "schema/robot_config_schema.jsonc"


class SceneConfigError(MappingError):
    """The scene or a robot config cannot be read, lies outside the config directory, or is invalid."""


@dataclass(frozen=True)
class CaptureSetting:
    image_type: int
    capture_enabled: bool
    streaming_enabled: bool
    settings: Mapping[str, Any]  # the capture-settings entry as written (width, height, fov-degrees, ...)


@dataclass(frozen=True)
class Sensor:
    id: str
    kind: str  # the config's "type" with '-' as '_' (camera, lidar, radar, imu, distance_sensor, ...)
    enabled: bool
    config: Mapping[str, Any]  # the sensor entry of the merged robot config

    @property
    def captures(self) -> tuple[CaptureSetting, ...]:
        """A camera's capture settings (empty for other sensors)."""
        entries = self.config.get("capture-settings") or []
        return tuple(
            CaptureSetting(
                image_type=int(entry.get("image-type", 0)),
                capture_enabled=bool(entry.get("capture-enabled", False)),
                streaming_enabled=bool(entry.get("streaming-enabled", False)),
                settings=entry,
            )
            for entry in entries
            if isinstance(entry, Mapping)
        )


@dataclass(frozen=True)
class Robot:
    name: str
    actor: Mapping[str, Any]  # the scene's actor entry without its (large) robot-config
    sensors: tuple[Sensor, ...]

    def enabled_sensors(self, kind: str) -> tuple[Sensor, ...]:
        return tuple(sensor for sensor in self.sensors if sensor.kind == kind and sensor.enabled)


@dataclass(frozen=True)
class StreamingCamera:
    robot_name: str
    camera_name: str


@dataclass(frozen=True)
class Scene:
    name: str  # the scene's "id": <scene_name>
    file: str  # the scene file name, as given
    config_dir: str  # the --simconfigpath directory, resolved
    robots: tuple[Robot, ...]
    config: Mapping[str, Any]  # the merged scene dict, robot configs inlined: what the simulator receives

    @property
    def streaming_cameras(self) -> tuple[StreamingCamera, ...]:
        """Enabled cameras with a capture- and streaming-enabled scene (type 0) setting, in scene order."""
        return tuple(
            StreamingCamera(robot.name, camera.id)
            for robot in self.robots
            for camera in robot.enabled_sensors("camera")
            if any(c.image_type == 0 and c.capture_enabled and c.streaming_enabled for c in camera.captures)
        )


def contained(root: Path, name: str, what: str) -> Path:
    """`root / name` if it stays inside `root` (no absolute path, no '..', no symlink escaping it)."""
    if not isinstance(name, str) or not name:
        raise SceneConfigError.single(str(root), f"{what} must be a non-empty file name, got {name!r}")
    pure = PurePath(name)
    if pure.is_absolute():
        raise SceneConfigError.single(name, f"{what} must be relative to the config directory {root}")
    if ".." in pure.parts:
        raise SceneConfigError.single(name, f"{what} may not leave the config directory {root} ('..')")
    path = root / pure
    resolved = path.resolve()
    if not resolved.is_relative_to(root):
        raise SceneConfigError.single(
            str(path), f"{what} resolves outside the config directory {root} (symlink)"
        )
    return path


def _parse(path: Path, what: str, unreadable: bool) -> Any:
    import commentjson

    try:
        text = read_config_text(path)
    except ConfigFileError as err:
        raise SceneConfigError.single(
            str(path), err.about(what), err.line, err.column, unreadable=unreadable and err.unreadable
        ) from None
    try:
        return commentjson.loads(text)
    except Exception as err:  # commentjson raises lark errors, ValueError, RecursionError...
        first = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise SceneConfigError.single(str(path), f"invalid JSON in the {what}: {first}") from None


def _schema_message(err: Any) -> str:
    where = "/".join(str(p) for p in err.absolute_path) or "top level"
    return f"{where}: {err.message}"


def _robot_config_names(actor: Mapping[str, Any]) -> list[str]:
    names = actor.get("robot-config")
    return list(names) if isinstance(names, list) else [names]


@contextlib.contextmanager
def _quiet_client_log() -> Iterator[None]:
    """Keep the client's logger from creating its console handler and projectairsim_client.log file."""
    logger = logging.getLogger("projectairsim")
    handler = None if logger.hasHandlers() else logging.NullHandler()
    if handler:
        logger.addHandler(handler)
    try:
        yield
    finally:
        if handler:
            logger.removeHandler(handler)


@cache
def _schema_json(get_schema: Callable[[str], Any], text: str) -> str:
    """A schema text parsed once by the client's own `get_schema` (it re-parses ~100 kB of jsonc per call)."""
    return json.dumps(get_schema(text))


def _schema(resource: str) -> dict[str, Any]:
    """The client's packaged schema `resource`, as a fresh dict."""
    import projectairsim.utils as client_utils

    with _CLIENT_READS:  # the client's own get_schema, never a reader's patch of it
        get_schema, load_text_resource = client_utils.get_schema, client_utils.load_text_resource
    return json.loads(_schema_json(get_schema, load_text_resource(resource)))


@contextlib.contextmanager
def _client_patched() -> Iterator[None]:
    """The client's loader with its schemas cached, its file reads checked and its logger quiet: every
    patch of the client's module state is made and undone under the one lock, so two readers never see
    each other's patches (nor a half-undone one)."""
    with _CLIENT_READS, _quiet_client_log(), _fast_client_schemas(), _checked_client_reads():
        yield


@contextlib.contextmanager
def _fast_client_schemas() -> Iterator[None]:
    """Let the client's loader reuse the schemas it already parsed (same results, ~1 s faster a call)."""
    import projectairsim.utils as client_utils

    original = client_utils.get_schema
    client_utils.get_schema = lambda text: json.loads(_schema_json(original, text))
    try:
        yield
    finally:
        client_utils.get_schema = original


@contextlib.contextmanager
def _checked_client_reads() -> Iterator[None]:
    """The client's loader opens the scene, robot and environment-actor configs with the builtin `open`;
    here it gets their text through read_config_text (regular files only, bounded, with a timeout)."""
    import io

    import projectairsim.utils as client_utils

    def checked_open(path: str, mode: str = "r", *args: Any, **kwargs: Any) -> Any:
        if mode not in ("r", "rt"):
            return open(path, mode, *args, **kwargs)
        try:
            return io.StringIO(read_config_text(path))
        except ConfigFileError as err:
            raise SceneConfigError.single(err.file, err.about("config file"), err.line, err.column) from None

    client_utils.open = checked_open  # under _client_patched's lock
    try:
        yield
    finally:
        del client_utils.open


def _precheck(root: Path, path: Path) -> dict[str, Any]:
    """Parse and schema-check the scene and locate its robot configs: errors name the file at fault."""
    import jsonschema

    data = _parse(path, "scene file", unreadable=True)
    validator = jsonschema.Draft4Validator(_schema(SCENE_SCHEMA))
    errors = sorted(validator.iter_errors(data), key=lambda e: [str(p) for p in e.path])
    if errors:
        raise SceneConfigError.single(
            str(path), "does not match the scene schema: " + _schema_message(errors[0])
        )
    for actor in data.get("actors", []):
        if actor.get("type") == "robot":
            for name in _robot_config_names(actor):
                config = contained(root, name, f"robot-config of actor '{actor['name']}'")
                if not config.exists():
                    raise SceneConfigError.single(
                        str(config), f"robot config of actor '{actor['name']}' not found"
                    )
                _parse(config, f"robot config of actor '{actor['name']}'", False)
    return data


def _diagnose_robot(root: Path, data: Mapping[str, Any], err: Exception) -> SceneConfigError:
    """Name the robot config file (or actor) at fault after the client's loader failed."""
    import jsonschema
    from projectairsim.utils import merge_dicts

    validator = jsonschema.Draft4Validator(_schema(ROBOT_SCHEMA))
    for actor in data.get("actors", []):
        if actor.get("type") != "robot":
            continue
        names = _robot_config_names(actor)
        merged: dict[str, Any] = {}
        for name in names:
            part = _parse(root / name, f"robot config of actor '{actor['name']}'", False)
            if not isinstance(part, dict):
                return SceneConfigError.single(str(root / name), "a robot config must be a JSON object")
            merged = merge_dicts(merged, part)
        errors = sorted(validator.iter_errors(merged), key=lambda e: [str(p) for p in e.path])
        if errors:
            files = ", ".join(str(root / name) for name in names)
            return SceneConfigError.single(
                files, "does not match the robot schema: " + _schema_message(errors[0])
            )
    return SceneConfigError.single(str(root), f"the client's loader failed: {type(err).__name__}: {err}")


def read_scene(simconfigpath: str | Path, scene_file: str) -> Scene:
    """Read `scene_file` from the `simconfigpath` directory with the client's loader, or SceneConfigError."""
    root = Path(simconfigpath).resolve()
    if not root.is_dir():
        raise SceneConfigError.single(
            str(simconfigpath), "the config directory does not exist", unreadable=True
        )
    path = contained(root, scene_file, "the scene file")
    try:
        raw = _precheck(root, path)
    except SceneConfigError as err:
        hint = "" if path.exists() else _missing_scene_hint(root, scene_file)
        if not hint:
            raise
        (problem,) = err.problems
        raise SceneConfigError.single(problem.file, problem.message + hint, unreadable=True) from None
    from projectairsim.utils import load_scene_config_as_dict

    try:
        with _client_patched():
            data, _ = load_scene_config_as_dict(str(PurePath(scene_file)), str(root) + "/")
    except SceneConfigError:
        raise
    except Exception as err:  # the client raises jsonschema, lark, OS and type errors
        raise _diagnose_robot(root, raw, err) from None
    return _scene(data, scene_file, path)


def _missing_scene_hint(root: Path, scene_file: str) -> str:
    """For a scene file that is not there: the file of that name in the folder (the name was given with
    the folder in it, `sim_config/scene.jsonc`), or a close name."""
    names = sorted(path.name for path in root.glob("*.jsonc"))
    name = PurePath(scene_file).name
    if name in names:
        return f" (scene files are named inside --simconfigpath {root}: '{name}')"
    close = difflib.get_close_matches(name, names, n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def scene_from_config(config: Mapping[str, Any], scene_file: str, simconfigpath: str | Path) -> Scene:
    """A Scene from an already merged scene dict (e.g. `World.get_configuration()` of a mission script)."""
    root = Path(simconfigpath).resolve()
    if not isinstance(config, Mapping) or not isinstance(config.get("id"), str):
        raise SceneConfigError.single(scene_file or str(root), "the scene configuration has no string 'id'")
    if not isinstance(config.get("actors", []), list):
        raise SceneConfigError.single(
            scene_file or str(root), "the scene configuration's 'actors' is not a list"
        )
    return _scene(dict(config), scene_file, root / (scene_file or "scene.jsonc"))


def _scene(data: dict[str, Any], scene_file: str, path: Path) -> Scene:
    robots = []
    for actor in data.get("actors", []):
        if not isinstance(actor, Mapping) or actor.get("type") != "robot":
            continue
        config = actor.get("robot-config") or {}
        if not isinstance(config, Mapping):
            raise SceneConfigError.single(
                str(path), f"actor '{actor.get('name')}': robot-config is not inlined"
            )
        sensors = []
        for entry in config.get("sensors", []) or []:
            if not isinstance(entry, Mapping) or not isinstance(entry.get("id"), str):
                raise SceneConfigError.single(
                    str(path), f"actor '{actor['name']}': a sensor has no string 'id'"
                )
            kind = str(entry.get("type", "")).replace("-", "_")
            sensors.append(Sensor(entry["id"], kind, entry.get("enabled", True) is not False, entry))
        header = {key: value for key, value in actor.items() if key != "robot-config"}
        robots.append(Robot(actor["name"], header, tuple(sensors)))
    return Scene(str(data["id"]), scene_file, str(path.parent), tuple(robots), data)
