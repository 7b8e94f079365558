"""Camera images: the camera model, its two renderers, the render worker, annotations and encoding.

`camera_model` holds what both renderers share (image types, pinhole, the render request); `gl_renderer`
(with `gl_shaders`) draws with OpenGL, `raycast_renderer` with the numpy ray caster; `rendering` chooses
one for the process and renders; `render_worker` renders in a child process at a lower priority;
`annotations` computes an image's bounding boxes and `image_encoding` packs a frame for the wire. Its face
(`__all__`, the modules the rooms above import): `annotations`, `camera_model`, `image_encoding`,
`render_worker`, `rendering`.
"""

from __future__ import annotations

__all__ = ["annotations", "camera_model", "image_encoding", "render_worker", "rendering"]
