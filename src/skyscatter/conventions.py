"""Frame, angle and direction conventions (see ``docs/conventions.md``).

skyscatter works in a local East-North-Up (ENU) frame, right-handed: x points east, y north, z up.
A direction is a unit vector in an array whose last axis has length 3. The zenith angle is
``theta = acos(z)`` and the azimuth is measured from north towards east (clockwise seen from above), as in
pvlib and CIE S 011/E:2003. All angles are radians.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidDirectionError, InvalidParameterError

__all__ = [
    "LUMINOUS_SOLAR_CONSTANT",
    "MAX_EXTRATERRESTRIAL_ILLUMINANCE",
    "MAX_EXTRATERRESTRIAL_IRRADIANCE",
    "MAX_SKY_LUMINANCE",
    "check_daylight_limit",
    "direction_from_angles",
    "angles_from_direction",
    "angle_between",
    "as_directions",
    "equirect_directions",
    "fisheye_directions",
    "pinhole_directions",
]

#: Physical upper bounds of daylight inputs (used to refuse impossible values with the reason).
#: Largest ratio of the extraterrestrial irradiance to its mean, at perihelion: (1 / (1 - e))^2 with the
#: orbital eccentricity e = 0.0167 (Spencer 1971's factor peaks at 1.0344 on 3 January).
PERIHELION_FACTOR = 1.0344
#: Extraterrestrial normal irradiance at perihelion [W m^-2]: the solar constant 1367 W m^-2 (WRC value that
#: Perez et al. 1990 and Radiance use; the measured TSI is 1360.8, [KoppLean2011])
#: times PERIHELION_FACTOR. No direct or diffuse irradiance at the ground exceeds it.
MAX_EXTRATERRESTRIAL_IRRADIANCE = 1367.0 * PERIHELION_FACTOR
#: Luminous solar constant [lx] ([Darula2005]): extraterrestrial normal illuminance at the mean Sun-Earth distance.
LUMINOUS_SOLAR_CONSTANT = 133_800.0
#: Extraterrestrial normal illuminance at perihelion [lx]: no sun or sky illuminance at the ground exceeds it.
MAX_EXTRATERRESTRIAL_ILLUMINANCE = LUMINOUS_SOLAR_CONSTANT * PERIHELION_FACTOR
#: Luminance of the solar disc outside the atmosphere [cd m^-2]: MAX_EXTRATERRESTRIAL_ILLUMINANCE over the
#: disc's solid angle at perihelion (6.80e-5 sr x 1.0344). No part of the sky is brighter.
MAX_SKY_LUMINANCE = MAX_EXTRATERRESTRIAL_ILLUMINANCE / (6.80e-5 * PERIHELION_FACTOR)


def check_daylight_limit(name: str, value: float, unit: str) -> None:
    """Refuse a daylight input above its physical limit, naming the limit and its source.

    ``unit`` chooses the limit: "W m^-2" (irradiance, :data:`MAX_EXTRATERRESTRIAL_IRRADIANCE`), "lx"
    (illuminance, :data:`MAX_EXTRATERRESTRIAL_ILLUMINANCE`) or "cd m^-2" (sky luminance,
    :data:`MAX_SKY_LUMINANCE`); other units are not checked.

    Raises
    ------
    InvalidParameterError
    """
    limits = {
        "W m^-2": (MAX_EXTRATERRESTRIAL_IRRADIANCE, "the extraterrestrial solar irradiance at perihelion",
                   "1367 W m^-2 x 1.0344", "irradiance at the ground"),
        "lx": (MAX_EXTRATERRESTRIAL_ILLUMINANCE, "the extraterrestrial solar illuminance at perihelion",
               "luminous solar constant 133.8 klx, Darula et al. 2005", "illuminance at the ground"),
        "cd m^-2": (MAX_SKY_LUMINANCE, "the luminance of the solar disc outside the atmosphere",
                    "133.8 klx x 1.0344 over 6.8e-5 sr", "part of the sky"),
    }
    if unit in limits and value > limits[unit][0]:
        limit, what, source, nothing = limits[unit]
        raise InvalidParameterError(
            f"{name} {value:g} {unit} exceeds {what}, {limit:.4g} {unit} ({source}), which no {nothing} exceeds"
        )


def direction_from_angles(zenith: ArrayLike, azimuth: ArrayLike) -> NDArray[np.float64]:
    """Unit ENU direction(s) from zenith and azimuth angles.

    Parameters
    ----------
    zenith : array_like
        Zenith angle [rad], 0 at the zenith, pi/2 on the horizon.
    azimuth : array_like
        Azimuth [rad] from north towards east (pi/2 = east).

    Returns
    -------
    ndarray, shape (..., 3)
        Unit vectors (x east, y north, z up), broadcast over the inputs.
    """
    zenith = np.asarray(zenith, dtype=float)
    azimuth = np.asarray(azimuth, dtype=float)
    s = np.sin(zenith)
    return np.stack(np.broadcast_arrays(s * np.sin(azimuth), s * np.cos(azimuth), np.cos(zenith)), axis=-1)


def angles_from_direction(directions: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Zenith [rad] and azimuth [rad, in [0, 2 pi), from north towards east] of direction(s) (..., 3).

    The directions need not be normalised; they are validated with :func:`as_directions`.
    """
    d = as_directions(directions)
    zenith = np.arccos(np.clip(d[..., 2], -1.0, 1.0))
    azimuth = np.mod(np.arctan2(d[..., 0], d[..., 1]), 2.0 * np.pi)
    return zenith, azimuth


