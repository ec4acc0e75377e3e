"""Images: sky images in several projections, the landscape renderer, glare, tone mapping and image files.

Names are imported lazily (on first use), so that a command which only needs ``sky_image`` and the image
writers does not import the landscape renderer, the aerial perspective and scipy's FFT.
"""

from __future__ import annotations

import importlib
from typing import Any

# public name -> module that defines it
_LAZY = {
    "PinholeCamera": "skyscatter.render.camera",
    "apply_glare": "skyscatter.render.glare",
    "read_exr": "skyscatter.render.image_io",
    "write_exr": "skyscatter.render.image_io",
    "write_exr_and_png": "skyscatter.render.image_io",
    "write_png": "skyscatter.render.image_io",
    "RenderResult": "skyscatter.render.scene",
    "Scene": "skyscatter.render.scene",
    "pixel_solid_angles": "skyscatter.render.sky_image",
    "sky_image": "skyscatter.render.sky_image",
    "Terrain": "skyscatter.render.terrain",
    "default_terrain": "skyscatter.render.terrain",
    "tonemap": "skyscatter.render.tonemap",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'skyscatter.render' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
