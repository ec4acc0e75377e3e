"""Scattering phase functions [sr^-1], each normalised to 1 over the sphere.

All take ``cos_theta``, the cosine of the scattering angle (0 = forward scattering), as an array of any shape
and return an array of the same shape.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError

__all__ = ["cornette_shanks", "henyey_greenstein", "rayleigh_phase"]


def _cos(cos_theta: ArrayLike) -> NDArray[np.float64]:
    mu = np.asarray(cos_theta, dtype=float)
    if np.any(np.isnan(mu)) or np.any(np.abs(mu) > 1.0 + 1e-12):
        raise InvalidParameterError("cos_theta must be the cosine of a scattering angle, in [-1, 1] (no NaN)")
    return np.clip(mu, -1.0, 1.0)


def _asymmetry(g: float) -> float:
    g = float(g)
    if not -1.0 < g < 1.0:
        raise InvalidParameterError(f"asymmetry parameter g must be in (-1, 1); got {g}")
    return g


def rayleigh_phase(cos_theta: ArrayLike) -> NDArray[np.float64]:
    """Rayleigh phase function ``3 / (16 pi) (1 + cos^2 theta)`` [sr^-1].

    Preetham (1999) A.3 (the angular/total ratio of the molecular coefficients); course notes (Preetham,
    "Modeling Skylight and Aerial Perspective"), f_air. Depolarisation is ignored in the angular shape, as in
    the paper.

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the scattering angle [-].
    """
    mu = _cos(cos_theta)
    return 3.0 / (16.0 * np.pi) * (1.0 + mu * mu)


def henyey_greenstein(cos_theta: ArrayLike, g: float) -> NDArray[np.float64]:
    """Henyey-Greenstein (1941) phase function [sr^-1].

    ``(1 - g^2) / (4 pi (1 + g^2 - 2 g cos theta)^(3/2))``, as given in Preetham's course notes (Mie
    scattering section).

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the scattering angle [-].
    g : float
        Asymmetry parameter (mean cosine) in (-1, 1) [-]; positive values scatter forwards.
    """
    mu = _cos(cos_theta)
    g = _asymmetry(g)
    return (1.0 - g * g) / (4.0 * np.pi * (1.0 + g * g - 2.0 * g * mu) ** 1.5)


def cornette_shanks(cos_theta: ArrayLike, g: float) -> NDArray[np.float64]:
    """Cornette & Shanks (1992) phase function [sr^-1], the Mie phase of Bruneton & Neyret (2008), Eq. 4.

    ``3 (1 - g^2) (1 + cos^2 theta) / (8 pi (2 + g^2) (1 + g^2 - 2 g cos theta)^(3/2))``.

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the scattering angle [-].
    g : float
        Asymmetry parameter in (-1, 1) [-] (Bruneton's default 0.8).
    """
    mu = _cos(cos_theta)
    g = _asymmetry(g)
    return (
        3.0 * (1.0 - g * g) * (1.0 + mu * mu)
        / (8.0 * np.pi * (2.0 + g * g) * (1.0 + g * g - 2.0 * g * mu) ** 1.5)
    )
