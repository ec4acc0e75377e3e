"""Images of a sky model: equirectangular environment maps, hemispherical fisheyes and pinhole views."""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import NDArray

from ..conventions import equirect_directions, fisheye_directions, pinhole_directions
from ..errors import InvalidParameterError
from ..sky.base import SkyModel, SolarDisc
from ..spectral import HDR_SCALE, xyz_to_linear_srgb

__all__ = ["pixel_solid_angles", "sky_image"]

Projection = Literal["equirect", "fisheye", "pinhole"]
Layout = Literal["skyscatter", "blender", "mitsuba"]

#: Column (fraction of the width, 0 = left edge) that looks north in each equirectangular layout; azimuth
#: always grows to the right (north -> east), row 0 is the zenith. With north = +Y, east = +X in a Z-up scene:
#: "skyscatter": north at the centre (the panorama convention); "blender": north at 1/4, what Blender's
#: Environment Texture with its default mapping puts on +Y (it puts the image centre on +X);
#: "mitsuba": north at the left/right edge, what Mitsuba's ``envmap`` puts on +Y with the usual Z-up
#: ``to_world = rotate([1, 0, 0], 90)`` (it puts the image centre on -Y). See docs/conventions.md.
LAYOUT_NORTH_COLUMN = {"skyscatter": 0.5, "blender": 0.25, "mitsuba": 0.0}
# XYZ of 1 cd m^-2 at the D65 white point (x, y) = (0.31271, 0.32902): the ground is shown as a neutral grey.
_D65_XYZ = np.array([0.31271 / 0.32902, 1.0, (1.0 - 0.31271 - 0.32902) / 0.32902])


#: Largest image sky_image renders in one piece [pixels] (about 3 GB of float64 working arrays).
MAX_PIXELS = 64 * 1024 * 1024


def _equirect_layout(width: int, height: int | None, layout: str) -> NDArray[np.float64]:
    """Pixel directions of an equirectangular map in ``layout`` (:data:`LAYOUT_NORTH_COLUMN`)."""
    d = equirect_directions(width, height)
    shift = 2.0 * np.pi * (0.5 - LAYOUT_NORTH_COLUMN[layout])  # azimuth added to the skyscatter layout's
    if shift == 0.0:
        return d
    c, s = np.cos(shift), np.sin(shift)
    # azimuth phi -> phi + shift (from north towards east): (x, y) = sin(theta) (sin phi, cos phi)
    x = d[..., 0] * c + d[..., 1] * s
    y = d[..., 1] * c - d[..., 0] * s
    return np.stack([x, y, d[..., 2]], axis=-1)


