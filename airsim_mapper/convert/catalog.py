"""The converter catalogue: every converter a mapping may name, with what it fits.

Pure data, importable without ROS, so that mapping validation can check a rule's converter against its
ROS type and direction. The implementation of each converter lives in the module named here and is
looked up by `airsim_mapper.convert.registry` at run time.

Contract of an implementation (see registry.py):
- sim_to_ros: ``fn(msg: dict, ctx: ConvertContext) -> ROS message`` (or None to publish nothing)
- ros_to_sim: ``fn(ros_msg, ctx: ConvertContext) -> dict`` (sim topic message or service params)
Converters raise ``ConversionError`` (airsim_mapper.convert.errors) for malformed input, nothing else.

Each entry also says how the engine runs the converter (`runner`, engine/bridges.py) and what follows a
successful simulator call (`after`), so the engine never tests converter names, and carries an example
message (`example`) that the property tests convert and then damage in every way they can.

The catalogue is the one source of the converters' names: the mapping schema's `converter` enum and the
table in `docs/converters.md` are generated from it (`python -m tools.catalogue`), and tests name any entry
either lacks. `converters_markdown` renders the catalogue for people (`airsim-mapper converters` prints it).

The entries live in `airsim_mapper.convert.entries`, one module a family (poses, cameras, lidar and radar,
instruments, commands, services); this module puts them in catalogue order, the order of the schema's
enum and of the table.
"""

from __future__ import annotations

from collections.abc import Iterable

from airsim_mapper.convert.entries import cameras, commands, instruments, lidar_radar, poses, services
from airsim_mapper.convert.entries.model import (
    ACTION,
    ACTIONS,
    AFTER_HOOKS,
    CALL,
    COLOUR,
    DEFAULT_QOS,
    FLOAT,
    PUBLISH,
    QOS_PROFILES,
    ROS_TO_SIM,
    RUNNERS,
    SEND,
    SENSOR_DATA,
    SERVE,
    SERVE_ALL,
    SERVICES,
    SIM_TO_ROS,
    STREAM,
    TRANSIENT_LOCAL,
    ConverterInfo,
)

__all__ = [
    "ACTION",
    "ACTIONS",
    "AFTER_HOOKS",
    "CALL",
    "COLOUR",
    "CONVERTERS",
    "DEFAULT_QOS",
    "FLOAT",
    "PUBLISH",
    "QOS_PROFILES",
    "ROS_TO_SIM",
    "RUNNERS",
    "SEND",
    "SENSOR_DATA",
    "SERVE",
    "SERVE_ALL",
    "SERVICES",
    "SIM_TO_ROS",
    "STREAM",
    "TRANSIENT_LOCAL",
    "ConverterInfo",
    "converters_markdown",
    "find",
    "runs_on",
]

CONVERTERS: dict[str, ConverterInfo] = {
    info.name: info
    for info in (
        # --- simulator -> ROS ----------------------------------------------------------------
        *poses.POSES,
        *cameras.IMAGES,
        *lidar_radar.SCANS,
        *instruments.INSTRUMENTS,
        cameras.STREAMING_IMAGE,
        # --- ROS -> simulator ----------------------------------------------------------------
        *commands.COMMANDS,
        *services.SERVICES,
    )
}


def find(name: str) -> ConverterInfo | None:
    return CONVERTERS.get(name)


DIRECTION_LABELS = {SIM_TO_ROS: "sim → ROS", ROS_TO_SIM: "ROS → sim"}
TABLE_HEADERS = ("converter", "direction", "ROS types", "runs on", "ROS 2 QoS", "what it does")


def runs_on(info: ConverterInfo) -> str:
    """The thread a converter runs on (engine/streams.py): light ones on the receive thread."""
    if info.direction == ROS_TO_SIM:
        return "rospy's callback"
    return "receive thread" if info.inline else "its topic's worker"


def converters_markdown(converters: Iterable[ConverterInfo] | None = None) -> str:
    """The converters (default: the whole catalogue, in its order) as a Markdown table, one row each."""
    rows = [
        (
            f"`{info.name}`",
            DIRECTION_LABELS[info.direction],
            ", ".join(f"`{t}`" for t in info.ros_types),
            runs_on(info),
            f"`{info.qos}`",
            info.summary.replace("|", "\\|"),
        )
        for info in (CONVERTERS.values() if converters is None else converters)
    ]
    lines = ["| " + " | ".join(TABLE_HEADERS) + " |", "|" + "---|" * len(TABLE_HEADERS)]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows]) + "\n"
