"""Annotations through the real 1.1.0 client, the way Project AirSim's example scripts read them: a camera
with `annotation-settings` reports the bounding boxes of the listed objects in view with each image, on its
topic and from `get_images`."""

from __future__ import annotations

import copy
import math

import numpy as np
from projectairsim import Drone, World
from projectairsim.types import ImageType, Pose
from projectairsim.utils import unpack_image

from airsim_mapper.simserver.render.camera_model import segmentation_color
from simserver.clientkit import scene_config, settle, subscribe

BALL_SEGMENTATION_ID = 11  # OrangeBall of the built-in world, at (20, 20, -3) with radius 1


def annotated_scene() -> dict:
    config = copy.deepcopy(scene_config("scene_drone_sensors.jsonc"))
    chase = next(s for s in config["actors"][0]["robot-config"]["sensors"] if s["id"] == "Chase")
    chase["capture-settings"].append(
        {
            "image-type": 3,
            "width": 640,
            "height": 360,
            "fov-degrees": 90,
            "capture-enabled": True,
            "pixels-as-float": False,
            "compress": False,
        }
    )
    chase["annotation-settings"] = {
        "enabled": True,
        "object-ids": ["OrangeBall", "BlockSouthWest", "PillarWest"],
        "bbox2D-settings": {"alignment": "axis"},
        "bbox3D-settings": {"alignment": "oriented"},
    }
    return config


def test_the_chase_camera_boxes_the_orange_ball_it_sees(client):
    world = World(client)
    world.load_scene(annotated_scene())
    drone = Drone(client, world, "Drone1")
    yaw = math.pi / 4  # facing the ball from the landing pad
    rotation = {"w": math.cos(yaw / 2), "x": 0.0, "y": 0.0, "z": math.sin(yaw / 2)}
    pose = Pose(
        {"translation": {"x": 0.0, "y": 0.0, "z": -4.0}, "rotation": rotation, "frame_id": "DEFAULT_ID"}
    )
    assert drone.set_pose(pose, True) is True
    world.pause()
    inbox = subscribe(client, drone.sensors["Chase"]["scene_camera"])
    settle(client, drone.robot_info["actual_pose"])
    world.continue_for_sim_time(100_000_000, wait_until_complete=True)
    published = inbox.wait_for()[-1]
    images = drone.get_images("Chase", [ImageType.SCENE, ImageType.SEGMENTATION])
    world.resume()

    boxes = {a["object_id"]: a for a in images[ImageType.SCENE]["annotations"]}
    assert set(boxes) == {"OrangeBall"}  # the other two are behind or beside the camera
    assert images[ImageType.SEGMENTATION]["annotations"] == images[ImageType.SCENE]["annotations"]
    assert [a["object_id"] for a in published["annotations"]] == ["OrangeBall"]
    ball = boxes["OrangeBall"]
    assert ball["bbox3d"]["center"] == {"x": 20.0, "y": 20.0, "z": -3.0}
    assert ball["bbox3d"]["size"] == {"x": 2.0, "y": 2.0, "z": 2.0}
    assert len(ball["bbox3d_in_image_space"]) == len(ball["bbox3d_in_projection_space"]) == 8

    # the ball's pixels in the segmentation image lie inside its 2D box (the box of its bounding cube)
    segmentation = unpack_image(images[ImageType.SEGMENTATION])
    rows, cols = np.nonzero((segmentation == segmentation_color(BALL_SEGMENTATION_ID)).all(axis=2))
    assert rows.size > 20
    center, size = ball["bbox2d"]["center"], ball["bbox2d"]["size"]
    left, right = center["x"] - size["x"] / 2, center["x"] + size["x"] / 2
    top, bottom = center["y"] - size["y"] / 2, center["y"] + size["y"] / 2
    assert left <= cols.min() and cols.max() + 1 <= right + 1
    assert top <= rows.min() and rows.max() + 1 <= bottom + 1
    # and the box is tight: the cube is at most 1.5x the sphere's apparent width
    assert size["x"] <= 1.5 * (cols.max() - cols.min() + 1) + 2
