"""Calls the client's example scripts make, driven through the real 1.1.0 client as the scripts drive them:
heading moves, rover controls, battery services, control signals and faults, JSBSim, Step, camera rays,
env actors, geo trajectories and unknown asynchronous calls."""

from __future__ import annotations

import asyncio
import copy
import math
import time

import pytest
from projectairsim import Drone, EnvActor, World
from projectairsim.rover import Rover
from projectairsim.types import Pose

from simserver.clientkit import position, scene_config, settle, subscribe

ROTORS = ["Prop_FR", "Prop_RL", "Prop_FL", "Prop_RR"]


def teleport(robot, x: float, y: float, z: float, yaw: float = 0.0) -> None:
    rotation = {"w": math.cos(yaw / 2), "x": 0.0, "y": 0.0, "z": math.sin(yaw / 2)}
    pose = Pose({"translation": {"x": x, "y": y, "z": z}, "rotation": rotation, "frame_id": "DEFAULT_ID"})
    assert robot.set_pose(pose, True) is True


def yaw_of(robot) -> float:
    rotation = robot.get_ground_truth_pose()["rotation"]
    return 2 * math.atan2(rotation["z"], rotation["w"])


def loaded(client, config: dict) -> World:
    world = World(client)
    world.load_scene(config)
    return world


def drone_scene() -> dict:
    """The sensor drone with four rotors and an env actor added (our robot files have no actuators)."""
    config = copy.deepcopy(scene_config("scene_drone_sensors.jsonc"))
    robot = config["actors"][0]["robot-config"]
    robot["actuators"] = [
        {"name": name, "type": "rotor", "rotor-settings": {"max-rpm": 6000.0}} for name in ROTORS
    ]
    config["environment-actors"] = [
        {"type": "env_actor", "name": "Car1", "origin": {"xyz": "5 5 0"}, "env-actor-config": {}}
    ]
    return config


def rover_scene() -> dict:
    config = copy.deepcopy(scene_config("scene_basic_drone.jsonc"))
    actor = config["actors"][0]
    actor["name"] = "Rover1"
    actor["origin"] = {"xyz": "0 0 0", "rpy-deg": "0 0 0"}
    actor["robot-config"]["controller"] = {"id": "Drive", "type": "simple-drive-api"}
    return config


@pytest.fixture
def drone_world(client):
    world = loaded(client, drone_scene())
    drone = Drone(client, world, "Drone1")
    assert drone.enable_api_control() is True and drone.arm() is True
    return world, drone


def test_move_by_heading_turns_first_then_flies_along_the_heading(drone_world):
    _, drone = drone_world
    teleport(drone, 0.0, 0.0, -10.0)

    async def fly():
        task = await drone.move_by_heading_async(math.pi / 2, 2.0, v_down=-1.0, duration=1.0)
        return await task

    assert asyncio.run(fly()) is True
    assert yaw_of(drone) == pytest.approx(math.pi / 2, abs=math.radians(5))
    x, y, z = position(drone)
    assert x == pytest.approx(0.0, abs=0.1) and y == pytest.approx(2.0, abs=0.1)
    assert z == pytest.approx(-11.0, abs=0.1)


