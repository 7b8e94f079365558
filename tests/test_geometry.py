"""geometry.compose (the hot path of camera poses and frames) against the matrix form."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from airsim_mapper.common.geometry import (
    compose,
    q_conjugate,
    q_mul,
    q_normalized,
    q_rotate,
    quat_from_rpy,
    quat_multiply,
    quat_normalize,
    rotate,
)

angle = st.floats(-math.pi, math.pi)
coord = st.floats(-100, 100)


@given(
    angle, angle, angle, angle, angle, angle, st.tuples(coord, coord, coord), st.tuples(coord, coord, coord)
)
def test_compose_equals_rotation_matrix_composition(r1, p1, y1, r2, p2, y2, parent_pos, child_pos):
    q1, q2 = quat_from_rpy(r1, p1, y1), quat_from_rpy(r2, p2, y2)
    position, q = compose(np.array(parent_pos), q1, np.array(child_pos), q2)
    assert np.allclose(position, np.array(parent_pos) + rotate(q1, child_pos), atol=1e-9)
    expected = quat_normalize(quat_multiply(q1, q2))
    assert np.allclose(q, expected, atol=1e-12) or np.allclose(q, -expected, atol=1e-12)


def test_compose_of_a_yawed_parent_moves_the_child_sideways():
    east = quat_from_rpy(0.0, 0.0, math.pi / 2)  # facing east in NED
    position, q = compose(
        np.array([1.0, 2.0, -4.0]), east, np.array([0.5, 0.0, 0.1]), np.array([1.0, 0, 0, 0])
    )
    assert np.allclose(position, [1.0, 2.5, -3.9])
    assert np.allclose(q, east)


quaternion = st.tuples(coord, coord, coord, coord).filter(lambda q: sum(v * v for v in q) > 1e-6)


@given(quaternion, quaternion, st.tuples(coord, coord, coord))
def test_the_single_pose_float_math_equals_the_vectorised_numpy_math(a, b, v):
    assert np.allclose(q_mul(a, b), quat_multiply(np.array(a), np.array(b)), atol=1e-9)
    unit = q_normalized(a)
    assert np.allclose(unit, quat_normalize(np.array(a)), atol=1e-12)
    assert np.allclose(q_rotate(unit, v), rotate(np.array(unit), np.array(v)), atol=1e-9)
    assert np.allclose(q_rotate(q_conjugate(unit), q_rotate(unit, v)), v, atol=1e-9)
    assert all(type(c) is float for c in (*q_mul(a, b), *q_normalized(a), *q_rotate(unit, v)))
