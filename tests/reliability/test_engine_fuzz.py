"""Property tests of the engine's message handling: whatever the simulator sends, a bridge either
publishes or drops the message with a counted error -- nothing else escapes, and the stream goes on."""

from __future__ import annotations

import threading
from typing import Any

import pytest
from fakes import FakeRos
from harness import wait_until
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from airsim_mapper.engine.bridges import BridgeParts, SimToRos
from airsim_mapper.engine.mounts import CameraMounts
from airsim_mapper.engine.runners import build
from airsim_mapper.engine.streams import Stream
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping
from airsim_mapper.mapping.model import SIM_TO_ROS
from airsim_mapper.mapping.scene import read_scene
from airsim_mapper.wrapper import DEFAULT_MAPPING
from reliability.relkit import PROJECT_SIM_CONFIG, SCENE

KEYS = [
    "time_stamp",
    "pose",
    "position",
    "orientation",
    "x",
    "y",
    "z",
    "w",
    "width",
    "height",
    "encoding",
    "data",
    "point_cloud",
    "intensity_cloud",
    "segmentation_cloud",
    "radar_detections",
    "radar_tracks",
    "range",
    "azimuth",
    "elevation",
    "velocity",
    "rcs_sqm",
    "id",
    "position_est",
    "velocity_est",
    "accel_est",
    "angular_velocity",
    "linear_acceleration",
    "latitude",
    "longitude",
    "altitude",
    "distance",
    "battery_pct_remaining",
    "diff_pressure",
]
SCALARS = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(2**64), max_value=2**64),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=8),
    st.binary(max_size=24),
)
VALUES = st.recursive(
    SCALARS,
    lambda inner: st.lists(inner, max_size=6) | st.dictionaries(st.sampled_from(KEYS), inner, max_size=6),
    max_leaves=20,
)
MESSAGES = st.dictionaries(st.sampled_from(KEYS), VALUES, max_size=8) | VALUES


class NoSim:
    """Stands in for the sim link: sim_to_ros handling never talks to the simulator."""

    def __getattr__(self, name: str) -> Any:
        raise AssertionError(f"sim_to_ros handling used the sim link ({name})")


@pytest.fixture(scope="module")
def bridges() -> list[SimToRos]:
    specs = expand(load_mapping(DEFAULT_MAPPING), read_scene(PROJECT_SIM_CONFIG, SCENE), "fuzz", "")
    services = BridgeParts(
        NoSim(), NoSim(), FakeRos(), CameraMounts(), lambda *_: None
    )  # "ros" stamps read its clock
    out = [build(spec, services) for spec in specs if spec.direction == SIM_TO_ROS]
    out = [bridge for bridge in out if isinstance(bridge, SimToRos)]  # static mounts take no messages
    assert {b.spec.converter for b in out} >= {"pose", "image", "pointcloud", "radar_scan", "camera_info"}
    return out


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(message=MESSAGES)
def test_every_sim_to_ros_bridge_publishes_or_counts_a_drop_for_any_message(bridges: list[SimToRos], message):
    for bridge in bridges:
        errors = bridge.stats.errors
        result = bridge.handle(message)  # raises nothing
        assert result is None or isinstance(result, list)
        if bridge.stats.errors > errors:
            assert bridge.stats.last_error


def test_a_stream_keeps_handling_messages_after_a_handler_raised():
    handled: list[Any] = []
    done = threading.Event()

    def handler(message: Any) -> None:
        if message == "boom":
            raise ValueError("boom")
        handled.append(message)
        if message == "last":
            done.set()

    stream = Stream("/fuzz", None, [handler])
    try:
        for message in ("boom", "ok"):
            stream.offer(None, message)
            wait_until(lambda m=message: stream.stats.handled >= (1 if m == "boom" else 2), 5)
        stream.offer(None, "last")
        assert done.wait(5)
    finally:
        stream.stop()
    assert handled == ["ok", "last"] and stream.stats.errors == 1
