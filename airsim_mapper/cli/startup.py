"""The node's start-up and stop: connecting with backoff, the start-up thread, the signal handler.

Start-up (connecting, making the wrapper, loading the start scene) runs on a thread of its own, so the
main thread always sees a signal. A simulator that is not running yet is waited for (one log line per
attempt; backoff 0.5 s, then 2 s, then 5 s); a port that accepts the connection but never answers is not
(SimSilent). The first SIGINT or SIGTERM asks the node to stop and arms a deadline; a second exits at once.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import select
import signal
import threading
import time
from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING, Any

from airsim_mapper.common.errors import ConfigError
from airsim_mapper.common.logs import ros_logger
from airsim_mapper.engine import Backoff, SimSilent, SimUnreachable, open_client, retry_quietly

if TYPE_CHECKING:
    from airsim_mapper.mapping.pipeline import Prepared

__all__ = ["StartUp", "Stopper", "connect"]

log = ros_logger("airsim_mapper.node")


class Stopper:
    """The node's signal handler: the first signal asks the main loop to stop and arms a deadline after
    which the process exits anyway (status 1); a second signal exits at once (status 128 + signal). With
    `at_once`, while there is nothing to undo, a signal exits at once with status 0."""

    def __init__(self, timeout: float, at_once: bool = False) -> None:
        self.timeout = timeout
        self.signals: list[int] = []
        self.at_once = at_once  # nothing to undo yet (before rospy.init_node): exit at once, status 0
        # Written by `wake` and, once installed, by Python's C-level signal handler on whichever thread
        # took the signal: the main loop's `wait` returns at once.
        self._woken, self._wake = os.pipe()
        os.set_blocking(self._woken, False)
        os.set_blocking(self._wake, False)

    def install(self, signals: tuple[int, ...] = (signal.SIGINT, signal.SIGTERM)) -> int:
        """Handle `signals` (main thread only); the previous wake-up fd of signals is returned."""
        for number in signals:
            signal.signal(number, self)
        return signal.set_wakeup_fd(self._wake, warn_on_full_buffer=False)

    def __call__(self, number: int, _frame: Any) -> None:
        if self.at_once:
            _say_and_exit(f"{signal.Signals(number).name} before the node registered: exiting", 0)
        if self.signals:
            _say_and_exit(f"second signal ({signal.Signals(number).name}): exiting at once", 128 + number)
        self.signals.append(number)
        self.wake()
        deadline = threading.Timer(self.timeout, self._overdue)
        deadline.daemon = True
        deadline.start()

    def wake(self) -> None:
        """End the current `wait`, or the next one (from a signal handler, or rospy's shutdown hook: a
        write to a pipe takes no lock the interrupted main thread could hold)."""
        with contextlib.suppress(OSError):
            os.write(self._wake, b"!")

    def wait(self, timeout: float) -> None:
        """Sleep until `wake` or a signal, at most `timeout` seconds: the main loop wakes when it has to,
        not 10 times a second. What woke it is read, so the next wait sleeps again."""
        if select.select([self._woken], [], [], timeout)[0]:
            with contextlib.suppress(BlockingIOError):
                while os.read(self._woken, 512):
                    pass

    def _overdue(self) -> None:
        _say_and_exit(f"shutdown took longer than {self.timeout:g} s (--shutdown-timeout): exiting", 1)

    def __bool__(self) -> bool:
        return bool(self.signals)


def _say_and_exit(message: str, status: int) -> None:
    """Exit now, without running more Python: the message goes straight to stderr."""
    with contextlib.suppress(OSError):
        os.write(2, f"[projectairsim_node] {message}\n".encode())
    os._exit(status)


def connect(
    address: str,
    topicsport: int,
    servicesport: int,
    is_shutdown: Callable[[], bool],
    sleep: Callable[[float], Any] | None = None,
    on_wait: Callable[[str, int], Any] | None = None,
) -> Any:
    """Connect to the simulator, retrying with backoff while nothing listens, until it answers or ROS shuts
    down (then None); `on_wait` is told why and the attempts so far before each wait. SimSilent (the ports
    are held but nothing answers) is raised, not retried."""
    sleep = sleep or time.sleep
    backoff = Backoff()
    while not is_shutdown():
        try:
            with retry_quietly(backoff.attempt > 0):
                client = open_client(address, topicsport, servicesport)
        except SimSilent:
            raise
        except SimUnreachable as exc:
            delay = backoff.next_delay()
            log.warning("%s; waiting for it: attempt %d, next in %.1f s", exc, backoff.attempt, delay)
            if on_wait is not None:
                on_wait(str(exc), backoff.attempt)
            sleep(delay)
            continue
        if backoff.attempt:
            log.info("simulator at %s:%d/%d answered", address, topicsport, servicesport)
        return client
    return None


class StartUp:
    """The node's start-up on a thread of its own: connect, make the wrapper, load the start scene.

    The main thread only waits for it, so a signal is seen at once even while a connect or a scene load
    is blocked in the simulator client. `failure` is the message to print (exit status 1)."""

    def __init__(
        self,
        args: argparse.Namespace,
        settings: dict[str, Any],
        prepared: Prepared,
        stopping: Callable[[], bool],
    ) -> None:
        self.args, self.settings, self.prepared, self.stopping = args, settings, prepared, stopping
        self.wrapper: Any = None
        self.failure = ""

    def run(self) -> None:
        try:
            self.failure = self._run()
        except Exception as exc:  # never leave the main thread waiting: say what happened
            self.failure = f"start-up failed: {type(exc).__name__}: {exc}"

    def _run(self) -> str:
        import rospy

        from airsim_mapper.engine import WaitingStatus
        from airsim_mapper.wrapper import ProjectAirSimWrapper

        args, settings, prepared = self.args, self.settings, self.prepared
        address, topicsport, servicesport = (settings[k] for k in ("address", "topicsport", "servicesport"))
        waiting = WaitingStatus(rospy.get_name())
        try:
            client = connect(address, topicsport, servicesport, self.stopping, on_wait=waiting.publish)
        except SimSilent as exc:
            return str(exc)
        finally:
            waiting.close()
        if client is None:
            return ""  # stopped while waiting for the simulator
        self.wrapper = ProjectAirSimWrapper(
            client,
            sim_config_path=settings["simconfigpath"],
            mapping=prepared.mapping,
            node_name=prepared.node_name,
            namespace=prepared.namespace,
            disconnect_on_shutdown=True,  # this node made the client
            client_factory=partial(open_client, address, topicsport, servicesport),
            shutdown_timeout=max(0.5, args.shutdown_timeout - 1.5),  # rospy's own unregistering comes after
            max_frame_mb=args.max_frame_mb,
            tune_process=True,  # this process is the bridge's own
        )
        if prepared.scene is None:
            return ""
        try:
            self.wrapper.load_scene(prepared.scene, prepared.specs)
        except ConfigError as exc:
            return str(exc)
        except Exception as exc:  # the simulator refused the scene: say why, without a traceback
            return f"{settings['scene']}: the simulator could not load it: {type(exc).__name__}: {exc}"
        return ""
