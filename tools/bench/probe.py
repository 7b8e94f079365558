"""A ROS subscriber process that measures delivered rate and latency (receive time - header stamp).

Messages are taken as `rospy.AnyMsg` (no deserialisation: the probe costs as little as possible); the
stamp is read from the serialised header (seq, secs, nsecs are its first 12 bytes), so every stamped type
works. Every message delivered is counted: with a `queue_size`, rospy keeps only the newest of the
messages one read of the socket brings, so a probe that fell behind by one pose would drop the older
one, from the rate and from the latencies alike. It waits until every topic delivered once, lets them
run for --warmup s, prints `measuring`, records for --duration s, prints `done` and writes its JSON
result to --out, with its own minor page faults in the window and its malloc thresholds.

It keeps its read buffers in the heap as the bridge does (`tuning.keep_frame_buffers`), as
docs/ros-usage.md tells a user's node that reads large images to: with glibc's adaptive malloc thresholds
the probe's own page faults on each image held its pose callback back by milliseconds, through either
bridge, and varied from run to run by more than the bench's targets leave (docs/performance.md, "A
subscriber's own image reading"). `--malloc glibc` leaves glibc's thresholds, for that comparison.

    python -m tools.bench.probe --out result.json [--warmup S] [--duration S] [--malloc glibc] TOPIC...
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import struct
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from airsim_mapper.common import tuning

MALLOC_CHOICES = ("fixed", "glibc")  # the probe's malloc thresholds: as the bridge's, or glibc's adaptive
DEFAULT_MALLOC, GLIBC_MALLOC = MALLOC_CHOICES
HEADER = struct.Struct("<III")
SOCKET_BUFFER = 1 << 24


@dataclass
class TopicRecord:
    latencies_ms: list[float] = field(default_factory=list)
    bytes: int = 0
    seen: int = 0


def write_result(path: str | Path, result: dict[str, Any]) -> None:
    """Write a measuring process's JSON result whole: to a temporary file renamed over `path`, so that a
    reader never sees it half written."""
    path = Path(path)
    partial = path.with_name(path.name + ".part")
    partial.write_text(json.dumps(result))
    os.replace(partial, path)


def summary(record: TopicRecord, seconds: float) -> dict[str, Any]:
    lat = np.asarray(record.latencies_ms, dtype=float)
    out: dict[str, Any] = {"count": int(lat.size), "rate_hz": lat.size / seconds, "bytes": record.bytes}
    if lat.size:
        out.update(
            latency_p50_ms=float(np.percentile(lat, 50)),
            latency_p99_ms=float(np.percentile(lat, 99)),
            latency_mean_ms=float(lat.mean()),
            message_bytes=record.bytes // lat.size,
        )
    return out


def usage() -> tuple[int, float]:
    """This process's minor page faults and CPU seconds (user + system) so far."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    return own.ru_minflt, own.ru_utime + own.ru_stime


def parse_arguments(argv: list[str] | None) -> tuple[argparse.Namespace, str]:
    """Both flavours' probe arguments, and the malloc thresholds in effect: glibc's when asked, or when
    tuning is off (AIRSIM_MAPPER_NO_TUNING)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("topics", nargs="+")
    parser.add_argument("--out", required=True)
    parser.add_argument("--warmup", type=float, default=2.0)
    parser.add_argument("--duration", type=float, default=8.0)
    parser.add_argument("--first-timeout", type=float, default=60.0)
    parser.add_argument("--malloc", choices=MALLOC_CHOICES, default=DEFAULT_MALLOC)
    args = parser.parse_args(argv)
    malloc = DEFAULT_MALLOC if args.malloc == DEFAULT_MALLOC and tuning.keep_frame_buffers() else GLIBC_MALLOC
    return args, malloc


def main(argv: list[str] | None = None) -> int:
    import rospy

    args, malloc = parse_arguments(rospy.myargv(argv)[1:] if argv is None else argv)
    rospy.init_node("bench_probe", anonymous=True, disable_signals=True)
    records = {topic: TopicRecord() for topic in args.topics}
    lock = threading.Lock()
    state = {"recording": False}

    def callback(msg: Any, topic: str) -> None:
        now = time.time()
        data = msg._buff
        secs, nsecs = HEADER.unpack_from(data, 0)[1:]
        with lock:
            record = records[topic]
            record.seen += 1
            if state["recording"]:
                record.latencies_ms.append((now - (secs + nsecs * 1e-9)) * 1e3)
                record.bytes += len(data)

    subscribers = [
        rospy.Subscriber(
            topic,
            rospy.AnyMsg,
            callback,
            callback_args=topic,
            queue_size=None,
            buff_size=SOCKET_BUFFER,
            tcp_nodelay=True,
        )
        for topic in args.topics
    ]
    if not measure(args, records, state, lock, malloc):
        return 1
    for subscriber in subscribers:
        subscriber.unregister()
    rospy.signal_shutdown("probe done")
    return 0


def measure(args: argparse.Namespace, records: dict, state: dict, lock: threading.Lock, malloc: str) -> bool:
    """Wait for a first message on every topic, warm up, record for `args.duration` and write the result
    (both flavours' probes); False when a topic stayed silent past `args.first_timeout`."""
    deadline = time.monotonic() + args.first_timeout
    while any(r.seen == 0 for r in records.values()):
        if time.monotonic() > deadline:
            silent = [t for t, r in records.items() if r.seen == 0]
            print(f"failed: no message on {', '.join(silent)}", flush=True)
            return False
        time.sleep(0.05)
    time.sleep(args.warmup)
    with lock:
        state["recording"] = True
        start, (faults, cpu_s) = time.monotonic(), usage()
    print("measuring", flush=True)
    time.sleep(args.duration)
    with lock:
        state["recording"] = False
        seconds, (faults_end, cpu_end) = time.monotonic() - start, usage()
    print("done", flush=True)
    write_result(
        args.out,
        {
            "seconds": seconds,
            "probe_malloc": malloc,
            "probe_minor_faults": faults_end - faults,
            "probe_cpu_cores": (cpu_end - cpu_s) / seconds,
            "topics": {topic: summary(record, seconds) for topic, record in records.items()},
        },
    )
    return True


if __name__ == "__main__":
    raise SystemExit(main())
