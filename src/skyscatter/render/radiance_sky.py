"""A sky that Radiance renders: an equirectangular Radiance picture, the function file that maps it onto the sky,
and a scene description with the sun as a light source (``skyscatter sky --format radiance``).

Files, for ``sky.rad`` (the others beside it, with the same stem):

* ``sky.hdr``: the sky and ground of the whole sphere without the solar disc, as ``sky_image`` draws an equirect
  map in the skyscatter layout (row 0 the zenith, north at the centre column, azimuth from north towards east to
  the right), in Radiance RGB radiance [W sr^-1 m^-2] with 179 lm/W and Radiance's primaries
  (:func:`skyscatter.spectral.xyz_to_radiance_rgb`; colours outside them desaturated at equal luminance).
* ``sky.cal``: ``sky_u``, ``sky_v``: the picture coordinates of a ray direction (``Dx, Dy, Dz``; Radiance's X
  east, Y north, Z up, as ``gensky``); a ``colorpict`` picture's smaller side is 1.
* ``sky.rad``: the sun as ``light`` + ``source`` (its disc-averaged radiance over the model's disc, angular
  diameter twice the model's radius), as ``gendaylit`` writes it, and the picture as a ``colorpict`` pattern on a
  ``glow`` ``source`` covering the whole sphere. Radiance reads ``sky.hdr`` and ``sky.cal`` by name at render time:
  run it in their folder, or put the folder on ``RAYPATH``.
* ``sky.png``: a tone-mapped preview of the picture.

Why a picture and a light source rather than the picture alone: Radiance's direct calculation samples light
sources only, so a sun inside a glow's picture would be found by the ambient calculation alone (noisy by orders
of magnitude); with the sun as a source, ``rtrace -I`` gives the sun's share exactly and the sky's by its
hemisphere sampling. Checked in tests/test_radiance_formats.py: ``rtrace -I`` at the ground against
``photometry.horizontal_illuminance(include_sun=True)``, an ``rpict`` angular fisheye against skyscatter's own.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from .. import __version__
from ..errors import InvalidParameterError
from ..fileio import atomic_paths, check_output_path
from ..sky.base import SkyModel
from ..spectral import (
    HDR_SCALE,
    RADIANCE_LUMINANCE_WEIGHTS,
    gamut_map_rgb,
    linear_srgb_to_xyz,
    xyz_to_radiance_rgb,
)
from .image_io import _save_hdr, _save_png
from .sky_image import sky_image
from .tonemap import tonemap

__all__ = ["radiance_sky_files", "write_radiance_sky"]

_CAL = """{{ skyscatter {version}: where a ray direction (Dx, Dy, Dz) falls in {picture}, an equirectangular map of
  the sphere: row 0 the zenith, north at the centre column, azimuth from north (+Y) towards east (+X) growing to
  the right. A Radiance picture's lower left corner is (0, 0) and its smaller side 1: it is {u_size:.10g} wide and
  {v_size:.10g} high. }}
