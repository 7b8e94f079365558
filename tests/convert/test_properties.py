"""Property tests: whatever a sim message or ROS request holds, converters either return a message
that its ROS can serialise (genpy on ROS1, rclpy's CDR on ROS 2) or raise ConversionError -- never
anything else.

Every converter's example message comes from its catalogue entry (`ConverterInfo.example`): a new
converter is covered here as soon as it is in the catalogue. The same tests run on both flavours: in .venv
with ROS1's messages, and in .venv-ros2 with ROS 2's (tests/ros2/test_ros2_properties.py runs them there)."""

from __future__ import annotations

import copy
import io
import math
from typing import Any

import numpy as np
import pytest
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion, Twist, Vector3
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from std_msgs.msg import Header

from airsim_mapper.common.ros_types import generated_kind
from airsim_mapper.convert import registry
from airsim_mapper.convert.catalog import CONVERTERS, SIM_TO_ROS
from airsim_mapper.convert.command import require_finite
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.flavour import ROS2
from airsim_mapper.mapping.model import Limits, Options

VALID: dict[str, dict[str, Any]] = {  # each converter's example message, from the catalogue
    name: dict(info.example.message) for name, info in CONVERTERS.items() if info.example is not None
}
SIM_CONVERTERS = sorted(name for name, info in CONVERTERS.items() if info.direction == SIM_TO_ROS)
ROS_CONVERTERS = sorted(name for name, info in CONVERTERS.items() if info.direction != SIM_TO_ROS)
CONTEXTS = [ConvertContext(), ConvertContext(convention="enu", frame_id="map")]

scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(2**70), 2**70),
    st.floats(width=32),
    st.text(max_size=5),
    st.binary(max_size=12),
)
junk = st.recursive(
    scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)
    ),
    max_leaves=12,
)


def serialises(msg: Any) -> None:
    if ROS2:
        from rclpy.serialization import serialize_message

        serialize_message(msg)
    else:
        msg.serialize(io.BytesIO())


def run_sim(name: str, msg: Any, ctx: ConvertContext) -> None:
    try:
        out = registry.get(name)(msg, ctx)
    except ConversionError:
        return
    serialises(out)


def test_every_converter_in_the_catalogue_has_an_example():
    assert [name for name, info in CONVERTERS.items() if info.example is None] == []


@pytest.mark.parametrize("name", SIM_CONVERTERS)
def test_every_sim_converters_example_converts_to_a_message_its_ros_serialises(name):
    for ctx in CONTEXTS:
        serialises(registry.get(name)(copy.deepcopy(VALID[name]), ctx))


def ros_message(ros_type: str, fields: dict) -> Any:
    """The ROS message (or service request) of `ros_type` holding `fields`."""
    if ROS2:
        from airsim_mapper.engine.ros2_link import message_class

        if generated_kind(ros_type) == "service":
            return filled(message_class(ros_type, "srv").Request(), fields)
        return filled(message_class(ros_type)(), fields)
    import genpy.message

    from airsim_mapper.engine.ros_link import message_class

    if generated_kind(ros_type) == "service":
        msg = message_class(ros_type, "srv")._request_class()
    else:
        msg = message_class(ros_type)()
    genpy.message.fill_message_args(msg, [fields])
    return msg


def filled(msg: Any, fields: dict) -> Any:
    """`msg` with `fields` set, nested dicts into nested messages (ROS 2's classes)."""
    for name, value in fields.items():
        if isinstance(value, dict):
            filled(getattr(msg, name), value)
        else:
            setattr(msg, name, value)
    return msg


@pytest.mark.parametrize("name", ROS_CONVERTERS)
def test_every_ros_converters_example_converts_to_finite_simulator_params(name):
    info = CONVERTERS[name]
    ctx = ConvertContext(params=info.example.params, source=info.example.source)
    for ros_type in info.ros_types:
        params = registry.get(name)(ros_message(ros_type, dict(info.example.message)), ctx)
        assert isinstance(params, dict), (name, ros_type)
        require_finite(params)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(SIM_CONVERTERS), junk, st.sampled_from(CONTEXTS))
def test_random_values_only_raise_conversion_error(name, value, ctx):
    run_sim(name, value, ctx)


