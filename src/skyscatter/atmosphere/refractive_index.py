"""Complex refractive indices of particle materials as functions of wavelength [nm].

``m = n + i k`` with ``k >= 0`` for an absorbing material (the sign convention of [BohrenHuffman1983] Sec. 2.5,
with time dependence ``exp(-i omega t)``; OPAC and miepython write ``n - i k`` for the same material, and
:mod:`.mie_optics` converts).

* :class:`RefractiveIndex` - a table of ``n`` and ``k`` interpolated linearly in wavelength (or a constant).
* :func:`water_refractive_index` - liquid water at 25 C, [HaleQuerry1973] Table I, 250-1200 nm (data file
  ``water_refractive_index_hale_querry1973``, from the refractiveindex.info database, CC0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import FileFormatError, InvalidParameterError
from .tables import load_table

__all__ = ["RefractiveIndex", "water_refractive_index"]


@dataclass(frozen=True)
class RefractiveIndex:
    """A complex refractive index ``n + i k`` tabulated in wavelength, linear between entries.

    Parameters
    ----------
    wavelengths : tuple of float
        Strictly increasing wavelengths [nm] (one entry: the same index at every wavelength).
    n : tuple of float
        Real parts, > 0 [-].
    k : tuple of float
        Imaginary parts, >= 0 (absorption) [-].
    name : str
        Label for messages.
    """

    wavelengths: tuple[float, ...]
    n: tuple[float, ...]
    k: tuple[float, ...]
    name: str = "refractive index"

    def __post_init__(self) -> None:
        wl, n, k = (np.atleast_1d(np.asarray(v, dtype=float)) for v in (self.wavelengths, self.n, self.k))
        if wl.ndim != 1 or wl.shape != n.shape or wl.shape != k.shape or wl.size < 1:
            raise InvalidParameterError(f"{self.name}: wavelengths, n and k must be 1-D and of equal length")
        if not (np.all(np.isfinite(wl)) and np.all(np.isfinite(n)) and np.all(np.isfinite(k))):
            raise InvalidParameterError(f"{self.name}: wavelengths, n and k must be finite")
        if np.any(wl <= 0) or np.any(np.diff(wl) <= 0):
            raise InvalidParameterError(f"{self.name}: wavelengths must be > 0 nm and strictly increasing")
        if np.any(n <= 0):
            raise InvalidParameterError(f"{self.name}: the real part n must be > 0; got {n.min():g}")
        if np.any(k < 0):
            raise InvalidParameterError(
                f"{self.name}: the imaginary part k must be >= 0 (m = n + i k, k > 0 absorbs); got {k.min():g}")
        for label, arr in (("wavelengths", wl), ("n", n), ("k", k)):
            object.__setattr__(self, label, tuple(float(x) for x in arr))

    @classmethod
    def constant(cls, m: complex, name: str = "refractive index") -> RefractiveIndex:
        """The same index ``m = n + i k`` (``k >= 0``) at every wavelength."""
        c = complex(m)
        return cls((550.0,), (c.real,), (c.imag,), name)

    @property
    def range(self) -> tuple[float, float]:
        """Wavelength range [nm] of the table (0 to infinity for a constant)."""
        if len(self.wavelengths) == 1:
            return 0.0, math.inf
        return self.wavelengths[0], self.wavelengths[-1]

    def __call__(self, wavelengths: ArrayLike) -> NDArray[np.complex128]:
        """``n + i k`` at ``wavelengths`` [nm]; InvalidParameterError outside the table."""
        wl = np.asarray(wavelengths, dtype=float)
        if len(self.wavelengths) == 1:
            return np.full(wl.shape, complex(self.n[0], self.k[0]))
        lo, hi = self.range
        if wl.size and (not np.all(np.isfinite(wl)) or np.min(wl) < lo - 1e-9 or np.max(wl) > hi + 1e-9):
            raise InvalidParameterError(f"{self.name} is tabulated for {lo:g}-{hi:g} nm; asked for "
                                        f"{np.min(wl):g}-{np.max(wl):g} nm")
        return np.interp(wl, self.wavelengths, self.n) + 1j * np.interp(wl, self.wavelengths, self.k)

    def to_dict(self) -> dict[str, Any]:
        return {"wavelengths": list(self.wavelengths), "n": list(self.n), "k": list(self.k), "name": self.name}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> RefractiveIndex:
        try:
            return cls(tuple(data["wavelengths"]), tuple(data["n"]), tuple(data["k"]), data.get("name", "refractive "
                                                                                                 "index"))
        except (KeyError, TypeError) as exc:
            raise FileFormatError(f"refractive index description is malformed: {exc}") from None


@cache
def water_refractive_index() -> RefractiveIndex:
    """Liquid water at 25 C, 250-1200 nm: Hale & Querry (1973), Table I (module docstring)."""
    t = load_table("water_refractive_index_hale_querry1973")
    return RefractiveIndex(tuple(t["wavelength_nm"]), tuple(t["n_real"]), tuple(t["n_imag"]),
                           "liquid water (Hale & Querry 1973)")
