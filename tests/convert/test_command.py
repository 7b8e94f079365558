"""ROS -> sim commands: cmd_vel with limits, pose commands with validation, services, load_scene."""

from __future__ import annotations

import math

import pytest
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion, Twist, Vector3
from std_msgs.msg import Header, String
from std_srvs.srv import SetBoolRequest, TriggerRequest

from airsim_mapper.convert.command import (
    camera_desired_pose,
    cmd_vel,
    desired_pose,
    load_scene,
    require_finite,
    set_bool,
    trigger,
)
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.mapping.model import Limits, Options, PositionBox

H = math.sqrt(0.5)


def twist(vx=1.0, vy=2.0, vz=-0.5, yaw_rate=0.3):
    return Twist(linear=Vector3(vx, vy, vz), angular=Vector3(0.0, 0.0, yaw_rate))


def limited(**limits):
    return ConvertContext(options=Options(limits=Limits(**limits)))


def test_cmd_vel_ned_passes_values_with_defaults():
    assert cmd_vel(twist(), ConvertContext()) == {
        "vx": 1.0,
        "vy": 2.0,
        "vz": -0.5,
        "duration": 3.0,
        "drivetrain": 0,
        "yaw_is_rate": True,
        "yaw": 0.3,
    }


def test_cmd_vel_enu_negates_lateral_vertical_and_yaw_for_frd():
    params = cmd_vel(twist(), ConvertContext(convention="enu"))
    assert (params["vx"], params["vy"], params["vz"], params["yaw"]) == (1.0, -2.0, 0.5, -0.3)


def test_cmd_vel_duration_comes_from_params_then_watchdog_then_three_seconds():
    assert cmd_vel(twist(), ConvertContext(params={"duration": 0.5}))["duration"] == 0.5
    assert cmd_vel(twist(), ConvertContext(options=Options(watchdog_s=1.5)))["duration"] == 1.5


def test_cmd_vel_clamp_scales_linear_speed_keeping_direction():
    params = cmd_vel(twist(3.0, 4.0, 0.0, 0.0), limited(max_linear_speed=2.5))
    assert (params["vx"], params["vy"], params["vz"]) == pytest.approx((1.5, 2.0, 0.0))


def test_cmd_vel_clamp_clips_vertical_speed_and_yaw_rate():
    params = cmd_vel(twist(0.0, 0.0, -3.0, -2.0), limited(max_vertical_speed=1.0, max_yaw_rate=0.5))
    assert (params["vz"], params["yaw"]) == (-1.0, -0.5)


def test_cmd_vel_within_limits_is_unchanged():
    params = cmd_vel(twist(), limited(max_linear_speed=10.0, max_vertical_speed=5.0, max_yaw_rate=1.0))
    assert (params["vx"], params["vy"], params["vz"], params["yaw"]) == (1.0, 2.0, -0.5, 0.3)


def test_cmd_vel_reject_names_the_linear_limit():
    ctx = limited(max_linear_speed=2.0, on_violation="reject")
    with pytest.raises(ConversionError, match=r"cmd_vel: linear speed 5 m/s exceeds max_linear_speed 2 m/s"):
        cmd_vel(twist(3.0, 4.0, 0.0), ctx)


def test_cmd_vel_reject_names_the_vertical_limit():
    ctx = limited(max_vertical_speed=1.0, on_violation="reject")
    with pytest.raises(ConversionError, match=r"cmd_vel: vertical speed 2 m/s exceeds max_vertical_speed 1"):
        cmd_vel(twist(0.0, 0.0, 2.0), ctx)


def test_cmd_vel_reject_names_the_yaw_rate_limit():
    ctx = limited(max_yaw_rate=0.1, on_violation="reject")
    with pytest.raises(ConversionError, match=r"cmd_vel: yaw rate 0.3 rad/s exceeds max_yaw_rate 0.1 rad/s"):
        cmd_vel(twist(), ctx)


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf")])
def test_cmd_vel_non_finite_is_always_rejected(bad):
    with pytest.raises(ConversionError, match=r"cmd_vel: linear.y must be finite"):
        cmd_vel(twist(vy=bad), ConvertContext())
    with pytest.raises(ConversionError, match=r"cmd_vel: angular.z must be finite"):
        cmd_vel(twist(yaw_rate=bad), ConvertContext())


