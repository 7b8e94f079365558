"""The benchmark's tables: converter costs, end-to-end figures, the bridge beside the bare forwarder, the
interleaved rounds and the targets (pure functions of the results)."""

from __future__ import annotations

from typing import Any

from tools.bench.results import (
    FLOOR_ROWS,
    judged_rounds,
    kind,
    latency_rounds,
    of_kind,
    p99_ratio,
    pairs,
    per_message_cpu_ms,
    ratio,
    topic,
    worst_pose,
)


def table(header: list[str], rows: list[list[str]]) -> str:
    """Columns aligned: the first to the left, the others to the right."""
    widths = [max(len(str(cell)) for cell in column) for column in zip(header, *rows)]

    def line(cells: list) -> str:
        return "  ".join(
            str(c).rjust(w) if i else str(c).ljust(w) for i, (c, w) in enumerate(zip(cells, widths))
        )

    return "\n".join([line(header), line(["-" * w for w in widths]), *(line(r) for r in rows)])


def ms(value: float | None) -> str:
    """A figure in ms to two decimals ("-" for none)."""
    return "-" if value is None else f"{value:.2f}"


def times(value: float | None) -> str:
    """A ratio as "1.25x" ("-" for none)."""
    return "-" if value is None else f"{value:.2f}x"


def costs_table(costs: dict[str, dict[str, Any]]) -> str:
    header = [
        "per message, frame bytes -> serialised ROS msg (CPU ms)",
        "bridge",
        "one buffer",
        "client path",
        "reference",
        "x faster",
        "bare serialise",
        "bridge/bare",
        "unpack client",
        "unpack fast",
    ]
    rows = []
    for name, c in costs.items():
        ref = c.get("reference_ms")
        ref_text = "-" if ref is None else f"{ref:.1f}" + ("*" if c.get("reference_extrapolated") else "")
        rows.append(
            [
                name,
                ms(c.get("bridge_ms")) if "bridge_error" not in c else "error",
                ms(c.get("one_buffer_ms")),
                ms(c.get("client_path_ms")),
                ref_text,
                f"{c['speedup_vs_reference']:.0f}x" if "speedup_vs_reference" in c else "-",
                ms(c.get("bare_serialize_ms")),
                f"{c['ratio_to_bare_serialize']:.2f}" if "ratio_to_bare_serialize" in c else "-",
                ms(c.get("unpack_client_ms")),
                ms(c.get("unpack_fast_ms")),
            ]
        )
    notes = [
        "* measured at 320x240 and scaled by the pixel count (the per-pixel loop takes seconds at 1080p)"
    ]
    notes += [f"error in {name}: {c['bridge_error']}" for name, c in costs.items() if "bridge_error" in c]
    return table(header, rows) + "\n" + "\n".join(notes)


def waiting_row(result: dict[str, Any]) -> list[str]:
    """The end-to-end table's row for the node waiting for a scene (`Bench.waiting_node`): no messages, its
    CPU to a thousandth of a core."""
    cores, rss = result["bridge_cpu_cores"], result["bridge_rss_mb"]
    return ["bridge waiting for a scene", "-", "-", "-", f"{cores:.3f} (bridge)", "-", f"{rss:.0f}"]