sky_u = mod(atan2(Dx, Dy) / (2 * PI) + 0.5, 1) * {u_size:.10g};
sky_v = (1 - acos(Dz) / PI) * {v_size:.10g};
"""


def radiance_sky_files(rad_path: str | os.PathLike[str], png_path: str | os.PathLike[str] | None = None
                       ) -> tuple[Path, Path, Path, Path]:
    """The files :func:`write_radiance_sky` writes for ``rad_path``: (.rad, .hdr, .cal, .png), checked."""
    rad = check_output_path(rad_path)
    if rad.suffix.lower() != ".rad":
        raise InvalidParameterError(f"{rad}: a Radiance scene description must end in .rad")
    png = Path(png_path) if png_path is not None else rad.with_suffix(".png")
    files = (rad, rad.with_suffix(".hdr"), rad.with_suffix(".cal"), png)
    for f in files[1:]:
        check_output_path(f)
    if png.suffix.lower() != ".png":
        raise InvalidParameterError(f"{png}: the preview must end in .png")
    if len({f.resolve() for f in files}) != len(files):
        raise InvalidParameterError("the .rad, .hdr, .cal and .png outputs must be different files")
    return files


def write_radiance_sky(rad_path: str | os.PathLike[str], model: SkyModel, *, width: int = 1024,
                       ground_albedo: float | None = 0.2, png_path: str | os.PathLike[str] | None = None,
                       exposure_ev: float | None = None) -> tuple[Path, Path, Path, Path]:
    """Write ``model`` as a sky Radiance renders (module docstring): ``.rad``, ``.hdr``, ``.cal`` and ``.png``,
    all together (:func:`skyscatter.fileio.atomic_paths`); returns their paths.

    Parameters
    ----------
    rad_path : path
        The scene description, ending in ``.rad``; the picture, function file and preview get its stem.
    model : SkyModel
        Any sky; with a sun above the horizon (or below it, for models that render their ground) it becomes a
        light source.
    width : int
        Width of the picture [px], height width / 2 (default 1024: 0.35 deg per pixel).
    ground_albedo : float or None
        The ground below the horizon, as :func:`skyscatter.render.sky_image` draws it (default 0.2).
    png_path : path, optional
        The preview (default: the stem with ``.png``).
    exposure_ev : float, optional
        Preview exposure compensation [EV].
    """
    rad, hdr, cal, png = radiance_sky_files(rad_path, png_path)
    srgb = sky_image(model, projection="equirect", width=width, sun_disc=False, ground_albedo=ground_albedo,
                     dtype=np.float64)
    picture = gamut_map_rgb(xyz_to_radiance_rgb(linear_srgb_to_xyz(srgb) / HDR_SCALE), RADIANCE_LUMINANCE_WEIGHTS)
    h, w = picture.shape[:2]
    text = _scene(model, hdr.name, cal.name)
    display = tonemap(srgb, exposure_ev=exposure_ev, key=0.45)
    with atomic_paths(rad, hdr, cal, png) as (t_rad, t_hdr, t_cal, t_png):
        _save_hdr(t_hdr, picture, [f"skyscatter {__version__}: {model!r}, Radiance RGB radiance [W sr^-1 m^-2], "
                                   "179 lm/W; equirectangular, north at the centre column"])
        # colorpict's coordinates: the smaller side of the picture is 1 ([Ward1994]; Radiance reference manual)
        t_cal.write_text(_CAL.format(version=__version__, picture=hdr.name, u_size=max(w / h, 1.0),
                                     v_size=max(h / w, 1.0)), encoding="ascii")
        t_rad.write_text(text, encoding="utf-8")
        _save_png(t_png, display)
    return rad, hdr, cal, png


def _sun_lines(model: SkyModel) -> list[str]:
    sun = model.sun
    if sun is None or not (sun.above_horizon or model.renders_ground):
        return ["# no sun above the horizon: the sky alone"]
    rgb = np.maximum(gamut_map_rgb(xyz_to_radiance_rgb(np.asarray(sun.xyz(), dtype=float)),
                                   RADIANCE_LUMINANCE_WEIGHTS), 0.0)
    if not np.any(rgb > 0):
        return ["# the sun carries no light: the sky alone"]
    d = np.asarray(sun.direction, dtype=float)
    diameter = math.degrees(2.0 * sun.angular_radius)
    return [f"# the sun: disc-averaged radiance, angular diameter {diameter:.6g} deg "
            f"(normal illuminance {sun.illuminance_normal():.6g} lx)",
            "void light solar", "0", "0", f"3 {rgb[0]:.6e} {rgb[1]:.6e} {rgb[2]:.6e}", "",
            "solar source sun", "0", "0", f"4 {d[0]:.9f} {d[1]:.9f} {d[2]:.9f} {diameter:.6g}", ""]


def _scene(model: SkyModel, picture: str, funcfile: str) -> str:
    lines = [f"# skyscatter {__version__}: {model!r}",
             "# Radiance RGB radiance [W sr^-1 m^-2] with 179 lm/W; X east, Y north, Z up. Radiance reads "
             f"{picture} and {funcfile}",
             "# at render time: run it in their folder or put that folder on RAYPATH.", ""]
    lines += _sun_lines(model)
    lines += ["# the sky and the ground: the picture on a glow covering the whole sphere",
              "void colorpict sky_map", f"7 red green blue {picture} {funcfile} sky_u sky_v", "0", "0", "",
              "sky_map glow sky_glow", "0", "0", "4 1 1 1 0", "",
              "sky_glow source sky_dome", "0", "0", "4 0 0 1 360", ""]
    return "\n".join(lines)
