"""Images of the precomputed atmosphere ([Bruneton2008]).

* :func:`camera_view`, :func:`fisheye_view` - the sky (and planet) from any position: the ground, an
  aircraft, orbit; :func:`preview_png` to look at them.
* :func:`bruneton_scene` - the landscape renderer (:class:`~skyscatter.render.Scene`) with the sky, the
  sunlight on the terrain and the aerial perspective all from the tables, and light shafts from the terrain's
  shadow (Eqs. 17-18; :mod:`skyscatter.aerial.bruneton`, :mod:`skyscatter.render.shafts`).

Views: the camera sits at ``altitude`` [m] above the point of the planet on the +z axis of the planet-centred frame,
whose axes are that point's East-North-Up frame; ``heading``, ``pitch`` and ``fov`` follow
:func:`skyscatter.conventions.pinhole_directions`. Images are (H, W, 3) CIE XYZ [cd m^-2] or linear sRGB in
skyscatter's HDR scale (``Y = luminance / 683``, :data:`skyscatter.spectral.HDR_SCALE`), with the solar disc
(radiance after transmission) deposited energy-true at any resolution (:mod:`skyscatter.render.sun_disc`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..aerial.base import DEFAULT_REFINE, DEFAULT_SHADOW_SAMPLES
from ..aerial.bruneton import BrunetonAerialPerspective
from ..conventions import as_directions, direction_from_angles, fisheye_directions, pinhole_directions
from ..deprecation import renamed_keywords
from ..errors import InvalidParameterError
from ..fileio import atomic_path
from ..precomputed import AtmosphereParameters, PrecomputedAtmosphere
from ..sky.bruneton import BrunetonSky
from ..spectral import HDR_SCALE, xyz_to_linear_srgb
from .camera import PinholeCamera
from .heightfield import HeightfieldTracer
from .scene import Scene
from .sun_disc import FisheyeProjection, PinholeProjection, disc_deposit
from .terrain import Terrain

__all__ = ["bruneton_scene", "camera_view", "fisheye_view", "preview_png", "render_directions"]

_OUTPUTS = ("rgb", "xyz", "spectral")


@renamed_keywords(atmosphere="precomputed")
def render_directions(precomputed: PrecomputedAtmosphere, position: ArrayLike, directions: ArrayLike,
                      sun_direction: ArrayLike, *, output: str = "rgb",
                      include_sun: bool = True) -> NDArray[np.float64]:
    """Radiance seen from one ``position`` [m, planet-centred] along ``directions`` (..., 3).

    Parameters
    ----------
    output : {"rgb", "xyz", "spectral"}
        HDR linear sRGB (Y = luminance / 683), CIE XYZ [cd m^-2], or spectral radiance at the table
        wavelengths [W m^-2 sr^-1 nm^-1].
    include_sun : bool
        Add the solar disc's radiance on directions inside it.
    """
    if output not in _OUTPUTS:
        raise InvalidParameterError(f"output must be one of {_OUTPUTS}; got {output!r}")
    d = as_directions(directions)
    sun = as_directions(sun_direction)
    pos = np.asarray(position, dtype=float)
    if output != "spectral" and precomputed.spectral_mode:
        # The output's channels straight from the lookups (linear in the spectrum, except the read along the sun
        # zenith at low sun, which then acts on each output channel, as the GLSL library's on its sRGB textures):
        # the disc is added in the same channels.
        if output == "xyz":
            xyz = precomputed.sky_xyz(pos, d, sun)
            if include_sun:
                _add_disc(precomputed, pos, d, sun, xyz, precomputed.to_xyz(precomputed.sun_radiance(pos, sun)))
            return xyz
        matrix = np.asarray(xyz_to_linear_srgb(precomputed.xyz_matrix.T).T * HDR_SCALE, dtype=np.float64)
        rgb = precomputed.sky_colour(pos, d, sun, matrix)
        if include_sun:
            _add_disc(precomputed, pos, d, sun, rgb, matrix @ precomputed.sun_radiance(pos, sun))
        return rgb
    rad = precomputed.sky_radiance(pos, d, sun)
    if include_sun:
        _add_disc(precomputed, pos, d, sun, rad, precomputed.sun_radiance(pos, sun))
    if output == "spectral":
        return rad
    xyz = precomputed.to_xyz(rad)
    if output == "xyz":
        return xyz
    return xyz_to_linear_srgb(xyz) * HDR_SCALE


def _add_disc(precomputed: PrecomputedAtmosphere, position: NDArray[np.float64], directions: NDArray[np.float64],
              sun: NDArray[np.float64], image: NDArray[np.float64], disc: NDArray[np.float64]) -> None:
    """Add the solar disc's value ``disc`` (spectrum or XYZ) to ``image`` on directions inside the disc."""
    cos_r = math.cos(precomputed.parameters.sun_angular_radius)
    inside = (directions @ sun) >= cos_r
    if np.any(inside):
        # A direction inside the disc sees the sun only if its ray does not meet the planet first.
        rmu = directions[inside] @ position
        blocked = (rmu < 0) & (rmu**2 - position @ position + precomputed.parameters.bottom_radius**2 >= 0)
        image[inside] += np.where(blocked[:, None], 0.0, disc[None, :])


