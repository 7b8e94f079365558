"""The actual_pose gaps of a soak run: printed with their sim-time step and lateness, and each less the
host's delay within it (the bridge's own part, which the verdict judges)."""

from __future__ import annotations

from tools.soak.probes import Wakes


def explain_gaps(times: list[float], stamps: list[float], wakes: Wakes | None = None, worst: int = 5) -> None:
    """Print the largest receive gaps with the sim-time step across them and the lateness after them.

    The headless server's steppable clock runs at wall speed, so `receive time - stamp` is a constant plus
    the delivery delay; its minimum over the run is the floor. A gap followed by a late message (lateness
    close to the gap) was a delay on the way; a gap with a matching stamp step and no lateness means no
    pose was produced or all were dropped. With `wakes`, two more columns: the longest stretch of the gap
    in which the wake probe was kept waiting (close to the gap, the host held up every process, not only
    the bridge), and the bridge's own part of the gap (`own_delays`), which the verdict judges.
    """
    import numpy as np

    if len(times) < 2:
        return
    t, st = np.asarray(times), np.asarray(stamps)
    gaps, steps = np.diff(t), np.diff(st)
    late = (t - st) - (t - st).min()
    host_cells = " / host delay / the bridge's own" if wakes is not None else ""
    head = "receive gap / sim-time step / lateness after" + host_cells
    own = own_delays(times, wakes)
    print(f"largest actual_pose gaps after warm-up ({head}, ms):")
    for i in np.argsort(gaps)[::-1][:worst]:
        host = [wakes.largest_within(t[i], t[i + 1]), own[i]] if wakes is not None else []
        cells = [gaps[i], steps[i], late[i + 1], *host]
        print("  " + " / ".join(f"{cell * 1000:7.1f}" for cell in cells))
    print(f"gaps over 50 ms: {int((gaps > 0.05).sum())}, over 100 ms: {int((gaps > 0.1).sum())}")
    print(
        f"actual_pose lateness p50 / p99 / max: {np.percentile(late, 50) * 1000:.1f} / "
        f"{np.percentile(late, 99) * 1000:.1f} / {late.max() * 1000:.1f} ms"
    )


def own_delays(times: list[float], wakes: Wakes | None) -> list[float]:
    """Each gap between two receive times less the time within it that the host kept the wake probe waiting.

    The wake probe does nothing but sleep, at the bridge's priority: while it waits for a CPU, so does every
    process of the rig, and a pose gap then says nothing about the bridge. What is left is the delay the
    bridge (or the server, or the link) added on its own. Without wake-ups, the gaps themselves.
    """
    pairs = list(zip(times, times[1:]))
    if wakes is None:
        return [end - start for start, end in pairs]
    return [max(0.0, end - start - wakes.covered_within(start, end)) for start, end in pairs]


def across_events(times: list[float], events: list[float], grace: float) -> list[bool]:
    """Per gap between two receive times: does it overlap an [event, event + grace) window?"""
    return [
        any(start < event + grace and end > event for event in events) for start, end in zip(times, times[1:])
    ]


def gap_percentile(times: list[float], q: float) -> float:
    import numpy as np

    return float(np.percentile(np.diff(times), q)) if len(times) > 1 else float("inf")


def largest_gap(times: list[float]) -> float:
    import numpy as np

    return float(np.diff(times).max()) if len(times) > 1 else float("inf")
