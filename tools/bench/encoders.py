"""Encoder choice for image_transport's `compressed` and `compressedDepth` topics (not a test): CPU per
1080p frame and output size of each candidate library, on a colour frame and a depth frame.

Run: .venv/bin/python -m tools.bench.encoders [--repeat N]

Then the bridge's own converters on the same frames, as the simulator sends them (BGR, float16 depth): CPU
per frame over the library's own encode of the same pixels in the same run, and the bytes on the wire per
transport (the serialised ROS message: raw Image, compressed JPEG and PNG, compressedDepth). `make bench`
runs this part too (`converter_costs`), and judges the JPEG converter's ratio.

The colour frame is a rendered-looking scene (sky gradient, textured ground, boxes, sensor noise); the depth
frame is a ground plane with boxes, 1 to 200 m, quantised as compressed_depth_image_transport does before
its 16-bit PNG. Libraries not installed are left out (simplejpeg is not a dependency: install it
beside the venv to compare, e.g. `pip install --target /tmp/sj simplejpeg` and PYTHONPATH=/tmp/sj).
"""

from __future__ import annotations

import argparse
import functools
import io
import statistics
import time
from collections.abc import Callable

import numpy as np

from airsim_mapper.convert.image_transport import encode_png, quantised_inverse_depth

W, H = 1920, 1080
JPEG_QUALITY = 80  # compressed_image_transport's default
PNG_LEVEL = 1  # compressed_depth_image_transport's default
# the transports' rows, as the converter rows name them
RAW, RAW_DEPTH = "raw Image bgr8", "raw Image 32FC1"
JPEG, PNG, COMPRESSED_DEPTH = "compressed jpeg", "compressed png", "compressedDepth"


