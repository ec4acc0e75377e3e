"""Images: sky images in several projections, the landscape renderer, glare, tone mapping and image files.

Names are imported lazily (on first use), so that a command which only needs ``sky_image`` and the image
writers does not import the landscape renderer, the aerial perspective and scipy's FFT.
"""

from __future__ import annotations

import importlib
from typing import Any

# Submodules named like the function they define are imported here, so that the package attribute is the
# function (importing a submodule later would otherwise leave the module object under that name).
from .sky_image import pixel_solid_angles, sky_image  # noqa: F401
from .tonemap import tonemap  # noqa: F401

# public name -> module that defines it
_LAZY = {
    "PinholeCamera": "skyscatter.render.camera",
    "apply_glare": "skyscatter.render.glare",
    "read_exr": "skyscatter.render.image_io",
    "write_exr": "skyscatter.render.image_io",
    "write_exr_and_png": "skyscatter.render.image_io",
    "write_hdr": "skyscatter.render.image_io",
    "write_png": "skyscatter.render.image_io",
    "write_radiance_sky": "skyscatter.render.radiance_sky",
    "RenderResult": "skyscatter.render.scene",
    "Scene": "skyscatter.render.scene",
    "Terrain": "skyscatter.render.terrain",
    "default_terrain": "skyscatter.render.terrain",
}

__all__ = sorted([*_LAZY, "pixel_solid_angles", "sky_image", "tonemap"])


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'skyscatter.render' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
