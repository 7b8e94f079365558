"""Scene parsing and the topic table the real server would register (protocol.md §4, §6)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from harness import SIM_CONFIG
from simconfigs import EXAMPLE_SCENES, scenes_of

from airsim_mapper.simserver.scene.config import SceneSpecError, default_scene, parse_scene
from airsim_mapper.simserver.scene.geo import geo_to_ned, ned_to_geo
from airsim_mapper.simserver.scene.topic_table import info_topic_path, topic_table
from simserver.clientkit import scene_config
from simserver.expected_topics import EXAMPLE_EXPECTED, EXPECTED, PROJECT_EXPECTED


def merged_scene(name: str, sim_config: Path = SIM_CONFIG) -> str:
    """The JSON string the real client sends with LoadScene (robot configs inlined by the client itself)."""
    return json.dumps(scene_config(name, sim_config))


def minimal(**overrides) -> dict:
    robot_config = {"physics-type": "non-physics", "sensors": []}
    actor = {
        "type": "robot",
        "name": "D",
        "origin": {"xyz": "1 2 -3", "rpy-deg": "0 0 90"},
        "robot-config": robot_config,
    }
    scene = {"id": "S", "actors": [actor], "clock": {"type": "steppable"}}
    scene.update(overrides)
    return scene


def test_the_catalogues_cover_every_project_scene_and_the_example_scenes_the_compatibility_tests_use():
    assert sorted(path.name for path in SIM_CONFIG.glob("scene_*.jsonc")) == sorted(PROJECT_EXPECTED)
    assert sorted(EXAMPLE_EXPECTED) == sorted(EXAMPLE_SCENES)


@pytest.mark.parametrize(
    ("sim_config", "scene_file"), scenes_of(PROJECT_EXPECTED, EXAMPLE_EXPECTED), indirect=["sim_config"]
)
def test_each_scene_registers_exactly_the_documented_topics(sim_config, scene_file):
    scene_id, expected = EXPECTED[sim_config][scene_file]
    spec = parse_scene(merged_scene(scene_file, sim_config))
    assert spec.id == scene_id
    paths = [row.path for row in topic_table(spec)]
    assert paths == sorted(paths)
    assert set(paths) == expected | {"/$topics"}


def test_topic_rows_carry_the_real_type_message_type_and_frequency():
    rows = {row.path: row for row in topic_table(parse_scene(merged_scene("scene_drone_sensors.jsonc")))}
    base = "/Sim/SceneDroneSensors/robots/Drone1"
    assert rows["/$topics"].message_type == "topic-list"
    assert (rows[f"{base}/desired_pose"].type, rows[f"{base}/desired_pose"].message_type) == (
        "subscribed",
        "",
    )
    assert rows[f"{base}/actual_pose"].message_type == ""
    assert rows[f"{base}/collision_info"].message_type == "collision-info"
    assert (
        rows[f"{base}/sensors/DownCamera/scene_camera"].message_type,
        rows[f"{base}/sensors/DownCamera/scene_camera"].frequency,
    ) == ("image", 60)
    assert rows[f"{base}/sensors/DownCamera/scene_camera_info"].message_type == "camera-info"
    assert rows[f"{base}/sensors/DownCamera/disparity_normalized_camera"].message_type == "image"
    assert rows[f"{base}/sensors/IMU1/imu_kinematics"].message_type == "imu"
    assert rows[f"{base}/sensors/GPS/gps"].message_type == ""
    assert rows[f"{base}/sensors/lidar1/lidar"].message_type == "lidar"
    assert rows[f"{base}/sensors/DistanceSensor/distance_sensor"].message_type == "distance-sensor"


def test_the_disparity_info_topic_has_the_image_topics_own_name():
    assert info_topic_path("/p", 5) == "/p/disparity_normalized_camera"
    assert info_topic_path("/p", 0) == "/p/scene_camera_info"


def test_robot_origin_clock_and_home_are_read():
    spec = parse_scene(
        json.dumps(minimal(clock={"type": "real-time", "step-ns": 1000, "pause-on-start": True}))
    )
    robot = spec.robots[0]
    assert robot.position.tolist() == [1.0, 2.0, -3.0]
    assert robot.orientation == pytest.approx([0.7071068, 0, 0, 0.7071068])
    assert (spec.clock.type, spec.clock.step_ns, spec.clock.pause_on_start) == ("real-time", 1000, True)
    assert spec.home_geo == (47.641468, -122.140165, 122.0)


def test_geo_point_origins_become_ned_offsets_from_home():
    home = (47.0, -122.0, 100.0)
    ned = geo_to_ned((47.001, -122.0, 110.0), home)
    assert (
        ned[0] == pytest.approx(111.3, abs=0.1)
        and ned[1] == pytest.approx(0.0)
        and ned[2] == pytest.approx(-10.0)
    )
    assert ned_to_geo(ned, home) == pytest.approx((47.001, -122.0, 110.0))
    scene = minimal(**{"home-geo-point": {"latitude": 47.0, "longitude": -122.0, "altitude": 100.0}})
    scene["actors"][0]["origin"] = {"geo-point": "47.001 -122.0 110.0", "rpy-deg": "0 0 0"}
    assert parse_scene(json.dumps(scene)).robots[0].position[2] == pytest.approx(-10.0)


def test_disabled_sensors_and_capture_disabled_images_have_no_topics():
    scene = minimal()
    scene["actors"][0]["robot-config"]["sensors"] = [
        {"id": "G", "type": "gps", "enabled": False},
        {
            "id": "C",
            "type": "camera",
            "enabled": True,
            "capture-settings": [
                {"image-type": 1, "capture-enabled": False},
                {"image-type": 3, "capture-enabled": True},
            ],
        },
    ]
    paths = {row.path for row in topic_table(parse_scene(json.dumps(scene)))}
    assert "/Sim/S/robots/D/sensors/C/segmentation_camera" in paths
    assert not any("/G/" in p or "depth_planar" in p for p in paths)


def test_the_default_scene_is_scene_basic_drone_with_one_drone():
    spec = default_scene()
    assert spec.prefix == "/Sim/SceneBasicDrone"
    assert [r.name for r in spec.robots] == ["Drone1"] and spec.robots[0].multirotor


def bad(mutate) -> str:
    scene = minimal()
    mutate(scene)
    return json.dumps(scene)


def set_sensor(scene: dict, sensor: dict) -> None:
    scene["actors"][0]["robot-config"]["sensors"] = [sensor]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{not json", "scene_config is not valid JSON"),
        ("[1]", "scene_config must be a JSON object, got list"),
        (json.dumps({"actors": []}), "scene config has no 'id'"),
        (json.dumps({"id": "a/b"}), "scene 'id' must be a non-empty string without '/'"),
        (json.dumps({"id": "S", "actors": {}}), "scene 'actors' must be a list"),
        (json.dumps({"id": "S", "actors": [3]}), "actor #0 must be an object"),
        (bad(lambda s: s["actors"][0].pop("name")), "actor #0 has no 'name'"),
        (bad(lambda s: s["actors"][0].pop("origin")), "robot 'D' has no 'origin'"),
        (
            bad(lambda s: s["actors"][0].update({"robot-config": "robot.jsonc"})),
            "'robot-config' must be the inlined",
        ),
        (
            bad(lambda s: s["actors"][0].update({"origin": {"xyz": "1 2"}})),
            "robot 'D': origin 'xyz' must hold three",
        ),
        (
            bad(lambda s: s["actors"][0].update({"origin": {"geo-point": "1 2"}})),
            "'geo-point' must hold three numbers",
        ),
        (bad(lambda s: s["actors"][0].update({"origin": 5})), "robot 'D' origin must be an object"),
        (bad(lambda s: s["actors"].append(dict(s["actors"][0]))), "duplicate robot names: D"),
        (
            bad(lambda s: s.update(clock={"type": "engine-driven"})),
            "clock type 'engine-driven' is not supported",
        ),
        (bad(lambda s: s.update(clock={"type": "steppable", "step-ns": 0})), "'step-ns' must be positive"),
        (bad(lambda s: s.update(clock=[])), "scene 'clock' must be an object"),
        (
            bad(lambda s: s.update({"home-geo-point": {"latitude": "x"}})),
            "'latitude' must be a finite number",
        ),
        (bad(lambda s: s.update({"home-geo-point": 3})), "'home-geo-point' must be an object"),
        (
            bad(lambda s: s["actors"][0]["robot-config"].update(sensors={})),
            "robot 'D' 'sensors' must be a list",
        ),
        (
            bad(lambda s: set_sensor(s, {"id": "X", "type": "sonar", "enabled": True})),
            "sensor 'X' has unknown type 'sonar'",
        ),
        (bad(lambda s: set_sensor(s, {"type": "gps"})), "robot 'D' sensor has no 'id'"),
        (bad(lambda s: set_sensor(s, 4)), "robot 'D' sensor must be an object"),
        (
            bad(
                lambda s: s["actors"][0]["robot-config"].update(
                    sensors=[{"id": "I", "type": "imu", "enabled": True}] * 2
                )
            ),
            "duplicate sensor ids: I",
        ),
        (
            bad(
                lambda s: set_sensor(
                    s, {"id": "C", "type": "camera", "enabled": True, "capture-settings": [{"image-type": 9}]}
                )
            ),
            r"invalid 'image-type' 9 \(expected 0..6\)",
        ),
        (
            bad(
                lambda s: set_sensor(
                    s, {"id": "C", "type": "camera", "enabled": True, "capture-settings": {}}
                )
            ),
            "'capture-settings' must be a list",
        ),
        (
            bad(
                lambda s: set_sensor(
                    s, {"id": "C", "type": "camera", "enabled": True, "capture-settings": [7]}
                )
            ),
            "capture setting must be an object",
        ),
        (
            bad(
                lambda s: set_sensor(
                    s,
                    {
                        "id": "C",
                        "type": "camera",
                        "enabled": True,
                        "capture-settings": [{"image-type": 0, "width": 0}],
                    },
                )
            ),
            "must have a positive width and height, got 0x144",
        ),
        (
            bad(
                lambda s: set_sensor(
                    s,
                    {
                        "id": "C",
                        "type": "camera",
                        "enabled": True,
                        "capture-settings": [{"image-type": 0, "fov-degrees": 180}],
                    },
                )
            ),
            r"'fov-degrees' must be in \(0, 180\), got 180",
        ),
        (
            bad(
                lambda s: set_sensor(
                    s,
                    {
                        "id": "C",
                        "type": "camera",
                        "enabled": True,
                        "capture-settings": [{"image-type": 4, "max-depth-meters": 0}],
                    },
                )
            ),
            "image-type 4 'max-depth-meters' must be positive, got 0",
        ),
        (
            bad(
                lambda s: set_sensor(s, {"id": "C", "type": "camera", "enabled": True, "capture-interval": 0})
            ),
            "'capture-interval' must be positive, got 0",
        ),
        (
            bad(
                lambda s: set_sensor(
                    s, {"id": "C", "type": "camera", "enabled": True, "capture-interval": "x"}
                )
            ),
            "'capture-interval' must be a finite number, got 'x'",
        ),
        (bad(lambda s: s["actors"][0].update(name="")), "actor #0 'name' must be a non-empty string"),
        (
            bad(
                lambda s: set_sensor(s, {"id": "L", "type": "lidar", "enabled": True, "report-frequency": -1})
            ),
            "sensor 'L' 'report-frequency' must be at least 0, got -1",
        ),
        (
            bad(
                lambda s: set_sensor(
                    s, {"id": "R", "type": "distance-sensor", "enabled": True, "report-frequency": "9"}
                )
            ),
            "sensor 'R' 'report-frequency' must be a finite number, got '9'",
        ),
        (
            bad(
                lambda s: set_sensor(
                    s,
                    {
                        "id": "C",
                        "type": "camera",
                        "enabled": True,
                        "annotation-settings": {
                            "enabled": True,
                            "object-ids": ["A"],
                            "bbox3D-settings": {"alignment": "x"},
                        },
                    },
                )
            ),
            "sensor 'C': 'annotation-settings.bbox3D-settings.alignment' must be 'oriented' or 'axis'",
        ),
        (
            json.dumps(minimal(wind={"velocity": "0 10"})),
            r"scene wind 'velocity' must be three numbers within 200 m/s, got '0 10'",
        ),
        (json.dumps(minimal(wind=[0, 10, 0])), r"scene 'wind' must be an object, got \[0, 10, 0\]"),
        (
            bad(lambda s: s["actors"][0]["robot-config"].update(links=[{"inertial": {"mass": 0}}])),
            r"robot 'D' links\[0\] 'inertial.mass' must be positive, got 0",
        ),
    ],
)
def test_invalid_scenes_are_rejected_with_a_message_saying_what_is_wrong(text, message):
    with pytest.raises(SceneSpecError, match=message):
        parse_scene(text)


def test_max_depth_meters_is_read_per_capture_and_defaults_to_100():
    scene = minimal()
    captures = [{"image-type": 4, "max-depth-meters": 25}, {"image-type": 0}]
    set_sensor(scene, {"id": "C", "type": "camera", "enabled": True, "capture-settings": captures})
    spec = parse_scene(json.dumps(scene))
    settings = {c.image_type: c for c in spec.robots[0].sensors[0].captures}
    assert (settings[4].max_depth_m, settings[0].max_depth_m) == (25.0, 100.0)


def test_the_scenes_wind_and_each_robots_mass_are_read():
    scene = minimal(wind={"velocity": "0.0 10.0 -1.5"})
    scene["actors"][0]["robot-config"]["links"] = [{"inertial": {"mass": 1.0}}, {"inertial": {"mass": 0.25}}]
    spec = parse_scene(json.dumps(scene))
    assert spec.wind == (0.0, 10.0, -1.5)
    assert spec.robots[0].mass_kg == 1.25
    calm = parse_scene(json.dumps(minimal()))
    assert calm.wind == (0.0, 0.0, 0.0) and calm.robots[0].mass_kg == 1.0
