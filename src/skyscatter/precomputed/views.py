"""Camera views of the precomputed atmosphere from any position: the ground, an aircraft, orbit.

The camera sits at ``altitude`` [m] above the point of the planet on the +z axis of the planet-centred frame,
whose axes are that point's East-North-Up frame; ``heading``, ``pitch`` and ``fov`` follow
:func:`skyscatter.conventions.pinhole_directions`. Images are (H, W, 3) CIE XYZ [cd m^-2] or linear sRGB in
skyscatter's HDR scale (``Y = luminance / 683``, :data:`skyscatter.spectral.HDR_SCALE`), with the solar disc
(radiance after transmission) on the pixels whose centres fall inside it.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..conventions import as_directions, direction_from_angles, fisheye_directions, pinhole_directions
from ..errors import InvalidParameterError
from ..fileio import atomic_path
from ..spectral import HDR_SCALE, xyz_to_linear_srgb
from .tables import PrecomputedAtmosphere

__all__ = ["camera_view", "fisheye_view", "preview_png", "render_directions"]

_OUTPUTS = ("rgb", "xyz", "spectral")


def render_directions(atmosphere: PrecomputedAtmosphere, position: ArrayLike, directions: ArrayLike,
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
    rad = atmosphere.sky_radiance(np.asarray(position, dtype=float), d, sun)
    if include_sun:
        cos_r = math.cos(atmosphere.parameters.sun_angular_radius)
        inside = (d @ sun) >= cos_r
        if np.any(inside):
            # A direction inside the disc sees the sun only if its ray does not meet the planet first.
            r0 = np.asarray(position, dtype=float)
            rmu = d[inside] @ r0
            blocked = (rmu < 0) & (rmu**2 - r0 @ r0 + atmosphere.parameters.bottom_radius**2 >= 0)
            sun_rad = atmosphere.sun_radiance(r0, sun)
            rad[inside] += np.where(blocked[:, None], 0.0, sun_rad[None, :])
    if output == "spectral":
        return rad
    xyz = atmosphere.to_xyz(rad)
    if output == "xyz":
        return xyz
    return xyz_to_linear_srgb(xyz) * HDR_SCALE


def _observer(atmosphere: PrecomputedAtmosphere, altitude: float) -> NDArray[np.float64]:
    if not (math.isfinite(altitude) and altitude >= 0):
        raise InvalidParameterError(f"altitude must be finite and >= 0 m; got {altitude!r}")
    return np.array([0.0, 0.0, atmosphere.parameters.bottom_radius + altitude])


def camera_view(atmosphere: PrecomputedAtmosphere, sun_zenith: float, sun_azimuth: float, *, altitude: float = 0.0,
                heading: float = 0.0, pitch: float = 0.0, fov: float = math.radians(90.0), width: int = 512,
                height: int = 384, output: str = "rgb", include_sun: bool = True) -> NDArray[np.float64]:
    """Pinhole camera image (height, width, 3) from ``altitude`` [m].

    ``sun_zenith``, ``sun_azimuth`` [rad] are the sun's angles in the observer's local frame (the zenith may
    exceed 90 deg); ``heading`` [rad, from north towards east], ``pitch`` [rad] and ``fov`` (horizontal, [rad])
    aim the camera. From orbit the Earth's limb is at a pitch of ``-acos(R / (R + altitude))``.
    """
    dirs = pinhole_directions(width, height, heading=heading, pitch=pitch, fov=fov)
    sun = direction_from_angles(sun_zenith, sun_azimuth)
    return render_directions(atmosphere, _observer(atmosphere, altitude), dirs, sun, output=output,
                             include_sun=include_sun)


def fisheye_view(atmosphere: PrecomputedAtmosphere, sun_zenith: float, sun_azimuth: float, *, altitude: float = 0.0,
                 size: int = 256, output: str = "rgb", include_sun: bool = True) -> NDArray[np.float64]:
    """Upper-hemisphere fisheye (equidistant, zenith at the centre, north up, east left); 0 outside the circle."""
    dirs, inside = fisheye_directions(size)
    img = render_directions(atmosphere, _observer(atmosphere, altitude), dirs, direction_from_angles(sun_zenith,
                            sun_azimuth), output=output, include_sun=include_sun)
    img[~inside] = 0.0
    return img


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