def test_cmd_vel_unknown_violation_policy_is_rejected():
    with pytest.raises(
        ConversionError, match=r"cmd_vel: on_violation must be 'clamp' or 'reject', got 'warn'"
    ):
        cmd_vel(twist(), limited(max_linear_speed=1.0, on_violation="warn"))


def test_cmd_vel_non_positive_duration_is_rejected():
    with pytest.raises(ConversionError, match=r"cmd_vel: duration must be positive, got 0"):
        cmd_vel(twist(), ConvertContext(params={"duration": 0}))


def pose_stamped(position=(1.0, 2.0, -3.0), q=(1.0, 0.0, 0.0, 0.0), frame_id=""):
    w, x, y, z = q
    return PoseStamped(
        header=Header(frame_id=frame_id),
        pose=Pose(position=Point(*position), orientation=Quaternion(x, y, z, w)),
    )


def test_desired_pose_ned_becomes_a_sim_pose_stamped():
    assert desired_pose(pose_stamped(q=(H, 0.0, 0.0, H)), ConvertContext()) == {
        "time_stamp": 0,
        "position": {"x": 1.0, "y": 2.0, "z": -3.0},
        "orientation": {"w": pytest.approx(H), "x": 0.0, "y": 0.0, "z": pytest.approx(H)},
    }


