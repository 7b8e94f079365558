"""collision (CollisionInfo -> PointStamped) and reset_pose (request -> SetPose to the actor's origin)."""

from __future__ import annotations

import math

import pytest
from std_srvs.srv import TriggerRequest

from airsim_mapper.convert.collision import collision
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.reset import reset_pose


def collision_info(point=(1.0, 2.0, -0.5)):
    return {
        "time_stamp": 3_000_000_001,
        "object_name": "Tower",
        "segmentation_id": 4,
        "position": {"x": 0.0, "y": 0.0, "z": 0.0},
        "impact_point": dict(zip("xyz", point)),
        "normal": {"x": -1.0, "y": 0.0, "z": 0.0},
        "penetration_depth": 0.1,
    }


@pytest.mark.parametrize(("convention", "expected"), [("ned", (1.0, 2.0, -0.5)), ("enu", (2.0, 1.0, 0.5))])
def test_collision_gives_the_impact_point_in_the_world_frame(roundtrip, convention, expected):
    msg = roundtrip(collision(collision_info(), ConvertContext(frame_id="map", convention=convention)))
    assert (msg.point.x, msg.point.y, msg.point.z) == pytest.approx(expected)
    assert (msg.header.frame_id, msg.header.stamp.to_nsec()) == ("map", 3_000_000_001)


def test_collision_without_an_impact_point_is_a_conversion_error():
    msg = collision_info()
    del msg["impact_point"]
    with pytest.raises(ConversionError, match="collision: message has no 'impact_point'"):
        collision(msg, ConvertContext())


def test_reset_pose_sets_the_actors_origin_with_kinematics_reset():
    ctx = ConvertContext(source={"name": "Drone1", "origin": {"xyz": "1 2 -4", "rpy-deg": "0 0 90"}})
    params = reset_pose(TriggerRequest(), ctx)
    h = math.sqrt(0.5)
    assert params["reset_kinematics"] is True
    assert params["pose"]["translation"] == {"x": 1.0, "y": 2.0, "z": -4.0}
    assert params["pose"]["rotation"] == pytest.approx({"w": h, "x": 0.0, "y": 0.0, "z": h})
    assert params["pose"]["frame_id"] == "DEFAULT_ID"


def test_reset_pose_without_an_origin_is_a_conversion_error():
    with pytest.raises(ConversionError, match="reset_pose: the robot's scene entry has no 'origin'"):
        reset_pose(TriggerRequest(), ConvertContext(source={"name": "Drone1"}))


def test_reset_pose_with_a_malformed_origin_is_a_conversion_error():
    ctx = ConvertContext(source={"origin": {"xyz": "1 2"}})
    with pytest.raises(ConversionError, match="reset_pose: origin: origin 'xyz' must hold three numbers"):
        reset_pose(TriggerRequest(), ctx)