def _observer(precomputed: PrecomputedAtmosphere, altitude: float) -> NDArray[np.float64]:
    if not (math.isfinite(altitude) and altitude >= 0):
        raise InvalidParameterError(f"altitude must be finite and >= 0 m; got {altitude!r}")
    return np.array([0.0, 0.0, precomputed.parameters.bottom_radius + altitude])


@renamed_keywords(atmosphere="precomputed")
def camera_view(precomputed: PrecomputedAtmosphere, sun_zenith: float, sun_azimuth: float, *, altitude: float = 0.0,
                heading: float = 0.0, pitch: float = 0.0, fov: float = math.radians(90.0), width: int = 512,
                height: int = 384, output: str = "rgb", include_sun: bool = True) -> NDArray[np.float64]:
    """Pinhole camera image (height, width, 3) from ``altitude`` [m].

    ``sun_zenith``, ``sun_azimuth`` [rad] are the sun's angles in the observer's local frame (the zenith may
    exceed 90 deg); ``heading`` [rad, from north towards east], ``pitch`` [rad] and ``fov`` (horizontal, [rad])
    aim the camera. From orbit the Earth's limb is at a pitch of ``-acos(R / (R + altitude))``.
    """
    dirs = pinhole_directions(width, height, heading=heading, pitch=pitch, fov=fov)
    sun = direction_from_angles(sun_zenith, sun_azimuth)
    pos = _observer(precomputed, altitude)
    img = render_directions(precomputed, pos, dirs, sun, output=output, include_sun=False)
    if include_sun:
        _draw_disc(precomputed, pos, sun, img, PinholeProjection(width, height, heading, pitch, fov), output)
    return img


@renamed_keywords(atmosphere="precomputed")
def fisheye_view(precomputed: PrecomputedAtmosphere, sun_zenith: float, sun_azimuth: float, *, altitude: float = 0.0,
                 size: int = 256, output: str = "rgb", include_sun: bool = True) -> NDArray[np.float64]:
    """Upper-hemisphere fisheye (equidistant, zenith at the centre, north up, east left); 0 outside the circle."""
    dirs, inside = fisheye_directions(size)
    sun = direction_from_angles(sun_zenith, sun_azimuth)
    pos = _observer(precomputed, altitude)
    img = render_directions(precomputed, pos, dirs, sun, output=output, include_sun=False)
    img[~inside] = 0.0
    if include_sun:
        _draw_disc(precomputed, pos, sun, img, FisheyeProjection(size), output)
    return img


def _draw_disc(precomputed: PrecomputedAtmosphere, position: NDArray[np.float64], sun: NDArray[np.float64],
               image: NDArray[np.float64], proj, output: str) -> None:
    """Add the solar disc to an image, energy-true at any resolution (:mod:`.sun_disc`); the planet in front of
    a pixel's centre hides that pixel's share."""
    deposit = disc_deposit(sun, precomputed.parameters.sun_angular_radius, proj)
    if deposit is None:
        return
    value = precomputed.sun_radiance(position, sun)
    if output != "spectral":
        value = precomputed.to_xyz(value)
    add = deposit.values(value[None, :])
    x, y = deposit.cols + 0.5, deposit.rows + 0.5
    d = proj.from_pixel(x.astype(float), y.astype(float))
    rmu = d @ position
    blocked = (rmu < 0) & (rmu**2 - position @ position + precomputed.parameters.bottom_radius**2 >= 0)
    add[blocked] = 0.0
    if output == "rgb":
        add = xyz_to_linear_srgb(add) * HDR_SCALE
    image[deposit.rows, deposit.cols] += add


