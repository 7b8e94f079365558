"""Checked field access names the offending field; the converter wrapper only lets ConversionError out."""

from __future__ import annotations

import numpy as np
import pytest

from airsim_mapper.convert import sim_fields
from airsim_mapper.convert.errors import ConversionError


def test_field_returns_the_value_of_a_present_key():
    assert sim_fields.field({"a": 1}, "a") == 1


def test_missing_key_is_named():
    with pytest.raises(ConversionError, match=r"image has no 'data'"):
        sim_fields.field({}, "data", "image")


def test_non_map_is_named():
    with pytest.raises(ConversionError, match=r"lidar must be a map, got int"):
        sim_fields.field(3, "point_cloud", "lidar")


@pytest.mark.parametrize("bad", [True, "1", None, [1]])
def test_number_rejects_non_numbers(bad):
    with pytest.raises(ConversionError, match=r"speed must be a number"):
        sim_fields.number(bad, "speed")


def test_number_rejects_nan_unless_allowed():
    with pytest.raises(ConversionError, match=r"speed must be finite, got nan"):
        sim_fields.number(float("nan"), "speed")
    assert np.isinf(sim_fields.number(float("inf"), "speed", finite=False))


def test_vector3_reads_x_y_z():
    assert sim_fields.vector3({"v": {"x": 1, "y": 2.5, "z": -3}}, "v").tolist() == [1.0, 2.5, -3.0]


def test_vector3_names_the_missing_axis():
    with pytest.raises(ConversionError, match=r"v has no 'z'"):
        sim_fields.vector3({"v": {"x": 1, "y": 2}}, "v")


def test_quaternion_is_read_in_wxyz_order():
    q = sim_fields.quaternion({"q": {"x": 0.1, "y": 0.2, "z": 0.3, "w": 0.9}}, "q")
    assert q.tolist() == [0.9, 0.1, 0.2, 0.3]


def test_zero_quaternion_is_rejected():
    with pytest.raises(ConversionError, match=r"orientation is a zero quaternion"):
        sim_fields.quaternion({"orientation": {"w": 0, "x": 0, "y": 0, "z": 0}}, "orientation")


def test_wrapper_turns_stray_errors_into_conversion_errors():
    @sim_fields.converter("demo")
    def broken(msg, ctx):
        return msg["missing"]

    with pytest.raises(ConversionError, match=r"demo: malformed message \(KeyError: 'missing'\)"):
        broken({}, None)


def test_wrapper_prefixes_conversion_errors_with_the_converter_name_once():
    @sim_fields.converter("demo")
    def failing(msg, ctx):
        raise ConversionError(msg)

    with pytest.raises(ConversionError, match=r"^demo: bad thing$"):
        failing("bad thing", None)
    with pytest.raises(ConversionError, match=r"^demo: already named$"):
        failing("demo: already named", None)
