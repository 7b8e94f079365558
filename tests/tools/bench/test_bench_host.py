"""The bench's account of the host itself: CPU time a hypervisor took, and how late an idle sleep wakes."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time

import pytest
from harness import ROOT

from tools.bench import host, tables
from tools.bench.e2e import quietest
from tools.bench.sampling import (
    QUIET_STOLEN_SHARE,
    HostSample,
    host_sample,
    stolen_share,
    threads_cpu_s,
    wake_delays_ms,
)

STAT = "cpu  807605 26193 313546 10859998 6006 0 30925 206029 0 0\ncpu0 1 2 3 4 5 6 7 8 0 0\n"


def test_the_host_sample_sums_the_first_eight_times_and_takes_steal_from_the_eighth():
    sample = host_sample(STAT)
    assert sample == HostSample(807605 + 26193 + 313546 + 10859998 + 6006 + 0 + 30925 + 206029, 206029)
    assert host_sample("cpu 10 0 5 85 0 0 0\n") == HostSample(100, 0)  # a kernel without steal


def test_the_stolen_share_is_steal_over_all_cpu_time_between_two_samples():
    assert stolen_share(HostSample(1000, 10), HostSample(1200, 40)) == pytest.approx(0.15)
    assert stolen_share(HostSample(1000, 10), HostSample(1000, 10)) == 0.0  # no tick between them


def test_the_live_host_sample_counts_forward():
    before = host_sample()
    after = host_sample()
    assert after.total >= before.total and after.stolen >= before.stolen
    assert 0.0 <= stolen_share(before, after) <= 1.0


def test_the_idle_wake_delays_are_ordered_and_measured():
    wake = wake_delays_ms(seconds=0.05)
    assert 0.0 <= wake["p50"] <= wake["p99"] <= wake["max"] < 1000.0


def _machine(stolen: float, p99: float) -> dict:
    return {
        "stolen_share": stolen,
        "stolen_share_since_boot": 0.017,
        "idle_wake_ms": {"p50": 0.11, "p99": p99, "max": 3.4},
    }


def test_the_host_line_says_what_the_hypervisor_took_and_how_late_a_sleep_woke():
    line = host.host_line(_machine(0.021, 0.76))
    assert line == (
        "host: 2.1% of the CPU time stolen by the hypervisor during the run (1.7% since boot); idle before "
        "the run, a 1 ms sleep overshot by 0.11 ms at the median, 0.76 ms at p99, 3.40 ms at most"
    )


def test_the_host_line_counts_the_windows_taken_again():
    line = host.host_line({**_machine(0.021, 0.76), "windows": 40, "windows_retaken": 3})
    assert line.endswith("at most; 3 of 40 measurement windows taken again for losing 0.5% or more")


@pytest.mark.parametrize(
    ("shares", "measured", "kept"),
    [
        ([0.0], 1, 0.0),  # quiet at once: measured once
        ([0.02, 0.001], 2, 0.001),  # taken again, and the quiet one kept
        ([0.03, QUIET_STOLEN_SHARE, 0.01], 3, QUIET_STOLEN_SHARE),  # never quiet: the least stolen kept
        ([0.03, 0.02, 0.01, 0.0], 3, 0.01),  # at most two more windows
    ],
)
def test_a_window_that_lost_cpu_time_is_measured_again_and_the_quietest_kept(shares, measured, kept):
    windows = iter(shares)
    calls = []

    def measure() -> dict:
        calls.append(1)
        share = next(windows)
        return {"host_stolen_share": share, "p99": 100 * share}

    result = quietest(measure, retakes=2)
    assert len(calls) == measured and result["windows_measured"] == measured
    assert result["host_stolen_share"] == kept and result["p99"] == 100 * kept  # the window's own figures


@pytest.mark.parametrize(
    ("stolen", "p99", "noisy"),
    [(0.02, 0.2, False), (0.049, 0.99, False), (0.05, 0.2, True), (0.02, 1.0, True), (0.12, 7.0, True)],
)
def test_a_host_past_either_limit_is_called_noisy(stolen, p99, noisy):
    warning = host.noisy_host(_machine(stolen, p99))
    assert (warning is not None) == noisy
    if noisy:
        assert warning.startswith(f"warning: the host was noisy ({100 * stolen:.1f}% of the CPU time stolen")


@pytest.mark.live
def test_a_costs_only_bench_run_completes_with_the_host_line_and_writes_its_results(tmp_path):
    out = tmp_path / "bench.json"
    run = subprocess.run(
        [sys.executable, "-m", "tools.bench", "--costs-only", "--quick", "--out", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "\nhost: " in run.stdout and "stolen by the hypervisor during the run" in run.stdout
    results = json.loads(out.read_text())
    machine = results["machine"]
    assert 0.0 <= machine["stolen_share"] <= 1.0 and 0.0 <= machine["stolen_share_since_boot"] <= 1.0
    assert set(machine["idle_wake_ms"]) == {"p50", "p99", "max"}
    assert "e2e" not in results and any(t["target"].startswith("100k-point scan") for t in results["targets"])


def test_the_threads_cpu_counts_what_a_thread_of_this_process_spent():
    def spin() -> None:
        until = time.thread_time() + 0.2
        while time.thread_time() < until:
            pass

    before = threads_cpu_s(os.getpid())
    thread = threading.Thread(target=spin)
    thread.start()
    time.sleep(0.05)  # measured while the thread is still alive: only live threads are counted
    mid = threads_cpu_s(os.getpid())
    thread.join()
    assert mid > before
    assert threads_cpu_s(os.getpid()) >= before  # the thread's time went with it; never negative


def test_the_waiting_nodes_row_shows_its_cpu_to_a_thousandth_of_a_core():
    row = tables.waiting_row({"bridge_cpu_cores": 0.00453, "bridge_rss_mb": 98.6})
    assert row == ["bridge waiting for a scene", "-", "-", "-", "0.005 (bridge)", "-", "99"]