def colour_frame() -> np.ndarray:
    rng = np.random.default_rng(0)
    rows = np.linspace(0.0, 1.0, H, dtype=np.float32)[:, None]
    frame = np.empty((H, W, 3), np.float32)
    frame[..., 0] = 200 - 80 * rows  # sky to ground
    frame[..., 1] = 160 - 40 * rows
    frame[..., 2] = 120 + 30 * rows
    ground = slice(H // 2, H)
    frame[ground] += rng.normal(0, 12, (H - H // 2, W, 1)).astype(np.float32)  # texture
    for x in range(100, W - 200, 300):
        frame[400:700, x : x + 150] = (40 + x % 90, 90, 160 - x % 70)
    frame += rng.normal(0, 2, frame.shape).astype(np.float32)  # sensor noise
    return np.clip(frame, 0, 255).astype(np.uint8)


def depth_frame() -> np.ndarray:
    rows = np.arange(H, dtype=np.float32)[:, None] - H / 2 + 0.5
    depth = np.where(rows > 0, 2.0 * (H / 2) / np.maximum(rows, 1e-3), np.inf) * np.ones((1, W), np.float32)
    depth = np.minimum(depth, 200.0).astype(np.float32)
    for x in range(100, W - 200, 300):
        depth[400:700, x : x + 150] = 5.0 + x / 100.0
    return depth


def candidates(bgr: np.ndarray, inverse: np.ndarray) -> dict[str, Callable[[], bytes]]:
    import cv2

    found: dict[str, Callable[[], bytes]] = {
        "jpeg opencv": lambda: cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])[1],
        "png bgr8 opencv": lambda: cv2.imencode(".png", bgr, [cv2.IMWRITE_PNG_COMPRESSION, PNG_LEVEL])[1],
        "depth png16 opencv": lambda: cv2.imencode(".png", inverse, [cv2.IMWRITE_PNG_COMPRESSION, PNG_LEVEL])[
            1
        ],
        "depth png16 zlib (ours)": lambda: encode_png(inverse, PNG_LEVEL),
        "png bgr8 zlib (ours)": lambda: encode_png(bgr, PNG_LEVEL),
    }
    try:
        from PIL import Image
    except ImportError:
        Image = None
    if Image is not None:

        def pillow(image: Image.Image, **options: object) -> Callable[[], bytes]:
            def encode() -> bytes:
                out = io.BytesIO()
                image.save(out, **options)
                return out.getvalue()

            return encode

        rgb = Image.fromarray(np.ascontiguousarray(bgr[..., ::-1]))
        found["jpeg pillow"] = pillow(rgb, format="JPEG", quality=JPEG_QUALITY)
        found["depth png16 pillow"] = pillow(Image.fromarray(inverse), format="PNG", compress_level=PNG_LEVEL)
    try:
        import simplejpeg
    except ImportError:
        simplejpeg = None
    if simplejpeg is not None:
        found["jpeg simplejpeg"] = lambda: simplejpeg.encode_jpeg(
            bgr, quality=JPEG_QUALITY, colorspace="BGR", colorsubsampling="420"
        )
    return found


def cpu_ms(encode: Callable[[], object], repeat: int) -> tuple[float, object]:
    """(median thread CPU ms, the output) over `repeat` encodes after one warm-up."""
    out = encode()
    times = []
    for _ in range(repeat):
        start = time.thread_time()
        encode()
        times.append((time.thread_time() - start) * 1e3)
    return statistics.median(times), out


def paired_ms(first: Callable[[], object], second: Callable[[], object], repeat: int) -> tuple[float, float]:
    """Median thread CPU ms of two callables run alternately, so that both see the same host."""
    first(), second()
    times: tuple[list[float], list[float]] = ([], [])
    for _ in range(repeat):
        for fn, kept in ((first, times[0]), (second, times[1])):
            start = time.thread_time()
            fn()
            kept.append((time.thread_time() - start) * 1e3)
    return statistics.median(times[0]), statistics.median(times[1])


def wire_bytes(message: object) -> int:
    buffer = io.BytesIO()
    message.serialize(buffer)
    return len(buffer.getvalue())


def converter_costs(repeat: int, bgr: np.ndarray | None = None, depth: np.ndarray | None = None) -> dict:
    """Per transport, the bridge's converter on one 1080p frame as the simulator sends it (BGR, float16
    depth): its CPU ms per frame (`converter_ms`), the library's own encode of the same pixels timed in
    turn with it (`library_ms`, `ratio`; none for the raw images) and the bytes on the wire (`wire_bytes`,
    the serialised ROS message). OpenCV on one thread, as one worker encodes."""
    import cv2

    from airsim_mapper.convert import image_transport, registry
    from airsim_mapper.convert.context import ConvertContext

    cv2.setNumThreads(1)
    bgr = colour_frame() if bgr is None else bgr
    depth = depth_frame() if depth is None else depth
    half = depth.astype("<f2")
    colour_msg = {"time_stamp": 1, "width": W, "height": H, "encoding": "BGR", "data": bgr.tobytes()}
    depth_msg = {"time_stamp": 1, "width": W, "height": H, "encoding": "16FC1", "data": half.tobytes()}
    metres = half.astype(np.float32)
    params = {"depth_max": 100.0, "depth_quantization": 100.0, "png_level": PNG_LEVEL}
    rows = [
        (RAW, "image", colour_msg, {}, None),
        (RAW_DEPTH, "image", depth_msg, {}, None),
        (JPEG, "image_compressed", colour_msg, {}, lambda: image_transport.encode_jpeg(bgr)),
        (
            PNG,
            "image_compressed",
            colour_msg,
            {"format": "png", "png_level": PNG_LEVEL},
            lambda: image_transport.encode_png(bgr, PNG_LEVEL),
        ),
        (
            COMPRESSED_DEPTH,
            "image_compressed_depth",
            depth_msg,
            params,
            lambda: image_transport.compressed_depth(metres, 100.0, 100.0, PNG_LEVEL).data,
        ),
    ]
    out: dict[str, dict] = {}
    for name, converter, message, rule_params, library in rows:
        convert = registry.get(converter)
        ctx = ConvertContext(frame_id="bench", params=rule_params)
        row: dict = {"wire_bytes": wire_bytes(convert(message, ctx))}
        run = functools.partial(convert, message, ctx)
        if library is None:
            row["converter_ms"], _out = cpu_ms(run, repeat)
        else:
            row["converter_ms"], row["library_ms"] = paired_ms(run, library, repeat)
            row["ratio"] = row["converter_ms"] / row["library_ms"] if row["library_ms"] > 0 else None
        out[name] = row
    return out


def converter_table(costs: dict) -> str:
    """The converters' rows: CPU per frame, the library's own and their ratio, and the bytes on the wire."""
    lines = [
        f"{'1080p transport':<22} {'converter ms':>12} {'library ms':>10} {'ratio':>6} {'wire bytes':>11}"
    ]
    for name, row in costs.items():
        own = f"{row['library_ms']:10.2f}" if "library_ms" in row else f"{'':>10}"
        times = f"{row['ratio']:6.2f}" if row.get("ratio") is not None else f"{'':>6}"
        lines.append(f"{name:<22} {row['converter_ms']:12.2f} {own} {times} {row['wire_bytes']:11d}")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=30)
    args = parser.parse_args()
    import cv2

    cv2.setNumThreads(1)  # one worker thread's cost
    bgr = colour_frame()
    depth = depth_frame()
    inverse, _a, _b = quantised_inverse_depth(depth, depth_max=100.0, depth_quantization=100.0)
    quantise_ms, _size = cpu_ms(
        lambda: quantised_inverse_depth(depth, 100.0, 100.0)[0].tobytes(), args.repeat
    )
    print(f"1080p frames; raw bgr8 {bgr.nbytes} bytes, raw 32FC1 {W * H * 4} bytes")
    print(f"{'encoder':<26} {'CPU ms':>8} {'bytes':>10}")
    for name, encode in candidates(bgr, inverse).items():
        ms, out = cpu_ms(encode, args.repeat)
        print(f"{name:<26} {ms:8.2f} {len(out):10d}")
    print(f"{'depth quantisation':<26} {quantise_ms:8.2f}")
    print()
    print(converter_table(converter_costs(args.repeat, bgr, depth)))


if __name__ == "__main__":
    main()
