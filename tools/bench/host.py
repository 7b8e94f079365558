"""What the host did to a bench run: the CPU time a hypervisor took, how late a sleep woke, and warnings
when the host alone, or the bare transports on it, missed a target (pure functions of the results)."""

from __future__ import annotations

from typing import Any

from tools.bench import scenes, transports
from tools.bench.results import (
    median_of,
    median_worst_p99,
    of_kind,
    ratio,
    round_medians,
    scale_rounds,
    topic,
)
from tools.bench.sampling import QUIET_STOLEN_SHARE
from tools.bench.tables import ms, times
from tools.bench.targets import SCALE_CORES, SCALE_POSE_P99_MS

# A host past either is noisy enough to decide the latency figures (docs/performance.md): the quiet hosts
# the targets were met on lost about 2% to steal, and an idle 1 ms sleep overshot by 0.2-0.8 ms at p99.
NOISY_STOLEN_SHARE = 0.05
NOISY_WAKE_P99_MS = 1.0


def host_line(machine: dict[str, Any]) -> str:
    """What the host itself did to the run's timing: the CPU time a hypervisor took, and how late a 1 ms
    sleep woke on the idle machine before the run."""
    wake = machine["idle_wake_ms"]
    line = (
        f"host: {100 * machine['stolen_share']:.1f}% of the CPU time stolen by the hypervisor during the run "
        f"({100 * machine['stolen_share_since_boot']:.1f}% since boot); idle before the run, a 1 ms sleep "
        f"overshot by {wake['p50']:.2f} ms at the median, {wake['p99']:.2f} ms at p99, {wake['max']:.2f} ms "
        "at most"
    )
    if machine.get("windows"):
        line += (
            f"; {machine['windows_retaken']} of {machine['windows']} measurement windows taken again for "
            f"losing {100 * QUIET_STOLEN_SHARE:g}% or more"
        )
    return line


def noisy_host(machine: dict[str, Any]) -> str | None:
    """A warning when the host's own delays were large enough to decide the latency figures."""
    stolen, wake_p99 = machine["stolen_share"], machine["idle_wake_ms"]["p99"]
    if stolen < NOISY_STOLEN_SHARE and wake_p99 < NOISY_WAKE_P99_MS:
        return None
    return (
        f"warning: the host was noisy ({100 * stolen:.1f}% of the CPU time stolen, idle wake-up p99 "
        f"{wake_p99:.2f} ms): the latency figures are mostly the host's; the CPU figures and ratios hold "
        "better"
    )


def _of_rounds(count: int) -> str:
    """The suffix that says a figure is a median of rounds (nothing for one round)."""
    return f" (the median of {count} rounds)" if count > 1 else ""


def floor_over_target(e2e: dict[str, Any]) -> str | None:
    """A warning when the receive floor alone (no ROS) missed the drones' pose latency target (the median
    over the rounds): then the host was too slow during the run for any bridge to meet it, and the ratios
    are the figures to read."""
    p99, known = median_worst_p99(scale_rounds(e2e), "receive_floor")
    if (p99 or 0.0) <= SCALE_POSE_P99_MS:
        return None
    return (
        f"warning: the poses through the receive loop alone, no ROS, had a worst p99 of {ms(p99)} ms"
        f"{_of_rounds(known)}, "
        f"over the {SCALE_POSE_P99_MS:g} ms target: the host was too slow for that target during this "
        "run, whatever the bridge does"
    )


def forwarder_over_cpu_target(e2e: dict[str, Any]) -> str | None:
    """A warning when the bare forwarder alone took more CPU than the drones' target (the median over the
    judged rounds): the host was slower during the run than the one the target was set on, and the
    bridge's ratio to the forwarder is the figure to read."""
    rounds = scale_rounds(e2e)
    if not rounds:
        return None
    cores = round_medians(rounds)[0]["forwarder_cpu_cores"] or 0.0
    if cores <= SCALE_CORES:
        return None
    drones = len(of_kind(rounds[0]["forwarder"], "pose"))
    bridge = ratio(median_of([r["bridge"]["bridge_cpu_cores"] for r in rounds]), cores)
    return (
        f"warning: the bare forwarder alone took {cores:.3f} cores with {drones} drones, over the "
        f"{SCALE_CORES:g}-core target: the host was slower during this run than the one the target was set "
        f"on; the bridge's ratio to the forwarder ({times(bridge)}) is the figure to read"
    )


def forwarder_over_latency_target(e2e: dict[str, Any]) -> str | None:
    """A warning when the bare forwarder alone missed the drones' pose latency target (the median over the
    judged rounds): a plain rospy subscriber got no better through the client on this host during the run,
    and the bridge's p99 over the forwarder's (their medians) is the figure to read."""
    rounds = scale_rounds(e2e)
    if not rounds:
        return None
    p99, known = median_worst_p99(rounds, "forwarder")
    if (p99 or 0.0) <= SCALE_POSE_P99_MS:
        return None
    drones = len(of_kind(rounds[0]["forwarder"], "pose"))
    bridge = ratio(median_worst_p99(rounds, "bridge")[0], p99)
    return (
        f"warning: the bare forwarder alone had a worst pose p99 of {ms(p99)} ms with {drones} drones"
        f"{_of_rounds(known)}, over the "
        f"{SCALE_POSE_P99_MS:g} ms target: a plain rospy subscriber got no better through the client on this "
        f"host during the run; the bridge's p99 over the forwarder's ({times(bridge)}) is the figure to read"
    )


def forwarder_under_compressed_rate(e2e: dict[str, Any]) -> str | None:
    """A warning when the bare forwarder alone delivered the raw 1080p camera at 30 Hz under the rate the
    `/compressed` topic's target asks: the host could not carry those frames during the run, encoded or
    not, and a missed compressed rate is the host's."""
    floor = e2e.get("forwarder", {}).get("camera")
    if not floor or "transports" not in e2e:
        return None
    rate = topic(floor, scenes.image_topic(1))["rate_hz"]
    if rate >= transports.JPEG_MIN_HZ:
        return None
    return (
        f"warning: the bare forwarder alone delivered the raw 1080p camera at {rate:.1f} Hz, under the "
        f"{transports.JPEG_MIN_HZ:g} Hz the /compressed target asks: the host could not carry those frames "
        "during this run, whatever the encoder does"
    )