def angle_between(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """Angle [rad] between direction arrays ``a`` and ``b`` (..., 3), broadcast.

    Uses ``atan2(|a x b|, a . b)``, which stays accurate for nearly parallel directions where ``acos`` loses
    precision (the solar disc is only 4.7 mrad in radius).
    """
    a = as_directions(a)
    b = as_directions(b)
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    dot = np.sum(a * b, axis=-1)
    return np.arctan2(cross, dot)


def as_directions(directions: ArrayLike, *, normalise: bool = True) -> NDArray[np.floating]:
    """Validate an array of directions and return it as unit vectors.

    Parameters
    ----------
    directions : array_like, shape (..., 3)
        Direction vectors in the ENU frame (any length > 0 if ``normalise``).
    normalise : bool
        Divide by the vector length (default). With False the array is only checked.

    Raises
    ------
    InvalidDirectionError
        If the last axis is not of length 3, or a vector contains NaN/inf or has zero length.
    """
    try:
        d = np.asarray(directions)
        if not np.issubdtype(d.dtype, np.floating):
            if d.dtype.kind not in "biu":
                raise ValueError(f"got values of type {d.dtype}")
            d = d.astype(float)
    except (ValueError, TypeError) as exc:  # ragged lists, strings, objects
        raise InvalidDirectionError(
            f"directions must be numbers in an array of shape (..., 3) (x east, y north, z up): {exc}"
        ) from None
    if d.ndim == 0 or d.shape[-1] != 3:
        raise InvalidDirectionError(
            f"directions must be an array of shape (..., 3) (x east, y north, z up); got shape {d.shape}"
        )
    if not np.all(np.isfinite(d)):
        n_bad = int(np.count_nonzero(~np.all(np.isfinite(d), axis=-1)))
        raise InvalidDirectionError(f"directions contain NaN or infinite values ({n_bad} vectors)")
    norm = np.linalg.norm(d, axis=-1, keepdims=True)
    if np.any(norm == 0):
        raise InvalidDirectionError("directions contain zero-length vectors")
    return d / norm if normalise else d


def _check_size(name: str, value: int) -> int:
    if isinstance(value, (bool, str, bytes)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InvalidParameterError(f"{name} must be a positive whole number of pixels; got {value!r}")
    if not np.isfinite(value) or int(value) != value or value < 1:
        raise InvalidParameterError(f"{name} must be a positive whole number of pixels; got {value!r}")
    return int(value)


def equirect_directions(width: int, height: int | None = None) -> NDArray[np.float64]:
    """Directions at pixel centres of an equirectangular (latitude-longitude) image of the full sphere.

    Row 0 is the zenith, the middle of the image the horizon, the last row the nadir. The image is a
    panorama seen from inside the sphere: the centre column looks north and azimuth grows to the right, so
    column ``u`` in [0, 1) (left to right, pixel centres) has azimuth ``phi = 2 pi (u - 1/2)`` measured from
    north towards east: east at u = 3/4, west at u = 1/4, south at both edges (skyscatter's layout).
    Renderers put the image centre elsewhere (Blender on +X, Mitsuba with the Z-up ``rotate(x, 90)`` on -Y);
    :func:`skyscatter.render.sky_image` writes maps for each with its ``layout`` argument
    (docs/conventions.md, "Image layouts").

    Parameters
    ----------
    width : int
        Image width [px]; ``height`` defaults to ``width // 2``.

    Returns
    -------
    ndarray, shape (height, width, 3)
    """
    width = _check_size("width", width)
    if height is None and width < 2:
        raise InvalidParameterError(f"an equirectangular image needs width >= 2 px (height = width / 2); got {width}")
    height = _check_size("height", width // 2 if height is None else height)
    v = (np.arange(height) + 0.5) / height
    u = (np.arange(width) + 0.5) / width
    zenith = np.pi * v[:, None]
    azimuth = 2.0 * np.pi * (u[None, :] - 0.5)
    return direction_from_angles(zenith, azimuth)


def fisheye_directions(size: int) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Directions of an equidistant (angular) fisheye image of the upper hemisphere, zenith at the centre.

    The image is seen from below looking up, the usual all-sky camera view: north at the top, east on the
    **left**, west on the right. The distance from the centre is proportional to the zenith angle, the circle
    of radius ``size / 2`` being the horizon.

    Parameters
    ----------
    size : int
        Image width and height [px].

    Returns
    -------
    directions : ndarray, shape (size, size, 3)
        Unit vectors; pixels outside the horizon circle hold the direction they would have on the extended
        projection (below the horizon), so callers can use or mask them.
    inside : ndarray of bool, shape (size, size)
        True for pixels inside the horizon circle.
    """
    size = _check_size("size", size)
    c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    px, py = np.meshgrid(c, c)  # px: right, py: down
    r = np.hypot(px, py)
    zenith = r * (np.pi / 2.0)
    # Up in the image is north, left is east (view from below).
    azimuth = np.arctan2(-px, -py)
    return direction_from_angles(zenith, azimuth), r <= 1.0


def pinhole_directions(width: int, height: int, *, heading: float, pitch: float, fov: float) -> NDArray[np.float64]:
    """Ray directions through the pixel centres of a pinhole (rectilinear) camera.

    Parameters
    ----------
    width, height : int
        Image size [px]; row 0 is the top of the image.
    heading : float
        Azimuth of the optical axis [rad], from north towards east.
    pitch : float
        Elevation of the optical axis above the horizon [rad], in (-pi/2, pi/2).
    fov : float
        Horizontal field of view [rad], in (0, pi).

    Returns
    -------
    ndarray, shape (height, width, 3)
        Unit ENU directions. The camera has no roll: image right is horizontal.
    """
    width = _check_size("width", width)
    height = _check_size("height", height)
    if not (np.isfinite(fov) and 0.0 < fov < np.pi):
        raise InvalidParameterError(f"fov must be in (0, pi) rad; got {fov!r}")
    if not (np.isfinite(pitch) and abs(pitch) < np.pi / 2):
        raise InvalidParameterError(f"pitch must be in (-pi/2, pi/2) rad; got {pitch!r}")
    if not np.isfinite(heading):
        raise InvalidParameterError(f"heading must be finite [rad]; got {heading!r}")
    forward = direction_from_angles(np.pi / 2 - pitch, heading)
    right = np.array([np.cos(heading), -np.sin(heading), 0.0])
    up = np.cross(right, forward)
    half_w = np.tan(fov / 2.0)
    half_h = half_w * height / width
    sx = ((np.arange(width) + 0.5) / width * 2.0 - 1.0) * half_w
    sy = (1.0 - (np.arange(height) + 0.5) / height * 2.0) * half_h
    d = forward + sx[None, :, None] * right + sy[:, None, None] * up
    return d / np.linalg.norm(d, axis=-1, keepdims=True)
