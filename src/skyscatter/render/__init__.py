"""Images: sky images in several projections, tone mapping and HDR/PNG files (landscape rendering joins later)."""

from .image_io import read_exr, write_exr, write_exr_and_png, write_png
from .sky_image import pixel_solid_angles, sky_image
from .tonemap import tonemap

__all__ = ["pixel_solid_angles", "read_exr", "sky_image", "tonemap", "write_exr", "write_exr_and_png", "write_png"]
