"""`compress` x `pixels-as-float` per image kind, as the real server packs frames (image_encoding.py)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from airsim_mapper.simserver.render.image_encoding import unsupported_combination, wire_image

W, H = 4, 3
BGR = np.arange(W * H * 3, dtype=np.uint8).tobytes()
DEPTH = np.linspace(1.0, 12.0, W * H).astype("<f2").tobytes()


@pytest.mark.parametrize("image_type", [0, 3, 4, 5, 6])
def test_colour_types_are_bgr_or_png_and_pixels_as_float_alone_changes_nothing(image_type):
    assert wire_image(image_type, "BGR", BGR, W, H, False, False) == wire_image(
        image_type, "BGR", BGR, W, H, False, True
    )
    raw = wire_image(image_type, "BGR", BGR, W, H, False, True)
    assert (raw.encoding, raw.data) == ("BGR", BGR)
    png = wire_image(image_type, "BGR", BGR, W, H, True, False)
    assert png.encoding == "PNG"
    decoded = cv2.imdecode(np.frombuffer(png.data, np.uint8), cv2.IMREAD_COLOR)
    assert decoded.tobytes() == BGR  # lossless


@pytest.mark.parametrize("image_type", [1, 2])
@pytest.mark.parametrize("as_float", [False, True])
def test_depth_is_float16_whatever_pixels_as_float_says(image_type, as_float):
    wire = wire_image(image_type, "16FC1", DEPTH, W, H, False, as_float)
    assert (wire.encoding, wire.data) == ("16FC1", DEPTH)
    assert unsupported_combination(image_type, False, as_float) is None


@pytest.mark.parametrize(
    ("image_type", "compress", "as_float", "encoding"),
    [(1, True, False, "16FC1"), (2, True, True, "16FC1"), (0, True, True, "PNG"), (3, True, True, "PNG")],
)
def test_the_real_servers_unsupported_combinations_send_empty_data(image_type, compress, as_float, encoding):
    frame = DEPTH if image_type in (1, 2) else BGR
    wire = wire_image(image_type, "16FC1" if image_type in (1, 2) else "BGR", frame, W, H, compress, as_float)
    assert (wire.encoding, wire.data) == (encoding, b"")
    assert "real server sends" in unsupported_combination(image_type, compress, as_float)


def test_supported_colour_combinations_have_no_warning():
    assert [unsupported_combination(0, c, f) for c, f in ((False, False), (True, False), (False, True))] == [
        None
    ] * 3
