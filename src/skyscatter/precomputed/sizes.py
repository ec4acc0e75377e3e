"""Table sizes and wavelengths of the precomputed atmosphere: what the tables of :mod:`.tables` are sampled on.

* :class:`TableSizes` - the resolutions of the four tables and the sample counts of the integrals (the paper's
  Sec. 6 sizes by default);
* :func:`table_wavelengths` - the table wavelengths [nm] from a list or a named set (``"spectral"``, the default
  16 wavelengths, or ``"rgb"``, the paper's three);
* :data:`DEFAULT_ORDERS` - scattering orders computed one by one (:mod:`.compute`, "Orders").
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..deprecation import warn_renamed
from ..errors import InvalidParameterError
from ..validation import whole_number

__all__ = ["DEFAULT_ORDERS", "DEFAULT_TABLE_WAVELENGTHS", "NAMED_WAVELENGTHS", "RGB_TABLE_WAVELENGTHS", "TableSizes",
           "table_wavelengths"]

#: Wavelengths [nm] of the default tables: 16 from 400 to 700 nm every 20 nm, the spectral mode (colour by the
#: CIE observer, :mod:`.conversion`). Chosen by measured colour error per second of precomputation
#: (``benchmarks/bruneton_colour_error.py``, ``docs/bruneton.md``): within delta-xy 0.005 and 2 % in luminance
#: of 41 wavelengths (380-780 nm, 10 nm) at sun elevations 90 to -6 deg, sky and ground. The 20 nm spacing, not
#: the range, sets the error: 20 wavelengths over 380-760 nm were no closer, 14 over 400-660 nm or 11 every
#: 30 nm failed the bounds.
DEFAULT_TABLE_WAVELENGTHS = tuple(float(w) for w in range(400, 701, 20))
#: Wavelengths [nm] of the fast 3-wavelength mode (red, green, blue samples of the 2008 paper): faster to
#: precompute, colour reconstructed from 3 samples; its measured error is in ``docs/bruneton.md``.
RGB_TABLE_WAVELENGTHS = (440.0, 550.0, 680.0)
#: Names accepted for ``wavelengths``: ``"spectral"`` (the default) and ``"rgb"`` (the 3-wavelength mode).
NAMED_WAVELENGTHS = {"spectral": DEFAULT_TABLE_WAVELENGTHS, "rgb": RGB_TABLE_WAVELENGTHS}
#: Scattering orders computed by default; the rest is the geometric tail (:mod:`.compute`, "Orders"). 8, not 6
#: (until 2026-12-05): in hazy air at 400 nm the orders' ratio is still rising at the sixth order, and the tail
#: after 6 orders was up to 18 % short of the converged sum near the ground in twilight (3 % with the sun up).
DEFAULT_ORDERS = 8


@dataclass(frozen=True)
class TableSizes:
    """Table resolutions and integration sample counts (defaults: the paper's Sec. 6 sizes).

    Parameters
    ----------
    transmittance_mu, transmittance_r : int
        Transmittance table (256 x 64).
    irradiance_mu_s, irradiance_r : int
        Irradiance table (64 x 16).
    scattering_r, scattering_mu, scattering_mu_s, scattering_nu : int
        4D scattering tables (32 x 128 x 32 x 8); ``scattering_mu`` is even (half per side of the horizon).
    transmittance_samples : int
        Trapezoid steps of the optical-length integrals (500).
    ray_samples : int
        Steps of the single and multiple scattering ray integrals (50).
    density_sphere_samples : int
        Zenith steps of the sphere quadrature of the scattering density (16, with twice as many azimuths).
    irradiance_sphere_samples : int
        Zenith steps of the hemisphere quadrature of the irradiance (32, with twice as many azimuths).
    """

    transmittance_mu: int = 256
    transmittance_r: int = 64
    irradiance_mu_s: int = 64
    irradiance_r: int = 16
    scattering_r: int = 32
    scattering_mu: int = 128
    scattering_mu_s: int = 32
    scattering_nu: int = 8
    transmittance_samples: int = 500
    ray_samples: int = 50
    density_sphere_samples: int = 16
    irradiance_sphere_samples: int = 32

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            object.__setattr__(self, f.name, whole_number(f"table size {f.name}", v, 2))
        if self.scattering_mu % 2 or self.scattering_mu < 4:
            raise InvalidParameterError(
                "scattering_mu must be even and >= 4 (half of it on each side of the horizon); "
                f"got {self.scattering_mu}"
            )

    @classmethod
    def coerce(cls, sizes: TableSizes | Mapping[str, int] | None) -> TableSizes:
        """A TableSizes from None (defaults), an instance, or a mapping of field overrides."""
        if sizes is None:
            return cls()
        if isinstance(sizes, TableSizes):
            return sizes
        if isinstance(sizes, Mapping):
            unknown = set(sizes) - {f.name for f in dataclasses.fields(cls)}
            if unknown:
                raise InvalidParameterError(
                    f"unknown table size(s) {sorted(unknown)}; allowed: {[f.name for f in dataclasses.fields(cls)]}"
                )
            return cls(**sizes)
        raise InvalidParameterError(f"sizes must be a TableSizes, a mapping or None; got {type(sizes).__name__}")

    @property
    def transmittance_shape(self) -> tuple[int, int]:
        """(n_r, n_mu)."""
        return self.transmittance_r, self.transmittance_mu

    @property
    def irradiance_shape(self) -> tuple[int, int]:
        """(n_r, n_mu_s)."""
        return self.irradiance_r, self.irradiance_mu_s

    @property
    def scattering_shape(self) -> tuple[int, int, int, int]:
        """(n_r, n_mu, n_mu_s, n_nu)."""
        return self.scattering_r, self.scattering_mu, self.scattering_mu_s, self.scattering_nu


def table_wavelengths(wavelengths: ArrayLike | str | None = None, tables: str | None = None) -> NDArray[np.float64]:
    """The table wavelengths [nm], sorted and unique: ``wavelengths`` [nm], or the named set ``tables`` (a key of
    :data:`NAMED_WAVELENGTHS`: ``"spectral"``, ``"rgb"``), or neither (the default, ``"spectral"``).

    A name given as ``wavelengths`` is the deprecated spelling of ``tables`` (DeprecationWarning).
    """
    if isinstance(wavelengths, str):
        if tables is not None:
            raise InvalidParameterError("give the named set as tables= only")
        warn_renamed("wavelengths=<name of a set>", "tables=<name>", "precomputed tables", stacklevel=4)
        wavelengths, tables = None, wavelengths
    if tables is not None:
        if wavelengths is not None:
            raise InvalidParameterError("give either tables (a named set of wavelengths) or wavelengths [nm], not both")
        named = NAMED_WAVELENGTHS.get(tables.strip().lower()) if isinstance(tables, str) else None
        if named is None:
            raise InvalidParameterError(
                f"tables {tables!r} is not a known set; use one of {sorted(NAMED_WAVELENGTHS)} (or give the "
                "wavelengths [nm] as wavelengths=)"
            )
        return np.array(named)
    if wavelengths is None:
        return np.array(DEFAULT_TABLE_WAVELENGTHS)
    wl = np.atleast_1d(np.asarray(wavelengths, dtype=float)).ravel()
    if wl.size == 0 or not np.all(np.isfinite(wl)) or np.any(wl <= 0):
        raise InvalidParameterError("wavelengths must be a non-empty list of positive finite values [nm]")
    wl = np.unique(wl)
    if wl.size > 200:
        raise InvalidParameterError(f"at most 200 wavelengths are supported; got {wl.size}")
    return wl
