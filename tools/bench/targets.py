"""The benchmark's targets, each judged against its limit on the measured results (pure functions)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from statistics import median
from typing import Any

from tools import camera_probe
from tools.bench import encoders, renderers, transports
from tools.bench.results import (
    BGR,
    DEPTH,
    LIDAR,
    frame_cpu_ms,
    judged_rounds,
    latency_rounds,
    median_of,
    median_worst_p99,
    of_kind,
    p99_ratio,
    pairs,
    per_message_cpu_ms,
    ratio,
    round_medians,
    topic,
    worst_pose,
)
from tools.bench.tables import ms, times

CAMERA_HZ = 30.0
POSE_HZ = 100.0
SCALE_CAMERA_HZ = 10.0
SCALE_POSE_P99_MS = 4.0  # the ten drones' worst pose p99 target
SCALE_CORES = 0.25  # the ten drones' CPU target
CAMERA_P99_RATIO = 0.8  # pose p99 under a 1080p camera @30 over the bare forwarder's
JPEG_LIBRARY_RATIO = 1.2  # the JPEG converter's CPU per frame over the library's own encode
ROS2_CPU_RATIO = 1.2  # the ROS 2 node's CPU over the bare rclpy forwarder's, each case
ROS2_P99_RATIO = 1.0  # the ROS 2 node's pose p99 under a 1080p camera @30 over the rclpy forwarder's
ROS2_CPU_CASES = (("pose_idle", "pose only"), ("camera_720p", "720p camera @30 + pose"))
ROS2_CPU_CASES += (("camera", "1080p camera @30 + pose"), ("scale", "10 drones"))


@dataclass(frozen=True)
class CostLimit:
    """A converter cost target: one figure of one cost case against its limit (at most, or `at_least`)."""

    target: str
    case: str
    figure: str
    limit: float
    unit: str
    at_least: bool = False
    note: str = ""


COST_LIMITS = (
    CostLimit("100k-point scan, frame bytes -> PointCloud2, CPU", LIDAR, "bridge_ms", 5.0, "ms"),
    CostLimit("100k-point scan, speed-up over the reference", LIDAR, "speedup_vs_reference", 10.0, "x", True),
    CostLimit("1080p depth, frame bytes -> Image, CPU", DEPTH, "bridge_ms", 10.0, "ms"),
    CostLimit(
        "1080p BGR bridge CPU / bare rospy serialisation of the same bytes",
        BGR,
        "ratio_to_bare_serialize",
        1.2,
        "x",
        note="pixels stay a view of the received frame and are written once, by BufferImage's serialiser",
    ),
)


def floor_targets(e2e: dict[str, Any]) -> list[dict[str, Any]]:
    """The targets against the bare forwarder, for the cases measured through both."""
    both = {key: (ours, floor) for key, _label, ours, floor in pairs(e2e)}
    out: list[dict[str, Any]] = []
    if "pose_idle" in both:
        every = latency_rounds(e2e, "pose_idle")
        rounds = judged_rounds(every)
        ratios = [_pose_cpu_ratio(r["bridge"], r["forwarder"]) for r in rounds]
        note = _rounds_note(ratios, times, None, len(every) - len(rounds))
        raw = [_pose_cpu_ratio(r["bridge"], r["forwarder"], per_probe=False) for r in rounds]
        if raw != ratios:
            note += "; each node's CPU over its probe's in the same window (raw: "
            note += ", ".join(times(value) for value in raw) + ")"
        out.append(
            _limit("pose only: bridge CPU per pose / the forwarder's", median_of(ratios), 1.3, "x", note)
        )
    if "camera" in both and "pose_idle" in both:
        (ours, floor), (ours_idle, floor_idle) = both["camera"], both["pose_idle"]
        ours_ms = frame_cpu_ms(ours, ours_idle, "bridge")
        floor_ms = frame_cpu_ms(floor, floor_idle, "forwarder")
        note = f"bridge {ms(ours_ms)} ms, forwarder {ms(floor_ms)} ms (above each one's pose-only CPU)"
        out.append(
            _limit(
                "1080p frame: bridge CPU per frame / the forwarder's",
                ratio(ours_ms, floor_ms),
                1.2,
                "x",
                note,
            )
        )
    for key, label in (("camera", "1080p camera @30 + pose"), ("camera_720p", "720p camera @30 + pose")):
        if key in both:
            ours, floor = both[key]
            cpu = ratio(ours["bridge_cpu_cores"], floor["forwarder_cpu_cores"])
            out.append(_limit(f"{label}: bridge CPU / the forwarder's", cpu, 1.2, "x"))
    if "camera" in both:
        every = latency_rounds(e2e, "camera")
        rounds = judged_rounds(every)
        note = _p99_note(*both["camera"], every[0].get("receive_floor"))
        if "camera_apart" in both:  # a figure beside the target, which stays judged on the one probe
            apart = both["camera_apart"]
            note += f"; images read apart: {times(p99_ratio(*apart))}, {_p99_note(*apart)}"
        name = "pose p99 under a 1080p camera @30 / the forwarder's"
        out.append(_p99_ratio_target(name, rounds, len(every) - len(rounds), CAMERA_P99_RATIO, note))
    if "camera_load" in both:
        every = latency_rounds(e2e, "camera_load")
        rounds = judged_rounds(every)
        left_out = len(every) - len(rounds)
        rates = [worst_pose(r["bridge"])[0] for r in rounds]
        rate = median(rates)
        note = _rounds_note(rates, lambda r: f"{r:.1f} Hz", None, left_out)
        out.append(_least("pose rate under a 1080p camera @60", rate, 98.0, "Hz", note))
        name = "pose p99 under a 1080p camera @60 / the forwarder's"
        out.append(_p99_ratio_target(name, rounds, left_out, 1.0, _p99_note(*both["camera_load"])))
    if "scale" in both:
        every = latency_rounds(e2e, "scale")
        rounds = judged_rounds(every)
        left_out = len(every) - len(rounds)
        drones = len(of_kind(rounds[0]["bridge"], "pose"))
        cores = [r["bridge"]["bridge_cpu_cores"] for r in rounds]
        note = _rounds_note(cores, lambda c: f"{c:.3f}", "their medians: ", left_out) + _cpu_note(
            *round_medians(rounds)
        )
        out.append(_limit(f"{drones} drones: bridge CPU", median_of(cores), SCALE_CORES, "cores", note))
        p99s = [worst_pose(r["bridge"])[1] for r in rounds]
        note = _rounds_note(p99s, lambda p: f"{ms(p)} ms", left_out=left_out)
        note += _p99_note(*both["scale"], every[0].get("receive_floor"))
        out.append(_limit(f"{drones} drones: worst pose p99", median_of(p99s), SCALE_POSE_P99_MS, "ms", note))
    return out


def _p99_ratio_target(
    name: str, rounds: list[dict[str, Any]], left_out: int, limit: float, note: str
) -> dict[str, Any]:
    """The bridge's worst pose p99 over the forwarder's: the median over the judged rounds, each round's
    figure in the note before `note`."""
    ratios = [p99_ratio(r["bridge"], r["forwarder"]) for r in rounds]
    return _limit(name, median_of(ratios), limit, "x", _rounds_note(ratios, times, left_out=left_out) + note)


def _pose_cpu_ratio(ours: dict[str, Any], floor: dict[str, Any], per_probe: bool = True) -> float | None:
    """The bridge's CPU per pose message over the forwarder's.

    With `per_probe`, where both windows have their probe's CPU, each node's CPU is taken over its probe's:
    the probe reads the same messages at the same rate from either node, so its CPU follows only how fast
    the host ran during that window, which moves small CPU figures between windows far more than anything
    the nodes do differently (docs/performance.md, "Reading the figures")."""
    probes = ours.get("probe_cpu_cores"), floor.get("probe_cpu_cores")
    if per_probe and all(probes):
        return ratio(ours["bridge_cpu_cores"] / probes[0], floor["forwarder_cpu_cores"] / probes[1])
    return ratio(
        per_message_cpu_ms(ours["bridge_cpu_cores"], worst_pose(ours)[0]),
        per_message_cpu_ms(floor["forwarder_cpu_cores"], worst_pose(floor)[0]),
    )


def _rounds_note(
    values: list[float | None],
    show: Callable[[float], str],
    then: str | None = "round 1: ",
    left_out: int = 0,
) -> str:
    """Each judged round's value as `show` writes it ("-" where a round gave none) and how many rounds were
    left out as not quiet, before the note that follows (`then` names what it shows; None: no note
    follows), when there was more than one round."""
    if len(values) + left_out < 2:
        return ""
    known = sum(value is not None for value in values)
    figures = ", ".join("-" if value is None else show(value) for value in values)
    rounds = f"median of {known} interleaved {'round' if known == 1 else 'rounds'} ({figures})"
    if left_out:
        rounds += f", {left_out} more left out for CPU time stolen in a window"
    return rounds if then is None else f"{rounds}; {then}"


def _p99_note(ours: dict[str, Any], floor: dict[str, Any], received: dict[str, Any] | None = None) -> str:
    """The worst pose p99 of the bridge, the bare forwarder and, if measured, the receive floor."""
    note = f"bridge {ms(worst_pose(ours)[1])} ms, bare forwarder {ms(worst_pose(floor)[1])} ms"
    if received:
        note += f"; the bridge's receive loop alone, no ROS: {ms(worst_pose(received)[1])} ms"
    return note


def _cpu_note(floor: dict[str, Any], received: dict[str, Any] | None = None) -> str:
    """The CPU of the bare forwarder and, if measured, of the receive loop alone on the same frames: an
    absolute target read beside what the transport alone took on this host in this run."""
    note = f"bare forwarder {floor['forwarder_cpu_cores']:.3f} cores"
    if received:
        note += f"; the bridge's receive loop alone, no ROS: {received['receiver_cpu_cores']:.3f} cores"
    return note


def _limit(name: str, value: float | None, limit: float, unit: str, note: str = "") -> dict[str, Any]:
    """A target met when `value` is at most `limit` (not applicable without a value)."""
    return _target(name, value, limit, None if value is None else value <= limit, unit, note)


def _least(name: str, value: float | None, limit: float, unit: str, note: str = "") -> dict[str, Any]:
    """A target met when `value` is at least `limit` (not applicable without a value)."""
    return _target(name, value, limit, None if value is None else value >= limit, unit, note)


def _target(
    name: str, value: float | None, limit: float, met: bool | None, unit: str, note: str = ""
) -> dict[str, Any]:
    return {"target": name, "value": value, "limit": limit, "unit": unit, "met": met, "note": note}


def transport_targets(results: dict[str, Any]) -> list[dict[str, Any]]:
    """image_transport's targets: the JPEG converter against the library's own encode of the same frame,
    and, end to end, the compressed topics' rates and the pose p99 with a `/compressed` subscriber over the
    bare forwarder's under the same camera (the pose p99 target of the raw camera at 30 Hz)."""
    out: list[dict[str, Any]] = []
    encoded = results.get("encoders")
    if encoded:
        jpeg = encoded[encoders.JPEG]
        wire = ", ".join(f"{name} {row['wire_bytes']}" for name, row in encoded.items())
        note = f"converter {ms(jpeg['converter_ms'])} ms, library {ms(jpeg['library_ms'])} ms; "
        note += f"bytes on the wire: {wire}"
        name = "1080p JPEG encode CPU per frame / the library's own encode of the same frame"
        out.append(_limit(name, jpeg.get("ratio"), JPEG_LIBRARY_RATIO, "x", note))
    e2e = results.get("e2e") or {}
    windows = e2e.get("transports")
    if not windows:
        return out
    jpeg_window, depth_window = windows["compressed"], windows["compressed_depth"]
    jpeg_topic = topic(jpeg_window, transports.compressed_topic())
    depth_topic = topic(depth_window, transports.depth_topic())
    note = f"{jpeg_topic.get('message_bytes', '-')} bytes/msg"
    out.append(
        _least(
            "1080p @30 BGR with a /compressed subscriber delivered",
            jpeg_topic["rate_hz"],
            transports.JPEG_MIN_HZ,
            "Hz",
            note,
        )
    )
    note = f"{depth_topic['rate_hz']:.1f} Hz, {depth_topic.get('message_bytes', '-')} bytes/msg"
    out.append(
        _least(
            "1080p @30 depth with a /compressedDepth subscriber delivered",
            depth_topic["rate_hz"],
            transports.DEPTH_MIN_HZ,
            "Hz",
            note,
        )
    )
    # the forwarder's p99 under the raw camera: the median over that case's judged rounds, as it is judged
    floor, known = median_worst_p99(judged_rounds(latency_rounds(e2e, "camera")), "forwarder")
    if floor:
        ours = worst_pose(jpeg_window)[1]
        name = "pose p99 under a 1080p camera @30 with a /compressed subscriber / the forwarder's"
        note = f"bridge {ms(ours)} ms, bare forwarder {ms(floor)} ms"
        note += f" (the median of its {known} rounds under the raw camera)" if known > 1 else ""
        out.append(_limit(name, ratio(ours, floor), CAMERA_P99_RATIO, "x", note))
    return out


