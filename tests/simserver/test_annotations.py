"""Bounding-box annotations (annotations.py): settings as the real server reads them, and hand-checked
projections through the pinhole model of camera_info_message."""

from __future__ import annotations

import math

import numpy as np
import pytest

from airsim_mapper.common.geometry import quat_from_rpy
from airsim_mapper.simserver.render.annotations import AnnotationError, AnnotationSettings, annotate
from airsim_mapper.simserver.render.camera_model import camera_info_message
from airsim_mapper.simserver.scene.config import SceneSpecError, parse_scene
from airsim_mapper.simserver.world.world_file import world_from_dict

ORIGIN, LEVEL = np.zeros(3), quat_from_rpy(0.0, 0.0, 0.0)
W, H, FOV = 100, 50, 90.0  # f = 50 px on both axes, principal point (50, 25)


def box(name, center, size, yaw_deg=0.0, seg=10):
    return {
        "name": name,
        "shape": "box",
        "center": center,
        "size": size,
        "yaw-deg": yaw_deg,
        "segmentation-id": seg,
        "color-bgr": [0, 0, 255],
    }


def world(*objects):
    return world_from_dict({"objects": list(objects)})


def settings(*ids, **extra):
    return AnnotationSettings.from_config(
        {"annotation-settings": {"enabled": True, "object-ids": list(ids), **extra}}
    )


def test_a_cube_ahead_projects_through_k_with_truncated_corners():
    boxes = annotate(world(box("Cube", [10, 0, 0], [2, 2, 2])), settings("Cube"), ORIGIN, LEVEL, W, H, FOV)
    assert [b["object_id"] for b in boxes] == ["Cube"]
    (b,) = boxes
    # corners at x = 9 and 11, y and z = +-1: u = 50 + 50 y / x, v = 25 + 50 z / x, truncated
    assert b["bbox2d"] == {"center": {"x": 49.5, "y": 24.5}, "size": {"x": 11.0, "y": 11.0}}
    pixels = [(p["x"], p["y"]) for p in b["bbox3d_in_image_space"]]
    # Unreal's CalcVertices order: x, then y, then up (NED -z), each - before +
    assert pixels == [(44, 30), (44, 19), (55, 30), (55, 19), (45, 29), (45, 20), (54, 29), (54, 20)]
    first = b["bbox3d_in_projection_space"][0]  # (9, -1, +1): left, below the centre, 9 m deep
    assert (first["x"], first["y"], first["z"]) == pytest.approx((-1 / 9, -2 / 9, 0.1 / 9))
    assert b["bbox3d"] == {
        "center": {"x": 10.0, "y": 0.0, "z": 0.0},
        "size": {"x": 2.0, "y": 2.0, "z": 2.0},
        "quaternion": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
    }


def test_the_projection_is_the_published_camera_matrix():
    k = camera_info_message(W, H, FOV)["intrinsic_camera_matrix"]
    (b,) = annotate(world(box("C", [20, 3, -2], [0.5, 0.5, 0.5])), settings("C"), ORIGIN, LEVEL, W, H, FOV)
    u, v = k[0] * 3 / 20 + k[2], k[4] * -2 / 20 + k[5]  # FRD camera: x depth, y right, z down
    assert (b["bbox2d"]["center"]["x"], b["bbox2d"]["center"]["y"]) == pytest.approx((u, v), abs=1.0)


def test_objects_behind_beside_or_not_listed_are_not_annotated():
    w = world(
        box("Behind", [-10, 0, 0], [2, 2, 2]),
        box("Beside", [10, 30, 0], [2, 2, 2]),  # every corner right of the image: clamped to a zero width
        box("Unlisted", [10, 0, 0], [2, 2, 2]),
    )
    assert annotate(w, settings("Behind", "Beside", "Missing"), ORIGIN, LEVEL, W, H, FOV) == []


def test_a_box_around_the_camera_fills_the_image_from_its_corners_in_front():
    (b,) = annotate(world(box("Room", [0, 0, 0], [2, 2, 2])), settings("Room"), ORIGIN, LEVEL, W, H, FOV)
    assert b["bbox2d"] == {"center": {"x": 50.0, "y": 25.0}, "size": {"x": 100.0, "y": 50.0}}
    behind = [p for p in b["bbox3d_in_image_space"][:4]]  # the x = -1 corners
    assert behind == [{"x": 0.0, "y": 0.0}] * 4
    assert b["bbox3d_in_projection_space"][:4] == [{"x": 0.0, "y": 0.0, "z": 0.0}] * 4


