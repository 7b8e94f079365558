"""Camera rendering with OpenGL (moderngl): the seven image types of `camera_model` in one rasterising pass.

One standalone context per process, made on first use: headless EGL (Mesa's llvmpipe on a machine without
a GPU, multi-threaded; a GPU's driver where there is one). Boxes are their 12 triangles, spheres are drawn
as their bounding cubes and solved per fragment, and the ground and sky are a full-screen pass drawn last
(`gl_shaders.py`; docs/rendering.md).
Each requested image type is one colour attachment of the same framebuffer, written by the same fragment,
and read back as the exact bytes the ray caster (`raycast_renderer`) produces (same pinhole, shading,
palette and encodings); tests/simserver/test_gl_renderer.py compares the two pixel by pixel.

`GLUnavailable` is raised when no OpenGL 4.1 context can be made (no EGL library, no driver) or the
shaders do not compile on it; `rendering.render` then falls back to the ray caster.
"""

from __future__ import annotations

import os
import threading
from dataclasses import dataclass
from typing import Any

import numpy as np

from airsim_mapper.common.geometry import quat_to_matrix
from airsim_mapper.simserver.errors import SimServerError
from airsim_mapper.simserver.render import camera_model, gl_shaders
from airsim_mapper.simserver.render.camera_model import RenderedImage, RenderRequest
from airsim_mapper.simserver.world.world import World

FRONT_FACE = "cw"  # counter-clockwise in NED appears clockwise in the window (image rows run down)
GL_VERSION = 410  # the shaders' #version
NEAR_CLIP = 1e-3  # metres; geometry closer than this to the camera is clipped
# image type -> (fragment output name, float depth?)
OUTPUTS = {
    camera_model.SCENE: ("scene", False),
    camera_model.DEPTH_PLANAR: ("planar", True),
    camera_model.DEPTH_PERSPECTIVE: ("perspective", True),
    camera_model.SEGMENTATION: ("segmentation", False),
    camera_model.DEPTH_VIS: ("depth_vis", False),
    camera_model.DISPARITY_NORMALIZED: ("disparity", False),
    camera_model.SURFACE_NORMALS: ("normals", False),
}
_CACHE_LIMIT = 16  # framebuffers (per size and type set) and scenes kept per process


class GLUnavailable(SimServerError, RuntimeError):
    """No OpenGL context can be made in this process (the message says why)."""


class GLRenderError(SimServerError, RuntimeError):
    """OpenGL refused one render (e.g. a size beyond the driver's limit); the context stays usable."""


@dataclass(frozen=True)
class _Scene:
    """A world's geometry in GL buffers, and the ground's per-image constants."""

    boxes: Any  # moderngl.Buffer or None
    box_vertices: int
    spheres: Any
    sphere_vertices: int
    ground_shade: tuple[float, float, float]
    ground_segment_bgr: tuple[float, float, float]
    ground_normal_bgr: tuple[float, float, float]
    sky_bgr: tuple[float, float, float]


def _face_constants(world: World) -> tuple[np.ndarray, np.ndarray]:
    """(3, F) lit colours and (3, F) normal colours per face code (float32), as the ray caster has them."""
    shade, normal_bgr = camera_model.face_constants(world)
    return shade, normal_bgr.astype(np.float32)


# the 2 triangles of a cube face: corner signs along the face's two other axes
_QUAD = ((-1, -1), (1, -1), (1, 1), (-1, -1), (1, 1), (-1, 1))


def _cube(center: np.ndarray, axes: np.ndarray, half: np.ndarray) -> list[tuple[int, np.ndarray]]:
    """The 36 corner positions of a box, as (face 0-5: -x, +x, -y, +y, -z, +z, position) pairs; every
    triangle winds counter-clockwise seen from outside (right-handed, as NED is)."""
    out = []
    for axis in range(3):
        a, b = (axis + 1) % 3, (axis + 2) % 3
        for side, sign in enumerate((-1.0, 1.0)):
            quad = _QUAD if sign > 0 else tuple((sb, sa) for sa, sb in _QUAD)  # outward: (a x b) . n > 0
            for sa, sb in quad:
                local = np.zeros(3)
                local[axis], local[a], local[b] = sign * half[axis], sa * half[a], sb * half[b]
                out.append((2 * axis + side, center + axes.T @ local))
    return out