def test_rover_controls_drive_and_steer_and_heading_moves_turn_it(client):
    world = loaded(client, rover_scene())
    rover = Rover(client, world, "Rover1")
    assert rover.enable_api_control() is True and rover.arm() is True

    async def drive():
        assert await (await rover.set_rover_controls(1.0, 0.0, 0.0)) is True
        world.continue_for_sim_time(1_000_000_000, wait_until_complete=True)
        straight = position(rover)
        assert await (await rover.set_rover_controls(1.0, 0.3, 0.0)) is True
        world.continue_for_sim_time(1_000_000_000, wait_until_complete=True)
        turned = yaw_of(rover)
        assert await (await rover.set_rover_controls(0.0, 0.0, 1.0)) is True
        world.continue_for_sim_time(1_000_000_000, wait_until_complete=True)
        stopped = position(rover)
        world.continue_for_sim_time(500_000_000, wait_until_complete=True)
        assert position(rover) == pytest.approx(stopped, abs=1e-6)
        world.resume()  # continue_for leaves the clock paused
        assert await (await rover.move_by_heading_async(-math.pi / 2, 2.0, duration=1.0, yaw_rate=0)) is True
        return straight, turned

    straight, turned = asyncio.run(drive())
    assert straight[0] == pytest.approx(1.0, abs=0.05) and straight[1] == pytest.approx(0.0, abs=1e-6)
    assert turned > 0.2  # positive steering turns right (towards east)
    assert math.remainder(yaw_of(rover) + math.pi / 2, 2 * math.pi) == pytest.approx(0.0, abs=math.radians(5))
    x, y, z = position(rover)
    assert max(abs(x), abs(y)) > 2.0 and z == pytest.approx(0.0, abs=1e-6)  # off the 4 m pad: on the ground


def test_a_rover_spawned_in_the_air_rests_on_the_ground(client):
    config = rover_scene()
    config["actors"][0]["origin"] = {"xyz": "0 0 -10", "rpy-deg": "0 0 0"}
    world = loaded(client, config)
    rover = Rover(client, world, "Rover1")
    assert position(rover) == pytest.approx([0.0, 0.0, -0.02], abs=1e-6)  # on the landing pad at once
    teleport(rover, 20.0, 0.0, -5.0)
    assert position(rover) == pytest.approx([20.0, 0.0, 0.0], abs=1e-6)  # on the ground plane


def test_the_scenes_wind_blows_and_an_external_force_pushes_an_idle_drone(client):
    config = copy.deepcopy(scene_config("scene_basic_drone.jsonc"))
    config["wind"] = {"velocity": "0.0 10.0 0.0"}  # as the client's wind example scene sets it
    world = loaded(client, config)
    drone = Drone(client, world, "Drone1")
    assert world.get_wind_velocity() == (0.0, 10.0, 0.0)
    assert drone.enable_api_control() is True and drone.arm() is True
    world.pause()
    teleport(drone, 0.0, 0.0, -10.0)
    world.continue_for_sim_time(1_000_000_000, wait_until_complete=True)
    assert position(drone) == pytest.approx([0.0, 10.0, -10.0], abs=0.01)
    assert world.set_wind_velocity(0.0, 0.0, 0.0) is True
    assert drone.set_external_force([0.0, -0.3, 0.0]) is True  # on a 1 kg robot: 0.3 m/s
    world.continue_for_sim_time(1_000_000_000, wait_until_complete=True)
    assert position(drone) == pytest.approx([0.0, 9.7, -10.0], abs=0.01)
    assert drone.set_external_force([0.0, 0.0, 0.0]) is True
    world.continue_for_sim_time(500_000_000, wait_until_complete=True)
    assert position(drone) == pytest.approx([0.0, 9.7, -10.0], abs=0.01)
    world.resume()


def test_battery_services_change_what_the_battery_topic_publishes(client, drone_world):
    _, drone = drone_world
    topic = drone.sensors["Battery"]["battery"]
    status = drone.get_battery_state("Battery")
    assert status["battery_charge_state"] == "BATTERY_CHARGE_STATE_OK"
    assert drone.set_battery_remaining(50.0) is True
    assert drone.set_battery_remaining(150.0) is False
    assert drone.set_battery_drain_rate(2.0) is True
    assert drone.get_battery_drain_rate("Battery") == pytest.approx(2.0)
    assert drone.set_battery_drain_rate(-1.0) is False
    inbox = subscribe(client, topic)
    fresh = inbox.wait_for(where=lambda m: m["battery_pct_remaining"] <= 50.0)[-1]
    assert fresh["battery_pct_remaining"] == pytest.approx(50.0, abs=5.0)
    assert drone.set_battery_health_status(False) is True
    inbox.wait_for(where=lambda m: m["battery_charge_state"] == "BATTERY_CHARGE_STATE_UNHEALTHY")
    assert drone.get_battery_state("Battery")["battery_charge_state"] == "BATTERY_CHARGE_STATE_UNHEALTHY"
    assert drone.set_battery_health_status(True) is True
    assert drone.get_battery_state("Battery")["battery_charge_state"] == "BATTERY_CHARGE_STATE_OK"