def _directions(projection: str, width: int, height: int | None, heading: float, pitch: float, fov: float,
                layout: str = "skyscatter"):
    for name, value in (("width", width), ("height", height)):
        if value is None and name == "height":
            continue
        if isinstance(value, (bool, str, bytes)) or not isinstance(value, (int, np.integer)) or value < 1:
            raise InvalidParameterError(f"{name} must be a whole number of pixels >= 1; got {value!r}")
    if layout not in LAYOUT_NORTH_COLUMN:
        raise InvalidParameterError(f"layout must be one of {sorted(LAYOUT_NORTH_COLUMN)}; got {layout!r}")
    if layout != "skyscatter" and projection != "equirect":
        raise InvalidParameterError(f"layout {layout!r} applies to equirect maps only (projection {projection!r})")
    h = height if height is not None else (width // 2 if projection == "equirect" else width)
    if width * max(h, 1) > MAX_PIXELS:
        raise InvalidParameterError(
            f"image of {width} x {h} px exceeds the {MAX_PIXELS // 2**20} Mpx that sky_image renders at once"
        )
    if projection == "equirect":
        d = _equirect_layout(width, height, layout)
        return d, np.ones(d.shape[:2], dtype=bool)
    if projection == "fisheye":
        if height is not None and height != width:
            raise InvalidParameterError("a fisheye image is square: give only width (or height == width)")
        return fisheye_directions(width)
    if projection == "pinhole":
        h = height if height is not None else max(1, round(width * 3 / 4))
        d = pinhole_directions(width, h, heading=heading, pitch=pitch, fov=fov)
        return d, np.ones(d.shape[:2], dtype=bool)
    raise InvalidParameterError(f"projection must be 'equirect', 'fisheye' or 'pinhole'; got {projection!r}")


def pixel_solid_angles(
    projection: Projection, width: int, height: int | None = None, *, fov: float = np.radians(60.0)
) -> NDArray[np.float64]:
    """Solid angle [sr] of each pixel of an image made by :func:`sky_image` with the same arguments.

    Equirect: ``(2 pi / W)(pi / H) sin(theta)``; fisheye (equidistant): ``(pi / W)^2 sin(theta) / theta``;
    pinhole: ``(2 tan(fov/2) / W)^2 cos^3(alpha)`` with alpha the angle off the optical axis.
    """
    if projection == "equirect":
        d = equirect_directions(width, height)
        h, w = d.shape[:2]
        theta = np.arccos(np.clip(d[..., 2], -1, 1))
        return (2 * np.pi / w) * (np.pi / h) * np.sin(theta)
    if projection == "fisheye":
        d, _ = fisheye_directions(width)
        theta = np.arccos(np.clip(d[..., 2], -1, 1))
        return (np.pi / width) ** 2 * _sin_over(theta)
    if projection == "pinhole":
        h = height if height is not None else max(1, round(width * 3 / 4))
        d = pinhole_directions(width, h, heading=0.0, pitch=0.0, fov=fov)
        cos_alpha = d[..., 1]  # heading 0, pitch 0: the optical axis is north
        return (2 * np.tan(fov / 2) / width) ** 2 * cos_alpha**3
    raise InvalidParameterError(f"projection must be 'equirect', 'fisheye' or 'pinhole'; got {projection!r}")


def _sin_over(theta: NDArray[np.float64]) -> NDArray[np.float64]:
    """sin(theta) / theta with the limit 1 at 0."""
    return np.sinc(theta / np.pi)


def sky_image(
    model: SkyModel,
    *,
    projection: Projection = "equirect",
    width: int = 1024,
    height: int | None = None,
    heading: float = 0.0,
    pitch: float = 0.0,
    fov: float = np.radians(60.0),
    sun_disc: bool = True,
    ground_albedo: float | None = 0.2,
    dtype: type = np.float32,
    layout: Layout = "skyscatter",
) -> NDArray:
    """Render a sky model to a linear HDR image (H, W, 3) in skyscatter's scale (Y = luminance / 683).

    Parameters
    ----------
    model : SkyModel
        Any sky answering the protocol (``xyz(directions)``).
    projection : {"equirect", "fisheye", "pinhole"}
        ``equirect``: full-sphere latitude-longitude map, north at the centre column, width x width/2 by
        default (:func:`skyscatter.conventions.equirect_directions`). ``fisheye``: equidistant upper hemisphere,
        zenith at the centre, north up, east left, width x width; pixels outside the horizon circle are 0.
        ``pinhole``: a rectilinear camera with ``heading``, ``pitch`` and horizontal ``fov``.
    width, height : int
        Image size [px]; ``height`` defaults to width/2 (equirect), width (fisheye) or 3/4 width (pinhole).
    heading, pitch, fov : float
        Pinhole camera: azimuth of the optical axis from north towards east [rad], its elevation [rad], and
        the horizontal field of view [rad] (default 60 deg).
    sun_disc : bool
        Add the solar disc of sun-aware models (default True), deposited with the bilinear kernel of the pixel
        grid (:mod:`skyscatter.render.sun_disc`): the image's flux is the disc's normal irradiance at any width
        and projection (a disc smaller than a pixel is splatted over the pixels around it), the irradiance on
        any plane is right to second order in the pixel size, and limb darkening is kept where the model has it
        (Hosek-Wilkie 2013).
    ground_albedo : float or None
        Below the horizon (for models that do not render the ground themselves): a neutral (D65) Lambertian
        ground of this albedo lit by the model's global horizontal illuminance,
        ``L = albedo * E_v / pi``, computed with :func:`skyscatter.photometry.horizontal_illuminance`
        (sun included). None leaves the ground black. Default 0.2.
    dtype : numpy dtype
        float32 (default, as stored in EXR files) or float64.
    layout : {"skyscatter", "blender", "mitsuba"}
        Equirect only: which column looks north (:data:`LAYOUT_NORTH_COLUMN`), so that a renderer loading the
        map with its default (Blender: World Environment Texture, default mapping) or conventional (Mitsuba:
        ``envmap`` with ``to_world = rotate([1, 0, 0], 90)``) set-up puts the sun where skyscatter says in a
        Z-up scene with north = +Y and east = +X. Default "skyscatter": north at the centre.

    Returns
    -------
    ndarray, shape (H, W, 3)
    """
    if not isinstance(model, SkyModel):
        raise InvalidParameterError(
            f"sky_image needs a sky model (skyscatter.sky.SkyModel); got {type(model).__name__}")
    if ground_albedo is not None and not (isinstance(ground_albedo, (int, float, np.integer, np.floating))
                                          and np.isfinite(ground_albedo) and 0.0 <= ground_albedo <= 1.0):
        raise InvalidParameterError(f"ground_albedo must be in [0, 1] or None; got {ground_albedo!r}")
    directions, inside = _directions(projection, width, height, heading, pitch, fov, layout)
    xyz = np.asarray(model.xyz(directions), dtype=float)
    below = directions[..., 2] < 0.0
    if not model.renders_ground:
        if ground_albedo is not None and np.any(below & inside):
            from ..photometry import horizontal_illuminance

            e_v = float(horizontal_illuminance(model, include_sun=model.sun is not None))
            xyz[below] = ground_albedo * e_v / np.pi * _D65_XYZ
        else:
            xyz[below] = 0.0
    sun = model.sun if sun_disc else None
    if sun is not None:
        _add_sun(xyz, sun, model.renders_ground, projection_for(projection, width, height, heading, pitch, fov,
                                                               layout))
    xyz[~inside] = 0.0
    return (xyz_to_linear_srgb(xyz) * HDR_SCALE).astype(dtype)


def projection_for(projection: str, width: int, height: int | None, heading: float, pitch: float, fov: float,
                   layout: str = "skyscatter"):
    """The continuous pixel <-> direction map of a :func:`sky_image` image (:mod:`.sun_disc`)."""
    from .sun_disc import EquirectProjection, FisheyeProjection, PinholeProjection

    if projection == "equirect":
        h = height if height is not None else width // 2
        return EquirectProjection(width, h, LAYOUT_NORTH_COLUMN[layout])
    if projection == "fisheye":
        return FisheyeProjection(width)
    h = height if height is not None else max(1, round(width * 3 / 4))
    return PinholeProjection(width, h, heading, pitch, fov)


def _add_sun(xyz, sun: SolarDisc, renders_ground: bool, proj) -> None:
    """Add the solar disc, energy-true at any resolution (:mod:`.sun_disc`; limb-darkened where the model has it)."""
    from .sun_disc import disc_deposit, disc_profile_xyz, profile_nodes_for

    if not renders_ground and not sun.above_horizon:
        return
    deposit = disc_deposit(sun.direction, sun.angular_radius, proj, nodes=profile_nodes_for(sun))
    if deposit is None:
        return
    xyz[deposit.rows, deposit.cols] += deposit.values(disc_profile_xyz(sun, deposit))
