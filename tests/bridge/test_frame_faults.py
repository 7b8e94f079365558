"""Image frames are not returned to the kernel and faulted back in: the node and a mission script's wrapper
take a bounded number of minor page faults per 1080p frame (the bench's replay server sends them)."""

from __future__ import annotations

import pytest

from tools.bench import scenes
from tools.bench.e2e import Bench

# A 1080p BGR frame is 1519 pages of 4 KiB. Measured (tools/bench/variants.py): about 20 faults per frame
# with the wrapper's malloc thresholds, 750-3100 with glibc's adaptive ones (docs/performance.md).
MAX_FAULTS_PER_FRAME = 300


@pytest.mark.live
@pytest.mark.parametrize("runner", ["node", "mission"])
def test_a_1080p_camera_costs_few_page_faults_per_frame(tmp_path, runner):
    bench = Bench(tmp_path, warmup_s=2.0, duration_s=4.0)
    try:
        scene = bench.scene("faults", 1, scenes.CameraSetup(1920, 1080, 1 / 30, (0,)))
        with bench.bridge_session(scene, runner=runner) as session:
            result = session.probe("faults", [scenes.image_topic(1)])
    finally:
        bench.close()
    frames_per_s = result["topics"][scenes.image_topic(1)]["rate_hz"]
    assert frames_per_s > 1, result
    faults_per_frame = result["bridge_minor_faults_per_s"] / frames_per_s
    assert faults_per_frame < MAX_FAULTS_PER_FRAME, result
