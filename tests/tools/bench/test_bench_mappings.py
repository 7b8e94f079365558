"""The bench's mapping without camera frames drops exactly those default rules (a rename breaks this test)."""

from __future__ import annotations

from airsim_mapper.mapping.loader import load_mapping
from tools.bench.scenes import CAMERA_FRAME_RULES, write_mapping_without_camera_frames


def test_the_lean_bench_mapping_removes_exactly_the_camera_frame_rules(tmp_path):
    default = {rule.name for rule in load_mapping("default").rules}
    lean = {rule.name for rule in load_mapping(str(write_mapping_without_camera_frames(tmp_path))).rules}
    assert set(CAMERA_FRAME_RULES) <= default
    assert default - lean == set(CAMERA_FRAME_RULES)
