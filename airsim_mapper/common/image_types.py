"""Project AirSim's camera image types: one table for the simulator's topic leaves, one for the ROS names.

The two differ only for type 6: the simulator publishes `surface_normals_camera`, while the Project AirSim
ROS bridge documentation (and so the default mapping) calls the ROS side `surface_normals`.
"""

from __future__ import annotations

# image-type id -> the simulator's topic leaf (protocol.md section 4); `<leaf>_info` is its CameraInfo topic
SIM_IMAGE_LEAVES: dict[int, str] = {
    0: "scene_camera",
    1: "depth_planar_camera",
    2: "depth_camera",
    3: "segmentation_camera",
    4: "depth_vis_camera",
    5: "disparity_normalized_camera",
    6: "surface_normals_camera",
}

# image-type id -> <image_type> in ROS names, as the table of the Project AirSim ROS bridge documentation
# gives it (a mapping may override it)
DOCUMENTED_IMAGE_TYPES: dict[int, str] = {**SIM_IMAGE_LEAVES, 6: "surface_normals"}

# image-type ids whose pixels are float depth in metres (the simulator sends float16, the bridge 32FC1); every
# other type is 8-bit colour
FLOAT_IMAGE_TYPES = frozenset({1, 2})
