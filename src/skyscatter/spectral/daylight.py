"""CIE daylight spectra from chromaticity (Preetham et al. 1999, Appendix A.5; Wyszecki & Stiles 1982).

``S_D(lambda) = S0(lambda) + M1 S1(lambda) + M2 S2(lambda)`` with the CIE daylight basis S0, S1, S2 as
tabulated by colour-science (CIE 15, 5 nm, 300-830 nm) and ``M1``, ``M2`` from the chromaticity (x, y)
(Preetham 1999 A.5, the CIE formula).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .grid import as_wavelengths

__all__ = ["daylight_basis", "daylight_coefficients", "daylight_spectrum"]


@lru_cache(maxsize=1)
def _basis_table() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    from ._colour import colour_module

    basis = colour_module("colour.colorimetry").SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES

    wl = np.asarray(basis["S0"].wavelengths, dtype=float)
    values = np.stack([np.asarray(basis[k].values, dtype=float) for k in ("S0", "S1", "S2")], axis=-1)
    return wl, values


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