def preview_png(image: ArrayLike, path: str | Path, *, exposure: float | None = None) -> Path:
    """Write a tone-mapped 8-bit PNG of an HDR linear sRGB image (for looking at, not for measurement).

    The exposure scales the image so that its log-average luminance maps to 0.18 (plus ``exposure`` EV stops
    if given); highlights are compressed with ``x / (1 + x)`` per channel and encoded with the sRGB curve.
    """
    from PIL import Image

    rgb = np.clip(np.asarray(image, dtype=float), 0.0, None)
    lum = rgb @ np.array([0.2126, 0.7152, 0.0722])
    key = math.exp(float(np.mean(np.log(lum[lum > 0] + 1e-12)))) if np.any(lum > 0) else 1.0
    scale = 0.18 / key * 2.0 ** (exposure or 0.0)
    x = rgb * scale
    x = x / (1.0 + x)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    img = Image.fromarray(np.clip(np.round(srgb * 255), 0, 255).astype(np.uint8))
    target = Path(path)
    with atomic_path(target) as tmp:
        img.save(tmp, format="PNG")
    return target


@renamed_keywords(albedo="terrain_albedo", table_wavelengths="tables")
def bruneton_scene(terrain: Terrain, camera: PinholeCamera, sun_zenith: float, sun_azimuth: float, *,
                   atmosphere: AtmosphereParameters | None = None, precomputed: PrecomputedAtmosphere | None = None,
                   terrain_albedo: float = 0.2, sun_disc: bool = True, wavelengths: ArrayLike | None = None,
                   shafts: bool = True, samples: int | None = None, refine: int | None = None,
                   tables: str | None = None, **medium: Any) -> Scene:
    """A :class:`~skyscatter.render.Scene` lit and hazed by the precomputed atmosphere.

    Parameters
    ----------
    terrain : Terrain
        The heightfield (heights above sea level [m]).
    camera : PinholeCamera
        The camera (ENU position [m]).
    sun_zenith, sun_azimuth : float
        Sun angles [rad] (azimuth from north towards east); the sun may be below the horizon down to the
        atmosphere's ``max_sun_zenith`` (then there are no terrain shadows, only the Earth's).
    atmosphere : AtmosphereParameters, optional
        The atmosphere (default: the Earth defaults; tables cached, computed once, about 20 s).
    precomputed : PrecomputedAtmosphere, optional
        Tables instead of ``atmosphere``.
    terrain_albedo : float
        Lambertian albedo of the terrain [-] (the atmosphere's ground albedo, which lights the sky from below, is
        the atmosphere's own: the ``ground_albedo`` option).
    sun_disc : bool
        Draw the solar disc.
    wavelengths : array_like, optional
        Wavelengths [nm] of the renderer (default 380-780 nm every 10 nm).
    shafts : bool
        Light shafts from the terrain's shadow (Eqs. 17-18); False gives Eq. 16 only.
    samples, refine : int, optional
        Ray-marching steps and boundary bisections of the shadow-length estimate (defaults of
        :func:`skyscatter.render.shafts.shadow_lengths`).
    tables : {"spectral", "rgb"}, optional
        Which tables to build from the atmosphere (:class:`~skyscatter.sky.bruneton.BrunetonSky`'s ``tables``).
    **medium
        The atmosphere's options (:data:`skyscatter.atmosphere.options.ATMOSPHERE_OPTIONS`: ``turbidity``,
        ``aerosol_optical_depth``, ``angstrom_alpha``, ``ground_albedo``, ``ozone_column``, ...).

    Deprecated spellings (until the next release): ``albedo`` for ``terrain_albedo``, ``table_wavelengths`` for
    ``tables``, tables passed as ``atmosphere``.

    Returns
    -------
    Scene
    """
    x, y, z = (float(v) for v in camera.position)
    sky = BrunetonSky(sun_zenith, sun_azimuth, altitude=max(z, 0.0), atmosphere=atmosphere, precomputed=precomputed,
                      tables=tables, **medium)
    tracer = HeightfieldTracer(terrain) if shafts else None
    aerial = BrunetonAerialPerspective(
        sky, terrain=tracer, camera_xy=(x, y),
        samples=DEFAULT_SHADOW_SAMPLES if samples is None else samples,
        refine=DEFAULT_REFINE if refine is None else refine,
    )
    return Scene(sky, terrain=terrain, camera=camera, aerial=aerial, terrain_albedo=terrain_albedo, sun_disc=sun_disc,
                 wavelengths=wavelengths)
