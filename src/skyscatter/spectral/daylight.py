"""CIE daylight spectra from chromaticity (Preetham et al. 1999, Appendix A.5; Wyszecki & Stiles 1982).

``S_D(lambda) = S0(lambda) + M1 S1(lambda) + M2 S2(lambda)`` with the CIE daylight basis S0, S1, S2 (CIE
015:2004 Table T.2, 5 nm, 300-830 nm; shipped as ``skyscatter/data/cie_daylight_basis.csv``, generated from
colour-science's table) and ``M1``, ``M2`` from the chromaticity (x, y) (Preetham 1999 A.5, the CIE formula).
The daylight locus for a correlated colour temperature is CIE 015:2004 Eqs. 3.3-3.4.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from .grid import as_wavelengths

__all__ = ["daylight_basis", "daylight_chromaticity", "daylight_coefficients", "daylight_spectrum"]


def _basis_table() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    from ._colour import cie_table

    return cie_table("cie_daylight_basis")


def daylight_chromaticity(cct: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """CIE daylight-locus chromaticity (x_D, y_D) for a correlated colour temperature [K], 4000-25000 K.

    CIE 015:2004 Eq. 3.3: ``x_D = -4.6070e9/T^3 + 2.9678e6/T^2 + 0.09911e3/T + 0.244063`` for
    4000 <= T <= 7000 K, ``x_D = -2.0064e9/T^3 + 1.9018e6/T^2 + 0.24748e3/T + 0.237040`` above; Eq. 3.4:
    ``y_D = -3.000 x_D^2 + 2.870 x_D - 0.275``.
    """
    t = np.asarray(cct, dtype=float)
    if not np.all(np.isfinite(t) & (t >= 4000.0) & (t <= 25000.0)):
        raise InvalidParameterError(f"daylight CCT must be within 4000-25000 K (CIE 015:2004); got {cct!r}")
    x = np.where(
        t <= 7000.0,
        -4.6070e9 / t**3 + 2.9678e6 / t**2 + 0.09911e3 / t + 0.244063,
        -2.0064e9 / t**3 + 1.9018e6 / t**2 + 0.24748e3 / t + 0.237040,
    )
    return x, -3.000 * x**2 + 2.870 * x - 0.275


def daylight_basis(wavelengths: ArrayLike) -> NDArray[np.float64]:
    """CIE daylight basis S0, S1, S2 at ``wavelengths`` [nm], shape (n, 3), linearly interpolated.

    Zero outside the tabulated 300-830 nm.
    """
    wl = as_wavelengths(wavelengths)
    table_wl, table = _basis_table()
    return np.stack([np.interp(wl, table_wl, table[:, i], left=0.0, right=0.0) for i in range(3)], axis=-1)


def daylight_coefficients(x: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Scalar multiples M1, M2 of the daylight basis for chromaticity (x, y) (Preetham 1999, A.5).

    ``M1 = (-1.3515 - 1.7703 x + 5.9114 y) / (0.0241 + 0.2562 x - 0.7341 y)``,
    ``M2 = (0.0300 - 31.4424 x + 30.0717 y) / (0.0241 + 0.2562 x - 0.7341 y)``.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    m = 0.0241 + 0.2562 * x - 0.7341 * y
    return (-1.3515 - 1.7703 * x + 5.9114 * y) / m, (0.0300 - 31.4424 * x + 30.0717 * y) / m


def daylight_spectrum(x: ArrayLike, y: ArrayLike, wavelengths: ArrayLike) -> NDArray[np.float64]:
    """Relative CIE daylight spectral power ``S0 + M1 S1 + M2 S2`` for chromaticity (x, y).

    Parameters
    ----------
    x, y : array_like
        CIE 1931 chromaticity, broadcast together (the model is meant for points near the daylight locus).
    wavelengths : array_like
        Wavelengths [nm].

    Returns
    -------
    ndarray, shape (..., n_wavelengths)
        Relative spectrum (dimensionless, S0 = 100 at 560 nm); scale it to the wanted luminance.
    """
    m1, m2 = daylight_coefficients(x, y)
    basis = daylight_basis(wavelengths)
    return basis[:, 0] + m1[..., None] * basis[:, 1] + m2[..., None] * basis[:, 2]
