"""Relative optical air mass, [Preetham1999] A.1.

    m(theta_s) = 1 / (cos theta_s + 0.15 (93.885 - theta_s[deg])^-1.253)

the form of [Kasten1966], as quoted by [Iqbal1983].
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError

__all__ = ["relative_optical_mass", "relative_optical_mass_kasten1966"]


def relative_optical_mass_kasten1966(zenith: ArrayLike) -> NDArray[np.float64] | float:
    """Relative optical mass m [-] of the path to a source at ``zenith`` (Preetham 1999, A.1).

    1 at the zenith, about 38 at the horizon; the formula is defined up to the horizon here.

    Parameters
    ----------
    zenith : array_like
        Zenith angle of the path [rad], in [0, pi/2].

    Returns
    -------
    float or ndarray
        Same shape as ``zenith`` (a float for scalar input).
    """
    z = np.asarray(zenith, dtype=float)
    if np.any(np.isnan(z)) or np.any(z < 0.0) or np.any(z > np.pi / 2 + 1e-12):
        raise InvalidParameterError("zenith angle for the optical mass must be in [0, pi/2] rad (no NaN)")
    z = np.clip(z, 0.0, np.pi / 2)
    m = 1.0 / (np.cos(z) + 0.15 * (93.885 - np.degrees(z)) ** -1.253)
    return float(m) if m.ndim == 0 else m


#: Former name of :func:`relative_optical_mass_kasten1966` (kept as an alias).
relative_optical_mass = relative_optical_mass_kasten1966
