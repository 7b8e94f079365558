"""The catalogue's lidar and radar entries: point clouds, radar scans and radar tracks."""

from __future__ import annotations

from airsim_mapper.convert.entries.model import (
    PUBLISH,
    SENSOR_DATA,
    SIM_TO_ROS,
    STAMP,
    Example,
    converter_info,
)

SCANS = (
    converter_info(
        "pointcloud",
        SIM_TO_ROS,
        ["sensor_msgs/PointCloud2"],
        PUBLISH,
        "pointcloud",
        "pointcloud",
        "sim Lidar -> PointCloud2 with x, y, z, intensity, segmentation",
        qos=SENSOR_DATA,
        example=Example(
            {
                **STAMP,
                "point_cloud": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
                "intensity_cloud": [0.5, 0.25],
                "segmentation_cloud": [1, 2],
            }
        ),
    ),
    converter_info(
        "radar_scan",
        SIM_TO_ROS,
        ["radar_msgs/RadarScan"],
        PUBLISH,
        "radar",
        "radar_scan",
        "sim RadarDetection -> RadarScan (range, azimuth, elevation, doppler, amplitude dB from rcs)",
        qos=SENSOR_DATA,
        example=Example(
            {
                **STAMP,
                "radar_detections": [
                    {"range": 1.0, "azimuth": 0.1, "elevation": 0.0, "velocity": 0.0, "rcs_sqm": 1.0}
                ],
            }
        ),
    ),
    converter_info(
        "radar_tracks",
        SIM_TO_ROS,
        ["radar_msgs/RadarTracks"],
        PUBLISH,
        "radar",
        "radar_tracks",
        "sim RadarTrack -> RadarTracks (uuid from id, position, velocity, acceleration)",
        qos=SENSOR_DATA,
        example=Example(
            {
                **STAMP,
                "radar_tracks": [
                    {
                        "id": 3,
                        "position_est": {"x": 1.0, "y": 0.0, "z": 0.0},
                        "velocity_est": {"x": 0.0, "y": 0.0, "z": 0.0},
                        "accel_est": {"x": 0.0, "y": 0.0, "z": 0.0},
                    }
                ],
            }
        ),
    ),
)
