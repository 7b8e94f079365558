"""The service methods of a robot's cameras: images, camera poses, fields of view and camera rays."""

from __future__ import annotations

import math
from typing import Any

from airsim_mapper.common.geometry import quat_from_rpy, quat_multiply
from airsim_mapper.simserver.render import camera_model
from airsim_mapper.simserver.robot.robot_params import finite, within_world
from airsim_mapper.simserver.robot.robots import RobotRuntime
from airsim_mapper.simserver.sensors.camera_stream import CameraStream
from airsim_mapper.simserver.wire import messages
from airsim_mapper.simserver.wire.messages import MessageError
from airsim_mapper.simserver.wire.services import Method, ServiceError


class CameraServices:
    """A robot's cameras as service methods (each camera's own, and the robot's GetCameraRay)."""

    def __init__(self, robot: RobotRuntime) -> None:
        self.robot = robot

    def methods(self) -> list[Method]:
        robot = self.robot
        table = [
            Method(f"{robot.prefix}/GetCameraRay", ("camera_id", "image_type", "x", "y"), self._camera_ray)
        ]
        for camera_id, camera in robot.cameras.items():
            table += self._camera_methods(robot.scene.sensor_prefix(robot.spec.name, camera_id), camera)
        return table

    def _camera_ray(self, params: dict[str, Any]) -> dict[str, Any]:
        """GetCameraRay: the pose of the ray through pixel (x, y) of a camera's image type (world NED)."""
        camera_id = str(params["camera_id"])
        stream = self.robot.cameras.get(camera_id)
        if stream is None:
            raise ServiceError(f"Robot '{self.robot.spec.name}' has no enabled camera '{camera_id}'")
        image_type = int(finite(params, "image_type"))
        capture = stream.captures.get(image_type)
        if capture is None:
            raise ServiceError(f"Camera '{camera_id}' has no capture-enabled image type {image_type}")
        x, y = finite(params, "x"), finite(params, "y")
        f = camera_model.focal_length(capture.width, stream.fov[image_type])
        right, down = (x - capture.width / 2.0) / f, (y - capture.height / 2.0) / f
        local = quat_from_rpy(0.0, -math.atan2(down, math.hypot(1.0, right)), math.atan2(right, 1.0))
        position, orientation = stream.world_pose()
        return messages.pose(position, quat_multiply(orientation, local))

    def _camera_methods(self, path: str, camera: CameraStream) -> list[Method]:
        def get_images(params: dict[str, Any]) -> dict[str, Any]:
            ids = params["image_type_ids"]
            if not isinstance(ids, list):
                raise ServiceError(f"image_type_ids must be a list, got {ids!r}", code=2.0)
            return camera.get_images(ids, self.robot.clock.now_ns)

        def set_pose(params: dict[str, Any]) -> bool:
            try:
                position, orientation = messages.parse_transform(params["pose"])
            except MessageError as exc:
                raise ServiceError(str(exc), code=2.0) from exc
            camera.set_pose(within_world("pose", position), orientation)
            return True

        def reset_pose(_: dict[str, Any]) -> bool:
            camera.reset_pose()
            return True

        def set_fov(params: dict[str, Any]) -> bool:
            image_type = int(params["image_type_id"])
            if image_type in camera.fov:
                camera.fov[image_type] = finite(params, "field_of_view")
            return True

        def look_at(params: dict[str, Any]) -> bool:
            return self.robot.world.object_named(str(params["object_name"])) is not None

        accept = lambda _: True  # noqa: E731 - settings this renderer does not model
        return [
            Method(f"{path}/GetImages", ("image_type_ids",), get_images),
            Method(f"{path}/SetPose", ("pose", "wait_for_pose_update"), set_pose),
            Method(f"{path}/ResetCameraPose", ("wait_for_pose_update",), reset_pose),
            Method(f"{path}/LookAtObject", ("object_name", "wait_for_pose_update"), look_at),
            Method(f"{path}/DrawFrustum", ("image_type", "to_enable"), accept),
            Method(f"{path}/SetFieldOfView", ("image_type_id", "field_of_view"), set_fov),
            Method(f"{path}/SetFocalLength", ("image_type_id", "focal_length"), accept),
            Method(f"{path}/SetChromaticAberrationIntensity", ("image_type_id", "intensity"), accept),
            Method(f"{path}/SetDepthOfFieldFocalRegion", ("image_type_id", "focal_length"), accept),
            Method(
                f"{path}/SetDepthOfFieldTransitionRegion", ("image_type_id", "transition_threshold"), accept
            ),
        ]
