"""End-to-end runs: replay server -> bridge node -> probe (three processes), next to the raw transports.

A `Bench` owns one private roscore (when it runs ROS1 rows), a ROS 2 domain (when it runs ROS 2 rows) and
a work folder. `bridge_session` starts a replay server and a bridge node on a generated scene; `probe`
measures the given topics through them while /proc samples the CPU and memory of the node (and the
server). Each session runs on one ROS flavour (`ros`, 1 or 2); ROS 2's processes run in .venv-ros2
(ros2.py): the bridge is `.venv-ros2/bin/airsim-mapper-node`, the probe probe_ros2.py, the bare forwarder
forwarder_ros2.py. `rospy_baseline` and `pynng_baseline` measure the bare transports with the same probe
logic, in the same run.
"""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

from airsim_mapper.cli.node import WAITING_FOR_SCENE
from tools.bench import ros2, scenes
from tools.bench.baselines import RAW_TOPIC
from tools.bench.probe import DEFAULT_MALLOC
from tools.bench.sampling import (
    QUIET_STOLEN_SHARE,
    cpu_share,
    fault_rate,
    host_sample,
    sample,
    stolen_share,
    threads_cpu_s,
)
from tools.rig import Child, Rig, free_port, port_open, wait_until

FIRST_MESSAGE_TIMEOUT_S = 120.0
APART_MARGIN_S = 5.0  # how long a second probe's window outlasts the first's: the first's start-up


T = TypeVar("T")


class BenchError(RuntimeError):
    """The benchmark could not start or finish one of its runs."""


def rotated(items: Sequence[T], n: int) -> list[T]:
    """`items` rotated left by `n`: round `n`'s order, so that no side is always measured first."""
    k = n % len(items)
    return [*items[k:], *items[:k]]


def wait_line(child: Child, word: str, timeout: float) -> None:
    def seen() -> bool:
        text = child.output()
        if "failed:" in text:
            raise BenchError(f"{child.name}: {text.strip().splitlines()[-1]}")
        if not child.alive() and word not in text:
            raise BenchError(f"{child.name} exited early:\n{text}")
        return any(line.strip() == word for line in text.splitlines())

    wait_until(seen, timeout, f"{child.name} to print {word!r}", interval=0.1)


def quietest(measure: Callable[[], dict[str, Any]], retakes: int) -> dict[str, Any]:
    """The first result of `measure` whose window was quiet (its `host_stolen_share` under
    QUIET_STOLEN_SHARE), measuring up to `retakes` more times; else the one that lost the least. Its
    `windows_measured` says how many windows were measured for it."""
    results: list[dict[str, Any]] = []
    for _ in range(1 + retakes):
        results.append(measure())
        if results[-1]["host_stolen_share"] < QUIET_STOLEN_SHARE:
            break
    best = min(results, key=lambda result: result["host_stolen_share"])
    return {**best, "windows_measured": len(results)}


@dataclass
class Session:
    bench: Bench
    server: Child
    node: Child
    role: str = "bridge"  # the node's name in the results: bridge, or forwarder (the floor)
    ros: int = 1

    def probe(
        self, label: str, topics: Sequence[str], apart: Sequence[str] = (), malloc: str = DEFAULT_MALLOC
    ) -> dict[str, Any]:
        """Rate and latency of `topics`, with the CPU (cores) and RSS of the node and server meanwhile;
        `apart` topics are read by a second probe process at the same time (see `Bench.measure`), each
        probe with `malloc`'s thresholds (probe.py)."""
        watched = {self.role: self.node, "server": self.server}
        return self.bench.measure(label, topics, watched, apart, malloc, self.ros)


