"""The precomputed atmosphere of Bruneton & Neyret (2008): its tables, how they are computed, stored and read.

:class:`PrecomputedAtmosphere` holds the tables of one atmosphere and brings together three concerns, one module
each:

* computing them - :mod:`.compute` (Algorithm 4.1, one function per step; :meth:`PrecomputedAtmosphere.compute`);
* storing them - :mod:`.storage` (cache key, file format, :meth:`~PrecomputedAtmosphere.save` /
  :meth:`~PrecomputedAtmosphere.load`; :mod:`.export` for real-time engines);
* evaluating them - :mod:`.evaluation` (sky radiance, aerial perspective, sun, irradiance, colour), with the
  numba kernels of :mod:`.lookup`.

Their sizes and wavelengths are in :mod:`.sizes`.

Storage follows the paper's separation of single scattering (Sec. 4, "Angular precision"): ``single_rayleigh``
holds ``S_R[L0]`` and ``single_mie`` ``S_M[L0]``, both without their phase functions, so the sharp Mie forward
peak is applied at full resolution at lookup; ``multiple`` holds ``S[L*]`` (orders 2 and up, phase included).
The radiance is ``single_rayleigh P_R(nu) + single_mie P_M(nu) + multiple``. The paper packs the multiple
scattering into the Rayleigh channel as ``C* = S_R[L0] + S[L*] / P_R``; where a texel's ``nu`` is clamped to
the range its ``mu`` and ``mu_s`` allow (views or sun near the zenith) that division and the multiplication
by ``P_R`` of the looked-up ``nu`` do not cancel, which skews multiple scattering towards the sun by up to 40 %
(measured against DISORT, ``docs/bruneton.md``). The packed ``C*`` is still produced by :meth:`export`.
With a tabulated (Mie) aerosol phase and two or more orders, the orders are computed in the delta-M scaled
medium (:meth:`.compute.Medium.delta_m_scaled`: the phase's forward peak left in the beam) and the two single
tables are its single scattering, with the scaled transmittances and per unit unscaled scattering coefficient,
so that ``P_M(nu)`` at lookup is the full phase: the TMS correction of [NakajimaTanaka1988], as DISORT's; they
then include the light the forward peak scattered on before or after the one scattering at ``nu`` (one order's
tables hold the exact single scattering).
Tables are float32 with a trailing wavelength axis: transmittance (n_r, n_mu), irradiance (n_r, n_mu_s),
scattering (n_r, n_mu, n_mu_s, n_nu); ``irradiance`` is the sky's (orders 1 and up), not the sun's. The three
scattering tables are kept and stored in half precision with a power-of-two scale per wavelength, radius and sun
zenith (:class:`.storage.HalfTable`, at most 0.049 % rounding), in the computation's results as in the files,
so computed and loaded tables give the same values.

Reference: [Bruneton2008].
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..deprecation import renamed_keywords
from ..errors import FileFormatError
from .evaluation import TableLookups
from .parameters import AtmosphereParameters
from .sizes import (
    DEFAULT_ORDERS,
    DEFAULT_TABLE_WAVELENGTHS,
    NAMED_WAVELENGTHS,
    RGB_TABLE_WAVELENGTHS,
    TableSizes,
)
from .storage import FORMAT_VERSION, HALF_TABLES, TABLE_NAMES, HalfTable, cache_key, read_tables, write_tables

# The constants, TableSizes and cache_key are defined in .sizes and .storage; they stay importable from here.
__all__ = ["DEFAULT_ORDERS", "DEFAULT_TABLE_WAVELENGTHS", "FORMAT_VERSION", "NAMED_WAVELENGTHS",
           "RGB_TABLE_WAVELENGTHS", "PrecomputedAtmosphere", "TableSizes", "cache_key"]


class PrecomputedAtmosphere(TableLookups):
    """Precomputed transmittance, irradiance and scattering tables of one atmosphere, and their lookups.

    Build one with :meth:`compute` (or :func:`skyscatter.precomputed.cached_atmosphere`, which keeps the
    tables on disk) or read one with :meth:`load`. Positions are in metres in a planet-centred frame (the
    planet's centre at the origin); directions are unit vectors in the same frame. Radiance is spectral, at
    :attr:`wavelengths`; :meth:`to_xyz` converts it (see :mod:`.conversion`). The lookups are those of
    :class:`.evaluation.TableLookups`.

    Constructed directly (``PrecomputedAtmosphere(atmosphere, wavelengths, sizes, orders, tables)``), the tables may
    be anyone's; ``computed=True`` says that they are the precomputation's of ``atmosphere`` (what :meth:`compute`
    and :meth:`load` give), so that the lookups may compute values the tables do not hold from ``atmosphere`` itself:
    the single scattering at the sub-texels of the refined sun-zenith axis (:func:`.lookup.refine_sun_zenith`;
    without it they take the interpolation rule there). ``ground_rows=True`` says that every radius row of the 4D
    tables holds the ground's (the weather family's ground-only nodes): those values are then the ground's in every
    row.
    """

    def __init__(self, atmosphere: AtmosphereParameters, wavelengths: ArrayLike, sizes: TableSizes, orders: int,
                 tables: Mapping[str, NDArray[np.float32]], timings: Mapping[str, float] | None = None, *,
                 computed: bool = False, ground_rows: bool = False) -> None:
        self.parameters = atmosphere
        #: True when the tables are the precomputation's of :attr:`parameters` (class docstring)
        self.computed = bool(computed)
        #: True when every radius row of the 4D tables holds the ground's (class docstring)
        self.ground_rows = bool(ground_rows)
        self.wavelengths = np.asarray(wavelengths, dtype=float)
        self.sizes = sizes
        self.orders = int(orders)
        stored: dict[str, NDArray[np.float32] | HalfTable] = {}
        for name in TABLE_NAMES:
            table = tables[name]
            if name in HALF_TABLES:
                stored[name] = table if isinstance(table, HalfTable) else HalfTable.encode(table)
            else:
                # a copy (small): a read-only memory map would make numba compile its kernels again for it
                stored[name] = np.array(table, dtype=np.float32, order="C")
        #: The tables as stored (:mod:`.storage`): float32 arrays and :class:`.storage.HalfTable` objects (possibly
        #: memory maps of a table file); :attr:`tables` decodes them.
        self.stored = stored
        self._decoded: dict[str, NDArray[np.float32]] | None = None
        self.timings = dict(timings or {})
        nl = self.wavelengths.size
        expected = {
            "transmittance": (*sizes.transmittance_shape, nl),
            "irradiance": (*sizes.irradiance_shape, nl),
            "single_rayleigh": (*sizes.scattering_shape, nl),
            "single_mie": (*sizes.scattering_shape, nl),
            "multiple": (*sizes.scattering_shape, nl),
        }
        for name, shape in expected.items():
            if tuple(self.stored[name].shape) != shape:
                raise FileFormatError(f"table {name} has shape {self.stored[name].shape}, expected {shape}")
        self._solar = atmosphere.solar_irradiance_at(self.wavelengths)
        self._albedo = atmosphere.ground_albedo_at(self.wavelengths)
        self._xyz_matrix: NDArray[np.float64] | None = None
        self._colour = None  # the ColourConversion, built on first use

    @property
    def tables(self) -> dict[str, NDArray[np.float32]]:
        """The tables as float32 arrays, wavelength last (module docstring): the half-precision scattering tables
        are decoded on first use (a sky seen by one observer reads only slices of :attr:`stored` and never needs
        this)."""
        if self._decoded is None:
            self._decoded = {name: t.decode() if isinstance(t, HalfTable) else t for name, t in self.stored.items()}
        return self._decoded

    # ------------------------------------------------------------------ computation

    @classmethod
    @renamed_keywords(params="atmosphere")
    def compute(cls, atmosphere: AtmosphereParameters | None = None, *, orders: int = DEFAULT_ORDERS,
                tables: str | None = None, wavelengths: ArrayLike | None = None,
                sizes: TableSizes | Mapping[str, int] | None = None, progress: bool | None = None,
                chunk_size: int | None = None) -> PrecomputedAtmosphere:
        """Run Algorithm 4.1 (Bruneton & Neyret 2008) and return the tables.

        Parameters
        ----------
        atmosphere : AtmosphereParameters, optional
            The atmosphere (default: Earth, see :class:`AtmosphereParameters`).
        orders : int
            Scattering orders computed one by one (>= 1; default 6); from 3 on, the orders beyond the last are
            added as their geometric tail (:mod:`.compute`, "Orders"). Bruneton & Neyret's 4 orders without
            the tail leave out 4-14 % of the Earth sky's radiance and up to 43 % with haze over a bright ground.
        tables : {"spectral", "rgb"}, optional
            A named set of table wavelengths. ``"spectral"`` (the default): :data:`DEFAULT_TABLE_WAVELENGTHS`,
            16 wavelengths 400-700 nm, the spectral mode (15 or more wavelengths: colour and spectra interpolated
            between the table wavelengths, :mod:`.conversion`). ``"rgb"`` (``(440, 550, 680)``): the faster
            3-wavelength mode, colour rebuilt from 3 samples (less accurate in twilight; ``docs/bruneton.md``).
        wavelengths : array_like, optional
            The table wavelengths [nm] instead of a named set. (A name here is the deprecated spelling of
            ``tables``.)
        sizes : TableSizes or mapping, optional
            Table resolutions (default: 256 x 64, 64 x 16, 32 x 128 x 32 x 8).
        progress : bool, optional
            tqdm progress bar per scattering order (default: when stderr is a terminal).
        chunk_size : int, optional
            Wavelengths computed together. Most of the work is geometry shared by all wavelengths of a chunk,
            so larger chunks are faster; memory grows with them (one whole 4D float32 table of the chunk is in
            memory at a time, 4 bytes per texel and wavelength; the others are streamed to scratch files).
            Default: as many as fit in 70 MB (all 16 with the default sizes: peak 280 MiB).
        """
        from .compute import compute_tables  # numba and the kernels load when tables are first computed

        atmosphere = AtmosphereParameters() if atmosphere is None else atmosphere
        wl, sz, arrays, timings = compute_tables(atmosphere, orders=orders, wavelengths=wavelengths, preset=tables,
                                                 sizes=sizes, progress=progress, chunk_size=chunk_size)
        return cls(atmosphere, wl, sz, orders, arrays, timings, computed=True)

    # ------------------------------------------------------------------ identity

    @property
    def cache_key(self) -> str:
        """Hash of parameters, orders, wavelengths, sizes, library version and format (hex SHA-256)."""
        return cache_key(self.parameters, self.orders, self.wavelengths, self.sizes)

    def __repr__(self) -> str:
        wl = ", ".join(f"{w:g}" for w in self.wavelengths[:5]) + (", ..." if self.wavelengths.size > 5 else "")
        return (f"PrecomputedAtmosphere(orders={self.orders}, wavelengths=[{wl}] nm, "
                f"scattering={self.sizes.scattering_shape})")

    # ------------------------------------------------------------------ files

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the tables and their description to an .npz file, atomically; returns the path
        (:mod:`.storage`)."""
        return write_tables(self, path)

    @classmethod
    def load(cls, path: str | os.PathLike[str], *, expected_key: str | None = None) -> PrecomputedAtmosphere:
        """Read tables written by :meth:`save`, verifying format, shapes and checksums (:mod:`.storage`).

        Raises
        ------
        FileFormatError
            If the file is not a skyscatter table file, is damaged, was written by another format version, or
            (with ``expected_key``) holds other parameters.
        """
        return read_tables(cls, path, expected_key=expected_key)

    def export(self, folder: str | os.PathLike[str]) -> Path:
        """Write raw float32 textures and a JSON description for real-time engines; returns the JSON path.

        See :mod:`skyscatter.precomputed.export` for the layout.
        """
        from .export import export_tables  # the exporter is only needed by export-luts

        return export_tables(self, Path(folder))
