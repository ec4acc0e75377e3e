"""Argument checks shared by the atmosphere modules."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ..spectral import as_wavelengths


def scattering_angles(theta: ArrayLike) -> NDArray[np.float64]:
    """Scattering angles [rad] as a float array, checked to lie in [0, pi] (no NaN)."""
    th = np.asarray(theta, dtype=float)
    if np.any(np.isnan(th)) or np.any(th < 0.0) or np.any(th > np.pi + 1e-12):
        raise InvalidParameterError("scattering angle theta must be in [0, pi] rad (no NaN)")
    return np.clip(th, 0.0, np.pi)


def wavelengths_m(wavelengths: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Validated wavelengths as (nm, m) arrays of shape (n,)."""
    wl = as_wavelengths(wavelengths)
    return wl, wl * 1e-9


def positive_finite(name: str, value: float, *, allow_zero: bool = False) -> float:
    """A float that is finite and > 0 (or >= 0), else InvalidParameterError naming the parameter."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a number; got {value!r}") from None
    if not np.isfinite(v) or v < 0.0 or (v == 0.0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise InvalidParameterError(f"{name} must be finite and {bound}; got {value!r}")
    return v