def e2e_table(e2e: dict[str, Any]) -> str:
    header = [
        "end to end (separate processes)",
        "rate Hz",
        "p50 ms",
        "p99 ms",
        "CPU cores",
        "CPU ms/msg",
        "RSS MB",
    ]
    rows = []

    def add(label: str, result: dict[str, Any], cpu_key: str, topic_name: str | None = None) -> None:
        t = topic(result, topic_name)
        cores = result.get(f"{cpu_key}_cpu_cores", 0.0)
        rows.append(
            [
                label,
                f"{t['rate_hz']:.1f}",
                ms(t.get("latency_p50_ms")),
                ms(t.get("latency_p99_ms")),
                f"{cores:.2f} ({cpu_key})",
                ms(per_message_cpu_ms(cores, t["rate_hz"])),
                f"{result.get(f'{cpu_key}_rss_mb', 0):.0f}" if f"{cpu_key}_rss_mb" in result else "-",
            ]
        )

    base = e2e["baselines"]
    add("raw rospy Image 1080p @30", base["rospy_image"], "publisher")
    add("raw pynng 1080p frame @30", base["pynng_image"], "receiver")
    camera_topics = list(e2e["bridge"]["camera"]["topics"])
    add("bridge camera 1080p @30", e2e["bridge"]["camera"], "bridge", camera_topics[0])
    add("bridge depth 1080p @30", e2e["bridge"]["depth"], "bridge")
    add("raw rospy PointCloud2 100k @20", base["rospy_cloud"], "publisher")
    add("raw pynng 100k scan @20", base["pynng_cloud"], "receiver")
    add("bridge lidar 100k @20", e2e["bridge"]["lidar"], "bridge")
    add("  (msgpack decoding, as the bare client)", e2e["bridge"]["lidar_client_path"], "bridge")
    add("bridge pose @100, idle", e2e["pose"]["idle"], "bridge")
    if "idle_without_camera_frames" in e2e["pose"]:
        add("  (mapping without the camera frames)", e2e["pose"]["idle_without_camera_frames"], "bridge")
    if "waiting" in e2e["pose"]:
        rows.append(waiting_row(e2e["pose"]["waiting"]))
    add("bridge pose @100, 1080p camera @30", e2e["bridge"]["camera"], "bridge", camera_topics[1])
    apart = e2e["bridge"].get("camera_apart")
    for name in apart["topics"] if apart else ():
        add(f"  (images read apart: {kind(name)})", apart, "bridge", name)
    for key, label in (("camera_load", "node"), ("camera_load_mission", "mission script")):
        load = e2e["pose"].get(key)
        if load is None:
            continue
        names = list(load["topics"])
        add(f"{label}: pose @100, 1080p camera @60 load", load, "bridge", names[0])
        add("  (the load: camera 1080p @60)", load, "bridge", names[1])
    floor = e2e.get("forwarder", {})
    for key, label in FLOOR_ROWS:
        if key in floor and key != "scale":  # the ten drones' floor is in the table below
            for name in floor[key]["topics"]:
                add(f"bare forwarder: {label}, {kind(name)}", floor[key], "forwarder", name)
    text = table(header, rows)
    scale_rows = []
    for drones, result in e2e["scale"].items():
        topics = result["topics"]
        pose = [v["rate_hz"] for k, v in topics.items() if k.endswith("actual_pose")]
        image = [v["rate_hz"] for k, v in topics.items() if k.endswith("/image")]
        cores = result["bridge_cpu_cores"]
        scale_rows.append(
            [
                drones,
                f"{min(pose):.1f} / {sum(pose) / len(pose):.1f}",
                f"{min(image):.1f} / {sum(image) / len(image):.1f}",
                f"{cores:.2f}",
                f"{cores / int(drones):.3f}",
                f"{result['bridge_rss_mb']:.0f}",
                f"{result['server_cpu_cores']:.2f}",
            ]
        )
    scale = table(
        [
            "drones (pose @100 + 320x240 camera @10 each)",
            "pose Hz min/mean",
            "image Hz min/mean",
            "bridge cores",
            "cores/drone",
            "bridge RSS MB",
            "server cores",
        ],
        scale_rows,
    )
    return text + "\n\n" + scale + ("\n\n" + floor_table(e2e) + rounds_table(e2e) if floor else "")


def floor_table(e2e: dict[str, Any], title: str = "bridge / bare forwarder (same frames, same run)") -> str:
    """Each case through the bridge and through the bare forwarder, in the same run, and their ratios."""
    rows = []
    for _key, label, ours, floor in pairs(e2e):
        cores, floor_cores = ours["bridge_cpu_cores"], floor["forwarder_cpu_cores"]
        (rate, p99), (floor_rate, floor_p99) = worst_pose(ours), worst_pose(floor)
        rows.append(
            [
                label,
                f"{cores:.3f} / {floor_cores:.3f}",
                times(ratio(cores, floor_cores)),
                f"{rate:.0f} / {floor_rate:.0f}",
                f"{ms(p99)} / {ms(floor_p99)}",
                times(ratio(p99, floor_p99)),
                f"{ours.get('bridge_minor_faults_per_s', 0):.0f} / "
                f"{floor.get('forwarder_minor_faults_per_s', 0):.0f}",
            ]
        )
    return table(
        [
            title,
            "CPU cores",
            "CPU ratio",
            "pose Hz (slowest)",
            "pose p99 ms (worst)",
            "p99 ratio",
            "minor faults/s",
        ],
        rows,
    )


