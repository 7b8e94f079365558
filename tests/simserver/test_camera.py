"""Camera rendering: depth, segmentation, shading, encodings, and CameraInfo as the real server builds it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from simconfigs import EXAMPLES, PROJECT, both_configs, robot_sensors

from airsim_mapper.common.geometry import quat_from_rpy, quat_to_matrix, rotate
from airsim_mapper.simserver.render import gl_renderer, rendering
from airsim_mapper.simserver.render.camera_model import (
    CameraError,
    RenderRequest,
    camera_info_message,
    segmentation_color,
    segmentation_palette,
)
from airsim_mapper.simserver.render.rendering import render
from airsim_mapper.simserver.world.world import World
from airsim_mapper.simserver.world.world_file import load_world

LEVEL_NORTH = quat_from_rpy(0.0, 0.0, 0.0)
# the robot configs with a DownCamera capturing all seven image types
SENSOR_ROBOT = {
    PROJECT: "robot_quadrotor_sensors.jsonc",
    EXAMPLES: "robot_quadrotor_fastphysics_sensors.jsonc",
}


@pytest.fixture(autouse=True, params=rendering.RENDERERS)
def renderer(request: pytest.FixtureRequest):
    """Every test here runs with the OpenGL renderer and with the ray caster (the reference)."""
    if request.param == "gl":
        gl_renderer.renderer()  # no skip: without EGL this fails loudly (`make setup` installs it)
    rendering.select_renderer(request.param)
    yield request.param
    assert rendering.renderer_name() == request.param  # the GL renderer did not fall back
    rendering.select_renderer(None)


@pytest.fixture(scope="module")
def world() -> World:
    return load_world()


@pytest.fixture(scope="module", params=both_configs())
def down_camera(request: pytest.FixtureRequest) -> dict:
    """The DownCamera of the project's sensor quadrotor, and of the example one where present."""
    return next(s for s in robot_sensors(request.param, SENSOR_ROBOT) if s["id"] == "DownCamera")


def as_array(image):
    if image.encoding == "16FC1":
        return np.frombuffer(image.data, dtype="<f2").reshape(image.height, image.width).astype(np.float64)
    return np.frombuffer(image.data, dtype=np.uint8).reshape(image.height, image.width, 3)


def test_camera_info_matches_the_real_server_for_the_down_camera_config(down_camera):
    setting = down_camera["capture-settings"][1]
    width, height = setting["width"], setting["height"]
    info = camera_info_message(width, height, setting["fov-degrees"])
    f = (width / 2) / math.tan(math.radians(setting["fov-degrees"]) / 2)
    assert info["intrinsic_camera_matrix"] == pytest.approx([f, 0, width / 2, 0, f, height / 2, 0, 0, 1])
    assert info["width"] == width and info["height"] == height
    assert info["distortion_model"] == "" and info["distortion_params"] == [0.0] * 5
    assert info["rectification_matrix"] == [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0]
    assert info["projection_matrix"] == [1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0, 0]
    assert set(info) == {
        "width",
        "height",
        "distortion_model",
        "distortion_params",
        "intrinsic_camera_matrix",
        "rectification_matrix",
        "projection_matrix",
    }


def test_focal_length_uses_the_horizontal_field_of_view_for_both_axes():
    info = camera_info_message(640, 480, 60.0)
    k = info["intrinsic_camera_matrix"]
    assert k[0] == pytest.approx(320 / math.tan(math.radians(30))) and k[4] == k[0]


def test_every_configured_image_type_has_the_configured_size_and_encoding(world, down_camera):
    settings = down_camera["capture-settings"]
    types = [s["image-type"] for s in settings]
    width, height, fov = settings[0]["width"], settings[0]["height"], settings[0]["fov-degrees"]
    images = render(
        world,
        RenderRequest(
            np.array([0.0, 0.0, -4.0]), quat_from_rpy(0, -math.pi / 2, 0), width, height, fov, types
        ),
    )
    assert sorted(images) == list(range(7))
    for kind, image in images.items():
        depth = kind in (1, 2)
        assert image.encoding == ("16FC1" if depth else "BGR")
        assert (image.width, image.height) == (width, height)
        assert len(image.data) == width * height * (2 if depth else 3)


