"""CameraInfo: pinhole K and P from the capture setting's fov, plumb_bob, cached per size and fov."""

from __future__ import annotations

import math

import pytest
import rospy

from airsim_mapper.convert.camera_info import camera_info, intrinsics
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError

SETTING = {"image-type": 0, "width": 640, "height": 480, "fov-degrees": 90}


def ctx(**source):
    return ConvertContext(frame_id="cam", source={**SETTING, **source})


def test_camera_info_for_90_degrees_has_focal_length_half_the_width(roundtrip):
    msg = camera_info({"time_stamp": 10, "width": 640, "height": 480}, ctx())
    assert msg.distortion_model == "plumb_bob"
    assert list(msg.D) == [0.0] * 5
    assert list(msg.K) == pytest.approx([320.0, 0, 320.0, 0, 320.0, 240.0, 0, 0, 1])
    assert list(msg.R) == [1, 0, 0, 0, 1, 0, 0, 0, 1]
    assert list(msg.P) == pytest.approx([320.0, 0, 320.0, 0, 0, 320.0, 240.0, 0, 0, 0, 1, 0])
    assert (msg.width, msg.height, msg.header.frame_id) == (640, 480, "cam")
    assert msg.header.stamp == rospy.Time(0, 10)
    assert roundtrip(msg) == msg


def test_focal_length_follows_the_field_of_view():
    msg = camera_info({"time_stamp": 0, "width": 400, "height": 225}, ctx(**{"fov-degrees": 60}))
    f = 200.0 / math.tan(math.radians(30.0))
    assert msg.K[0] == pytest.approx(f)
    assert msg.K[4] == pytest.approx(f)
    assert (msg.K[2], msg.K[5]) == (200.0, 112.5)


def test_intrinsics_are_cached_per_size_and_fov():
    assert intrinsics(64, 48, 90.0) is intrinsics(64, 48, 90.0)
    assert intrinsics(64, 48, 90.0) is not intrinsics(64, 48, 80.0)


def test_each_message_is_restamped_but_shares_nothing_mutable():
    first = camera_info({"time_stamp": 1, "width": 64, "height": 48}, ctx())
    second = camera_info({"time_stamp": 2, "width": 64, "height": 48}, ctx())
    assert first.header.stamp != second.header.stamp
    assert first.D is not second.D


def test_missing_fov_defaults_to_90_degrees():
    msg = camera_info({"time_stamp": 0, "width": 100, "height": 50}, ConvertContext())
    assert msg.K[0] == pytest.approx(50.0)


def test_camera_info_without_width_is_rejected():
    with pytest.raises(ConversionError, match=r"camera_info: image has no 'width'"):
        camera_info({"time_stamp": 0, "height": 480}, ctx())


@pytest.mark.parametrize("width, height", [(0, 480), (2**32, 1), (640, -1)])
def test_a_size_that_is_not_a_positive_uint32_is_rejected(width, height):
    with pytest.raises(ConversionError, match=rf"camera_info: size {width}x{height} must be positive"):
        camera_info({"time_stamp": 0, "width": width, "height": height}, ctx())


@pytest.mark.parametrize("fov", [0, 180, -5])
def test_fov_outside_0_180_is_rejected(fov):
    with pytest.raises(ConversionError, match=r"camera_info: fov-degrees must be in \(0, 180\)"):
        camera_info({"time_stamp": 0, "width": 64, "height": 48}, ctx(**{"fov-degrees": fov}))


def test_non_numeric_fov_is_rejected():
    with pytest.raises(ConversionError, match=r"camera_info: fov-degrees must be a number"):
        camera_info({"time_stamp": 0, "width": 64, "height": 48}, ctx(**{"fov-degrees": "wide"}))
