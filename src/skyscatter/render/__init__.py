"""Images: sky images in several projections, the landscape renderer, glare, tone mapping and image files."""

from .camera import PinholeCamera
from .glare import apply_glare
from .image_io import read_exr, write_exr, write_exr_and_png, write_png
from .scene import RenderResult, Scene
from .sky_image import pixel_solid_angles, sky_image
from .terrain import Terrain, default_terrain
from .tonemap import tonemap

__all__ = [
    "PinholeCamera",
    "RenderResult",
    "Scene",
    "Terrain",
    "apply_glare",
    "default_terrain",
    "pixel_solid_angles",
    "read_exr",
    "sky_image",
    "tonemap",
    "write_exr",
    "write_exr_and_png",
    "write_png",
]
