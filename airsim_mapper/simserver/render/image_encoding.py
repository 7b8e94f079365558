"""How a rendered frame goes on the wire: `compress` and `pixels-as-float` as the real server packs them.

The 1.1.0-era server (Unreal plugin `ImagePackingAsyncTask.cpp`, the float16-depth version the 1.1.0 client
decodes) chooses by image kind and the capture setting's two flags:

| kind      | compress | pixels-as-float | encoding | data                                            |
|-----------|----------|-----------------|----------|-------------------------------------------------|
| depth 1,2 | false    | either          | `16FC1`  | float16 metres (the flag is ignored)             |
| depth 1,2 | true     | either          | `16FC1`  | empty: "unsupported combination" (a warning)      |
| colour    | false    | false           | `BGR`    | 8-bit B, G, R                                    |
| colour    | true     | false           | `PNG`    | lossless PNG of the BGR frame                    |
| colour    | false    | true            | `BGR`    | the float colour target as uint8(v * 255)        |
| colour    | true     | true            | `PNG`    | empty: "unsupported combination" (a warning)      |

So `pixels-as-float` never changes the encoding: colour frames read from the float render target are
truncated back to 8 bits, which for this renderer's 8-bit colours gives the same bytes. The two empty
cases are reproduced (the 1.1.0 client's `unpack_image` cannot reshape them; neither can it on the real
server); `unsupported_combination` names them so the scene loader can warn once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from airsim_mapper.simserver.errors import SimServerError

DEPTH_TYPES = frozenset({1, 2})


class EncodingError(SimServerError, RuntimeError):
    """PNG encoding of a frame failed."""


@dataclass(frozen=True)
class WireImage:
    encoding: str
    data: bytes


def unsupported_combination(image_type: int, compress: bool, pixels_as_float: bool) -> str | None:
    """Why the real server sends an empty image for this capture setting, or None if it sends pixels."""
    if image_type in DEPTH_TYPES and compress:
        return "depth images cannot be compressed ('compress': true): the real server sends them empty"
    if image_type not in DEPTH_TYPES and compress and pixels_as_float:
        return "'compress' and 'pixels-as-float' together are unsupported: the real server sends empty PNGs"
    return None


def png_bytes(bgr: bytes, width: int, height: int) -> bytes:
    """A BGR buffer as lossless PNG."""
    import cv2

    ok, encoded = cv2.imencode(".png", np.frombuffer(bgr, dtype=np.uint8).reshape(height, width, 3))
    if not ok:
        raise EncodingError(f"PNG encoding of a {width}x{height} frame failed")
    return encoded.tobytes()


def wire_image(
    image_type: int,
    encoding: str,
    data: bytes,
    width: int,
    height: int,
    compress: bool,
    pixels_as_float: bool,
) -> WireImage:
    """The (encoding, data) the real server sends for a rendered frame (`BGR` or `16FC1`) of this type."""
    if image_type in DEPTH_TYPES:
        return WireImage("16FC1", b"" if compress else data)
    if compress:
        return WireImage("PNG", b"" if pixels_as_float else png_bytes(data, width, height))
    return WireImage(encoding, data)