def test_desired_pose_enu_is_converted_to_ned():
    # ENU yaw +90 (facing north) at (2, 1, 3) is NED (1, 2, -3) with identity attitude
    params = desired_pose(
        pose_stamped((2.0, 1.0, 3.0), (H, 0.0, 0.0, H), "map"), ConvertContext(convention="enu")
    )
    assert params["position"] == pytest.approx({"x": 1.0, "y": 2.0, "z": -3.0})
    assert params["orientation"] == pytest.approx({"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0})


def test_desired_pose_normalises_a_slightly_off_quaternion():
    params = desired_pose(pose_stamped(q=(0.0, 0.0, 0.0, 1.5)), ConvertContext())
    assert params["orientation"] == {"w": 0.0, "x": 0.0, "y": 0.0, "z": 1.0}


def test_desired_pose_zero_quaternion_is_rejected():
    with pytest.raises(ConversionError, match=r"desired_pose: orientation is a zero quaternion"):
        desired_pose(pose_stamped(q=(0.0, 0.0, 0.0, 0.0)), ConvertContext())


@pytest.mark.parametrize("scale", [0.1, 3.0])
def test_desired_pose_quaternion_far_from_unit_is_rejected(scale):
    with pytest.raises(ConversionError, match=r"desired_pose: orientation has norm .* outside \[0.5, 2\]"):
        desired_pose(pose_stamped(q=(scale, 0.0, 0.0, 0.0)), ConvertContext())


def test_desired_pose_nan_position_is_rejected():
    with pytest.raises(ConversionError, match=r"desired_pose: position.z must be finite, got nan"):
        desired_pose(pose_stamped(position=(0.0, 0.0, float("nan"))), ConvertContext())


def test_desired_pose_in_an_unaccepted_frame_is_rejected():
    with pytest.raises(ConversionError, match=r"desired_pose: header.frame_id 'base_link' is not accepted"):
        desired_pose(pose_stamped(frame_id="base_link"), ConvertContext())


@pytest.mark.parametrize("frame_id", ["map", "/map"])
def test_desired_pose_accepts_map_with_or_without_a_leading_slash_as_tf2_does(frame_id):
    assert desired_pose(pose_stamped(frame_id=frame_id), ConvertContext())["position"]["x"] == 1.0
    ctx = ConvertContext(params={"accepted_frames": ["/world"]})
    assert desired_pose(pose_stamped(frame_id="world"), ctx)["position"]["x"] == 1.0
    with pytest.raises(ConversionError, match=r"header.frame_id '//map' is not accepted"):
        desired_pose(pose_stamped(frame_id="//map"), ConvertContext())


def test_desired_pose_accepted_frames_come_from_params():
    ctx = ConvertContext(params={"accepted_frames": ["world"]})
    assert desired_pose(pose_stamped(frame_id="world"), ctx)["position"]["x"] == 1.0


def test_camera_desired_pose_has_both_keys_the_server_requires():
    assert camera_desired_pose(pose_stamped(), ConvertContext()) == {
        "pose": {
            "translation": {"x": 1.0, "y": 2.0, "z": -3.0},
            "rotation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
            "frame_id": "DEFAULT_ID",
        },
        "wait_for_pose_update": True,
    }


def test_camera_desired_pose_enu_is_relative_flu_converted_to_frd():
    # camera 1 m forward, 0.5 m left, 0.2 m up, yawed 0.5 rad left in FLU
    q = (math.cos(0.25), 0.0, 0.0, math.sin(0.25))
    params = camera_desired_pose(pose_stamped((1.0, 0.5, 0.2), q), ConvertContext(convention="enu"))
    assert params["pose"]["translation"] == pytest.approx({"x": 1.0, "y": -0.5, "z": -0.2})
    assert params["pose"]["rotation"] == pytest.approx(
        {"w": math.cos(0.25), "x": 0.0, "y": 0.0, "z": -math.sin(0.25)}
    )


def test_camera_desired_pose_zero_quaternion_is_rejected():
    with pytest.raises(ConversionError, match=r"camera_desired_pose: orientation is a zero quaternion"):
        camera_desired_pose(pose_stamped(q=(0.0, 0.0, 0.0, 0.0)), ConvertContext())


def test_trigger_returns_a_fresh_copy_of_the_rule_args():
    args = {"camera_id": "FrontCamera"}
    ctx = ConvertContext(params={"args": args})
    params = trigger(TriggerRequest(), ctx)
    assert params == args and params is not args
    assert trigger(TriggerRequest(), ConvertContext()) == {}


def test_trigger_with_non_map_args_is_rejected():
    with pytest.raises(ConversionError, match=r"trigger: params.args must be a map, got list"):
        trigger(TriggerRequest(), ConvertContext(params={"args": [1]}))


def test_set_bool_adds_the_bool_under_the_named_argument():
    ctx = ConvertContext(params={"arg": "enable", "args": {"robot": "Drone1"}})
    assert set_bool(SetBoolRequest(data=True), ctx) == {"robot": "Drone1", "enable": True}
    assert set_bool(SetBoolRequest(data=False), ctx)["enable"] is False


def test_set_bool_without_an_argument_name_is_rejected():
    with pytest.raises(ConversionError, match=r"set_bool: params.arg must name the sim parameter"):
        set_bool(SetBoolRequest(data=True), ConvertContext())


def test_set_bool_with_non_bool_data_is_rejected():
    with pytest.raises(ConversionError, match=r"set_bool: data must be a bool, got 1"):
        set_bool(SetBoolRequest(data=1), ConvertContext(params={"arg": "enable"}))


def test_load_scene_strips_the_name():
    assert load_scene(String(data="  scene_basic_drone.jsonc\n"), ConvertContext()) == {
        "scene": "scene_basic_drone.jsonc"
    }


@pytest.mark.parametrize("data", ["", "   "])
def test_load_scene_with_an_empty_name_is_rejected(data):
    with pytest.raises(ConversionError, match=r"load_scene: the scene name is empty"):
        load_scene(String(data=data), ConvertContext())


def test_load_scene_with_non_string_data_is_rejected():
    with pytest.raises(ConversionError, match=r"load_scene: data must be a string, got int"):
        load_scene(String(data=3), ConvertContext())


def boxed(on_violation: str):
    box = PositionBox((-10.0, -10.0, -10.0), (10.0, 10.0, 0.0))
    return ConvertContext(options=Options(limits=Limits(position_box=box, on_violation=on_violation)))


def test_a_pose_outside_the_position_box_is_rejected_or_clamped_into_it():
    far = PoseStamped(pose=Pose(position=Point(1e308, -3.0, 5.0), orientation=Quaternion(0, 0, 0, 1)))
    with pytest.raises(ConversionError, match=r"outside the position box \[-10, -10, -10\] .. \[10, 10, 0\]"):
        desired_pose(far, boxed("reject"))
    with pytest.raises(ConversionError, match="outside the position box"):
        camera_desired_pose(far, boxed("reject"))
    assert desired_pose(far, boxed("clamp"))["position"] == {"x": 10.0, "y": -3.0, "z": 0.0}
    inside = PoseStamped(pose=Pose(position=Point(1.0, 2.0, -3.0), orientation=Quaternion(0, 0, 0, 1)))
    assert desired_pose(inside, boxed("reject"))["position"] == {"x": 1.0, "y": 2.0, "z": -3.0}


def test_a_command_holding_a_non_finite_number_anywhere_is_refused():
    require_finite({"vx": 1.0, "pose": {"translation": {"x": 2.0}}, "path": [[1.0, 2.0]], "name": "a"})
    with pytest.raises(ConversionError, match=r"params.pose.translation.x is inf"):
        require_finite({"vx": 1.0, "pose": {"translation": {"x": math.inf}}})
    with pytest.raises(ConversionError, match=r"params.path\[0\]\[1\] is nan"):
        require_finite({"path": [[1.0, math.nan]]})


def test_cmd_vel_clamp_of_a_huge_speed_keeps_its_direction_at_the_limit():
    params = cmd_vel(twist(1e308, 1e308, 0.0, 0.0), limited(max_linear_speed=20.0))
    assert (params["vx"], params["vy"]) == pytest.approx((20 * H, 20 * H))


def test_load_scene_refuses_a_name_longer_than_its_limit_and_shows_only_its_start():
    with pytest.raises(ConversionError) as err:
        load_scene(String(data="s" * 10_000_000), ConvertContext())
    message = str(err.value)
    assert len(message) < 400 and "is 10000000 characters long; at most 4096 are accepted" in message
    seven = ConvertContext(params={"max_length": 7})
    assert load_scene(String(data="a.jsonc"), seven) == {"scene": "a.jsonc"}
    with pytest.raises(ConversionError, match="at most 6 are accepted"):
        load_scene(String(data="a.jsonc"), ConvertContext(params={"max_length": 6}))


def test_cmd_vel_in_the_world_frame_converts_enu_to_ned():
    """params.frame world (MoveByVelocity): an ENU Twist east 1, north 2, up 0.5 is NED north 2, east 1,
    down -0.5; the yaw rate about up is negated about down. In NED it passes as it is."""
    world = {"frame": "world"}
    params = cmd_vel(twist(1.0, 2.0, 0.5), ConvertContext(convention="enu", params=world))
    assert (params["vx"], params["vy"], params["vz"], params["yaw"]) == (2.0, 1.0, -0.5, -0.3)
    params = cmd_vel(twist(), ConvertContext(params=world))
    assert (params["vx"], params["vy"], params["vz"], params["yaw"]) == (1.0, 2.0, -0.5, 0.3)
    body = cmd_vel(twist(), ConvertContext(convention="enu", params={"frame": "body"}))
    assert body == cmd_vel(twist(), ConvertContext(convention="enu"))


def test_cmd_vel_refuses_an_unknown_frame():
    with pytest.raises(ConversionError, match=r"params.frame must be one of .'body', 'world'., got 'wrold'"):
        cmd_vel(twist(), ConvertContext(params={"frame": "wrold"}))
