"""Kinematic motion: commands move the body as asked, complete, pre-empt and respect the ground."""

from __future__ import annotations

import math

import numpy as np
import pytest

from airsim_mapper.common.geometry import IDENTITY_Q, quat_from_rpy, yaw_of
from airsim_mapper.simserver.motion.motion import DRAG_TIME_S, Body, Hold, Kinematic, wrap_angle
from airsim_mapper.simserver.motion.motion_commands import (
    Land,
    Path,
    Rotate,
    Velocity,
    YawMode,
    body_to_world_velocity,
    turn_rate,
)

DT = 0.005


def flat_ground(_position: np.ndarray) -> float:
    return 0.0


def body_at(z: float = -4.0, yaw: float = 0.0) -> Body:
    return Body(np.array([0.0, 0.0, z]), quat_from_rpy(0, 0, yaw), flat_ground)


def run(body: Body, seconds: float) -> None:
    for _ in range(round(seconds / DT)):
        body.tick(DT)


def test_velocity_moves_for_its_duration_then_holds_and_succeeds():
    body = body_at()
    command = body.run(Velocity([2.0, -1.0, 0.0], 1.0, YawMode()))
    run(body, 1.5)
    assert command.done and command.result is True
    assert body.state.position == pytest.approx([2.0, -1.0, -4.0], abs=0.02)
    assert body.state.linear_velocity == pytest.approx([0, 0, 0])


def test_velocity_z_holds_the_commanded_altitude():
    body = body_at()
    body.run(Velocity([1.0, 0.0, 0.0], 3.0, YawMode(), z=-6.0))
    run(body, 3.0)
    assert body.state.position[2] == pytest.approx(-6.0, abs=0.05)


def test_body_frame_velocity_is_rotated_by_the_yaw():
    world = body_to_world_velocity(quat_from_rpy(0, 0, math.pi / 2), 1.0, 0.0, 0.5)
    assert world == pytest.approx([0.0, 1.0, 0.5], abs=1e-9)


def test_path_reaches_each_waypoint_at_the_requested_speed():
    body = body_at()
    command = body.run(Path([[3.0, 0.0, -4.0], [3.0, 4.0, -4.0]], 5.0, YawMode(), math.inf))
    run(body, 1.0)
    assert not command.done
    run(body, 0.5)
    assert command.result is True
    assert body.state.position == pytest.approx([3.0, 4.0, -4.0], abs=1e-6)


def test_a_command_that_times_out_completes_false():
    body = body_at()
    command = body.run(Path([[100.0, 0.0, -4.0]], 1.0, YawMode(), 0.5))
    run(body, 0.6)
    assert command.result is False and body.active is None


def test_a_new_command_pre_empts_the_running_one_which_completes_false():
    body = body_at()
    first = body.run(Velocity([1.0, 0.0, 0.0], 10.0, YawMode()))
    run(body, 0.1)
    second = body.run(Hold())
    assert first.wait(0) is False
    run(body, 0.01)
    assert second.result is True


def test_the_body_never_sinks_below_the_ground_and_lands_there():
    body = body_at(z=-1.0)
    body.run(Velocity([0.0, 0.0, 5.0], 1.0, YawMode()))
    run(body, 1.0)
    assert body.state.position[2] == pytest.approx(0.0)
    land = body_at(z=-2.0)
    command = land.run(Land())
    run(land, 10.9)  # 2 m at LAND_SPEED (0.2 m/s), then LAND_CONFIRM_S (1 s) at rest
    assert command.result is None and land.state.position[2] == pytest.approx(0.0)
    run(land, 0.2)
    assert command.result is True and land.landed()


def test_landing_on_the_ground_already_waits_for_a_descent_then_confirms():
    body = body_at(z=0.0)
    command = body.run(Land())
    run(body, 10.9)
    assert command.result is None
    run(body, 0.2)
    assert command.result is True


def test_yaw_rate_and_absolute_yaw_turn_the_body():
    body = body_at()
    body.run(Rotate(None, math.pi / 2, duration=1.0))
    run(body, 1.2)
    assert yaw_of(body.state.orientation) == pytest.approx(math.pi / 2, abs=0.02)
    command = body.run(Rotate(-math.pi / 2, 0.0, margin=0.01))
    run(body, 1.5)
    assert command.result is True
    assert yaw_of(body.state.orientation) == pytest.approx(-math.pi / 2, abs=0.02)


def test_forward_only_drivetrain_faces_the_direction_of_travel():
    body = body_at()
    body.run(Velocity([0.0, 2.0, 0.0], 1.0, YawMode(is_rate=False, value=0.0, drivetrain=1)))
    run(body, 1.0)
    assert yaw_of(body.state.orientation) == pytest.approx(math.pi / 2, abs=0.02)


def test_teleport_moves_the_body_cancels_its_command_and_resets_rates():
    body = body_at()
    command = body.run(Velocity([1.0, 0.0, 0.0], 10.0, YawMode()))
    run(body, 0.1)
    body.teleport(np.array([5.0, 5.0, -2.0]), IDENTITY_Q, reset_kinematics=True)
    assert command.result is False
    assert body.state.position.tolist() == [5.0, 5.0, -2.0]
    assert body.state.linear_velocity.tolist() == [0.0, 0.0, 0.0]


