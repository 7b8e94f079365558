"""Which renderer draws a camera's images in this process, and the render call the server makes.

`render` draws with OpenGL (`gl_renderer.py`) in this process's own headless context (Mesa's llvmpipe
without a GPU). Where no context can be made it logs that once and ray casts from then on
(`raycast_renderer.py`). `AIRSIM_MAPPER_RENDERER=raycast` (or `airsim-mapper-sim --renderer raycast`,
or `select_renderer`) chooses the ray caster; both produce the images of `camera_model.py`.

The choice is process-wide: `RendererChoice` owns it, behind its own lock.
"""

from __future__ import annotations

import logging
import os
import threading
from dataclasses import replace

from airsim_mapper.simserver.render import gl_renderer
from airsim_mapper.simserver.render.camera_model import CameraError, RenderedImage, RenderRequest
from airsim_mapper.simserver.render.raycast_renderer import render_raycast
from airsim_mapper.simserver.world.world import World

LOG = logging.getLogger("airsim_mapper.simserver.rendering")
RENDERER_ENV = "AIRSIM_MAPPER_RENDERER"
RENDERERS = ("gl", "raycast")


class RendererChoice:
    """The renderer this process uses: chosen by `select`, else read from RENDERER_ENV on first use, and
    set to the ray caster for good when OpenGL is unavailable."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._name: str | None = None

    def select(self, name: str | None) -> None:
        """Use `name` ("gl" or "raycast") from now on; None reads RENDERER_ENV again on next use."""
        if name is not None and name not in RENDERERS:
            raise CameraError(f"unknown renderer {name!r} (expected one of {', '.join(RENDERERS)})")
        with self._lock:
            self._name = name

    def name(self) -> str:
        """ "gl" or "raycast"."""
        with self._lock:
            if self._name is None:
                wanted = os.environ.get(RENDERER_ENV, "gl").strip().lower() or "gl"
                if wanted not in RENDERERS:
                    LOG.error("%s=%r is not one of %s; using gl", RENDERER_ENV, wanted, ", ".join(RENDERERS))
                    wanted = "gl"
                self._name = wanted
            return self._name

    def fall_back(self) -> None:
        """OpenGL is unavailable in this process: ray cast from now on."""
        with self._lock:
            self._name = "raycast"


CHOICE = RendererChoice()


def select_renderer(name: str | None) -> None:
    """`RendererChoice.select` on this process's choice."""
    CHOICE.select(name)


def renderer_name() -> str:
    """The renderer `render` uses in this process: "gl" or "raycast"."""
    return CHOICE.name()


def render(world: World, request: RenderRequest, into: memoryview | None = None) -> dict[int, RenderedImage]:
    """The requested images of a camera, by this process's renderer; CameraError if the request is invalid.

    A changing world is drawn as it is now, all of one image from one World. With `into` (at least
    `request.nbytes`), the images are written there at `request.layout()` and their data are views of it.
    """
    world = world.current
    request.check()
    if not request.kinds:
        return {}
    if CHOICE.name() == "gl":
        try:
            return gl_renderer.render(world, request, into)
        except gl_renderer.GLUnavailable as exc:
            LOG.error("camera images: %s; rendering with the numpy ray caster from now on (much slower)", exc)
            CHOICE.fall_back()
        except gl_renderer.GLRenderError as exc:
            LOG.warning("camera images: %s; ray casting this one", exc)
    images = render_raycast(world, request)
    if into is None:
        return images
    for kind, (_, offset, size) in request.layout().items():
        into[offset : offset + size] = images[kind].data
        images[kind] = replace(images[kind], data=into[offset : offset + size])
    return images