def test_depth_equals_the_distance_to_a_box_face_and_perspective_grows_towards_the_edges(world):
    # 2 m south of BlockNorth's south face (x = 28, 8 m wide, 10 m tall): the face fills a 90 degree view
    width, height = 64, 48
    images = render(
        world, RenderRequest(np.array([26.0, 0.0, -5.0]), LEVEL_NORTH, width, height, 90.0, [1, 2])
    )
    planar, perspective = as_array(images[1]), as_array(images[2])
    assert np.allclose(planar, 2.0, atol=2e-3)
    assert perspective[height // 2, width // 2] == pytest.approx(2.0, abs=2e-3)
    f = (width / 2) / math.tan(math.radians(45))
    u, v = np.meshgrid(np.arange(width) - width / 2, np.arange(height) - height / 2)
    expected = 2.0 * np.sqrt(1 + (u / f) ** 2 + (v / f) ** 2)
    assert np.allclose(perspective, expected, rtol=2e-3)
    assert perspective[0, 0] > planar[0, 0] * 1.6  # corner ray is long, its planar depth is not


def test_depth_is_infinite_where_the_camera_sees_only_sky(world):
    looking_up = quat_from_rpy(0.0, math.pi / 2, 0.0)
    assert np.allclose(rotate(looking_up, [1.0, 0.0, 0.0]), [0.0, 0.0, -1.0])
    images = render(world, RenderRequest(np.array([0.0, 0.0, -5.0]), looking_up, 32, 24, 60.0, [1, 2, 3]))
    assert np.isposinf(as_array(images[1])).all() and np.isposinf(as_array(images[2])).all()
    assert (as_array(images[3]) == 0).all()


def test_segmentation_colours_identify_ball_ground_and_sky_at_pixels_projected_with_k(world):
    ball = world.object_named("OrangeBall")
    position = np.array([10.0, 10.0, -3.0])  # ball centre 10 m ahead along the camera x axis
    yaw = math.atan2(ball.center[1] - position[1], ball.center[0] - position[0])
    orientation = quat_from_rpy(0.0, 0.0, yaw)
    width, height = 80, 60
    images = render(world, RenderRequest(position, orientation, width, height, 90.0, [3]))
    seg = as_array(images[3])
    k = camera_info_message(width, height, 90.0)["intrinsic_camera_matrix"]

    def pixel_of(point):
        cam = (np.asarray(point) - position) @ quat_to_matrix(orientation)  # world -> camera frame
        return round(k[0] * cam[1] / cam[0] + k[2]), round(k[4] * cam[2] / cam[0] + k[5])

    u, v = pixel_of(ball.center)
    assert tuple(seg[v, u]) == segmentation_color(ball.segmentation_id)
    ground_point = position + rotate(orientation, [6.0, -1.0, 0.0]) + [0.0, 0.0, 3.0]  # on z = 0
    u, v = pixel_of(ground_point)
    assert tuple(seg[v, u]) == segmentation_color(world.ground_segmentation_id)
    assert tuple(seg[0, 0]) == (0, 0, 0)  # top-left looks into the sky


def test_segmentation_palette_gives_distinct_colours_to_the_world_ids(world):
    ids = [o.segmentation_id for o in world.objects] + [world.ground_segmentation_id]
    colours = {segmentation_color(i) for i in ids}
    assert len(colours) == len(ids) and (0, 0, 0) not in colours
    assert segmentation_palette().shape == (256, 3)


def test_scene_image_shades_each_object_in_its_own_colour(world):
    ball = world.object_named("OrangeBall")
    position = np.array([20.0, 15.0, -3.0])  # 5 m west of the ball, looking east
    orientation = quat_from_rpy(0.0, 0.0, math.pi / 2)
    scene = as_array(render(world, RenderRequest(position, orientation, 64, 48, 60.0, [0]))[0]).astype(float)
    centre = scene[24, 32]
    base = np.array(ball.color_bgr, dtype=float)
    light = centre[2] / base[2]
    assert 0.3 < light <= 1.0
    assert np.allclose(centre, base * light, atol=4.0)
    ground = scene[47, 32]
    assert ground[1] > ground[2] and ground[1] > ground[0]  # the ground colour is green-dominant
    sky = scene[0, 32]
    assert sky[0] > sky[2]  # the sky is blue-dominant (BGR)


def test_surface_normals_depth_vis_and_disparity_encode_a_facing_wall(world):
    images = render(world, RenderRequest(np.array([26.0, 0.0, -5.0]), LEVEL_NORTH, 32, 24, 60.0, [4, 5, 6]))
    normals = as_array(images[6])
    assert (normals[12, 16] == [128, 128, 0]).all()  # world normal (-1, 0, 0): B = z, G = y, R = x
    assert (as_array(images[4])[12, 16] == round(2.0 / 100.0 * 255)).all()
    assert (as_array(images[5])[12, 16] == round(0.5 * 255)).all()


def test_only_the_requested_types_are_rendered(world):
    images = render(world, RenderRequest(np.array([0.0, 0.0, -4.0]), LEVEL_NORTH, 16, 12, 90.0, [3, 0, 3]))
    assert sorted(images) == [0, 3]
    assert render(world, RenderRequest(np.array([0.0, 0.0, -4.0]), LEVEL_NORTH, 16, 12, 90.0, [])) == {}


@pytest.mark.parametrize(
    ("size", "fov", "types", "message"),
    [
        ((16, 12), 90.0, [9], "unknown image type 9 (expected 0-6)"),
        ((16, 12), 180.0, [0], "fov-degrees must be between 0 and 180 (exclusive), got 180.0"),
        ((0, 12), 90.0, [0], "image size must be positive integers, got 0 x 12"),
    ],
)
def test_invalid_render_requests_are_refused(world, size, fov, types, message):
    with pytest.raises(CameraError) as caught:
        render(world, RenderRequest(np.zeros(3), LEVEL_NORTH, size[0], size[1], fov, types))
    assert str(caught.value) == message


class PublishedImages:
    """The parts of TopicHub a CameraStream uses: everything is subscribed, images are kept."""

    def __init__(self) -> None:
        self.messages: dict[str, dict] = {}

    def is_subscribed(self, path: str) -> bool:
        return True

    def publish(self, path: str, frame) -> None:
        from airsim_mapper.simserver.wire import protocol

        self.messages[path] = protocol.decode_body(frame.body)


def test_a_camera_stream_renders_depth_vis_with_its_capture_max_depth_meters(world):
    from airsim_mapper.simserver.motion.motion import Body
    from airsim_mapper.simserver.scene.config import CaptureSpec, SensorSpec
    from airsim_mapper.simserver.sensors.camera_stream import CameraStream

    captures = (
        CaptureSpec(4, 64, 48, 90.0, True, False, max_depth_m=5.0, compress=False),
        CaptureSpec(2, 64, 48, 90.0, True, False, compress=False),
    )
    sensor = SensorSpec("C", "camera", {}, captures=captures, capture_interval=0.1)
    body = Body(np.array([0.0, 0.0, -20.0]), quat_from_rpy(0.0, -math.pi / 2, 0.0), lambda p: 0.0)
    hub = PublishedImages()
    CameraStream(sensor, "/S/C", body, world, hub).capture(0, [2, 4])
    vis = np.frombuffer(bytes(hub.messages["/S/C/depth_vis_camera"]["data"]), np.uint8)
    depth = np.frombuffer(bytes(hub.messages["/S/C/depth_camera"]["data"]), "<f2")
    assert depth.min() > 5.0  # everything is farther than max-depth-meters, so depth vis is all white
    assert (vis == 255).all()