def cost_targets(costs: dict[str, dict[str, Any]]) -> list[dict[str, Any]]:
    """The converter costs against COST_LIMITS."""
    judge = {False: _limit, True: _least}
    return [
        judge[c.at_least](c.target, costs[c.case][c.figure], c.limit, c.unit, c.note) for c in COST_LIMITS
    ]


def ros2_targets(e2e: dict[str, Any]) -> list[dict[str, Any]]:
    """The ROS 2 rows' targets (`run_e2e_ros2`'s results), each against the bare rclpy forwarder in the same
    run, on the median of a case's quiet rounds where it had rounds: the node's CPU per case (pose only's
    over each one's probe, as on ROS1), the pose p99 under the 1080p camera, and the ten drones' slowest
    pose delivered."""
    both = {key: (ours, floor) for key, _label, ours, floor in pairs(e2e)}
    out: list[dict[str, Any]] = []
    for key, label in ROS2_CPU_CASES:
        if key not in both:
            continue
        every = latency_rounds(e2e, key)
        rounds = judged_rounds(every)
        per_probe = key == "pose_idle"
        cores = [(r["bridge"]["bridge_cpu_cores"], r["forwarder"]["forwarder_cpu_cores"]) for r in rounds]
        ratios = [ratio(*pair) for pair in cores]
        if per_probe:
            ratios = [_pose_cpu_ratio(r["bridge"], r["forwarder"]) for r in rounds]
        note = _rounds_note(ratios, times, "cores: ", len(every) - len(rounds))
        note += ", ".join(f"{ours:.3f} / {floor:.3f}" for ours, floor in cores)
        note += " (each over its probe's CPU in the window)" if per_probe else ""
        name = f"ROS 2 {label}: bridge CPU / the rclpy forwarder's"
        out.append(_limit(name, median_of(ratios), ROS2_CPU_RATIO, "x", note))
    if "camera" in both:
        every = latency_rounds(e2e, "camera")
        rounds = judged_rounds(every)
        name = "ROS 2 pose p99 under a 1080p camera @30 / the rclpy forwarder's"
        note = _p99_note(*both["camera"])
        out.append(_p99_ratio_target(name, rounds, len(every) - len(rounds), ROS2_P99_RATIO, note))
    if "scale" in both:
        every = latency_rounds(e2e, "scale")
        rounds = judged_rounds(every)
        rates = [worst_pose(r["bridge"])[0] for r in rounds]
        cameras = [min(t["rate_hz"] for t in of_kind(r["bridge"], "image")) for r in rounds]
        note = _rounds_note(rates, lambda r: f"{r:.1f} Hz", None, len(every) - len(rounds))
        note += f"; slowest camera {median(cameras):.1f} Hz, the forwarder's slowest pose "
        note += f"{median(worst_pose(r['forwarder'])[0] for r in rounds):.1f} Hz"
        drones = len(of_kind(rounds[0]["bridge"], "pose"))
        name = f"ROS 2 {drones} drones: slowest pose delivered"
        out.append(_least(name, median(rates), 0.9 * POSE_HZ, "Hz", note.lstrip("; ")))
    return out


