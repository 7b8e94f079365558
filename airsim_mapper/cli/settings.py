"""The node's settings: each a switch and a private parameter; the command line wins over the parameter,
the parameter over the default (the log says where each value came from)."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from airsim_mapper.cli.errors import SettingError
from airsim_mapper.common.ports import SERVICES_PORT, TOPICS_PORT, port
from airsim_mapper.common.resources import DEFAULT_SIM_CONFIG

__all__ = [
    "SETTINGS",
    "SWITCHES_ONLY",
    "Resolved",
    "Setting",
    "given_settings",
    "resolve_settings",
    "unread_parameters",
    "values",
]


@dataclass(frozen=True)
class Setting:
    """A node switch that is also a private parameter (`--mapping` and `~mapping`)."""

    name: str
    default: Any
    help: str
    kind: Callable[[Any], Any] = str  # a type, or a parser such as ports.port


SETTINGS = (
    Setting("address", "127.0.0.1", "host running Project AirSim"),
    Setting("topicsport", TOPICS_PORT, "Project AirSim pub-sub port", port),
    Setting("servicesport", SERVICES_PORT, "Project AirSim services port", port),
    Setting(
        "simconfigpath",
        DEFAULT_SIM_CONFIG,
        "directory holding the scene configs (./sim_config/, else the package's own)",
    ),
    Setting("mapping", "default", "mapping YAML file, or a shipped mapping's name"),
    Setting("scene", "", "scene config file to load at start (without one: wait for load_scene)"),
    Setting("namespace", "", "topic namespace and frame prefix, resolved in the node's ROS namespace"),
)
COMMAND_LINE, DEFAULT = "command line", "default"
SWITCHES_ONLY = ("nodename", "no-watch", "shutdown-timeout", "max-frame-mb")  # switches without a parameter


@dataclass(frozen=True)
class Resolved:
    """One setting's value and where it came from ("command line", "parameter ~x" or "default")."""

    value: Any
    source: str


def resolve_settings(
    given: dict[str, Any], get_param: Callable[[str], Any] | None = None
) -> dict[str, Resolved]:
    """Each setting from the command line (a value in `given` that is not None), else from its private
    parameter (`get_param("~name")`, KeyError when unset), else its default."""
    resolved: dict[str, Resolved] = {}
    for setting in SETTINGS:
        if given.get(setting.name) is not None:
            resolved[setting.name] = Resolved(given[setting.name], COMMAND_LINE)
            continue
        try:
            value = get_param(f"~{setting.name}") if get_param is not None else None
        except KeyError:
            value = None
        if value is None:
            resolved[setting.name] = Resolved(setting.default, DEFAULT)
            continue
        try:
            value = setting.kind(value)
        except (TypeError, ValueError):
            raise SettingError(setting.name, value, setting.kind) from None
        resolved[setting.name] = Resolved(value, f"parameter ~{setting.name}")
    return _sim_config_fallback(resolved)


def given_settings(args: Any) -> dict[str, Any]:
    """Each setting as the command line gives it (None where it says nothing), for `resolve_settings`."""
    return {setting.name: getattr(args, setting.name) for setting in SETTINGS}


def values(resolved: dict[str, Resolved]) -> dict[str, Any]:
    """The values of resolved settings, by name."""
    return {name: setting.value for name, setting in resolved.items()}


def _sim_config_fallback(resolved: dict[str, Resolved]) -> dict[str, Resolved]:
    """The default sim_config/ is the working directory's; where there is none, the package's own."""
    from airsim_mapper.common.resources import package_sim_config

    current = resolved["simconfigpath"]
    if current.source != DEFAULT or Path(current.value).is_dir():
        return resolved
    shipped = package_sim_config()
    if shipped is None:
        return resolved
    why = f"default: ./{DEFAULT_SIM_CONFIG} does not exist here, so the package's own"
    return {**resolved, "simconfigpath": Resolved(str(shipped), why)}


def unread_parameters(names: Iterable[str], node_name: str) -> list[str]:
    """What to say of the node's private parameters that no setting reads (`names`: the parameters on the
    master; `node_name`: the node's full ROS name), so that a mistyped `<param>` is not passed over. The
    image_transport topics' own parameters (`<topic>/compressed/jpeg_quality`) are read by their bridges."""
    from airsim_mapper.convert.transport_params import is_topic_parameter
    from airsim_mapper.mapping.names import did_you_mean

    prefix = node_name.rstrip("/") + "/"
    known = [setting.name for setting in SETTINGS]
    mine = [name for name in names if name.startswith(prefix) and not is_topic_parameter(name)]
    unread = sorted({name[len(prefix) :].split("/")[0] for name in mine})
    said = []
    for key in (key for key in unread if key not in known):
        switch = key.replace("_", "-")
        hint = (
            f"; --{switch} is a command-line switch only"
            if switch in SWITCHES_ONLY
            else did_you_mean(key, known)
        )
        said.append(f"parameter ~{key} is not one the node reads{hint}")
    return said