ROUND_ROWS = (
    ("pose_idle", "pose @100"),
    ("camera", "1080p camera @30 + pose"),
    ("camera_load", "1080p camera @60 + pose"),
    ("scale", "10 drones"),
)


def rounds_table(e2e: dict[str, Any]) -> str:
    """Each round of the cases whose targets are judged on the median of interleaved rounds (empty with
    one round)."""
    rows = []
    for key, label in ROUND_ROWS:
        rounds = latency_rounds(e2e, key)
        kept = judged_rounds(rounds)
        for n, r in enumerate(rounds if len(rounds) > 1 else (), 1):
            ours, floor = r["bridge"], r["forwarder"]
            received = ms(worst_pose(r["receive_floor"])[1]) if "receive_floor" in r else "-"
            stolen = " / ".join(_stolen(r.get(role)) for role in ("bridge", "forwarder", "receive_floor"))
            rows.append(
                [
                    f"{label}, round {n}{'' if any(r is k for k in kept) else ' (left out)'}",
                    f"{ms(worst_pose(ours)[1])} / {ms(worst_pose(floor)[1])} / {received}",
                    times(p99_ratio(ours, floor)),
                    f"{ours['bridge_cpu_cores']:.3f} / {floor['forwarder_cpu_cores']:.3f}",
                    stolen,
                ]
            )
    if not rows:
        return ""
    header = [
        "interleaved rounds (latency targets, pose only's and ten drones' CPU: the median of the quiet ones)",
        "pose p99 ms: bridge / forwarder / receive loop",
        "p99 ratio",
        "CPU cores: bridge / forwarder",
        "CPU time stolen %",
    ]
    return "\n\n" + table(header, rows)


def ros2_table(e2e: dict[str, Any]) -> str:
    """The ROS 2 rows (`run_e2e_ros2`'s results): each case through the node in .venv-ros2 and through the
    bare rclpy forwarder, their ratios, the images each delivered to the probe, and every round."""
    images = [
        [
            label,
            " / ".join(_slowest_image(result) for result in (ours, floor)),
            " / ".join(_image_latency(result) for result in (ours, floor)),
        ]
        for _key, label, ours, floor in pairs(e2e)
        if of_kind(ours, "image")
    ]
    header = ["ROS 2 images delivered (best effort)", "Hz (slowest): bridge / forwarder", "p50 ms (largest)"]
    title = "ROS 2: bridge / bare rclpy forwarder (same frames, same run)"
    return floor_table(e2e, title) + "\n\n" + table(header, images) + rounds_table(e2e)


def _slowest_image(result: dict[str, Any]) -> str:
    return f"{min(t['rate_hz'] for t in of_kind(result, 'image')):.1f}"


def _image_latency(result: dict[str, Any]) -> str:
    """The image topics' largest p50 latency, in ms ("-" when none delivered in the window)."""
    known = [t["latency_p50_ms"] for t in of_kind(result, "image") if "latency_p50_ms" in t]
    return ms(max(known) if known else None)


def _stolen(result: dict[str, Any] | None) -> str:
    """The share of the machine's CPU time a hypervisor took during one measurement window, in %."""
    share = (result or {}).get("host_stolen_share")
    return "-" if share is None else f"{100 * share:.1f}"


def targets_table(rows: list[dict[str, Any]]) -> str:
    body = []
    for r in rows:
        value = "-" if r["value"] is None else f"{r['value']:.2f} {r['unit']}".strip()
        verdict = {True: "met", False: "MISSED", None: "n/a"}[r["met"]]
        body.append([r["target"], value, f"{r['limit']:g} {r['unit']}".strip(), verdict, r["note"]])
    return table(["target", "measured", "limit", "", "note"], body)
