"""Frame conventions, checked against hand-computed cases (in the style of mavros' frame tests)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from airsim_mapper.common.geometry import quat_from_rpy, quat_to_matrix, rotate, rpy_from_quat
from airsim_mapper.convert import frames
from airsim_mapper.convert.errors import ConversionError

finite = st.floats(-1e3, 1e3, allow_nan=False)
angles = st.floats(-math.pi, math.pi, allow_nan=False)


def same_rotation(a: np.ndarray, b: np.ndarray) -> bool:
    return bool(np.allclose(quat_to_matrix(a), quat_to_matrix(b), atol=1e-9))


def test_ned_point_becomes_enu_by_swapping_x_y_and_negating_z():
    assert frames.ned_to_enu(np.array([1.0, 2.0, 3.0])).tolist() == [2.0, 1.0, -3.0]


def test_point_arrays_convert_row_by_row():
    points = np.array([[1.0, 2.0, 3.0], [-4.0, 5.0, -6.0]])
    assert frames.ned_to_enu(points).tolist() == [[2.0, 1.0, -3.0], [5.0, -4.0, 6.0]]
    assert frames.frd_to_flu(points).tolist() == [[1.0, -2.0, -3.0], [-4.0, -5.0, 6.0]]


def test_enu_to_ned_undoes_ned_to_enu():
    point = np.array([7.0, -8.0, 9.5])
    assert frames.enu_to_ned(frames.ned_to_enu(point)).tolist() == point.tolist()
    assert frames.flu_to_frd(frames.frd_to_flu(point)).tolist() == point.tolist()


def test_identity_attitude_in_ned_faces_north_which_is_enu_yaw_plus_90_degrees():
    q = frames.ned_frd_to_enu_flu(np.array([1.0, 0.0, 0.0, 0.0]))
    roll, pitch, yaw = rpy_from_quat(q)
    assert yaw == pytest.approx(math.pi / 2)
    assert roll == pytest.approx(0.0, abs=1e-12)
    assert pitch == pytest.approx(0.0, abs=1e-12)


def test_drone_yawed_90_degrees_in_ned_faces_east_which_is_enu_yaw_zero():
    q = frames.ned_frd_to_enu_flu(quat_from_rpy(0.0, 0.0, math.pi / 2))
    assert rpy_from_quat(q)[2] == pytest.approx(0.0, abs=1e-12)
    assert q.tolist() == pytest.approx([1.0, 0.0, 0.0, 0.0])


def test_ned_roll_right_is_enu_roll_right_and_ned_pitch_up_is_enu_pitch_up():
    # Rolling right wing down is positive roll about forward in FRD; in FLU that is also positive roll
    # (x forward both), and nose-up pitch is positive in FRD but negative about FLU's left-pointing y.
    q = frames.ned_frd_to_enu_flu(quat_from_rpy(0.3, 0.0, 0.0))
    roll, pitch, yaw = rpy_from_quat(q)
    assert (roll, pitch, yaw) == pytest.approx((0.3, 0.0, math.pi / 2))
    roll, pitch, yaw = rpy_from_quat(frames.ned_frd_to_enu_flu(quat_from_rpy(0.0, 0.2, 0.0)))
    assert (roll, pitch, yaw) == pytest.approx((0.0, -0.2, math.pi / 2))


def test_converted_attitude_maps_body_forward_to_the_same_world_direction():
    q_ned = quat_from_rpy(0.1, -0.4, 2.0)
    forward_ned = rotate(q_ned, np.array([1.0, 0.0, 0.0]))
    forward_enu = rotate(frames.ned_frd_to_enu_flu(q_ned), np.array([1.0, 0.0, 0.0]))
    assert forward_enu == pytest.approx(frames.ned_to_enu(forward_ned))
    left_enu = rotate(frames.ned_frd_to_enu_flu(q_ned), np.array([0.0, 1.0, 0.0]))
    right_ned = rotate(q_ned, np.array([0.0, 1.0, 0.0]))
    assert left_enu == pytest.approx(-frames.ned_to_enu(right_ned))


def test_converted_quaternions_have_non_negative_w():
    q = frames.ned_frd_to_enu_flu(quat_from_rpy(0.0, 0.0, -3.0))
    assert q[0] >= 0.0


@settings(deadline=None)
@given(angles, st.floats(-1.5, 1.5), angles)
def test_attitude_round_trip_ned_enu_ned_is_the_same_rotation(roll, pitch, yaw):
    q = quat_from_rpy(roll, pitch, yaw)
    back = frames.enu_flu_to_ned_frd(frames.ned_frd_to_enu_flu(q))
    assert same_rotation(back, q)


@settings(deadline=None)
@given(st.lists(st.tuples(finite, finite, finite), min_size=1, max_size=20))
def test_point_round_trips_are_exact(points):
    array = np.array(points)
    assert np.array_equal(frames.enu_to_ned(frames.ned_to_enu(array)), array)
    assert np.array_equal(frames.flu_to_frd(frames.frd_to_flu(array)), array)


@settings(deadline=None)
@given(angles, st.floats(-1.5, 1.5), angles)
def test_relative_rotation_round_trip_frd_flu_frd_is_the_same_rotation(roll, pitch, yaw):
    q = quat_from_rpy(roll, pitch, yaw)
    assert same_rotation(frames.flu_to_frd_rotation(frames.frd_to_flu_rotation(q)), q)


def test_a_mount_yawed_right_in_frd_is_yawed_left_in_flu():
    q = frames.frd_to_flu_rotation(quat_from_rpy(0.0, 0.0, 0.5))
    assert rpy_from_quat(q) == pytest.approx((0.0, 0.0, -0.5))


def test_frd_optical_frame_has_z_forward_x_right_y_down():
    m = quat_to_matrix(frames.body_to_optical(np.array([1.0, 0.0, 0.0, 0.0]), "ned"))
    # columns are the optical axes expressed in the FRD body frame
    assert m[:, 0] == pytest.approx([0.0, 1.0, 0.0])  # x right
    assert m[:, 1] == pytest.approx([0.0, 0.0, 1.0])  # y down
    assert m[:, 2] == pytest.approx([1.0, 0.0, 0.0])  # z forward


def test_flu_optical_frame_has_z_forward_x_right_y_down():
    m = quat_to_matrix(frames.body_to_optical(np.array([1.0, 0.0, 0.0, 0.0]), "enu"))
    assert m[:, 0] == pytest.approx([0.0, -1.0, 0.0])
    assert m[:, 1] == pytest.approx([0.0, 0.0, -1.0])
    assert m[:, 2] == pytest.approx([1.0, 0.0, 0.0])


def test_optical_frames_agree_between_conventions_in_the_world():
    q_ned = quat_from_rpy(0.2, 0.1, 1.0)
    optical_ned = frames.body_to_optical(q_ned, "ned")
    optical_enu = frames.body_to_optical(frames.ned_frd_to_enu_flu(q_ned), "enu")
    # the optical axes point the same physical way: compare in ENU
    axes_ned = quat_to_matrix(optical_ned)
    axes_enu = quat_to_matrix(optical_enu)
    assert axes_enu == pytest.approx(frames.R_NED_TO_ENU @ axes_ned)


def test_covariance_3x3_swaps_north_east_variances_in_enu():
    cov = np.diag([1.0, 2.0, 3.0])
    cov[0, 1] = cov[1, 0] = 0.5
    cov[0, 2] = cov[2, 0] = 0.25
    out = frames.ned_to_enu_covariance(cov)
    assert out.tolist() == [[2.0, 0.5, 0.0], [0.5, 1.0, -0.25], [0.0, -0.25, 3.0]]


def test_flat_covariance_stays_flat_and_body_change_negates_cross_terms():
    cov = [1.0, 0.1, 0.2, 0.1, 2.0, 0.3, 0.2, 0.3, 3.0]
    out = frames.frd_to_flu_covariance(cov)
    assert out.tolist() == pytest.approx([1.0, -0.1, -0.2, -0.1, 2.0, 0.3, -0.2, 0.3, 3.0])


def test_covariance_6x6_rotates_both_blocks():
    cov = np.diag([1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    assert np.diag(frames.ned_to_enu_covariance(cov)).tolist() == [2.0, 1.0, 3.0, 5.0, 4.0, 6.0]


def test_covariance_of_wrong_size_is_rejected():
    with pytest.raises(ConversionError, match=r"covariance must have 9 or 36 elements, got 8"):
        frames.ned_to_enu_covariance([0.0] * 8)