def _box_rows(world: World) -> np.ndarray:
    """(36 B, 15) float32 vertex rows: position, face normal, lit colour, normal colour, segment colour."""
    normals, _ = world.face_table
    shade, normal_bgr = _face_constants(world)
    palette = camera_model.segmentation_palette().astype(np.float32)
    rows = []
    boxes = [o for o in world.objects if o.shape == "box"]
    for b, obj in enumerate(boxes):
        cos, sin = np.cos(obj.yaw), np.sin(obj.yaw)
        axes = np.array([[cos, sin, 0.0], [-sin, cos, 0.0], [0.0, 0.0, 1.0]])
        segment = palette[obj.segmentation_id & 255]
        for face, position in _cube(np.asarray(obj.center, float), axes, np.asarray(obj.size, float) / 2):
            code = 2 + 6 * b + face
            rows.append(
                np.concatenate([position, normals[:, code], shade[:, code], normal_bgr[:, code], segment])
            )
    return np.array(rows, dtype=np.float32).reshape(-1, 15)


def _sphere_rows(world: World) -> np.ndarray:
    """(36 S, 13) float32 vertex rows: bounding-cube position, centre and radius, base colour, segment."""
    palette = camera_model.segmentation_palette().astype(np.float32)
    rows = []
    for obj in world.objects:
        if obj.shape != "sphere":
            continue
        radius = float(obj.size[0]) / 2.0
        center = np.asarray(obj.center, float)
        sphere = [*center, radius]
        extra = [*sphere, *obj.color_bgr, *palette[obj.segmentation_id & 255]]
        for _, position in _cube(center, np.eye(3), np.full(3, radius * 1.01)):
            rows.append([*position, *extra])
    return np.array(rows, dtype=np.float32).reshape(-1, 13)


def clip_from_world(
    position: np.ndarray, rotation: np.ndarray, width: int, height: int, fov_deg: float, far: float
) -> np.ndarray:
    """4x4 (float64) from world NED to clip space; window (x, y) = (column + 0.5, row + 0.5) of the pixel
    whose ray `camera_model.camera_rays` gives (so image row 0 is the first row glReadPixels returns)."""
    f = camera_model.focal_length(width, fov_deg)
    n = NEAR_CLIP
    # camera frame (forward x, right y, down z) -> clip; w_clip = forward distance
    proj = np.array(
        [
            [1.0 / width, 2.0 * f / width, 0.0, 0.0],
            [1.0 / height, 0.0, 2.0 * f / height, 0.0],
            [(far + n) / (far - n), 0.0, 0.0, -2.0 * far * n / (far - n)],
            [1.0, 0.0, 0.0, 0.0],
        ]
    )
    view = np.eye(4)
    view[:3, :3] = rotation.T
    view[:3, 3] = -rotation.T @ position
    return proj @ view


# vertex rows: (attribute, float count) in buffer order
_BOX_ATTRIBUTES = (
    ("position", 3),
    ("face_normal", 3),
    ("face_shade", 3),
    ("face_normal_bgr", 3),
    ("face_segment_bgr", 3),
)
_SPHERE_ATTRIBUTES = (("position", 3), ("sphere", 4), ("base_bgr", 3), ("face_segment_bgr", 3))


def _layout(program: Any, buffer: Any, attributes: tuple[tuple[str, int], ...]) -> tuple:
    """A moderngl buffer binding that skips the attributes the program's compiler optimised away."""
    formats, names = [], []
    for name, count in attributes:
        if name in program:
            formats.append(f"{count}f")
            names.append(name)
        else:
            formats.append(f"{count}x4")
    return (buffer, " ".join(formats), *names)