def targets(results: dict[str, Any]) -> list[dict[str, Any]]:
    """Every target with the measured value, the limit and whether it is met (those of the rows a run
    measured)."""
    return ros1_targets(results) + ros2_targets(results.get("e2e_ros2") or {})


def ros1_targets(results: dict[str, Any]) -> list[dict[str, Any]]:
    """The targets of the converter costs, the renderers and the ROS1 rows."""
    out = cost_targets(results["costs"]) if "costs" in results else []
    out += transport_targets(results)
    if "renderers" in results:
        for name, value, limit in renderers.targets(results["renderers"]):
            out.append(_least(name, value, limit, "/s", "headless server, OpenGL on llvmpipe"))
    server_camera = results.get("server_camera")
    if server_camera:
        out.append(
            _least(
                "camera 1280x720, all seven types, delivered by the server",
                server_camera["delivered_min_hz"],
                camera_probe.TARGET_HZ * 0.95,
                "Hz",
                "render worker + topics channel (tools/camera_probe.py)",
            )
        )
    e2e = results.get("e2e")
    if not e2e:
        return out
    base, bridge = e2e["baselines"], e2e["bridge"]
    camera = topic(bridge["camera"], next(k for k in bridge["camera"]["topics"] if k.endswith("/image")))
    floor = topic(base["pynng_image"])["latency_p50_ms"] + topic(base["rospy_image"])["latency_p50_ms"]
    out.append(_least("1080p camera delivered end to end", camera["rate_hz"], CAMERA_HZ * 0.95, "Hz"))
    p50 = camera["latency_p50_ms"] / floor
    out.append(_limit("1080p camera p50 / (raw pynng p50 + raw rospy p50)", p50, 1.3, "x"))
    bridge_ms = per_message_cpu_ms(
        bridge["camera"]["bridge_cpu_cores"] - e2e["pose"]["idle"]["bridge_cpu_cores"], camera["rate_hz"]
    )
    pub = topic(base["rospy_image"])
    pub_ms = per_message_cpu_ms(base["rospy_image"]["publisher_cpu_cores"], pub["rate_hz"])
    received = topic(base["pynng_image"])
    receive_ms = per_message_cpu_ms(base["pynng_image"]["receiver_cpu_cores"], received["rate_hz"])
    if bridge_ms is not None and pub_ms and receive_ms:
        # The bridge receives each frame and publishes it: the floor is the raw transports doing both.
        out.append(
            _limit(
                "1080p BGR bridge CPU per frame (above idle) / raw pynng receive + raw rospy publish",
                bridge_ms / (receive_ms + pub_ms),
                1.2,
                "x",
                f"bridge {bridge_ms:.1f} ms, receive {receive_ms:.1f} + publish {pub_ms:.1f} ms "
                f"(the publisher alone: {bridge_ms / pub_ms:.2f}x)",
            )
        )
    pose_idle = topic(e2e["pose"]["idle"])
    loads = [
        ("30 Hz (nominal)", latency_rounds(e2e, "camera"), bridge["camera"]),
        ("60 Hz (saturating)", latency_rounds(e2e, "camera_load"), e2e["pose"]["camera_load"]),
    ]
    if "camera_load_mission" in e2e["pose"]:
        loads.append(("60 Hz (saturating), mission script", [], e2e["pose"]["camera_load_mission"]))
    for label, every, result in loads:  # the node's, on the median of its quiet rounds where it had rounds
        rounds = judged_rounds(every)
        runs = [r["bridge"] for r in rounds] or [result]
        p99s = [worst_pose(run)[1] for run in runs]
        out.append(
            _limit(
                f"pose p99 under 1080p camera load at {label}",
                median(p99s),
                10.0,
                "ms",
                _rounds_note(p99s, lambda p: f"{ms(p)} ms", "", len(every) - len(rounds))
                + f"idle p99 {pose_idle['latency_p99_ms']:.1f} ms; "
                f"rate {median(worst_pose(run)[0] for run in runs):.0f} Hz loaded vs "
                f"{pose_idle['rate_hz']:.0f} Hz idle",
            )
        )
    out += floor_targets(e2e)
    scale = e2e["scale"]
    if scale:
        counts = sorted(int(k) for k in scale)
        cores = {n: scale[str(n)]["bridge_cpu_cores"] for n in counts}
        small, large = counts[0], counts[-1]
        mid = counts[len(counts) // 2]
        slope_low = (cores[mid] - cores[small]) / max(mid - small, 1)
        slope_high = (cores[large] - cores[mid]) / max(large - mid, 1)
        growth = slope_high / slope_low if slope_low > 0 else None
        out.append(
            _limit(
                f"bridge CPU growth per drone, {mid}->{large} vs {small}->{mid} drones",
                growth,
                1.25,
                "x",
                f"{slope_low:.3f} then {slope_high:.3f} cores per added drone",
            )
        )
        rates = scale[str(large)]["topics"]
        slowest_pose = min(v["rate_hz"] for k, v in rates.items() if k.endswith("actual_pose"))
        slowest_image = min(v["rate_hz"] for k, v in rates.items() if k.endswith("/image"))
        sustained = slowest_pose >= 0.9 * POSE_HZ and slowest_image >= 0.9 * SCALE_CAMERA_HZ
        out.append(
            _target(
                f"{large} drones sustained (every pose >= 90 Hz, every camera >= 9 Hz)",
                None,
                0.9,
                sustained,
                "",
                f"slowest pose {slowest_pose:.1f} Hz, slowest camera {slowest_image:.1f} Hz",
            )
        )
    return out
