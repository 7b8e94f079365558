"""End to end with image_transport's sibling topics subscribed: the replay server's 1080p camera at 30 Hz
through the bridge node (the default mapping) to a probe of `<image>/compressed` with the pose alongside,
then of the depth image's `<image>/compressedDepth`. Rate, latency, the node's CPU per message and the
bytes each message carries; the raw topics' bytes come from the same scene's raw probes in `make bench`.

    .venv/bin/python -m tools.bench.transports [--quick]     # on its own: just these two windows
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path
from typing import Any

from tools.bench import scenes
from tools.bench.e2e import Bench
from tools.bench.results import per_message_cpu_ms, topic

CAMERA_HZ = 30.0
JPEG_MIN_HZ = 29.0  # the targets: 1080p @30 JPEG delivered, 1080p depth on 2 cores
DEPTH_MIN_HZ = 15.0


def compressed_topic(image_type: str = "scene_camera") -> str:
    return f"{scenes.image_topic(1, image_type)}/compressed"


def depth_topic() -> str:
    return f"{scenes.image_topic(1, 'depth_planar_camera')}/compressedDepth"


def run(bench: Bench, scene_file: str) -> dict[str, Any]:
    """The two windows, in one bridge session of `scene_file` (a 1080p camera with image types 0 and 1)."""
    with bench.bridge_session(scene_file) as session:
        return {
            "compressed": session.probe("camera_compressed", [compressed_topic(), scenes.pose_topic(1)]),
            "compressed_depth": session.probe("depth_compressed", [depth_topic()]),
        }


def table(result: dict[str, Any], raw: dict[str, Any] | None = None) -> str:
    """The windows as rows, with the targets; `raw`: the bench's raw camera and depth windows, for bytes."""
    rows = [
        ("image_transport, 1080p @30", "rate Hz", "p50 ms", "p99 ms", "CPU ms/msg", "bytes/msg", "target")
    ]

    def add(label: str, window: dict[str, Any], name: str | None, minimum: float | None) -> None:
        t = topic(window, name)
        cpu = per_message_cpu_ms(window.get("bridge_cpu_cores", 0.0), t["rate_hz"])
        target = (
            "-" if minimum is None else ("met" if t["rate_hz"] >= minimum else "MISSED") + f" >= {minimum:g}"
        )
        p50, p99 = t.get("latency_p50_ms"), t.get("latency_p99_ms")
        rows.append(
            (
                label,
                f"{t['rate_hz']:.1f}",
                "-" if p50 is None else f"{p50:.2f}",
                "-" if p99 is None else f"{p99:.2f}",
                "-" if cpu is None else f"{cpu:.2f}",
                str(t.get("message_bytes", "-")),
                target,
            )
        )

    add("compressed (JPEG q80)", result["compressed"], compressed_topic(), JPEG_MIN_HZ)
    add("  pose @100 alongside", result["compressed"], scenes.pose_topic(1), None)
    add("compressedDepth (PNG level 1)", result["compressed_depth"], depth_topic(), DEPTH_MIN_HZ)
    for label, key, name in (
        ("raw Image bgr8", "camera", scenes.image_topic(1)),
        ("raw Image 32FC1", "depth", None),
    ):
        if raw and key in raw:
            add(label, raw[key], name, None)
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return "\n".join("  ".join(cell.ljust(w) for cell, w in zip(row, widths)) for row in rows) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="shorter measurement windows (3 s)")
    args = parser.parse_args(argv)
    bench = Bench(
        Path(tempfile.mkdtemp(prefix="airsim_mapper_transports_")), duration_s=3.0 if args.quick else 8.0
    )
    try:
        single = bench.scene("single", 1, scenes.CameraSetup(1920, 1080, 1 / CAMERA_HZ, (0, 1)))
        print(table(run(bench, single)), flush=True)
    finally:
        bench.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