def _paths(value: Any, prefix: tuple = ()) -> list[tuple]:
    paths = [prefix] if prefix else []
    if isinstance(value, dict):
        for key, item in value.items():
            paths += _paths(item, (*prefix, key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            paths += _paths(item, (*prefix, index))
    return paths


def _mutate(msg: dict, path: tuple, action: str, replacement: Any) -> dict:
    msg = copy.deepcopy(msg)
    parent = msg
    for key in path[:-1]:
        parent = parent[key]
    key = path[-1]
    if action == "delete":
        del parent[key]
    elif action == "truncate" and isinstance(parent[key], (bytes, list)):
        parent[key] = parent[key][: len(parent[key]) // 2]
    else:
        parent[key] = replacement
    return msg


@st.composite
def mutated(draw):
    name = draw(st.sampled_from(SIM_CONVERTERS))
    base = VALID[name]
    path = draw(st.sampled_from(_paths(base)))
    action = draw(st.sampled_from(["delete", "truncate", "replace"]))
    return name, _mutate(base, path, action, draw(junk))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated(), st.sampled_from(CONTEXTS))
def test_damaged_valid_messages_only_raise_conversion_error(case, ctx):
    name, msg = case
    run_sim(name, msg, ctx)


@settings(deadline=None)
@given(st.integers(0, 64), st.sampled_from(["BGR", "16FC1", "16UC1", "GRAY8", "PNG"]))
def test_truncated_image_data_only_raises_conversion_error(keep, encoding):
    msg = {"time_stamp": 1, "width": 4, "height": 4, "encoding": encoding, "data": bytes(range(64))[:keep]}
    run_sim("image", msg, ConvertContext())


floats = st.floats(width=32)


def pose_of(position: tuple, q: tuple) -> Pose:
    """A Pose of an (x, y, z) position and a (w, x, y, z) orientation, built by keyword (both flavours)."""
    (px, py, pz), (w, x, y, z) = position, q
    return Pose(position=Point(x=px, y=py, z=pz), orientation=Quaternion(x=x, y=y, z=z, w=w))


LIMITED = ConvertContext(
    options=Options(limits=Limits(max_linear_speed=2.0, max_vertical_speed=1.0, max_yaw_rate=1.0))
)


@settings(deadline=None)
@given(floats, floats, floats, floats, st.sampled_from([*CONTEXTS, LIMITED]))
def test_cmd_vel_returns_finite_bounded_params_or_conversion_error(vx, vy, vz, yaw, ctx):
    twist = Twist(linear=Vector3(x=vx, y=vy, z=vz), angular=Vector3(x=0.0, y=0.0, z=yaw))
    try:
        params = registry.get("cmd_vel")(twist, ctx)
    except ConversionError:
        assert not all(math.isfinite(v) for v in (vx, vy, vz, yaw))
        return
    values = np.array([params["vx"], params["vy"], params["vz"], params["yaw"]])
    assert np.isfinite(values).all()
    if ctx is LIMITED:
        assert np.linalg.norm(values[:3]) <= 2.0 + 1e-9
        assert abs(values[2]) <= 1.0 and abs(values[3]) <= 1.0


@settings(deadline=None)
@given(
    st.tuples(floats, floats, floats), st.tuples(floats, floats, floats, floats), st.sampled_from(CONTEXTS)
)
def test_pose_commands_return_unit_quaternions_or_conversion_error(position, q, ctx):
    w, x, y, z = q
    msg = PoseStamped(header=Header(frame_id=""), pose=pose_of(position, (w, x, y, z)))
    for name in ("desired_pose", "camera_desired_pose"):
        try:
            params = registry.get(name)(msg, ctx)
        except ConversionError:
            continue
        rotation = params["orientation"] if name == "desired_pose" else params["pose"]["rotation"]
        assert math.isclose(math.sqrt(sum(v * v for v in rotation.values())), 1.0, rel_tol=1e-9)


@settings(deadline=None)
@given(st.tuples(floats, floats, floats), st.tuples(floats, floats, floats, floats))
def test_enu_pose_command_round_trips_through_the_pose_converter(position, q):
    w, x, y, z = q
    if not all(math.isfinite(v) and abs(v) < 1e6 for v in (*position, *q)):
        return
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    if not 0.5 <= norm <= 2.0:
        return
    enu = ConvertContext(convention="enu")
    msg = PoseStamped(pose=pose_of(position, (w, x, y, z)))
    sim = registry.get("desired_pose")(msg, enu)
    back = registry.get("pose")({"time_stamp": 0, **sim}, enu).pose
    assert [back.position.x, back.position.y, back.position.z] == np.asarray(position).tolist()
    original = np.array([w, x, y, z]) / norm
    returned = np.array([back.orientation.w, back.orientation.x, back.orientation.y, back.orientation.z])
    assert np.allclose(returned, original, atol=1e-9) or np.allclose(returned, -original, atol=1e-9)
