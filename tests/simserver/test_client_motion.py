"""Kinematic flight through the real client's Drone API: moves, pre-emption, teleports, collisions."""

from __future__ import annotations

import asyncio
import math
import time

import pytest
from projectairsim import Drone
from projectairsim.types import Pose

from simserver.clientkit import load_world, position, subscribe


@pytest.fixture
def drone(client):
    world = load_world(client, "scene_basic_drone.jsonc")
    drone = Drone(client, world, "Drone1")
    assert drone.enable_api_control() is True and drone.arm() is True
    return drone


def yaw_of(drone) -> float:
    rotation = drone.get_ground_truth_pose()["rotation"]
    return 2 * math.atan2(rotation["z"], rotation["w"])


def teleport(drone, x: float, y: float, z: float, yaw: float = 0.0) -> None:
    rotation = {"w": math.cos(yaw / 2), "x": 0.0, "y": 0.0, "z": math.sin(yaw / 2)}
    pose = Pose({"translation": {"x": x, "y": y, "z": z}, "rotation": rotation, "frame_id": "DEFAULT_ID"})
    assert drone.set_pose(pose, True) is True


def test_api_flags_and_landed_state_follow_the_commands(drone):
    assert drone.is_api_control_enabled() is True and drone.can_arm() is True
    assert drone.get_landed_state() == 1
    teleport(drone, 0.0, 0.0, -0.02)
    assert drone.get_landed_state() == 0
    assert drone.disarm() is True and drone.disable_api_control() is True
    assert drone.is_api_control_enabled() is False


def test_takeoff_climbs_three_metres_and_land_returns_to_the_pad(drone):
    teleport(drone, 0.0, 0.0, -0.02)

    async def fly():
        assert await (await drone.takeoff_async()) is True
        up = position(drone)
        assert drone.get_landed_state() == 1
        assert await (await drone.land_async()) is True
        return up

    up = asyncio.run(fly())
    assert up == pytest.approx([0.0, 0.0, -3.02], abs=0.01)
    assert position(drone) == pytest.approx([0.0, 0.0, -0.02], abs=0.01)
    assert drone.get_landed_state() == 0


def test_velocity_moves_follow_world_and_body_frames(drone):
    teleport(drone, 0.0, 0.0, -4.0, yaw=math.pi / 2)

    async def fly():
        assert await (await drone.move_by_velocity_async(2.0, 0.0, 0.0, 0.5)) is True
        after_world = position(drone)
        assert await (await drone.move_by_velocity_body_frame_async(2.0, 0.0, 0.0, 0.5)) is True
        after_body = position(drone)
        assert await (await drone.move_by_velocity_z_async(0.0, 2.0, -6.0, 1.0)) is True
        return after_world, after_body, position(drone)

    after_world, after_body, after_z = asyncio.run(fly())
    assert after_world == pytest.approx([1.0, 0.0, -4.0], abs=0.05)
    assert after_body == pytest.approx([1.0, 1.0, -4.0], abs=0.05)  # facing east: forward is +y
    assert after_z[1] == pytest.approx(3.0, abs=0.05) and after_z[2] == pytest.approx(-6.0, abs=0.2)


def test_move_to_position_path_rotation_and_go_home_reach_their_goals(drone):
    async def fly():
        assert await (await drone.move_to_position_async(3.0, 4.0, -5.0, 10.0)) is True
        reached = position(drone)
        assert await (await drone.move_on_path_async([[3.0, 0.0, -4.0], [0.0, 0.0, -3.0]], 10.0)) is True
        on_path = position(drone)
        assert await (await drone.rotate_to_yaw_async(math.pi / 2)) is True
        turned = yaw_of(drone)
        assert await (await drone.rotate_by_yaw_rate_async(-math.pi, 0.5)) is True
        yaws = (turned, yaw_of(drone))
        assert await (await drone.go_home_async(velocity=10.0)) is True
        assert await (await drone.hover_async()) is True
        return reached, on_path, yaws

    reached, on_path, (turned, back) = asyncio.run(fly())
    assert reached == pytest.approx([3.0, 4.0, -5.0], abs=1e-6)
    assert on_path == pytest.approx([0.0, 0.0, -3.0], abs=1e-6)
    assert turned == pytest.approx(math.pi / 2, abs=math.radians(5.0))  # the client's default margin
    assert back == pytest.approx(turned - math.pi / 2, abs=1e-6)
    assert position(drone) == pytest.approx([0.0, 0.0, -4.0], abs=1e-6)


def test_a_new_motion_command_pre_empts_the_running_one_which_replies_false(drone):
    async def fly():
        first = await drone.move_by_velocity_async(0.0, 1.0, 0.0, 30.0)
        await asyncio.sleep(0.3)
        second = await drone.move_by_velocity_async(0.0, 0.0, 0.0, 0.05)
        return await first, await second

    assert asyncio.run(fly()) == (False, True)


def test_sync_requests_are_served_while_a_motion_command_is_pending(drone):
    async def fly():
        task = await drone.move_by_velocity_async(1.0, 0.0, 0.0, 1.5)
        await asyncio.sleep(0.2)
        started = time.monotonic()
        kinematics = drone.get_ground_truth_kinematics()
        answered = time.monotonic() - started
        await task
        return kinematics, answered

    kinematics, answered = asyncio.run(fly())
    assert answered < 0.5
    assert kinematics["twist"]["linear"]["x"] == pytest.approx(1.0, abs=0.01)
    assert set(kinematics) == {"time_stamp", "pose", "twist", "accels"}
    assert drone.get_estimated_kinematics()["pose"]["position"]["x"] == pytest.approx(1.5, abs=0.05)