def test_control_signals_and_faults_show_on_rotor_info(client, drone_world):
    _, drone = drone_world
    inbox = subscribe(client, f"{drone.parent_topic}/rotor_info")
    assert drone.set_control_signals({"Prop_FL": 1.0, "Prop_RR": 0.25}) is True
    assert drone.set_control_signals({"NoSuchRotor": 1.0}) is False
    assert drone.update_actuator_fault_state("Prop_FR", True) is True

    def speeds(message):
        return {r["rotor_id"]: r["speed"] for r in message["rotor_info_vec"]}

    full = 6000.0 * 2 * math.pi / 60
    latest = inbox.wait_for(where=lambda m: speeds(m)["Prop_FR"] == 0.0)[-1]
    assert speeds(latest)["Prop_FL"] == pytest.approx(full)
    assert speeds(latest)["Prop_RR"] == pytest.approx(full / 4)
    assert drone.update_actuator_fault_state("Prop_FR", False) is True
    inbox.wait_for(where=lambda m: speeds(m)["Prop_FR"] > 0.0)


def test_jsbsim_properties_answer_with_a_clear_error(drone_world):
    _, drone = drone_world
    with pytest.raises(RuntimeError, match="no JSBSim model"):
        drone.get_jsbsim_property("velocities/vc-kts")
    with pytest.raises(RuntimeError, match="no JSBSim model"):
        drone.set_jsbsim_property("fcs/throttle-cmd-norm", 1.0)


def test_step_advances_paused_time_and_reports_state_and_collisions(drone_world):
    world, drone = drone_world
    world.pause()
    start = world.get_sim_time()
    result = world.step(30_000_000)
    assert result["sim_time_ns"] == start + 30_000_000 == world.get_sim_time()
    state = result["robots"]["Drone1"]["state"]
    assert state["position"]["z"] == pytest.approx(-4.0)
    assert set(state) == {"position", "orientation", "linear_velocity", "angular_velocity"}
    teleport(drone, 27.5, 0.0, -5.0)  # touching BlockNorth's south face
    world.resume()

    async def push():
        return await (await drone.move_by_velocity_async(1.0, 0.0, 0.0, 0.3))

    asyncio.run(push())
    world.pause()
    events = world.step(3_000_000)["robots"]["Drone1"]["events"]
    assert events and events[0]["type"] == "collision" and events[0]["object_name"] == "BlockNorth"
    assert world.step(3_000_000)["robots"]["Drone1"]["events"] == []
    world.resume()


def test_camera_ray_through_the_centre_pixel_looks_along_the_camera(client, drone_world):
    _, drone = drone_world
    method = f"{drone.parent_topic}/GetCameraRay"
    centre = client.request(
        {"method": method, "params": {"camera_id": "Chase", "image_type": 0, "x": 320, "y": 180}}
    )
    corner = client.request(
        {"method": method, "params": {"camera_id": "Chase", "image_type": 0, "x": 640, "y": 180}}
    )
    assert set(centre) == {"position", "orientation"}
    q = centre["orientation"]
    q2 = corner["orientation"]
    # the right edge of a 90-degree camera is 45 degrees to the right of its centre
    yaw = 2 * math.atan2(q["z"], q["w"])
    yaw2 = 2 * math.atan2(q2["z"], q2["w"])
    assert yaw2 - yaw == pytest.approx(math.pi / 4, abs=1e-3)
    with pytest.raises(RuntimeError, match="no enabled camera"):
        client.request({"method": method, "params": {"camera_id": "Nope", "image_type": 0, "x": 0, "y": 0}})