class GLRenderer:
    """The renderer of one process: its context, compiled programs, framebuffers and world buffers."""

    def __init__(self) -> None:
        try:
            import moderngl

            backend = os.environ.get("AIRSIM_MAPPER_GL_BACKEND", "egl")
            self.ctx = moderngl.create_standalone_context(backend=backend, require=GL_VERSION)
        except Exception as exc:  # ImportError, or glcontext's errors when EGL or a driver is missing
            raise GLUnavailable(f"cannot create an OpenGL {GL_VERSION / 100:g} context: {exc}") from exc
        self.description = f"{self.ctx.info['GL_RENDERER']}, {self.ctx.info['GL_VERSION']}"
        self._programs: dict[tuple[int, ...], dict[str, Any]] = {}
        try:  # every output at once: a driver that cannot compile the shaders is found here, not mid-run
            with self.ctx:
                self._program_set(tuple(OUTPUTS))
        except Exception as exc:
            raise GLUnavailable(f"the camera shaders do not compile on {self.description}: {exc}") from exc
        self._framebuffers: dict[tuple[int, int, tuple[int, ...]], Any] = {}
        self._depth: dict[tuple[int, int], Any] = {}
        self._scenes: dict[int, tuple[World, _Scene]] = {}
        self._arrays: dict[tuple[int, tuple[int, ...]], tuple[Any, Any, Any]] = {}

    # -- resources, made on first use and kept

    def _program_set(self, kinds: tuple[int, ...]) -> dict[str, Any]:
        programs = self._programs.get(kinds)
        if programs is None:
            defines = "".join(f"#define WANT_{OUTPUTS[k][0].upper()}\n" for k in kinds)
            outputs = "".join(
                f"layout(location = {i}) out {'float' if OUTPUTS[k][1] else 'uvec4'} out_{OUTPUTS[k][0]};\n"
                for i, k in enumerate(kinds)
            )
            common = gl_shaders.HEADER + defines + gl_shaders.FRAGMENT_COMMON.replace("OUTPUTS", outputs)

            def build(vertex: str, fragment: str) -> Any:
                return self.ctx.program(
                    vertex_shader=gl_shaders.HEADER + vertex, fragment_shader=common + fragment
                )

            programs = {
                "ground": build(gl_shaders.VERTEX_GROUND, gl_shaders.FRAGMENT_GROUND),
                "box": build(gl_shaders.VERTEX_BOX, gl_shaders.FRAGMENT_BOX),
                "sphere": build(gl_shaders.VERTEX_SPHERE, gl_shaders.FRAGMENT_SPHERE),
            }
            self._programs[kinds] = programs
        return programs

    def _scene(self, world: World) -> _Scene:
        cached = self._scenes.get(id(world))
        if cached is not None and cached[0] is world:
            return cached[1]
        if len(self._scenes) >= _CACHE_LIMIT:
            self._release_scenes()
        boxes, spheres = _box_rows(world), _sphere_rows(world)
        shade, normal_bgr = _face_constants(world)
        palette = camera_model.segmentation_palette()
        scene = _Scene(
            boxes=self.ctx.buffer(boxes.tobytes()) if len(boxes) else None,
            box_vertices=len(boxes),
            spheres=self.ctx.buffer(spheres.tobytes()) if len(spheres) else None,
            sphere_vertices=len(spheres),
            ground_shade=tuple(float(c) for c in shade[:, 1]),
            ground_segment_bgr=tuple(float(c) for c in palette[world.ground_segmentation_id & 255]),
            ground_normal_bgr=tuple(float(c) for c in normal_bgr[:, 1]),
            sky_bgr=tuple(float(c) for c in world.sky_color_bgr),
        )
        self._scenes[id(world)] = (world, scene)
        return scene

    def _release_scenes(self) -> None:
        for vaos in self._arrays.values():
            for vao in vaos:
                if vao is not None:
                    vao.release()
        self._arrays.clear()
        for _, scene in self._scenes.values():
            for buffer in (scene.boxes, scene.spheres):
                if buffer is not None:
                    buffer.release()
        self._scenes.clear()

    def _vertex_arrays(self, world: World, scene: _Scene, kinds: tuple[int, ...]) -> tuple[Any, Any, Any]:
        key = (id(world), kinds)
        arrays = self._arrays.get(key)
        if arrays is None:
            programs = self._program_set(kinds)
            ground = self.ctx.vertex_array(programs["ground"], [])
            box = sphere = None
            if scene.boxes is not None:
                box = self.ctx.vertex_array(
                    programs["box"], [_layout(programs["box"], scene.boxes, _BOX_ATTRIBUTES)]
                )
            if scene.spheres is not None:
                sphere = self.ctx.vertex_array(
                    programs["sphere"], [_layout(programs["sphere"], scene.spheres, _SPHERE_ATTRIBUTES)]
                )
            arrays = self._arrays[key] = (ground, box, sphere)
        return arrays

    def _framebuffer(self, width: int, height: int, kinds: tuple[int, ...]) -> Any:
        key = (width, height, kinds)
        fbo = self._framebuffers.get(key)
        if fbo is None:
            if len(self._framebuffers) >= _CACHE_LIMIT:
                for old in self._framebuffers.values():
                    for attachment in old.color_attachments:
                        attachment.release()
                    old.release()
                self._framebuffers.clear()
                for depth in self._depth.values():
                    depth.release()
                self._depth.clear()
            depth = self._depth.get((width, height))
            if depth is None:
                depth = self._depth[(width, height)] = self.ctx.depth_renderbuffer((width, height))
            colors = [
                self.ctx.renderbuffer((width, height), 1, dtype="f2")
                if OUTPUTS[k][1]
                else self.ctx.renderbuffer((width, height), 4, dtype="u1")
                for k in kinds
            ]
            try:
                fbo = self._framebuffers[key] = self.ctx.framebuffer(colors, depth)
            except Exception:  # e.g. a size beyond the driver's limit: keep nothing of it
                for attachment in (*colors, self._depth.pop((width, height))):
                    attachment.release()
                raise
        return fbo

    # -- rendering

    def draw(self, world: World, request: RenderRequest, kinds: tuple[int, ...]) -> Any:
        """Render `kinds` (the request's image types, sorted) into their framebuffer, which is returned for
        reading (with the context current in this thread)."""
        import moderngl

        width, height, fov_deg = request.width, request.height, request.fov_deg
        max_distance = request.max_distance

        scene = self._scene(world)
        ground, box, sphere = self._vertex_arrays(world, scene, kinds)
        rotation = quat_to_matrix(np.asarray(request.orientation, dtype=float))
        eye = np.asarray(request.position, dtype=float).reshape(3)
        clip = clip_from_world(eye, rotation, width, height, fov_deg, 2.0 * max_distance)
        f = camera_model.focal_length(width, fov_deg)
        # window (x, y) is pixel (x - 0.5, y - 0.5), whose camera ray is (1, (u - w/2) / f, (v - h/2) / f)
        uniforms = {
            "eye": tuple(eye.astype(np.float32)),
            "ray0": tuple(rotation @ [1.0, -(width / 2.0 + 0.5) / f, -(height / 2.0 + 0.5) / f]),
            "ray_x": tuple(rotation[:, 1] / f),
            "ray_y": tuple(rotation[:, 2] / f),
            "window": (float(width), float(height)),
            "axis": tuple(rotation[:, 0]),
            "max_distance": float(max_distance),
            "max_depth_vis": float(request.max_depth_vis),
            "sky_bgr": scene.sky_bgr,
            "sun": tuple(camera_model.sun()),
            "clip_from_world": tuple(clip.astype(np.float32).T.ravel()),
            "ground_shade": scene.ground_shade,
            "ground_segment_bgr": scene.ground_segment_bgr,
            "ground_normal_bgr": scene.ground_normal_bgr,
        }
        fbo = self._framebuffer(width, height, kinds)
        fbo.use()
        fbo.clear(depth=1.0)
        self.ctx.enable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        self.ctx.depth_func = "<"
        self.ctx.front_face = FRONT_FACE
        # objects first (they write their exact depth); then the ground and sky where no object was drawn,
        # at a constant depth behind every object, so the depth test skips its shader on covered pixels
        passes = (
            (box, scene.box_vertices, "back"),  # one-sided boxes: the outward faces
            (sphere, scene.sphere_vertices, "front"),  # the far side of a bounding cube covers its sphere
            (ground, 3, "back"),
        )
        for vao, count, cull in passes:
            if vao is None:
                continue
            program = vao.program
            for name, value in uniforms.items():
                if name in program:
                    program[name].value = value
            self.ctx.cull_face = cull
            vao.render(moderngl.TRIANGLES, vertices=count)
        return fbo

    def render(
        self, world: World, request: RenderRequest, into: memoryview | None = None
    ) -> dict[int, RenderedImage]:
        """`rendering.render` (the request already checked): the same images, rendered with OpenGL; read
        back into `into` at the request's `layout` if given (the images' data are then views of it)."""
        types = request.kinds
        if not types:
            return {}
        import moderngl

        kinds = tuple(sorted(types))
        width, height = request.width, request.height
        out: dict[int, RenderedImage] = {}
        try:
            with self.ctx:  # current in this thread for the render (a context is current per thread)
                fbo = self.draw(world, request, kinds)
                for kind, (encoding, offset, size) in request.layout().items():
                    depth = OUTPUTS[kind][1]
                    read = {"components": 1 if depth else 3, "attachment": kinds.index(kind)}
                    read["dtype"] = "f2" if depth else "u1"
                    if into is None:
                        data: bytes | memoryview = fbo.read(**read)
                    else:
                        fbo.read_into(into, write_offset=offset, **read)
                        data = into[offset : offset + size]
                    out[kind] = RenderedImage(encoding, width, height, data)
        except moderngl.Error as exc:
            raise GLRenderError(f"OpenGL cannot render {width}x{height}: {exc}") from exc
        return out


_LOCK = threading.Lock()
_RENDERER: tuple[int, GLRenderer] | None = None


def renderer() -> GLRenderer:
    """This process's renderer, made on first use (a forked child makes its own); GLUnavailable if none."""
    global _RENDERER
    with _LOCK:
        if _RENDERER is None or _RENDERER[0] != os.getpid():
            _RENDERER = (os.getpid(), GLRenderer())
        return _RENDERER[1]


def render(world: World, request: RenderRequest, into: memoryview | None = None) -> dict[int, RenderedImage]:
    """`rendering.render` with OpenGL in this process's context; one render at a time per process.

    A changing world is rendered as it is now (its GL buffers are kept per World, which never changes)."""
    gl = renderer()
    with _LOCK:
        return gl.render(world.current, request, into)
