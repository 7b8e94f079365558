"""The bench's ROS 2 rows: the node in .venv-ros2 beside a bare rclpy forwarder, judged on their ratios in
one run, printed beside the ROS1 rows; `--ros 1|2` runs one flavour's rows only."""

from __future__ import annotations

import struct

import pytest

from tools.bench import ros2, scenes, tables, targets
from tools.bench.__main__ import main
from tools.bench.e2e import Bench
from tools.bench.probe_ros2 import stamp_s

POSE, IMAGE = scenes.pose_topic(1), scenes.image_topic(1)
DRONES = {scenes.pose_topic(i): (100.0, 3.0) for i in (1, 2)}
DRONES |= {scenes.image_topic(i): (10.0, 9.0) for i in (1, 2)}


def _result(role: str, cores: float, topics: dict[str, tuple[float, float]], probe: float = 0.01) -> dict:
    """A probe result: {topic: (rate Hz, p99 ms)}, the CPU of `role` and of the probe."""
    return {
        f"{role}_cpu_cores": cores,
        "probe_cpu_cores": probe,
        "topics": {
            name: {"rate_hz": rate, "latency_p50_ms": p99 / 2, "latency_p99_ms": p99, "count": 1}
            for name, (rate, p99) in topics.items()
        },
    }


def _e2e_ros2(scale_pose_hz: float = 100.0) -> dict:
    """`run_e2e_ros2`'s results, one round of each case."""
    drones = DRONES | {scenes.pose_topic(2): (scale_pose_hz, 3.0)}
    return {
        "pose": {"idle": _result("bridge", 0.06, {POSE: (100.0, 1.0)}, probe=0.02)},
        "bridge": {
            "camera": _result("bridge", 0.5, {IMAGE: (3.0, 40.0), POSE: (100.0, 8.0)}),
            "camera_720p": _result("bridge", 0.3, {IMAGE: (30.0, 20.0), POSE: (100.0, 4.0)}),
        },
        "scale": {"2": _result("bridge", 0.2, drones)},
        "forwarder": {
            "pose_idle": _result("forwarder", 0.05, {POSE: (100.0, 1.0)}),
            "camera": _result("forwarder", 0.5, {IMAGE: (2.0, 60.0), POSE: (100.0, 10.0)}),
            "camera_720p": _result("forwarder", 0.2, {IMAGE: (30.0, 25.0), POSE: (100.0, 5.0)}),
            "scale": _result("forwarder", 0.25, DRONES),
        },
        "rounds": {},
    }


def test_the_ros2_targets_are_judged_on_the_ratios_to_the_rclpy_forwarder():
    verdicts = {t["target"]: (round(t["value"], 3), t["met"]) for t in targets.ros2_targets(_e2e_ros2())}
    assert verdicts == {
        # 0.06 / 0.02 against 0.05 / 0.01: each node's CPU over its probe's
        "ROS 2 pose only: bridge CPU / the rclpy forwarder's": (0.6, True),
        "ROS 2 720p camera @30 + pose: bridge CPU / the rclpy forwarder's": (1.5, False),
        "ROS 2 1080p camera @30 + pose: bridge CPU / the rclpy forwarder's": (1.0, True),
        "ROS 2 10 drones: bridge CPU / the rclpy forwarder's": (0.8, True),
        "ROS 2 pose p99 under a 1080p camera @30 / the rclpy forwarder's": (0.8, True),
        "ROS 2 2 drones: slowest pose delivered": (100.0, True),
    }
    slow = {t["target"]: t for t in targets.ros2_targets(_e2e_ros2(scale_pose_hz=85.0))}
    row = slow["ROS 2 2 drones: slowest pose delivered"]
    assert row["met"] is False and row["limit"] == 90.0
    assert row["note"] == "slowest camera 10.0 Hz, the forwarder's slowest pose 100.0 Hz"