def test_env_actor_follows_an_imported_trajectory(client, drone_world):
    world, _ = drone_world
    car = EnvActor(client, world, "Car1")
    inbox = subscribe(client, car.actor_info["actual_kinematics"])
    first = inbox.wait_for()[0]["kinematics"]["pose"]["position"]
    assert (first["x"], first["y"]) == (5.0, 5.0)
    times = [0.0, 100.0]
    zeros = [0.0, 0.0]
    world.import_ned_trajectory(
        "line", times, [0.0, 100.0], zeros, zeros, zeros, zeros, zeros, vel_lin_x=[1.0, 1.0]
    )
    car.set_trajectory("line", x_offset=10.0)
    later = inbox.wait_for(where=lambda m: m["kinematics"]["pose"]["position"]["x"] > 10.2)[-1]
    assert later["kinematics"]["twist"]["linear"]["x"] == pytest.approx(1.0)
    car.set_link_rotation_angle("wheel", 30.0)
    with pytest.raises(RuntimeError, match="not found"):
        EnvActor(client, world, "Ghost").set_link_rotation_angle("wheel", 1.0)


def test_geo_coordinates_import_as_a_trajectory_in_ned(client, drone_world):
    world, _ = drone_world
    home = world.home_geo_point
    lat, lon, alt = home["latitude"], home["longitude"], home["altitude"]
    world.import_geo_trajectory(
        "geo", [0.0, 1.0], [lat + 1e-4, lat + 1e-4], [lon, lon], [alt + 5.0, alt + 5.0]
    )
    car = EnvActor(client, world, "Car1")
    inbox = subscribe(client, car.actor_info["actual_kinematics"])
    car.set_trajectory("geo")
    moved = inbox.wait_for(where=lambda m: m["kinematics"]["pose"]["position"]["z"] < -1.0)[-1]
    where = moved["kinematics"]["pose"]["position"]
    assert where["x"] == pytest.approx(11.13, abs=0.05) and where["z"] == pytest.approx(-5.0)


def test_an_unknown_asynchronous_call_is_answered_at_once_with_the_real_error(shared_simserver):
    client = shared_simserver.client()
    request = {"method": "/Sim/SceneBasicDrone/robots/Drone1/MoveByWishes", "params": {}, "version": 1.0}

    async def call():
        task = await client.request_async(request)
        return await asyncio.wait_for(task, 5.0)

    with pytest.raises(RuntimeError, match=r"ERROR code: 1\.0.*is not supported by Request-Response Service"):
        asyncio.run(call())
    # the 1.1.0 client disconnects itself on any async error; the server serves the next client
    again = shared_simserver.client()
    try:
        hash_request = {"method": "/Sim/GetBuildCommitHash", "params": {}, "version": 1.0}
        assert again.request(hash_request) == "airsim-mapper-simserver"
    finally:
        again.disconnect()


def test_visual_and_debug_calls_are_accepted_as_logged_no_ops(shared_simserver, drone_world):
    world, drone = drone_world
    world.plot_debug_points([[0.0, 0.0, -1.0]], [1.0, 0.0, 0.0, 1.0], 5.0, 1.0, False)
    world.flush_persistent_markers()
    world.set_trace_line([1.0, 0.0, 0.0, 1.0], 2.0)
    assert world.set_weather_visual_effects_param(1, 0.5) is True
    assert world.get_weather_visual_effects_param() == {1: 0.5}
    world.set_time_of_day(True, "2024-06-01 18:30:00", False, 1.0, 1.0, True)
    assert world.get_time_of_day() == "2024-06-01 18:30:00"
    assert world.set_sunlight_intensity(3.0) is True and world.get_sunlight_intensity() == 3.0
    teleport(drone, 0.0, 0.0, -10.0)
    world.pause()
    assert world.set_wind_velocity(1.0, 2.0, 0.0) is True
    assert world.get_wind_velocity() == (1.0, 2.0, 0.0)
    world.continue_for_sim_time(1_000_000_000, wait_until_complete=True)
    assert position(drone) == pytest.approx([1.0, 2.0, -10.0], abs=0.01)  # an idle drone drifts
    world.set_wind_velocity(0.0, 0.0, 0.0)
    world.resume()
    assert drone.get_landed_state() in (0, 1)  # the scene is still served
    deadline = time.monotonic() + 5.0
    while "debugPlotPoints ignored" not in shared_simserver.process.output() and time.monotonic() < deadline:
        time.sleep(0.1)
    log = shared_simserver.process.output()
    assert "debugPlotPoints ignored" in log and "SetWindVelocity ignored" in log