def test_occluded_objects_are_still_annotated():
    w = world(box("Wall", [5, 0, 0], [1, 20, 20]), box("Hidden", [10, 0, 0], [2, 2, 2]))
    ids = [b["object_id"] for b in annotate(w, settings("Wall", "Hidden"), ORIGIN, LEVEL, W, H, FOV)]
    assert ids == ["Wall", "Hidden"]


def test_oriented_and_axis_aligned_3d_boxes_of_a_yawed_box():
    w = world(box("Bar", [10, 0, 0], [4, 2, 2], yaw_deg=90))
    (oriented,) = annotate(w, settings("Bar"), ORIGIN, LEVEL, W, H, FOV)
    (axis,) = annotate(
        w, settings("Bar", **{"bbox3D-settings": {"alignment": "axis"}}), ORIGIN, LEVEL, W, H, FOV
    )
    q = oriented["bbox3d"]["quaternion"]
    assert (q["w"], q["z"]) == pytest.approx((math.cos(math.pi / 4), math.sin(math.pi / 4)))
    assert oriented["bbox3d"]["size"] == {"x": 4.0, "y": 2.0, "z": 2.0}
    assert axis["bbox3d"]["size"] == pytest.approx({"x": 2.0, "y": 4.0, "z": 2.0})
    assert axis["bbox3d"]["quaternion"] == {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0}
    # the projected corners are always the oriented box's: the yawed bar spans y = +-2 at x = 9..11
    assert oriented["bbox2d"] == axis["bbox2d"]
    assert oriented["bbox2d"]["size"]["x"] == 23.0  # u from trunc(50 - 100/9) = 38 to trunc(50 + 100/9) = 61


def test_a_sphere_is_boxed_by_its_cube_and_a_turned_camera_sees_it():
    w = world_from_dict(
        {
            "objects": [
                {
                    "name": "Ball",
                    "shape": "sphere",
                    "center": [0, 10, 0],
                    "radius": 1.0,
                    "segmentation-id": 11,
                    "color-bgr": [0, 140, 255],
                }
            ]
        }
    )
    east = quat_from_rpy(0.0, 0.0, math.pi / 2)  # camera looking east
    (b,) = annotate(w, settings("Ball"), ORIGIN, east, W, H, FOV)
    assert b["bbox3d"]["size"] == {"x": 2.0, "y": 2.0, "z": 2.0}
    assert b["bbox2d"]["center"] == pytest.approx({"x": 49.5, "y": 24.5})
    assert annotate(w, settings("Ball"), ORIGIN, LEVEL, W, H, FOV) == []  # looking north it is beside


def test_the_distance_filter_drops_far_objects():
    w = world(box("Cube", [10, 0, 0], [2, 2, 2]))
    near = settings("Cube", **{"distance-filter-enabled": True, "distance-filter-range": 5})
    far = settings("Cube", **{"distance-filter-enabled": True, "distance-filter-range": 11})
    assert annotate(w, near, ORIGIN, LEVEL, W, H, FOV) == []
    assert len(annotate(w, far, ORIGIN, LEVEL, W, H, FOV)) == 1


@pytest.mark.parametrize(
    "config",
    [
        {},
        {"annotation-settings": {}},
        {"annotation-settings": {"object-ids": ["A"]}},
        {"annotation-settings": {"enabled": True, "object-ids": []}},
    ],
)
def test_annotations_are_off_unless_enabled_with_object_ids(config):
    assert AnnotationSettings.from_config(config) is None


def test_an_invalid_alignment_is_refused_at_scene_load():
    with pytest.raises(AnnotationError, match=r"bbox3D-settings\.alignment"):
        settings("A", **{"bbox3D-settings": {"alignment": "tight"}})
    camera = {
        "id": "Cam",
        "type": "camera",
        "enabled": True,
        "capture-settings": [],
        "annotation-settings": {"enabled": True, "object-ids": "Cube"},
    }
    scene = {
        "id": "S",
        "actors": [
            {
                "type": "robot",
                "name": "D",
                "origin": {"xyz": "0 0 0", "rpy-deg": "0 0 0"},
                "robot-config": {"sensors": [camera]},
            }
        ],
    }
    import json

    with pytest.raises(
        SceneSpecError, match=r"sensor 'Cam': 'annotation-settings\.object-ids' must be a list"
    ):
        parse_scene(json.dumps(scene))