def test_a_blocked_move_keeps_the_body_in_place():
    body = body_at()
    body.run(Velocity([1.0, 0.0, 0.0], 1.0, YawMode()))
    for _ in range(10):
        body.tick(DT, blocked=lambda old, new: True)
    assert body.state.position.tolist() == [0.0, 0.0, -4.0]


def test_angle_helpers_wrap_and_limit_turns():
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert turn_rate(0.0, 1.0, 0.5, 0.01) == 0.5
    assert turn_rate(0.0, 0.001, 0.5, 0.01) == pytest.approx(0.1)
    assert turn_rate(0.0, 1.0, 0.5, 0.0) == 0.0


def test_kinematic_copies_are_independent():
    kin = Kinematic(np.zeros(3), IDENTITY_Q.copy())
    copy = kin.copy()
    copy.position[0] = 1.0
    assert kin.position[0] == 0.0


def test_a_fast_descent_stops_on_a_raised_surface_even_with_one_long_tick():
    def pad(position: np.ndarray) -> float:
        return -0.5 if position[2] <= -0.5 else 0.0  # a 0.5 m platform seen only from above

    body = Body(np.array([0.0, 0.0, -1.0]), IDENTITY_Q, pad)
    body.run(Velocity([0.0, 0.0, 20.0], 1.0, YawMode()))
    body.tick(0.1)
    assert body.state.position[2] == -0.5


def test_a_step_that_would_make_the_state_non_finite_ends_the_command_and_the_body_rests():
    body = body_at()
    command = body.run(Velocity([1e308, 0.0, 0.0], 3.0, YawMode(True, 0.0)))
    run(body, 0.05)
    state = body.snapshot()
    assert command.done and command.result is False
    for values in (state.position, state.linear_velocity, state.linear_acceleration):
        assert np.all(np.isfinite(values)), values
    assert state.position.tolist() == [0.0, 0.0, -4.0]


def test_wind_makes_an_idle_airborne_body_drift_but_not_a_commanded_or_landed_one():
    body = body_at(z=-4.0)
    body.wind = np.array([1.0, -0.5, 0.0])
    run(body, 0.5)
    assert body.state.position == pytest.approx([0.0, 0.0, -4.0])  # disarmed: held as on a stand
    body = body_at(z=-4.0)
    body.armed = True
    body.wind = np.array([1.0, -0.5, 0.0])
    run(body, 1.0)
    assert body.state.position == pytest.approx([1.0, -0.5, -4.0], abs=1e-6)
    body.run(Velocity([0.0, 0.0, 0.0], 1.0, YawMode()))
    run(body, 0.5)
    assert body.state.position == pytest.approx([1.0, -0.5, -4.0], abs=1e-6)  # the controller holds
    grounded = body_at(z=0.0)
    grounded.armed = True
    grounded.wind = np.array([3.0, 0.0, 0.0])
    run(grounded, 1.0)
    assert grounded.state.position == pytest.approx([0.0, 0.0, 0.0])


def test_an_external_force_pushes_an_idle_body_by_force_over_mass_per_drag_time():
    body = Body(np.array([0.0, 0.0, -4.0]), IDENTITY_Q, flat_ground, mass_kg=2.0)
    body.armed = True
    body.external_force = np.array([0.0, -0.6, 0.0])
    run(body, 1.0)
    assert body.state.position == pytest.approx([0.0, -0.3 * DRAG_TIME_S, -4.0], abs=1e-6)
    body.wind = np.array([1.0, 0.0, 0.0])
    assert body.drift() == pytest.approx([1.0, -0.3 * DRAG_TIME_S, 0.0])


def test_a_ground_vehicle_rests_on_the_surface_below_wherever_it_is_put():
    def step(position: np.ndarray) -> float:  # a 1 m step up east of y = 5
        return -1.0 if position[1] >= 5.0 else 0.0

    rover = Body(np.array([0.0, 0.0, -10.0]), IDENTITY_Q, step, grounded=True)
    assert rover.state.position.tolist() == [0.0, 0.0, 0.0]
    assert rover.home.tolist() == [0.0, 0.0, 0.0]
    rover.teleport(np.array([0.0, 6.0, -7.0]), IDENTITY_Q, reset_kinematics=True)
    assert rover.state.position.tolist() == [0.0, 6.0, -1.0]
    rover.run(Velocity([0.0, -2.0, 0.0], 1.0, YawMode()))
    run(rover, 1.0)
    assert rover.state.position == pytest.approx([0.0, 4.0, 0.0], abs=0.01)  # down the step with it


def test_a_bodys_pose_is_its_snapshots_position_and_orientation_as_floats():
    body = body_at(yaw=0.7)
    body.run(Velocity([1.0, 0.5, 0.0], 10.0, YawMode()))
    run(body, 0.2)
    position, orientation = body.pose()
    snapshot = body.snapshot()
    assert position == snapshot.position.tolist() and orientation == snapshot.orientation.tolist()
    assert all(type(value) is float for value in (*position, *orientation))
    position[0] = 99.0  # a copy: the body is not moved by its reader
    assert body.state.position[0] != 99.0