def test_the_ros2_targets_take_the_median_of_the_quiet_rounds():
    e2e = _e2e_ros2()
    quiet = {"host_stolen_share": 0.0}
    e2e["rounds"]["camera"] = [
        {
            "bridge": _result("bridge", 0.5, {IMAGE: (3.0, 40.0), POSE: (100.0, p99)}) | quiet,
            "forwarder": _result("forwarder", 0.4, {IMAGE: (2.0, 60.0), POSE: (100.0, 10.0)}) | quiet,
        }
        for p99 in (12.0, 9.0)
    ]
    rows = {t["target"]: t for t in targets.ros2_targets(e2e)}
    p99 = rows["ROS 2 pose p99 under a 1080p camera @30 / the rclpy forwarder's"]
    assert p99["value"] == pytest.approx(0.9) and p99["met"] is True
    rounds = "median of 3 interleaved rounds (0.80x, 1.20x, 0.90x)"
    assert p99["note"].startswith(f"{rounds}; round 1: bridge 8.00 ms")
    cpu = rows["ROS 2 1080p camera @30 + pose: bridge CPU / the rclpy forwarder's"]
    assert cpu["value"] == pytest.approx(1.25) and cpu["met"] is False
    assert cpu["note"].endswith("cores: 0.500 / 0.500, 0.500 / 0.400, 0.500 / 0.400")


def test_the_ros2_rows_print_each_case_with_its_ratios_and_the_images_delivered():
    text = tables.ros2_table(_e2e_ros2())
    assert text.startswith("ROS 2: bridge / bare rclpy forwarder (same frames, same run)")
    lines: dict[str, str] = {}
    for line in text.splitlines():  # the first table's line of each case
        lines.setdefault(line.split("  ")[0], line)
    assert "0.500 / 0.500" in lines["1080p camera @30 + pose"] and "0.80x" in lines["1080p camera @30 + pose"]
    assert "1.50x" in lines["720p camera @30 + pose"] and "0.060 / 0.050" in lines["pose @100"]
    images = [line for line in text.splitlines() if line.startswith("1080p camera @30 + pose")][1]
    assert "3.0 / 2.0" in images and "20.00 / 30.00" in images


def test_a_ros2_only_run_is_judged_on_the_ros2_targets_only():
    rows = targets.targets({"e2e_ros2": _e2e_ros2()})
    assert rows and all(row["target"].startswith("ROS 2 ") for row in rows)
    assert not any(row["target"].startswith("ROS 2 ") for row in targets.targets({"costs": _costs()}))


def _costs() -> dict:
    costs: dict = {}
    for limit in targets.COST_LIMITS:
        costs.setdefault(limit.case, {})[limit.figure] = limit.limit
    return costs


def test_the_probe_reads_the_stamp_from_the_serialised_header():
    little = b"\x00\x01\x00\x00" + struct.pack("<iI", 1_700_000_000, 250_000_000) + b"\x05\x00\x00\x00map\x00"
    big = b"\x00\x00\x00\x00" + struct.pack(">iI", 12, 500_000_000)
    assert stamp_s(little) == pytest.approx(1_700_000_000.25) and stamp_s(big) == pytest.approx(12.5)


def test_each_bench_takes_a_ros2_domain_of_its_own_and_gives_it_back(tmp_path):
    first = ros2.claim_domain(tmp_path, range(1, 3))
    second = ros2.claim_domain(tmp_path, range(1, 3))
    assert {first.number, second.number} == {1, 2}
    with pytest.raises(ros2.Ros2Unavailable, match="every ROS 2 domain in range"):
        ros2.claim_domain(tmp_path, range(1, 3))
    first.release()
    assert ros2.claim_domain(tmp_path, range(1, 3)).number == first.number


def test_the_bench_runs_one_flavour_or_both(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--ros", "3", "--costs-only"])
    assert stop.value.code == 2 and "--ros" in capsys.readouterr().err


@pytest.mark.live
def test_the_ros2_node_and_the_rclpy_forwarder_carry_pose_and_images_to_the_rclpy_probe(tmp_path):
    bench = Bench(tmp_path, warmup_s=0.5, duration_s=2.0, flavours=(2,))
    try:
        scene = bench.scene("ros2", 1, scenes.CameraSetup(320, 240, 0.1, (0,)))
        measured = {}
        with bench.bridge_session(scene, ros=2) as session:
            measured["bridge"] = session.probe("ros2_bridge", [POSE, IMAGE])
        with bench.forwarder_session(scene, camera=True, ros=2) as session:
            measured["forwarder"] = session.probe("ros2_forwarder", [POSE, IMAGE])
    finally:
        bench.close()
    for role, result in measured.items():
        pose, image = result["topics"][POSE], result["topics"][IMAGE]
        assert pose["rate_hz"] > 50 and image["rate_hz"] > 5, (role, result)
        assert image["message_bytes"] > 320 * 240 * 3 and 0 < pose["latency_p50_ms"] < 1000
        assert result[f"{role}_cpu_cores"] > 0 and result["probe_cpu_cores"] > 0
