"""The bridge's receive-path variants side by side: 1080p camera @30 + pose @100, one run, same frames.

Each variant is the node with the comparison options of tools/bench/node.py (`--malloc glibc` leaves
glibc's adaptive malloc thresholds, `--receive copy` receives with pynng's `recv`), next to the bare
forwarder. Prints CPU, minor page faults per image frame, RSS, pose rate and p99 for each, interleaved
`--rounds` times so that a slow moment of the host touches every variant.

    python -m tools.bench.variants [--rounds 2] [--duration 8] [--width 1920 --height 1080]
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path
from typing import Any

from tools.bench import scenes
from tools.bench.e2e import Bench
from tools.bench.report import _table

VARIANTS: dict[str, tuple[str, ...]] = {
    "bridge": (),
    "bridge, glibc malloc thresholds": ("--malloc", "glibc"),
    "bridge, pynng recv (copies)": ("--receive", "copy"),
    "bridge, both (the previous receive path)": ("--malloc", "glibc", "--receive", "copy"),
}


def figures(result: dict[str, Any], role: str) -> dict[str, float]:
    topics = result["topics"]
    image = next(t for name, t in topics.items() if name.endswith("/image"))
    pose = next(t for name, t in topics.items() if name.endswith("actual_pose"))
    faults = result[f"{role}_minor_faults_per_s"]
    return {
        "cpu": result[f"{role}_cpu_cores"],
        "faults_per_frame": faults / max(image["rate_hz"], 1e-9),
        "rss": result[f"{role}_rss_mb"],
        "image_hz": image["rate_hz"],
        "pose_hz": pose["rate_hz"],
        "pose_p99": pose.get("latency_p99_ms", float("nan")),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--duration", type=float, default=8.0)
    parser.add_argument("--width", type=int, default=1920)
    parser.add_argument("--height", type=int, default=1080)
    args = parser.parse_args(argv)
    bench = Bench(Path(tempfile.mkdtemp(prefix="airsim_mapper_variants_")), duration_s=args.duration)
    load_start = os.getloadavg()[0]
    rows: dict[str, list[dict[str, float]]] = {name: [] for name in [*VARIANTS, "bare forwarder"]}
    topics = [scenes.image_topic(1), scenes.pose_topic(1)]
    try:
        scene = bench.scene("variants", 1, scenes.CameraSetup(args.width, args.height, 1 / 30, (0,)))
        for _ in range(args.rounds):
            for name, options in VARIANTS.items():
                with bench.bridge_session(scene, node_args=options) as session:
                    rows[name].append(figures(session.probe("variant", topics), "bridge"))
            with bench.forwarder_session(scene, camera=True) as session:
                rows["bare forwarder"].append(figures(session.probe("forwarder", topics), "forwarder"))
    finally:
        bench.close()
    body = []
    for name, runs in rows.items():

        def mean(key: str, runs: list = runs) -> float:
            return sum(r[key] for r in runs) / len(runs)

        body.append(
            [
                name,
                f"{mean('cpu'):.3f}",
                f"{mean('faults_per_frame'):.0f}",
                f"{mean('rss'):.0f}",
                f"{mean('image_hz'):.1f}",
                f"{mean('pose_hz'):.1f}",
                f"{mean('pose_p99'):.1f}",
                " ".join(f"{r['cpu']:.3f}" for r in runs),
            ]
        )
    header = ["variant", "CPU cores", "faults/frame", "RSS MB", "image Hz", "pose Hz", "pose p99", "CPU runs"]
    print(_table(header, body))
    print(
        f"{args.width}x{args.height} @30; load average {load_start:.1f} at start, "
        f"{os.getloadavg()[0]:.1f} at end"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
