"""Reading a `make bench` results dict (out/bench.json): its keys, the figures the tables and the targets
take from it, and the interleaved rounds a latency target is judged on (pure functions)."""

from __future__ import annotations

from statistics import median
from typing import Any

from tools.bench.sampling import QUIET_STOLEN_SHARE

# The converter cost cases (tools/bench/costs.py), the keys of results["costs"].
BGR = "image 1920x1080 BGR"
DEPTH = "depth 1920x1080 (16FC1, 1.1.0 server)"
DEPTH_FLOAT = "depth 1920x1080 (32FC1 data_float, git server)"
LIDAR = "lidar 100k points"
RADAR = "radar 200 detections"
# The bare forwarder's sessions (tools/bench/forwarder.py) and what they carry.
FLOOR_ROWS = (
    ("pose_idle", "pose @100"),
    ("camera", "1080p camera @30 + pose"),
    ("camera_apart", "1080p camera @30 + pose, images read apart"),
    ("camera_720p", "720p camera @30 + pose"),
    ("camera_load", "1080p camera @60 + pose"),
    ("scale", "10 drones"),
)
# A round of a latency case is quiet when both windows its targets compare (the bridge's, the bare
# forwarder's) were (QUIET_STOLEN_SHARE); a round that was not is left out of the medians and run again.
# The receive loop's window is a reference beside them, not judged.
JUDGED_WINDOWS = ("bridge", "forwarder")


def topic(result: dict[str, Any], name: str | None = None) -> dict[str, Any]:
    topics = result["topics"]
    return topics[name] if name else next(iter(topics.values()))


def per_message_cpu_ms(cores: float, rate_hz: float) -> float | None:
    return cores / rate_hz * 1e3 if rate_hz > 0 else None


def kind(topic_name: str) -> str:
    return "pose" if topic_name.endswith("actual_pose") else "image"


def of_kind(result: dict[str, Any], wanted: str) -> list[dict[str, Any]]:
    return [t for name, t in result["topics"].items() if kind(name) == wanted]


def worst_pose(result: dict[str, Any]) -> tuple[float, float]:
    """(slowest rate Hz, largest p99 ms) over the result's pose topics."""
    poses = of_kind(result, "pose")
    return min(t["rate_hz"] for t in poses), max(t.get("latency_p99_ms", float("inf")) for t in poses)


def ratio(ours: float | None, floor: float | None) -> float | None:
    return None if ours is None or not floor else ours / floor


def p99_ratio(ours: dict[str, Any], floor: dict[str, Any]) -> float | None:
    """The bridge's worst pose p99 over the bare forwarder's."""
    return ratio(worst_pose(ours)[1], worst_pose(floor)[1])


def median_of(values: list[float | None]) -> float | None:
    """The median of the known values (None when there is none)."""
    known = [value for value in values if value is not None]
    return median(known) if known else None


def pairs(e2e: dict[str, Any]) -> list[tuple[str, str, dict[str, Any], dict[str, Any]]]:
    """(key, label, bridge result, forwarder result) for every case measured through both (none in a
    `--costs-only` run)."""
    floor = e2e.get("forwarder", {})
    if not floor:
        return []
    bridge = {
        "pose_idle": e2e["pose"].get("idle"),
        "camera": e2e["bridge"].get("camera"),
        "camera_apart": e2e["bridge"].get("camera_apart"),
        "camera_720p": e2e["bridge"].get("camera_720p"),
        "camera_load": e2e["pose"].get("camera_load"),
        "scale": e2e["scale"].get(max(e2e["scale"], key=int)) if e2e["scale"] else None,
    }
    return [
        (key, label, bridge[key], floor[key])
        for key, label in FLOOR_ROWS
        if key in floor and bridge.get(key) is not None
    ]


def frame_cpu_ms(result: dict[str, Any], idle: dict[str, Any], role: str) -> float | None:
    """CPU ms per image frame above the same process's pose-only CPU."""
    rate = sum(t["rate_hz"] for t in of_kind(result, "image"))
    return per_message_cpu_ms(result[f"{role}_cpu_cores"] - idle[f"{role}_cpu_cores"], rate)


def latency_rounds(e2e: dict[str, Any], key: str) -> list[dict[str, Any]]:
    """Every round of a case measured in interleaved rounds, each {bridge, forwarder[, receive_floor]}: the
    case's main runs, then the bench's further rounds of it."""
    both = {name: (ours, floor) for name, _label, ours, floor in pairs(e2e)}
    if key not in both:
        return []
    first = {"bridge": both[key][0], "forwarder": both[key][1]}
    received = e2e.get("receive_floor", {}).get(key)
    if received:
        first["receive_floor"] = received
    return [first, *e2e.get("rounds", {}).get(key, [])]


def stolen_in_round(round_: dict[str, Any]) -> float:
    """The largest share of the machine's CPU time a hypervisor took in a judged window of a round."""
    windows = [round_[name] for name in JUDGED_WINDOWS if name in round_]
    return max((window.get("host_stolen_share") or 0.0 for window in windows), default=0.0)


def quiet_round(round_: dict[str, Any]) -> bool:
    """Neither the bridge's nor the forwarder's window lost QUIET_STOLEN_SHARE of the CPU time or more."""
    return stolen_in_round(round_) < QUIET_STOLEN_SHARE


def judged_rounds(rounds: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The rounds a latency target is judged on: the quiet ones, or every round when none was quiet."""
    return [r for r in rounds if quiet_round(r)] or rounds


def scale_rounds(e2e: dict[str, Any]) -> list[dict[str, Any]]:
    """The ten drones' judged rounds (every quiet one, or all when none was quiet)."""
    return judged_rounds(latency_rounds(e2e, "scale"))


def round_medians(rounds: list[dict[str, Any]]) -> tuple[dict[str, Any], dict[str, Any] | None]:
    """The forwarder's and the receive loop's CPU as the median over the rounds, each in the shape of one
    run's result."""
    floor = {"forwarder_cpu_cores": median_of([r["forwarder"]["forwarder_cpu_cores"] for r in rounds])}
    received = [r["receive_floor"]["receiver_cpu_cores"] for r in rounds if "receive_floor" in r]
    return floor, ({"receiver_cpu_cores": median_of(received)} if received else None)


def median_worst_p99(rounds: list[dict[str, Any]], role: str) -> tuple[float | None, int]:
    """The median over the rounds of one role's worst pose p99, and how many rounds had that role."""
    p99s = [worst_pose(r[role])[1] for r in rounds if role in r]
    return median_of(p99s), len(p99s)