def test_set_pose_teleports_and_pre_empts_the_running_command(drone):
    async def fly():
        task = await drone.move_by_velocity_async(1.0, 0.0, 0.0, 30.0)
        await asyncio.sleep(0.2)
        teleport(drone, 10.0, -5.0, -7.0, yaw=1.0)
        return await task

    assert asyncio.run(fly()) is False
    pose = drone.get_ground_truth_pose()
    assert position(drone) == [10.0, -5.0, -7.0]
    assert pose["frame_id"] == "DEFAULT_ID"
    assert 2 * math.atan2(pose["rotation"]["z"], pose["rotation"]["w"]) == pytest.approx(1.0)
    geo = drone.get_ground_truth_geo_location()
    assert geo["altitude"] == pytest.approx(122.0 + 7.0)
    assert geo["latitude"] == pytest.approx(47.641468 + 10.0 / 111_319.5, abs=1e-6)


def test_a_desired_pose_message_from_the_client_teleports_the_robot(client, drone):
    poses = subscribe(client, drone.robot_info["actual_pose"])
    client.publish(
        f"{drone.parent_topic}/desired_pose",
        {
            "time_stamp": 0,
            "position": {"x": 5.0, "y": 6.0, "z": -2.0},
            "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
        },
    )
    poses.wait_for(1, where=lambda m: m["position"] == {"x": 5.0, "y": 6.0, "z": -2.0})
    assert position(drone) == [5.0, 6.0, -2.0]


def test_the_drone_never_sinks_below_the_ground(drone):
    async def fly():
        return await (await drone.move_by_velocity_async(0.0, 0.0, 20.0, 0.5))

    assert asyncio.run(fly()) is True
    assert position(drone)[2] == pytest.approx(-0.02, abs=1e-6)  # the landing pad's top


def test_flying_into_an_object_is_stopped_and_reported_on_collision_info(client, drone):
    collisions = subscribe(client, drone.robot_info["collision_info"])
    teleport(drone, 24.0, 0.0, -4.0)

    async def fly():
        return await (await drone.move_by_velocity_async(10.0, 0.0, 0.0, 0.6))

    assert asyncio.run(fly()) is True
    report = collisions.wait_for(1)[0]
    assert report["object_name"] == "BlockNorth"
    assert report["normal"]["x"] == pytest.approx(-1.0)
    assert report["penetration_depth"] > 0
    assert 27.5 < position(drone)[0] < 28.0


@pytest.mark.parametrize(
    ("method", "params", "named"),
    [
        ("MoveByVelocity", {"vx": 1e308, "vy": 0.0, "vz": 0.0, "duration": 3.0}, "vx, vy, vz"),
        ("MoveByVelocityBodyFrame", {"vx": 0.0, "vy": 0.0, "vz": float("inf"), "duration": 3.0}, "vz"),
        ("MoveByVelocity", {"vx": 1e4, "vy": 0.0, "vz": 0.0, "duration": 1e305}, "duration"),
        ("MoveToPosition", {"x": 1e308, "y": 0.0, "z": -3.0, "velocity": 5.0}, "x"),
        ("MoveToPosition", {"x": 1.0, "y": 0.0, "z": -3.0, "velocity": 1e308}, "velocity"),
        ("RotateByYawRate", {"yaw_rate": 1e308, "duration": 1.0}, "yaw_rate"),
        ("MoveByVelocity", {"vx": float("nan"), "vy": 0.0, "vz": 0.0, "duration": 1.0}, "vx"),
        (
            "MoveByHeading",
            {"heading": 0.0, "speed": float("nan"), "vz": 0.0, "duration": 1.0, "heading_margin": 0.1},
            "speed",
        ),
        (
            "MoveByHeading",
            {"heading": float("nan"), "speed": 1.0, "vz": 0.0, "duration": 1.0, "heading_margin": 0.1},
            "heading",
        ),
    ],
)
def test_a_motion_command_that_would_make_the_state_non_finite_gets_a_parameter_error(
    drone, client, method, params, named
):
    teleport(drone, 0.0, 0.0, -4.0)
    defaults = {"drivetrain": 0, "yaw_is_rate": True, "yaw": 0.0, "timeout_sec": 10.0, "lookahead": -1.0}
    defaults |= {"adaptive_lookahead": 1.0, "yaw_rate": 0.0}
    request = {"method": f"/Sim/SceneBasicDrone/robots/Drone1/{method}", "params": defaults | params}
    with pytest.raises(RuntimeError, match=f"Parameter '{named}'"):
        client.request({**request, "version": 1.0})
    assert position(drone) == pytest.approx([0.0, 0.0, -4.0])
    kinematics = drone.get_ground_truth_kinematics()
    assert all(math.isfinite(v) for v in kinematics["accels"]["linear"].values())


def test_a_teleport_beyond_the_world_is_refused(drone):
    with pytest.raises(RuntimeError, match="Parameter 'pose'"):
        teleport(drone, 1e308, 0.0, -4.0)
