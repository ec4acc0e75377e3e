"""Images: sky images in several projections, the landscape renderer, glare, tone mapping and image files.

Names are imported lazily (on first use), so that a command which only needs ``sky_image`` and the image
writers does not import the landscape renderer, the aerial perspective and scipy's FFT.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy import lazy_namespace

# Submodules named like the function they define are imported here, so that the package attribute is the
# function (importing a submodule later would otherwise leave the module object under that name).
from .sky_image import pixel_solid_angles, sky_image  # noqa: F401
from .tonemap import tonemap  # noqa: F401

if TYPE_CHECKING:  # the names below, as type checkers see them (imported on first use at run time)
    from .camera import PinholeCamera as PinholeCamera
    from .glare import apply_glare as apply_glare
    from .image_io import read_exr as read_exr
    from .image_io import write_exr as write_exr
    from .image_io import write_exr_and_png as write_exr_and_png
    from .image_io import write_hdr as write_hdr
    from .image_io import write_png as write_png
    from .radiance_sky import write_radiance_sky as write_radiance_sky
    from .scene import RenderResult as RenderResult
    from .scene import Scene as Scene
    from .terrain import Terrain as Terrain
    from .terrain import default_terrain as default_terrain

# public name -> submodule that defines it
_LAZY = {
    "PinholeCamera": "camera",
    "apply_glare": "glare",
    "read_exr": "image_io",
    "write_exr": "image_io",
    "write_exr_and_png": "image_io",
    "write_hdr": "image_io",
    "write_png": "image_io",
    "write_radiance_sky": "radiance_sky",
    "RenderResult": "scene",
    "Scene": "scene",
    "Terrain": "terrain",
    "default_terrain": "terrain",
}

__all__ = sorted([*_LAZY, "pixel_solid_angles", "sky_image", "tonemap"])

__getattr__, __dir__ = lazy_namespace(globals(), _LAZY)
