"""The benchmark's yardsticks: the old bridge's algorithms give the same data as the bridge's converters."""

from __future__ import annotations

import numpy as np
import pytest

from airsim_mapper.convert import registry
from airsim_mapper.convert.context import ConvertContext
from tools.bench import costs, reference, results, targets


def test_the_reference_lidar_packs_the_nwu_flipped_points_the_bridge_gives_in_enu():
    message = costs.client_unpack(costs.lidar_frame(points=500))
    ours = registry.get("pointcloud")(message, ConvertContext(frame_id="l", convention="enu"))
    theirs = reference.lidar_to_cloud(message)
    xyz = np.frombuffer(theirs.data, dtype="<f4").reshape(-1, 3)
    cloud = np.frombuffer(
        ours.data, dtype=np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("i", "<f4"), ("s", "<i4")])
    )
    np.testing.assert_array_equal(xyz, np.stack([cloud["x"], cloud["y"], cloud["z"]], axis=1))
    assert (theirs.point_step, theirs.width, [f.name for f in theirs.fields]) == (12, 500, ["x", "y", "z"])


def test_the_reference_depth_loop_produces_the_same_32fc1_pixels_as_the_bridge():
    message = costs.client_unpack(costs.image_frame(32, 24, "32FC1"))
    theirs = reference.depth_32fc1_to_image(message)
    expected = np.asarray(message["data_float"], dtype="<f4").tobytes()
    assert (theirs.encoding, theirs.step, theirs.data) == ("32FC1", 4 * 32, expected)


def test_the_reference_radar_loses_the_scan_on_a_zero_cross_section_as_the_old_bridge_did():
    message = costs.client_unpack(costs.radar_frame(detections=3))
    assert len(reference.radar_to_scan(message).returns) == 3
    message["radar_detections"][1]["rcs_sqm"] = 0.0
    with pytest.raises(ValueError, match="math domain error"):
        reference.radar_to_scan(message)


def test_a_cost_case_times_every_path_and_checks_the_fast_path_serialises_identically():
    case = costs.Case(
        "lidar 2k", costs.lidar_frame(points=2000), "pointcloud", reference.lidar_to_cloud, repeat=2
    )
    result = costs.measure_case(case)
    for key in ("bridge_ms", "client_path_ms", "reference_ms", "bare_serialize_ms", "unpack_fast_ms"):
        assert result[key] > 0
    assert result["frame_bytes"] == len(case.frame)


def test_the_bridge_cost_takes_the_node_s_path_and_sends_the_pixels_from_the_frame():
    frame = costs.image_frame(128, 128, "BGR")  # over the size at which the node parses frames in place
    convert = registry.get("image")
    parts = costs.node_serialize(convert(costs.bridge_unpack(frame), ConvertContext(frame_id="c")))
    pixels = np.frombuffer(parts[1], dtype=np.uint8)
    assert pixels.size == 128 * 128 * 3
    assert np.shares_memory(pixels, np.frombuffer(frame, dtype=np.uint8))
    client = costs.serialize(convert(costs.client_unpack(frame), ConvertContext(frame_id="c")))
    assert costs.sent_bytes(parts) == client


def test_converter_costs_are_judged_against_the_issue_limits():
    measured = {
        results.LIDAR: {"bridge_ms": 6.0, "speedup_vs_reference": 12.0},
        results.DEPTH: {"bridge_ms": 4.0},
        results.BGR: {"ratio_to_bare_serialize": 1.5, "bare_serialize_ms": 2.0},
    }
    verdicts = {t["target"]: t["met"] for t in targets.targets({"costs": measured})}
    assert verdicts == {
        "100k-point scan, frame bytes -> PointCloud2, CPU": False,
        "100k-point scan, speed-up over the reference": True,
        "1080p depth, frame bytes -> Image, CPU": True,
        "1080p BGR bridge CPU / bare rospy serialisation of the same bytes": False,
    }


def test_every_cost_limit_judges_a_case_the_bench_measures():
    measured = {case.name for case in costs.cases()}
    assert {limit.case for limit in targets.COST_LIMITS} <= measured
    assert measured == {results.BGR, results.DEPTH, results.DEPTH_FLOAT, results.LIDAR, results.RADAR}
