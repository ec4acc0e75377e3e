"""Quadrature over the part of the sky a plane sees: ``E = integral L(d) cos(incidence) dOmega``.

The visible part of the sky is the lune between the horizon and the plane. It is integrated exactly in its own
bounds: Gauss-Legendre in the zenith angle theta, split where the plane's edge starts to cut the azimuth range
(theta* = |pi/2 - tilt|), and for every theta a Gauss-Legendre rule over the visible azimuth interval
``|phi - phi_n| <= arccos(-cot theta cot tilt)``. The rule lives below the sky models (layer 0) because the CIE and
Perez skies scale themselves to a diffuse illuminance with it; :mod:`skyscatter.photometry` uses it for every
illuminance (accuracy in that module's docstring).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .conventions import direction_from_angles
from .errors import InvalidParameterError

__all__ = ["DEFAULT_NODES", "check_angle", "plane_integral", "plane_quadrature"]

#: Default Gauss-Legendre node counts (per zenith segment, azimuth) of :func:`plane_quadrature`.
DEFAULT_NODES = (96, 192)


@cache
def _gauss(n: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    x, w = np.polynomial.legendre.leggauss(n)
    x.flags.writeable = False
    w.flags.writeable = False
    return x, w


def check_angle(name: str, value: float, low: float, high: float) -> float:
    """``value`` as a float [rad] in [low, high]; InvalidParameterError naming ``name`` otherwise."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a number in radians; got {value!r}") from None
    if not (np.isfinite(v) and low <= v <= high):
        raise InvalidParameterError(f"{name} must be within [{low:.6g}, {high:.6g}] rad; got {v!r}")
    return v


@cache
def _plane_quadrature_cached(tilt: float, azimuth: float, n_zenith: int, n_azimuth: int):
    normal = direction_from_angles(tilt, azimuth)
    cos_b, sin_b = np.cos(tilt), np.sin(tilt)
    # theta* where the plane's edge (great circle n . d = 0) meets the horizon band structure
    split = abs(np.pi / 2 - tilt)
    edges = [0.0, np.pi / 2] if split <= 1e-12 or split >= np.pi / 2 - 1e-12 else [0.0, split, np.pi / 2]
    xg, wg = _gauss(n_zenith)
    xa, wa = _gauss(n_azimuth)
    thetas, wthetas = [], []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        thetas.append(lo + (hi - lo) * 0.5 * (xg + 1.0))
        wthetas.append((hi - lo) * 0.5 * wg)
    theta = np.concatenate(thetas)
    w_theta = np.concatenate(wthetas)
    # visible half-width of the azimuth range at each theta: n . d >= 0 <=> cos(dphi) >= -cot(theta) cot(tilt)
    q = -np.cos(theta) * cos_b
    r = np.sin(theta) * sin_b
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(np.abs(r) > 1e-15, q / np.where(np.abs(r) > 1e-15, r, 1.0), np.where(q <= 0, -2.0, 2.0))
    half = np.arccos(np.clip(ratio, -1.0, 1.0))  # (T,)
    dphi = half[:, None] * xa[None, :]  # (T, A)
    weights = w_theta[:, None] * np.sin(theta)[:, None] * (half[:, None] * wa[None, :])
    dirs = direction_from_angles(theta[:, None], azimuth + dphi)
    cos_inc = np.clip(dirs @ normal, 0.0, None)
    weights = weights * cos_inc
    keep = weights > 0
    d = dirs[keep]
    w = weights[keep]
    d.flags.writeable = False
    w.flags.writeable = False
    return d, w


def plane_quadrature(
    tilt: float = 0.0, azimuth: float = 0.0, *, nodes: tuple[int, int] = DEFAULT_NODES
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Quadrature rule for the sky seen by a plane: ``E = sum(L(directions) * weights)``.

    Parameters
    ----------
    tilt : float
        Angle between the plane's outward normal and the zenith [rad], in [0, pi]: 0 horizontal facing up,
        pi/2 vertical.
    azimuth : float
        Azimuth of the normal's horizontal component [rad, from north towards east]; ignored for tilt 0.
    nodes : (int, int)
        Gauss-Legendre nodes per zenith-angle segment and over the visible azimuth range.

    Returns
    -------
    directions : ndarray, shape (M, 3)
        Sky directions (z >= 0) in front of the plane.
    weights : ndarray, shape (M,)
        ``cos(incidence) dOmega`` [sr]; for the horizontal plane they sum to pi.
    """
    t = check_angle("tilt", tilt, 0.0, np.pi)
    a = float(np.mod(check_angle("azimuth", azimuth, -4 * np.pi, 4 * np.pi), 2 * np.pi))
    if t == 0.0:
        a = 0.0
    nz, na = (int(n) for n in nodes)
    if nz < 2 or na < 2 or nz > 2048 or na > 4096:
        raise InvalidParameterError(f"nodes must be two whole numbers in [2, 2048] and [2, 4096]; got {nodes!r}")
    return _plane_quadrature_cached(t, a, nz, na)


def plane_integral(
    func: Callable[[NDArray[np.float64]], ArrayLike],
    tilt: float = 0.0,
    azimuth: float = 0.0,
    *,
    nodes: tuple[int, int] = DEFAULT_NODES,
) -> float:
    """``integral f(d) cos(incidence) dOmega`` over the sky in front of a plane, for ``f`` mapping (M, 3) -> (M,).

    With ``f`` a luminance [cd m^-2] the result is an illuminance [lx]. See :func:`plane_quadrature`.
    """
    d, w = plane_quadrature(tilt, azimuth, nodes=nodes)
    values = np.asarray(func(d), dtype=float)
    return float(values @ w)