def test_takeoff_and_land_take_the_real_controllers_time(drone_world):
    """Takeoff climbs 3 m at 0.5 m/s from where it is; Land descends at 0.2 m/s and confirms for 1 s."""
    world, drone = drone_world
    teleport(drone, 0.0, 0.0, -4.0)
    world.pause()

    async def timed(start_command) -> tuple[bool, float]:
        start = world.get_sim_time()
        task = await start_command()
        while not task.done():
            world.continue_for_sim_time(100_000_000, wait_until_complete=True)
            await asyncio.sleep(0.02)
        return await task, (world.get_sim_time() - start) / 1e9

    ok, up_s = asyncio.run(timed(drone.takeoff_async))
    assert ok is True and position(drone)[2] == pytest.approx(-7.0, abs=0.01)  # from 4 m, not to 3 m
    assert up_s == pytest.approx(6.0, abs=0.15)
    teleport(drone, 0.0, 0.0, -2.02)  # 2 m above the landing pad
    ok, down_s = asyncio.run(timed(drone.land_async))
    assert ok is True and position(drone)[2] == pytest.approx(-0.02, abs=0.01)
    assert down_s == pytest.approx(2.0 / 0.2 + 1.0, abs=0.15)
    assert drone.get_landed_state() == 0
    world.resume()


def test_compress_and_pixels_as_float_are_packed_as_the_real_server_packs_them(client):
    import cv2
    import numpy as np
    from projectairsim.utils import unpack_image

    config = copy.deepcopy(scene_config("scene_drone_sensors.jsonc"))
    down = next(s for s in config["actors"][0]["robot-config"]["sensors"] if s["id"] == "DownCamera")
    settings = {s["image-type"]: s for s in down["capture-settings"]}
    for setting in down["capture-settings"]:
        setting.pop("compress")  # the real server's default is true
    settings[2]["compress"] = False  # depth: float16 whatever pixels-as-float says
    settings[4].update({"compress": False, "pixels-as-float": True})  # colour from the float target: BGR
    settings[6]["pixels-as-float"] = True  # with compress: an unsupported combination, sent empty
    world = loaded(client, config)
    drone = Drone(client, world, "Drone1")
    world.pause()
    inbox = subscribe(client, drone.sensors["DownCamera"]["scene_camera"])
    settle(client, drone.robot_info["actual_pose"])
    world.continue_for_sim_time(200_000_000, wait_until_complete=True)
    published = inbox.wait_for()[-1]
    assert published["encoding"] == "PNG"
    decoded = cv2.imdecode(np.frombuffer(published["data"], dtype=np.uint8), cv2.IMREAD_COLOR)
    images = drone.get_images("DownCamera", [0, 1, 2, 3, 4, 6])
    assert {t: images[t]["encoding"] for t in images} == {
        0: "PNG",
        1: "16FC1",
        2: "16FC1",
        3: "PNG",
        4: "BGR",
        6: "PNG",
    }
    scene = unpack_image(images[0])
    assert scene.shape == decoded.shape == (240, 320, 3)
    assert np.array_equal(scene, decoded)  # lossless, the same paused frame
    assert unpack_image(images[2]).shape == (240, 320) and unpack_image(images[4]).shape == (240, 320, 3)
    # depth with compress, and compress with pixels-as-float: the real server's empty images
    assert images[1]["data"] == [] and images[6]["data"] == []
    world.resume()