@dataclass
class Bench:
    """`retakes`: how many more times a window that was not quiet is measured (`quietest`).
    `windows` and `windows_retaken` count the windows measured and those taken again. `flavours`: the
    ROS flavours the bench runs rows of."""

    workdir: Path
    warmup_s: float = 2.0
    duration_s: float = 8.0
    retakes: int = 2
    flavours: tuple[int, ...] = (1,)
    windows: int = field(default=0, init=False)
    windows_retaken: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        self.procs = Rig(self.workdir)
        self.config_dir = self.workdir / "sim_config"
        self.roscore = self.procs.roscore() if 1 in self.flavours else None
        self.domain = ros2.claim_domain() if 2 in self.flavours else None

    def close(self) -> None:
        self.procs.stop_all()
        if self.domain is not None:
            self.domain.release()

    def python(self, name: str, args: Sequence[str], ros: int = 1) -> Child:
        """Run Python with `args` in the bench's rig: .venv's, or on ROS 2 .venv-ros2's in its domain."""
        if ros == 1:
            return self.procs.python(name, args)
        if self.domain is None:
            raise BenchError("a ROS 2 run in a bench made without ROS 2 among its flavours")
        return self.procs.start(name, [*ros2.interpreter(), *args], env=ros2.environment(self.domain.number))

    def module(self, name: str, module: str, *args: str, ros: int = 1) -> Child:
        """Run `python -m module args` in the bench's rig (on ROS 2: in .venv-ros2)."""
        return self.python(name, ["-m", module, *args], ros)

    # -- measuring

    def measure(
        self,
        label: str,
        topics: Sequence[str],
        watched: dict[str, Child],
        apart: Sequence[str] = (),
        malloc: str = DEFAULT_MALLOC,
        ros: int = 1,
    ) -> dict[str, Any]:
        """The probe's result for `topics` (probe.py, or probe_ros2.py on ROS 2), with the `apart` topics
        (images, say) read by a second probe process whose window spans the first's, their figures merged
        in: a subscriber of `topics` that does not also hold the GIL to read large messages, as in a ROS
        graph where each node reads its own.
        A window in which a hypervisor took QUIET_STOLEN_SHARE of the CPU time or more is measured again,
        up to `retakes` times (`quietest`)."""
        return self._quiet_window(lambda: self._measure_once(label, topics, watched, apart, malloc, ros))

    def _quiet_window(self, measure: Callable[[], dict[str, Any]]) -> dict[str, Any]:
        """`measure`'s quietest window (`quietest`), counted in `windows` and `windows_retaken`."""
        result = quietest(measure, self.retakes)
        self.windows += 1
        self.windows_retaken += result["windows_measured"] > 1
        return result

    def _measure_once(
        self,
        label: str,
        topics: Sequence[str],
        watched: dict[str, Child],
        apart: Sequence[str],
        malloc: str,
        ros: int,
    ) -> dict[str, Any]:
        if set(topics) & set(apart):
            raise BenchError(f"topics both read together and apart: {sorted(set(topics) & set(apart))}")
        other: tuple[Child, Path] | None = None
        try:
            if apart:
                span = self.warmup_s + self.duration_s + APART_MARGIN_S
                other = self._probe(f"{label}_apart", apart, span, malloc, ros)
                wait_line(other[0], "measuring", FIRST_MESSAGE_TIMEOUT_S + 30)
            probe, out = self._probe(label, topics, self.duration_s, malloc, ros)
            try:
                result = self._collect(probe, out, watched)
            finally:
                self.procs.stop(probe)
            if other is not None:
                wait_line(other[0], "done", self.warmup_s + self.duration_s + APART_MARGIN_S + 30)
                result["topics"].update(self._result(other[1])["topics"])
            return result
        finally:
            if other is not None:
                self.procs.stop(other[0])

    def _probe(
        self, label: str, topics: Sequence[str], duration_s: float, malloc: str, ros: int
    ) -> tuple[Child, Path]:
        out = self.workdir / f"probe_{label}.json"
        out.unlink(missing_ok=True)  # a result of an earlier run under the same label is not this one's
        args = ["--out", str(out), "--warmup", str(self.warmup_s), "--duration", str(duration_s)]
        args += ["--first-timeout", str(FIRST_MESSAGE_TIMEOUT_S), "--malloc", malloc, *topics]
        module = "tools.bench.probe" if ros == 1 else "tools.bench.probe_ros2"
        return self.module(f"probe_{label}", module, *args, ros=ros), out

    @staticmethod
    def _result(out: Path) -> dict[str, Any]:
        """The JSON a measuring process writes once it has printed `done`."""
        wait_until(out.exists, 10, f"{out.name}")  # written whole (probe.write_result)
        return json.loads(out.read_text())

    def _collect(self, measurer: Child, out: Path, watched: dict[str, Child]) -> dict[str, Any]:
        """The JSON result `measurer` writes to `out` between its `measuring` and `done` lines, with the
        CPU, RSS and minor faults of the `watched` processes meanwhile, and the share of the machine's
        CPU time a hypervisor took (`host_stolen_share`)."""
        wait_line(measurer, "measuring", FIRST_MESSAGE_TIMEOUT_S + 30)
        before = {name: sample(child.pid) for name, child in watched.items()}
        host_before = host_sample()
        wait_line(measurer, "done", self.duration_s + 30)
        after = {name: sample(child.pid) for name, child in watched.items()}
        result = self._result(out)
        result["host_stolen_share"] = stolen_share(host_before, host_sample())
        for name in watched:
            result[f"{name}_cpu_cores"] = cpu_share(before[name], after[name])
            result[f"{name}_rss_mb"] = after[name].rss_mb
            result[f"{name}_minor_faults_per_s"] = fault_rate(before[name], after[name])
        return result

    # -- the bridge

    def _replay_server(self, log_level: str) -> tuple[Child, int, int]:
        """Start the replay server on free ports: (process, topics port, services port)."""
        topics_port, services_port = free_port(), free_port()
        server = self.module(
            "replay_server",
            "tools.bench.replay_server",
            "--address",
            "127.0.0.1",
            "--topicsport",
            str(topics_port),
            "--servicesport",
            str(services_port),
            "--log-level",
            log_level,
        )
        return server, topics_port, services_port

    @contextlib.contextmanager
    def bridge_session(
        self,
        scene_file: str,
        runner: str = "node",
        decode: str = "bridge",
        profile: str | None = None,
        node_args: Sequence[str] = (),
        ros: int = 1,
    ) -> Iterator[Session]:
        """The bridge on a replay server: on ROS1 tools.bench.node's `runner` (the node or a mission script)
        with `decode`; on ROS 2 `.venv-ros2/bin/airsim-mapper-node` as users start it, or under cProfile
        (profiling.py) with `profile`."""
        if ros == 1:
            args = ["--as", runner, "--decode", decode, "--nodename", "bench_bridge"]
            args += [*(["--profile", profile] if profile else []), *node_args]
            program = ["-m", "tools.bench.node"]
        else:
            args = ["--nodename", "bench_bridge", *node_args]
            program = ["-m", "tools.bench.profiling", profile] if profile else [str(ros2.ROS2_NODE)]
        with self._replay_client("bridge", program, scene_file, "bridge", args, ros) as session:
            yield session

    def waiting_node(self) -> dict[str, Any]:
        """The node started without a scene, connected to a replay server and waiting for one: its CPU
        (from its threads' schedstat, `sampling.threads_cpu_s`) and RSS over a window in which nothing
        arrives and nothing is published; a window that was not quiet is measured again, as any other."""
        args = ["--nodename", "bench_waiting"]
        program = ["-m", "tools.bench.node"]
        with self._replay_client("waiting_bridge", program, None, "bridge", args) as session:
            node = session.node
            wait_until(lambda: WAITING_FOR_SCENE in node.output(), FIRST_MESSAGE_TIMEOUT_S, "the node")
            time.sleep(self.warmup_s)

            def window() -> dict[str, Any]:
                start, cpu_s, host_before = time.monotonic(), threads_cpu_s(node.pid), host_sample()
                time.sleep(self.duration_s)
                seconds, cpu_s = time.monotonic() - start, threads_cpu_s(node.pid) - cpu_s
                return {
                    "seconds": seconds,
                    "bridge_cpu_cores": cpu_s / seconds,
                    "bridge_rss_mb": sample(node.pid).rss_mb,
                    "host_stolen_share": stolen_share(host_before, host_sample()),
                }

            return self._quiet_window(window)

    @contextlib.contextmanager
    def forwarder_session(self, scene_file: str, camera: bool = False, ros: int = 1) -> Iterator[Session]:
        """The bare forwarder (forwarder.py, on ROS 2 forwarder_ros2.py) on a replay server: the floor of
        the bridge's figures."""
        args = ["--camera"] if camera else []
        program = ["-m", "tools.bench.forwarder" if ros == 1 else "tools.bench.forwarder_ros2"]
        client = self._replay_client("forwarder", program, scene_file, "forwarder", args, ros)
        with client as session:
            yield session

    def receive_floor(self, scene_file: str, camera: bool = False) -> dict[str, Any]:
        """The poses through the bridge's receive loop alone, no ROS (receive_floor.py), on a replay
        server."""
        out = self.workdir / f"receive_floor_{Path(scene_file).stem}.json"
        out.unlink(missing_ok=True)  # each round of a scene writes here: wait for this round's
        args = ["--out", str(out), "--warmup", str(self.warmup_s), "--duration", str(self.duration_s)]
        args += ["--camera"] if camera else []
        program = ["-m", "tools.bench.receive_floor"]
        with self._replay_client("receive_floor", program, scene_file, "receiver", args) as session:
            return self._collect(session.node, out, {"server": session.server})

    @contextlib.contextmanager
    def _replay_client(
        self,
        name: str,
        program: Sequence[str],
        scene_file: str | None,
        role: str,
        args: Sequence[str],
        ros: int = 1,
    ) -> Iterator[Session]:
        """`program` (Python's arguments before `args`: `-m module`, or a script) run as `name` on ROS `ros`
        against a fresh replay server on `scene_file` (None: no scene given), both stopped afterwards."""
        server, topics_port, services_port = self._replay_server("WARNING")
        client: Child | None = None
        try:
            wait_until(lambda: port_open(topics_port) and port_open(services_port), 30, "the replay server")
            ports = ["--topicsport", str(topics_port), "--servicesport", str(services_port)]
            scene = ["--simconfigpath", str(self.config_dir), "--scene", scene_file] if scene_file else []
            client = self.python(name, [*program, *ports, *scene, *args], ros)
            yield Session(self, server, client, role=role, ros=ros)
        finally:
            if client is not None:
                self.procs.stop(client)
            self.procs.stop(server)
            time.sleep(0.5)  # let the master drop the client's registrations

    # -- baselines

    def rospy_baseline(self, kind: str, rate: float) -> dict[str, Any]:
        publisher = self.module(
            f"rospy_{kind}", "tools.bench.baselines", "rospy-pub", "--kind", kind, "--rate", str(rate)
        )
        try:
            return self.measure(f"rospy_{kind}", [RAW_TOPIC], {"publisher": publisher})
        finally:
            self.procs.stop(publisher)
            time.sleep(0.5)

    def pynng_baseline(self, kind: str, rate: float) -> dict[str, Any]:
        port = free_port()
        sender = self.module(
            f"pynng_send_{kind}",
            "tools.bench.baselines",
            "pynng-send",
            "--kind",
            kind,
            "--rate",
            str(rate),
            "--port",
            str(port),
        )
        out = self.workdir / f"pynng_{kind}.json"
        out.unlink(missing_ok=True)
        receiver: Child | None = None
        try:
            wait_until(lambda: port_open(port), 30, "the pynng sender")
            receiver = self.module(
                f"pynng_recv_{kind}",
                "tools.bench.baselines",
                "pynng-recv",
                "--port",
                str(port),
                "--warmup",
                str(self.warmup_s),
                "--duration",
                str(self.duration_s),
                "--out",
                str(out),
            )
            wait_line(receiver, "done", 60 + self.duration_s + 30)  # it measures its own CPU time
            return self._result(out)
        finally:
            if receiver is not None:
                self.procs.stop(receiver)
            self.procs.stop(sender)

    # -- scenes

    def scene(
        self, name: str, drones: int, camera: scenes.CameraSetup | None = None, lidar: bool = False
    ) -> str:
        return scenes.write_scene(self.config_dir, name, drones, camera, lidar)
