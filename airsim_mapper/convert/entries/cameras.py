"""The catalogue's camera entries: images, compressed images, image_transport's encoded siblings, camera
info, and the streaming camera's image (which the catalogue lists after the instruments)."""

from __future__ import annotations

from airsim_mapper.convert.entries.model import (
    COLOUR,
    FLOAT,
    PUBLISH,
    SENSOR_DATA,
    SIM_TO_ROS,
    STAMP,
    STREAM,
    Example,
    converter_info,
)

# a 1x1 PNG of one black pixel, as the simulator sends a compressed colour image
PNG_1X1 = bytes.fromhex(
    "89504e470d0a1a0a0000000d4948445200000001000000010802000000907753de"
    "0000000a49444154081d63000200000400010d3ba4b90000000049454e44ae426082"
)

IMAGES = (
    converter_info(
        "image",
        SIM_TO_ROS,
        ["sensor_msgs/Image"],
        PUBLISH,
        "image",
        "image",
        "sim Image (BGR, PNG, 16FC1, 16UC1, GRAY8) -> Image (bgr8, 32FC1 metres, mono8)",
        qos=SENSOR_DATA,
        example=Example({**STAMP, "width": 2, "height": 1, "encoding": "BGR", "data": bytes(6)}),
        max_pixels=True,
    ),
    converter_info(
        "compressed_image",
        SIM_TO_ROS,
        ["sensor_msgs/CompressedImage"],
        PUBLISH,
        "compressed_image",
        "compressed_image",
        "sim Image sent as PNG (capture setting compress: true) -> CompressedImage of those bytes, "
        "format 'bgr8; png compressed bgr8' (image_transport's compressed transport)",
        qos=SENSOR_DATA,
        example=Example({**STAMP, "width": 1, "height": 1, "encoding": "PNG", "data": PNG_1X1}),
        max_pixels=True,
    ),
    # image_transport's sibling topics, encoded here (convert/encoded_image.py)
    converter_info(
        "image_compressed",
        SIM_TO_ROS,
        ["sensor_msgs/CompressedImage"],
        PUBLISH,
        "encoded_image",
        "image_compressed",
        "sim colour Image -> CompressedImage as image_transport's compressed transport writes it: "
        "params.format jpeg (jpeg_quality, default 80) or png (png_level, default 9)",
        qos=SENSOR_DATA,
        example=Example({**STAMP, "width": 2, "height": 1, "encoding": "BGR", "data": bytes(6)}),
        max_pixels=True,
        param_choices={"format": {"jpeg": "", "png": ""}},  # the default first
        image_kind=COLOUR,
    ),
    converter_info(
        "image_compressed_depth",
        SIM_TO_ROS,
        ["sensor_msgs/CompressedImage"],
        PUBLISH,
        "encoded_image",
        "image_compressed_depth",
        "sim depth Image -> CompressedImage as image_transport's compressedDepth transport writes it "
        "(quantised inverse depth in a 16-bit PNG: depth_max, depth_quantization, png_level)",
        qos=SENSOR_DATA,
        example=Example({**STAMP, "width": 1, "height": 1, "encoding": "16FC1", "data": bytes(2)}),
        max_pixels=True,
        image_kind=FLOAT,
    ),
    converter_info(
        "camera_info",
        SIM_TO_ROS,
        ["sensor_msgs/CameraInfo"],
        PUBLISH,
        "camera_info",
        "camera_info",
        "sim Image (for its size and stamp) + capture settings -> CameraInfo (plumb_bob, K, P from fov)",
        qos=SENSOR_DATA,
        example=Example({**STAMP, "width": 2, "height": 1}),
    ),
)

STREAMING_IMAGE = converter_info(
    "streaming_image",
    SIM_TO_ROS,
    ["sensor_msgs/Image"],
    STREAM,
    "image",
    "image",
    "the active streaming camera's scene image (the engine follows switch_view)",
    qos=SENSOR_DATA,
    example=Example({**STAMP, "width": 1, "height": 1, "encoding": "16FC1", "data": bytes(2)}),
    max_pixels=True,
)
