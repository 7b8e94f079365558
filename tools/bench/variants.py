"""The bridge's variants side by side, interleaved `--rounds` times in one run on the same frames.

Camera (default): 1080p camera @30 + pose @100 through the node with the comparison options of
tools/bench/node.py (`--malloc glibc` leaves glibc's adaptive malloc thresholds, `--receive copy` receives
with pynng's `recv`), next to the bare forwarder. `--drones N`: N drones, each pose @100 + 320x240 @10,
through the node with the default mapping, with the previous default (camera frames converted per pose,
camera_pose eager; pose_path.PREVIOUS) and with the previous receive path as well, next to the forwarder.
`--probe-malloc`: the bridge and the forwarder only, each session read in turn by the probe with its
malloc thresholds fixed (the bench's) and with glibc's (probe.py). Prints CPU, minor page faults per image
frame (the bridge's, the probe's), RSS, the slowest pose rate and the worst pose p99 (the mean over rounds,
then each round's).

    python -m tools.bench.variants [--rounds 2] [--duration 8] [--width 1920 --height 1080] [--drones N]
        [--probe-malloc]
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path
from typing import Any

from tools.bench import scenes, tables
from tools.bench.e2e import Bench, rotated
from tools.bench.pose_path import PREVIOUS
from tools.bench.probe import DEFAULT_MALLOC, MALLOC_CHOICES

VARIANTS: dict[str, tuple[str, ...]] = {
    "bridge": (),
    "bridge, glibc malloc thresholds": ("--malloc", "glibc"),
    "bridge, pynng recv (copies)": ("--receive", "copy"),
    "bridge, both (the previous receive path)": ("--malloc", "glibc", "--receive", "copy"),
}


def figures(result: dict[str, Any], role: str) -> dict[str, float]:
    topics = result["topics"]
    images = [t for name, t in topics.items() if name.endswith("/image")]
    poses = [t for name, t in topics.items() if name.endswith("actual_pose")]
    image_hz = sum(t["rate_hz"] for t in images)
    per_frame = 1 / max(image_hz, 1e-9)  # seconds per image frame
    return {
        "cpu": result[f"{role}_cpu_cores"],
        "faults_per_frame": result[f"{role}_minor_faults_per_s"] * per_frame,
        "probe_faults_per_frame": result["probe_minor_faults"] / result["seconds"] * per_frame,
        "rss": result[f"{role}_rss_mb"],
        "image_hz": image_hz / len(images),
        "pose_hz": min(t["rate_hz"] for t in poses),
        "pose_p99": max(t.get("latency_p99_ms", float("nan")) for t in poses),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--duration", type=float, default=8.0)
    parser.add_argument("--width", type=int, default=1920)
    parser.add_argument("--height", type=int, default=1080)
    parser.add_argument("--drones", type=int, default=0, help="the pose case: N drones instead")
    parser.add_argument(
        "--probe-malloc", action="store_true", help="the bridge and the forwarder through both probes"
    )
    args = parser.parse_args(argv)
    bench = Bench(Path(tempfile.mkdtemp(prefix="airsim_mapper_variants_")), duration_s=args.duration)
    load_start = os.getloadavg()[0]
    variants = dict(VARIANTS)
    if args.drones:
        previous = bench.config_dir / "previous.yaml"
        previous.parent.mkdir(parents=True, exist_ok=True)
        previous.write_text(PREVIOUS)
        variants = {
            "bridge": (),
            "bridge, previous default mapping": ("--mapping", str(previous)),
            "bridge, previous mapping and receive path": (
                ("--mapping", str(previous), "--malloc", "glibc", "--receive", "copy")
            ),
        }
    probes: tuple[str, ...] = (DEFAULT_MALLOC,)
    if args.probe_malloc:
        variants, probes = {"bridge": ()}, MALLOC_CHOICES

    def label(name: str, probe: str) -> str:
        return f"{name}, probe malloc {probe}" if args.probe_malloc else name

    sides = [*variants, "bare forwarder"]
    rows: dict[str, list[dict[str, float]]] = {label(n, p): [] for n in sides for p in probes}
    drones = args.drones or 1
    topics = [t for i in range(1, drones + 1) for t in (scenes.image_topic(i), scenes.pose_topic(i))]
    try:
        if args.drones:
            camera = scenes.CameraSetup(320, 240, 0.1, (0,))
        else:
            camera = scenes.CameraSetup(args.width, args.height, 1 / 30, (0,))
        scene = bench.scene("variants", drones, camera)
        for n in range(args.rounds):
            for name in sides:
                if name == "bare forwarder":
                    session_of, role = bench.forwarder_session(scene, camera=True), "forwarder"
                else:
                    session_of, role = bench.bridge_session(scene, node_args=variants[name]), "bridge"
                with session_of as session:
                    for probe in rotated(probes, n):
                        result = session.probe(role, topics, malloc=probe)
                        rows[label(name, probe)].append(figures(result, role))
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
                f"{mean('probe_faults_per_frame'):.0f}",
                f"{mean('rss'):.0f}",
                f"{mean('image_hz'):.1f}",
                f"{mean('pose_hz'):.1f}",
                f"{mean('pose_p99'):.2f}",
                " ".join(f"{r['cpu']:.3f}" for r in runs),
                " ".join(f"{r['pose_p99']:.2f}" for r in runs),
            ]
        )
    header = [
        "variant",
        "CPU cores",
        "faults/frame",
        "probe faults/frame",
        "RSS MB",
        "image Hz",
        "pose Hz min",
        "pose p99 max",
        "CPU runs",
        "pose p99 runs",
    ]
    print(tables.table(header, body))
    case = f"{drones} drones, 320x240 @10" if args.drones else f"{args.width}x{args.height} @30"
    print(f"{case}; load average {load_start:.1f} at start, {os.getloadavg()[0]:.1f} at end")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
