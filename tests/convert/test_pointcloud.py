"""Lidar -> PointCloud2: one structured array, five fields, FRD or FLU points, strict lengths."""

from __future__ import annotations

import numpy as np
import pytest
from sensor_msgs import point_cloud2
from sensor_msgs.msg import PointField

from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.pointcloud import POINT_DTYPE, pointcloud

CTX = ConvertContext(frame_id="airsim_node/Drone1/lidar1")


def lidar(points, intensity=None, segmentation=None, **extra):
    n = len(points) // 3
    msg = {
        "time_stamp": 77,
        "point_cloud": points,
        "azimuth_elevation_range_cloud": [],
        "intensity_cloud": [0.5] * n if intensity is None else intensity,
        "segmentation_cloud": [7] * n if segmentation is None else segmentation,
        "laser_index_cloud": [0] * n,
        "pose": {"position": {"x": 0, "y": 0, "z": 0}, "orientation": {"w": 1, "x": 0, "y": 0, "z": 0}},
    }
    msg.update(extra)
    return msg


def test_points_and_fields_are_packed_into_twenty_byte_records(roundtrip):
    msg = pointcloud(lidar([1.0, 2.0, 3.0, -4.0, 5.5, 6.0], [0.25, 0.75], [3, -1]), CTX)
    assert (msg.height, msg.width, msg.point_step, msg.row_step) == (1, 2, 20, 40)
    assert [(f.name, f.offset, f.datatype, f.count) for f in msg.fields] == [
        ("x", 0, PointField.FLOAT32, 1),
        ("y", 4, PointField.FLOAT32, 1),
        ("z", 8, PointField.FLOAT32, 1),
        ("intensity", 12, PointField.FLOAT32, 1),
        ("segmentation", 16, PointField.INT32, 1),
    ]
    assert msg.is_dense is True and msg.is_bigendian is False
    assert msg.header.frame_id == CTX.frame_id
    copy = roundtrip(msg)
    points = list(point_cloud2.read_points(copy))
    assert points == [(1.0, 2.0, 3.0, 0.25, 3), (-4.0, 5.5, 6.0, 0.75, -1)]


def test_enu_negates_y_and_z_for_flu():
    msg = pointcloud(lidar([1.0, 2.0, 3.0]), ConvertContext(convention="enu"))
    assert list(point_cloud2.read_points(msg, field_names=("x", "y", "z"))) == [(1.0, -2.0, -3.0)]


def test_numpy_arrays_and_raw_bytes_are_accepted():
    xyz = np.array([1, 2, 3, 4, 5, 6], dtype="<f4")
    by_array = pointcloud(lidar(xyz, np.array([1.0, 2.0]), np.array([1, 2])), CTX)
    by_bytes = pointcloud(lidar(xyz.tobytes(), np.array([1, 2], dtype="<f4").tobytes(), [1, 2]), CTX)
    assert by_array.data == by_bytes.data


def test_missing_intensity_and_segmentation_default_to_zero():
    msg = lidar([1.0, 2.0, 3.0])
    del msg["intensity_cloud"], msg["segmentation_cloud"]
    cloud = np.frombuffer(pointcloud(msg, CTX).data, dtype=POINT_DTYPE)
    assert cloud["intensity"].tolist() == [0.0]
    assert cloud["segmentation"].tolist() == [0]


def test_empty_scan_gives_an_empty_cloud(roundtrip):
    msg = pointcloud(lidar([]), CTX)
    assert (msg.width, msg.data) == (0, b"")
    assert roundtrip(msg) == msg


def test_non_finite_points_mark_the_cloud_not_dense():
    assert pointcloud(lidar([float("nan"), 0.0, 0.0]), CTX).is_dense is False


def test_list_of_ints_is_packed_to_int32_and_floats_to_float32():
    msg = pointcloud(lidar([0.1, 0.2, 0.3], [0.5], [2**31 - 1]), CTX)
    cloud = np.frombuffer(msg.data, dtype=POINT_DTYPE)
    assert cloud["x"][0] == np.float32(0.1)
    assert cloud["segmentation"][0] == 2**31 - 1


