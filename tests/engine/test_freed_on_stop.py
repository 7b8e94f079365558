"""What a live mapping edit stops is freed by reference counting, with no garbage collection: the node
freezes its heap (engine/process_tuning.py), and a reference cycle in there is never collected
(docs/reliability.md, "A reload's memory")."""

from __future__ import annotations

import contextlib
import gc
import threading
import types
import weakref

import pytest
from fakes import EngineRig
from harness import SIM_CONFIG

from airsim_mapper.engine.rospy_internals import ConnectionPoll, PromptQueuedConnection
from airsim_mapper.mapping.loader import load_mapping_text

SCENE = "scene_drone_sensors.jsonc"
# Each edit restarts a publisher (imu), a subscriber (cmd_vel), a service (takeoff) and a static mount.
EDIT = """version: 1
extends: default
variables: {{frame: <robot_name>_{n}}}
rules:
  - {{name: imu, queue_size: {n}}}
  - {{name: cmd_vel, queue_size: {n}}}
  - {{name: takeoff, params: {{args: {{timeout_sec: {n}}}}}}}
  - {{name: camera_tf, frame_id: <frame>}}
"""


@contextlib.contextmanager
def no_collection():
    """No automatic collection runs inside: what is freed is freed by reference counting."""
    enabled = gc.isenabled()
    gc.collect()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def edit(n: int):
    return load_mapping_text(EDIT.format(n=n), str(SIM_CONFIG / "edited.yaml"))


def test_the_bridges_an_edit_stops_are_freed_without_a_collection():
    rig = EngineRig()
    try:
        rig.engine.load_scene(SCENE)
        rig.engine.apply_mapping(edit(1))
        rig.ros.publishers["/airsim_node/Drone1/IMU1/imu"].subscribers(1)  # the lazy imu bridge attaches
        with no_collection():
            before = {name: weakref.ref(bridge) for name, bridge in rig.engine.bridges.items()}
            diff = rig.engine.apply_mapping(edit(2))
            kinds = {type(rig.engine.bridges[name]).__name__ for name in diff.changed}
            assert kinds == {"SimToRos", "RosToSim", "RosService", "MountTransform"}
            alive = [name for name in diff.changed if before[name]() is not None]
            assert alive == [], "stopped bridges kept alive by a reference cycle"
            assert all(before[name]() is not None for name in before if name not in diff.changed)
    finally:
        rig.engine.shutdown(timeout=2.0)


def test_loading_a_mapping_with_variables_leaves_no_cyclic_garbage():
    with no_collection():
        assert edit(1).rules
        gc.set_debug(gc.DEBUG_SAVEALL)  # what the collection finds stays in gc.garbage
        try:
            gc.collect()
            found = [o for o in gc.garbage if _mapping_code(o)]
        finally:
            gc.set_debug(0)
            gc.garbage.clear()
    assert found == []  # the variables' resolution was a closure calling itself, holding the marks


def _mapping_code(thing: object) -> bool:
    """Made by the mapping package: an instance of one of its classes, or one of its functions."""
    module = thing.__module__ if isinstance(thing, types.FunctionType) else type(thing).__module__
    return (module or "").startswith("airsim_mapper.mapping")


class Transport:
    """The part of a rospy transport a queued connection uses, keeping its cleanup callback as rospy's."""

    def __init__(self) -> None:
        self.done = False
        self.cleanup_cb = None

    def set_cleanup_callback(self, callback) -> None:
        self.cleanup_cb = callback

    def close(self) -> None:  # rospy's Transport.close
        self.done = True
        if self.cleanup_cb:
            self.cleanup_cb(self)


def test_a_closed_publisher_connection_is_freed_without_a_collection():
    with no_collection():
        transport = Transport()
        connection = PromptQueuedConnection(transport, 1)
        writer, freed = connection._thread, weakref.ref(connection)
        transport.close()  # wakes the writer thread, which ends
        writer.join(5)
        assert not writer.is_alive()
        del connection
        assert freed() is None and transport.cleanup_cb is not None


def test_a_topic_poll_is_freed_without_a_collection():
    with no_collection():
        poll = ConnectionPoll()
        freed = weakref.ref(poll)
        del poll
        assert freed() is None


@pytest.fixture(autouse=True)
def _no_thread_left():
    before = set(threading.enumerate())
    yield
    assert not [t for t in threading.enumerate() if t not in before and t.name.startswith("stream:")]
