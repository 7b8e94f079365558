"""Camera mounts moved by camera pose commands: one owner, one lock, and listeners told of each change.

A camera's pose relative to its robot is its config origin until a `camera_desired_pose` command (SetPose)
takes effect; from then on the commanded pose. The command's reply thread writes here; the camera pose
converters read through their context (`ConvertContext.mounts`), and the static camera frames
(`bridges.MountTransform`) are told to send their transform again.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

MountKey = tuple  # convert.pose.camera_pose_key(robot, camera)
Listener = Callable[[], None]


class CameraMounts:
    """Commanded camera mounts by `camera_pose_key`; read like a read-only mapping."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._mounts: dict[MountKey, Any] = {}
        self._listeners: dict[MountKey, list[Listener]] = {}

    def get(self, key: MountKey, default: Any = None) -> Any:
        with self._lock:
            return self._mounts.get(key, default)

    def __contains__(self, key: object) -> bool:
        with self._lock:
            return key in self._mounts

    def set(self, key: MountKey, mount: Any) -> None:
        """A command moved a camera: remember its mount, then tell that camera's listeners."""
        with self._lock:
            self._mounts[key] = mount
            listeners = list(self._listeners.get(key, ()))
        for listener in listeners:
            listener()

    def listen(self, key: MountKey, listener: Listener) -> None:
        with self._lock:
            self._listeners.setdefault(key, []).append(listener)

    def unlisten(self, key: MountKey, listener: Listener) -> None:
        with self._lock:
            remaining = [f for f in self._listeners.get(key, ()) if f != listener]
            if remaining:
                self._listeners[key] = remaining
            else:
                self._listeners.pop(key, None)

    def clear(self) -> None:
        """A new scene, or a simulator that restarted: every camera is back on its config origin, and the
        listeners of the cameras that had moved are told."""
        with self._lock:
            moved, self._mounts = list(self._mounts), {}
            listeners = [f for key in moved for f in self._listeners.get(key, ())]
        for listener in listeners:
            listener()