def test_hundred_thousand_point_scan_converts_in_a_few_milliseconds_plus_list_cost(timed):
    rng = np.random.default_rng(1)
    points = rng.normal(size=300_000).astype(np.float32)
    msg_lists = lidar(points.tolist(), rng.random(100_000).tolist(), [1] * 100_000)
    msg_arrays = lidar(points, rng.random(100_000).astype(np.float32), np.ones(100_000, dtype=np.int32))
    out = pointcloud(msg_arrays, CTX)
    array_seconds = timed(5, lambda: pointcloud(msg_arrays, CTX))
    list_seconds = timed(2, lambda: pointcloud(msg_lists, CTX))
    assert out.width == 100_000 and len(out.data) == 2_000_000
    assert array_seconds < 0.05  # ~0.5 ms on an idle machine (tools/bench/converters.py)
    assert list_seconds < 0.25  # ~25 ms, nearly all of it Python list -> array


def test_point_cloud_not_a_multiple_of_three_is_rejected():
    with pytest.raises(ConversionError, match=r"pointcloud: point_cloud has 4 values, not a multiple of 3"):
        pointcloud(lidar([1.0, 2.0, 3.0, 4.0], [0.0], [0]), CTX)


def test_intensity_of_another_length_is_rejected():
    with pytest.raises(
        ConversionError, match=r"pointcloud: intensity_cloud has 1 values, expected 2 \(one per point\)"
    ):
        pointcloud(lidar([0.0] * 6, [1.0], [1, 2]), CTX)


def test_segmentation_of_another_length_is_rejected():
    with pytest.raises(ConversionError, match=r"pointcloud: segmentation_cloud has 3 values, expected 1"):
        pointcloud(lidar([0.0] * 3, [1.0], [1, 2, 3]), CTX)


def test_truncated_raw_bytes_are_rejected():
    with pytest.raises(ConversionError, match=r"pointcloud: point_cloud has 13 bytes, not a multiple of 4"):
        pointcloud(lidar(bytes(13), [], []), CTX)


def test_missing_point_cloud_is_rejected():
    msg = lidar([])
    del msg["point_cloud"]
    with pytest.raises(ConversionError, match=r"pointcloud: lidar has no 'point_cloud'"):
        pointcloud(msg, CTX)


def test_non_numeric_points_are_rejected():
    with pytest.raises(ConversionError, match=r"pointcloud: point_cloud must hold numbers"):
        pointcloud(lidar(["a", "b", "c"], [0.0], [0]), CTX)


def test_nested_point_lists_are_rejected():
    with pytest.raises(ConversionError, match=r"pointcloud: point_cloud must be a flat list of numbers"):
        pointcloud(lidar([[1.0, 2.0, 3.0]], [0.0], [0]), CTX)


@pytest.mark.parametrize("convention", ["ned", "enu"])
@pytest.mark.parametrize("dense", [True, False])
def test_a_cloud_goes_on_the_wire_byte_for_byte_as_genpy_writes_it(convention, dense):
    from io import BytesIO

    from sensor_msgs.msg import PointCloud2

    points = np.arange(30, dtype=np.float32)
    if not dense:
        points[4] = np.inf
    msg = pointcloud(lidar(points.tolist(), intensity=[0.25] * 10), ConvertContext(convention=convention))
    plain = PointCloud2(
        **{**{name: getattr(msg, name) for name in PointCloud2.__slots__}, "data": bytes(msg.data)}
    )
    ours, genpys = BytesIO(), BytesIO()
    msg.serialize(ours)
    plain.serialize(genpys)
    assert ours.getvalue() == genpys.getvalue()
    assert PointCloud2().deserialize(ours.getvalue()).is_dense is dense


def test_the_points_are_serialised_apart_from_where_they_are():
    from io import BytesIO

    msg = pointcloud(lidar([1.0, 2.0, 3.0] * 4), CTX)
    head = BytesIO()
    points, after = msg.serialize_apart(head)
    assert isinstance(msg.data.obj, np.ndarray) and points.obj is msg.data.obj  # no copy of the points
    assert (bytes(points), after) == (bytes(msg.data), b"\x01")
    assert head.getvalue().endswith(len(points).to_bytes(4, "little"))
