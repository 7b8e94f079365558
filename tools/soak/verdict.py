"""The soak's verdict: the bridge process's samples and the pose gaps after warm-up against their limits,
printed with the delivered rates and the bridge's stream counts."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

from tools.soak.gaps import across_events, gap_percentile, largest_gap, own_delays
from tools.soak.probes import Wakes

RSS_LIMIT_MB = 20.0
THREAD_SLACK = 2
FD_SLACK = 4
RELOAD_GRACE_S = 5.0  # after a scene reload or a mapping edit: its gap and samples are reported apart
POSE_GAP_LIMIT_S = 0.100


@dataclass
class Sample:
    t: float
    rss_mb: float
    threads: int
    fds: int = 0


@dataclass
class Verdict:
    failures: list[str] = field(default_factory=list)

    def check(self, ok: bool, message: str) -> None:
        if not ok:
            self.failures.append(message)


@dataclass
class Events:
    """When (seconds into the run) the mapping was edited and the scene reloaded."""

    edits: list[float] = field(default_factory=list)
    scenes: list[float] = field(default_factory=list)

    def near(self, t: float) -> bool:
        """True within RELOAD_GRACE_S after any event: a sample there is left out of the flat checks."""
        return any(0.0 <= t - event < RELOAD_GRACE_S for event in (*self.edits, *self.scenes))


@dataclass
class PoseJudgement:
    """The probe's actual_pose gaps: the largest, the bridge's own part (judged), and those across reloads."""

    times: list[float]
    largest_own_s: float
    largest_across_reload_s: float | None


def judge_poses(times: list[float], wakes: Wakes | None, scenes: list[float]) -> PoseJudgement:
    """The bridge's own delays (`own_delays`) of the gaps outside a scene reload's window, and apart the
    largest gap across a reload (a reload rebuilds every bridge: a pause there is expected)."""
    own = own_delays(times, wakes)
    gaps = [end - start for start, end in zip(times, times[1:])]
    near = across_events(times, scenes, RELOAD_GRACE_S)
    kept = [value for value, skip in zip(own, near) if not skip]
    across = [gap for gap, skip in zip(gaps, near) if skip]
    return PoseJudgement(
        times, max(kept, default=float("inf")), max(across, default=None) if scenes else None
    )


def print_cpu(shares: list[tuple[str, float, int]]) -> float:
    """Print each process's CPU after warm-up; return the cores used at nice 0 or below (what competes)."""
    print(f"CPU after warm-up (% of one core, nice value) on {os.cpu_count()} CPUs:")
    for name, percent, nice in shares:
        if percent >= 0.5:
            print(f"  {percent:6.1f}  nice {nice:3d}  {name}")
    nice0 = sum(percent for _, percent, nice in shares if nice <= 0) / 100.0
    print(f"  {nice0:6.2f} cores at nice 0 or below, in all")
    return round(nice0, 2)


def report(
    samples: list[Sample],
    warmup: float,
    counts: dict[str, int],
    counts_at_warmup: dict[str, int],
    poses: PoseJudgement,
    monitor_pose_times: list[float],
    status: dict,
    seconds: float,
    host: dict | None = None,
    events: Events | None = None,
) -> int:
    events = events or Events()
    after = [s for s in samples if s.t >= warmup and not events.near(s.t)]
    verdict = Verdict()
    verdict.check(len(after) >= 2, f"run too short for a verdict after the {warmup:.0f} s warm-up")
    window = max(1e-9, seconds - warmup)
    rates = {topic: (counts[topic] - counts_at_warmup.get(topic, 0)) / window for topic in sorted(counts)}
    print("delivered rates after warm-up (Hz):")
    for topic, rate in rates.items():
        print(f"  {rate:8.1f}  {topic}")
    streams = status.get("streams", {})
    print("bridge streams (received / dropped):")
    for topic, s in sorted(streams.items()):
        print(f"  {s['received']:8d} / {s['dropped']:6d}  {topic}")
    gap, own = largest_gap(poses.times), poses.largest_own_s
    summary = {
        "largest_pose_gap_ms": round(gap * 1000, 1),
        "largest_bridge_delay_ms": round(own * 1000, 1),  # the verdict's figure
        "p99_pose_gap_ms": round(gap_percentile(poses.times, 99) * 1000, 1),
        "monitor_largest_pose_gap_ms": round(largest_gap(monitor_pose_times) * 1000, 1),
        "state": status.get("state"),
        "sim_losses": status.get("sim_losses"),
        **(host or {}),
    }
    if events.edits or events.scenes:
        across = poses.largest_across_reload_s
        summary.update(mapping_edits=len(events.edits), scene_reloads=len(events.scenes))
        summary.update(largest_pose_gap_across_reload_ms=None if across is None else round(across * 1000, 1))
        summary.update(reloads_rejected=(status.get("mapping") or {}).get("rejections"))
    if after:
        rss_growth = max(s.rss_mb for s in after) - after[0].rss_mb
        threads, fds = [s.threads for s in after], [s.fds for s in after]
        summary.update(rss_start_mb=round(after[0].rss_mb, 1), rss_growth_mb=round(rss_growth, 1))
        summary.update(
            threads_min=min(threads), threads_max=max(threads), files_min=min(fds), files_max=max(fds)
        )
        verdict.check(rss_growth < RSS_LIMIT_MB, f"RSS grew {rss_growth:.1f} MB (limit {RSS_LIMIT_MB:.0f})")
        verdict.check(
            max(threads) - min(threads) <= THREAD_SLACK, f"thread count varied {min(threads)}..{max(threads)}"
        )
        verdict.check(max(fds) - min(fds) <= FD_SLACK, f"open files varied {min(fds)}..{max(fds)}")
    verdict.check(
        own <= POSE_GAP_LIMIT_S,
        f"the bridge added {own * 1000:.0f} ms to an actual_pose gap on its own (limit 100; the largest gap "
        f"was {gap * 1000:.0f} ms)",
    )
    print("summary: " + json.dumps(summary))
    print("rates: " + json.dumps({topic: round(rate, 2) for topic, rate in rates.items()}))
    for failure in verdict.failures:
        print(f"FAIL: {failure}")
    print("PASS" if not verdict.failures else "FAIL", flush=True)
    return 0 if not verdict.failures else 1
