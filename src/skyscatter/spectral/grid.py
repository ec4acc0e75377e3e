"""Wavelength grids [nm]."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError

__all__ = ["DEFAULT_WAVELENGTHS", "REFERENCE_WAVELENGTHS", "as_wavelengths", "wavelength_grid"]


def wavelength_grid(start: float = 380.0, stop: float = 780.0, step: float = 10.0) -> NDArray[np.float64]:
    """Evenly spaced wavelengths [nm] from ``start`` to ``stop`` inclusive, ``step`` apart [nm]."""
    if not (0 < start < stop) or step <= 0:
        raise InvalidParameterError(
            f"wavelength grid needs 0 < start < stop and step > 0 [nm]; got {start}, {stop}, {step}"
        )
    n = int(round((stop - start) / step)) + 1
    return np.linspace(start, start + (n - 1) * step, n)


#: 41 wavelengths, 380-780 nm every 10 nm: the grid used when a caller gives none.
DEFAULT_WAVELENGTHS = wavelength_grid(380.0, 780.0, 10.0)
#: 5 nm grid over the whole CIE observer range, used internally to normalise spectra to a luminance.
REFERENCE_WAVELENGTHS = wavelength_grid(360.0, 830.0, 5.0)


def as_wavelengths(wavelengths: ArrayLike | None) -> NDArray[np.float64]:
    """Validate wavelengths [nm] (finite, positive, 1-D); ``None`` gives :data:`DEFAULT_WAVELENGTHS`."""
    if wavelengths is None:
        return DEFAULT_WAVELENGTHS
    wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
    if wl.ndim != 1 or wl.size == 0:
        raise InvalidParameterError(f"wavelengths must be a 1-D array of values in nm; got shape {wl.shape}")
    if not np.all(np.isfinite(wl)) or np.any(wl <= 0):
        raise InvalidParameterError("wavelengths must be finite and positive [nm]")
    return wl
