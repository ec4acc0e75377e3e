"""The precomputed atmosphere: tables of Bruneton & Neyret (2008), their computation, storage and lookups.

:meth:`PrecomputedAtmosphere.compute` runs Algorithm 4.1:

1. transmittance ``T(r, mu)`` to the top of the atmosphere (Eq. 5);
2. direct irradiance ``DE = E[L0]`` and single scattering ``DS = S[L0]``, Rayleigh and Mie apart (Sec. 4);
3. for each further order: the scattering density ``DJ = J[(a / pi) T DE + DS]`` (Eqs. 6, 7), the indirect
   irradiance ``DE = E[DS]`` (Eq. 15) and the scattered radiance ``DS = integral T DJ`` (Eq. 11), summed into
   the irradiance table ``E`` and the scattering table ``S``.

Storage follows the paper's separation of single scattering (Sec. 4, "Angular precision"): ``single_rayleigh``
holds ``S_R[L0]`` and ``single_mie`` ``S_M[L0]``, both without their phase functions, so the sharp Mie forward
peak is applied at full resolution at lookup; ``multiple`` holds ``S[L*]`` (orders 2 and up, phase included).
The radiance is ``single_rayleigh P_R(nu) + single_mie P_M(nu) + multiple``. The paper packs the multiple
scattering into the Rayleigh channel as ``C* = S_R[L0] + S[L*] / P_R``; where a texel's ``nu`` is clamped to
the range its ``mu`` and ``mu_s`` allow (views or sun near the zenith) that division and the multiplication
by ``P_R`` of the looked-up ``nu`` do not cancel, which skews multiple scattering towards the sun by up to 40 %
(measured against DISORT, ``docs/bruneton.md``). The packed ``C*`` is still produced by :meth:`export`.
Tables are float32 with a trailing wavelength axis: transmittance (n_r, n_mu), irradiance (n_r, n_mu_s),
scattering (n_r, n_mu, n_mu_s, n_nu).

Orders. Each order of the radiance field is, after a few orders, close to the previous one times a constant
``lambda < 1`` (the dominant eigenvalue of the scattering operator with the ground's reflection: successive
orders settle on its eigenfunction), so the orders after the last computed one ``K`` sum to
``DS_K lambda / (1 - lambda)``. From ``orders >= 3`` on this tail is added to the scattering and to the irradiance
table, with ``lambda`` per wavelength the ratio of the sums of the last two orders' tables (at most
:data:`MAX_ORDER_RATIO`). Measured against 16 orders computed one by one (400 and 550 nm, largest error over
sky and ground, sun 60 / 10 / -3 deg): Earth defaults, 4 orders without the tail 4.3 / 6.7 / 13.8 %, 6 orders with
it 0.00 / 0.01 / 0.26 %; turbidity 3 over albedo 0.3, 23 / 34 / 43 % and 0.15 / 0.22 / 2.2 %; against DISORT,
aerosol optical depth 0.5 over albedo 0.8, 6 orders with the tail are within 0.9 % of 16 orders
(``docs/bruneton.md``). Four orders are too few for the tail (the shape has not settled: +10 % in that case).

Reference: Bruneton & Neyret (2008), Precomputed Atmospheric Scattering, Comput. Graph. Forum 27(4),
doi:10.1111/j.1467-8659.2008.01245.x.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere.phase import aerosol_phase_kind
from ..errors import FileFormatError, InvalidDirectionError, InvalidParameterError
from ..fileio import atomic_path
from .parameters import AtmosphereParameters

__all__ = ["DEFAULT_TABLE_WAVELENGTHS", "FORMAT_VERSION", "NAMED_WAVELENGTHS", "RGB_TABLE_WAVELENGTHS",
           "PrecomputedAtmosphere", "TableSizes"]

#: Wavelengths [nm] of the default tables: 16 from 400 to 700 nm every 20 nm, the spectral mode (colour by the
#: CIE observer, :mod:`.conversion`). Chosen by measured colour error per second of precomputation (issue 11,
#: ``benchmarks/bruneton_colour_error.py``, ``docs/bruneton.md``): within delta-xy 0.005 and 2 % in luminance
#: of 41 wavelengths (380-780 nm, 10 nm) at sun elevations 90 to -6 deg, sky and ground. The 20 nm spacing, not
#: the range, sets the error: 20 wavelengths over 380-760 nm were no closer, 14 over 400-660 nm or 11 every
#: 30 nm failed the bounds.
DEFAULT_TABLE_WAVELENGTHS = tuple(float(w) for w in range(400, 701, 20))
#: Wavelengths [nm] of the fast 3-wavelength mode (red, green, blue samples of the 2008 paper): faster to
#: precompute, colour reconstructed from 3 samples; its measured error is in ``docs/bruneton.md``.
RGB_TABLE_WAVELENGTHS = (440.0, 550.0, 680.0)
#: Names accepted for ``wavelengths``: ``"spectral"`` (the default) and ``"rgb"`` (the 3-wavelength mode).
NAMED_WAVELENGTHS = {"spectral": DEFAULT_TABLE_WAVELENGTHS, "rgb": RGB_TABLE_WAVELENGTHS}
#: Scattering orders computed by default; the rest is the geometric tail (module docstring, "Orders").
DEFAULT_ORDERS = 6
#: Largest ratio of successive orders used for the tail (a bound against a noisy estimate: 1 would be infinite).
MAX_ORDER_RATIO = 0.95
#: Version of the table layout and algorithm; part of the cache key and checked by :meth:`load`.
FORMAT_VERSION = 5
_TABLE_NAMES = ("transmittance", "irradiance", "single_rayleigh", "single_mie", "multiple")


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
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 2:
                raise InvalidParameterError(f"table size {f.name} must be a whole number >= 2; got {v!r}")
            object.__setattr__(self, f.name, int(v))
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


def _as_wavelengths(wavelengths: ArrayLike | str | None) -> NDArray[np.float64]:
    if wavelengths is None:
        return np.array(DEFAULT_TABLE_WAVELENGTHS)
    if isinstance(wavelengths, str):
        named = NAMED_WAVELENGTHS.get(wavelengths.strip().lower())
        if named is None:
            raise InvalidParameterError(
                f"wavelengths {wavelengths!r} is not a known set; use one of {sorted(NAMED_WAVELENGTHS)} or a list "
                "of wavelengths [nm]"
            )
        return np.array(named)
    wl = np.atleast_1d(np.asarray(wavelengths, dtype=float)).ravel()
    if wl.size == 0 or not np.all(np.isfinite(wl)) or np.any(wl <= 0):
        raise InvalidParameterError("wavelengths must be a non-empty list of positive finite values [nm]")
    wl = np.unique(wl)
    if wl.size > 200:
        raise InvalidParameterError(f"at most 200 wavelengths are supported; got {wl.size}")
    return wl


def _profiles(params: AtmosphereParameters) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    profs = [params.rayleigh_density.as_array(), params.mie_density.as_array(), params.ozone_density.as_array()]
    n_max = max(p.shape[0] for p in profs)
    arr = np.zeros((3, n_max, 5))
    for i, p in enumerate(profs):
        arr[i, : p.shape[0]] = p
    return arr, np.array([p.shape[0] for p in profs], dtype=np.int64)


def _progress_enabled(progress: bool | None) -> bool:
    if progress is None:
        return bool(getattr(sys.stderr, "isatty", lambda: False)())
    return bool(progress)


def _checksum(arr: NDArray[Any]) -> str:
    h = hashlib.sha256()
    h.update(f"{arr.dtype.str}{arr.shape}".encode())
    h.update(np.ascontiguousarray(arr).tobytes())
    return h.hexdigest()


def cache_key(params: AtmosphereParameters, orders: int, wavelengths: NDArray[np.float64], sizes: TableSizes) -> str:
    """SHA-256 (hex) of the parameters, orders, wavelengths, sizes, library version and table format."""
    from .. import __version__

    described = params.to_dict()
    if described.get("mie_phase_function") == "cornette-shanks":
        # the phase function the tables had before the field existed: keep the keys of existing caches
        del described["mie_phase_function"]
    blob = json.dumps(
        {
            "params": described,
            "orders": int(orders),
            "wavelengths": [float(w) for w in wavelengths],
            "sizes": dataclasses.asdict(sizes),
            "version": __version__,
            "format": FORMAT_VERSION,
        },
        sort_keys=True,
        separators=(",", ":"),
    )
    return hashlib.sha256(blob.encode()).hexdigest()


def _check_colour_range(params: AtmosphereParameters, wavelengths: NDArray[np.float64]) -> None:
    """Refuse a solar spectrum too narrow for the colour conversion of the few-wavelength mode.

    Below 15 wavelengths, XYZ integrates spectra rebuilt over the CIE observer's range, which needs the solar
    irradiance (a 10 nm band average) there too; the spectral mode integrates the table wavelengths only.
    """
    from . import conversion
    from .parameters import SOLAR_BAND_WIDTH

    if wavelengths.size >= conversion.SPECTRAL_MODE_MIN_WAVELENGTHS:
        return
    grid = np.asarray(getattr(conversion, "_FINE_GRID", np.arange(360.0, 831.0)), dtype=float)
    try:
        params.solar_irradiance_at(grid)
    except InvalidParameterError:
        lo, hi = grid.min() - SOLAR_BAND_WIDTH / 2, grid.max() + SOLAR_BAND_WIDTH / 2
        spec = params.solar_irradiance
        covers = f"covers {spec.range[0]:g}-{spec.range[1]:g} nm" if hasattr(spec, "range") else "does not"
        raise InvalidParameterError(
            f"solar_irradiance {covers}; with fewer than {conversion.SPECTRAL_MODE_MIN_WAVELENGTHS} table "
            f"wavelengths the colour conversion rebuilds spectra over {grid.min():g}-{grid.max():g} nm, so the "
            f"solar spectrum must cover {lo:g}-{hi:g} nm. Extend it, or use 15 or more wavelengths "
            f"(spectral mode)"
        ) from None


def _as_points(name: str, value: ArrayLike) -> NDArray[np.float64]:
    a = np.asarray(value, dtype=float)
    if a.ndim == 0 or a.shape[-1] != 3:
        raise InvalidParameterError(f"{name} must have shape (..., 3) [m]; got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InvalidParameterError(f"{name} contains NaN or infinite values")
    return a


def _as_dirs(name: str, value: ArrayLike) -> NDArray[np.float64]:
    from ..conventions import as_directions

    try:
        return as_directions(value)
    except InvalidDirectionError as exc:
        raise InvalidDirectionError(f"{name}: {exc}") from None


class PrecomputedAtmosphere:
    """Precomputed transmittance, irradiance and scattering tables of one atmosphere, and their lookups.

    Build one with :meth:`compute` (or :func:`skyscatter.precomputed.cached_atmosphere`, which keeps the
    tables on disk) or read one with :meth:`load`. Positions are in metres in a planet-centred frame (the
    planet's centre at the origin); directions are unit vectors in the same frame. Radiance is spectral, at
    :attr:`wavelengths`; :meth:`to_xyz` converts it (see :mod:`.conversion`).
    """

    def __init__(self, params: AtmosphereParameters, wavelengths: ArrayLike, sizes: TableSizes, orders: int,
                 tables: Mapping[str, NDArray[np.float32]], timings: Mapping[str, float] | None = None) -> None:
        self.parameters = params
        self.wavelengths = np.asarray(wavelengths, dtype=float)
        self.sizes = sizes
        self.orders = int(orders)
        self.tables = {name: np.ascontiguousarray(tables[name], dtype=np.float32) for name in _TABLE_NAMES}
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
            if self.tables[name].shape != shape:
                raise FileFormatError(f"table {name} has shape {self.tables[name].shape}, expected {shape}")
        self._solar = params.solar_irradiance_at(self.wavelengths)
        self._albedo = params.ground_albedo_at(self.wavelengths)
        self._xyz_matrix: NDArray[np.float64] | None = None
        self._colour = None

    # ------------------------------------------------------------------ computation

    @classmethod
    def compute(cls, params: AtmosphereParameters | None = None, *, orders: int = DEFAULT_ORDERS,
                wavelengths: ArrayLike | str | None = None, sizes: TableSizes | Mapping[str, int] | None = None,
                progress: bool | None = None, chunk_size: int | None = None) -> PrecomputedAtmosphere:
        """Run Algorithm 4.1 (Bruneton & Neyret 2008) and return the tables.

        Parameters
        ----------
        params : AtmosphereParameters, optional
            The atmosphere (default: Earth, see :class:`AtmosphereParameters`).
        orders : int
            Scattering orders computed one by one (>= 1; default 6); from 3 on, the orders beyond the last are
            added as their geometric tail (module docstring, "Orders"). Bruneton & Neyret's 4 orders without
            the tail leave out 4-14 % of the Earth sky's radiance and up to 43 % with haze over a bright ground.
        wavelengths : array_like or str, optional
            Wavelengths [nm]. Default (or ``"spectral"``): :data:`DEFAULT_TABLE_WAVELENGTHS`, 16 wavelengths
            400-700 nm, the spectral mode (15 or more wavelengths: colour and spectra interpolated between the
            table wavelengths, :mod:`.conversion`). ``"rgb"`` (or ``(440, 550, 680)``): the faster 3-wavelength
            mode, colour rebuilt from 3 samples (less accurate in twilight; ``docs/bruneton.md``).
        sizes : TableSizes or mapping, optional
            Table resolutions (default: 256 x 64, 64 x 16, 32 x 128 x 32 x 8).
        progress : bool, optional
            tqdm progress bar per scattering order (default: when stderr is a terminal).
        chunk_size : int, optional
            Wavelengths computed together. Most of the work is geometry shared by all wavelengths of a chunk,
            so larger chunks are faster; memory grows with them (about 6 x 4 bytes per texel of the 4D tables
            and wavelength). Default: as many as fit in 512 MB of working tables (20 with the default sizes).
        """
        from tqdm.auto import tqdm

        from . import kernels
        from .parallel import parallel_for

        params = AtmosphereParameters() if params is None else params
        if not isinstance(params, AtmosphereParameters):
            raise InvalidParameterError(f"params must be AtmosphereParameters; got {type(params).__name__}")
        if isinstance(orders, bool) or not isinstance(orders, (int, np.integer)) or not 1 <= orders <= 50:
            raise InvalidParameterError(f"orders must be a whole number in [1, 50]; got {orders!r}")
        if params.aerosol is not None or params.particles:
            # until the tables read the particle components (issue 20): never a sky with the wrong aerosol
            raise InvalidParameterError(
                "the precomputed tables take the default aerosol of the mie_* fields only (no aerosol component "
                "or further particle components yet)")
        wl = _as_wavelengths(wavelengths)
        params.check_wavelengths(wl)
        _check_colour_range(params, wl)
        sz = TableSizes.coerce(sizes)
        if chunk_size is None:
            chunk_size = max(1, int(512e6 // (24 * math.prod(sz.scattering_shape))))
        if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) or chunk_size < 1:
            raise InvalidParameterError(f"chunk_size must be a whole number >= 1; got {chunk_size!r}")
        bottom, top, mu_s_min = params.bottom_radius, params.top_radius, params.mu_s_min
        alpha, g = params.sun_angular_radius, params.mie_phase_g
        mie_kind = aerosol_phase_kind(params.mie_phase_function)
        profiles, counts = _profiles(params)
        beta_r = params.rayleigh_scattering_at(wl)
        beta_m_ext = params.mie_extinction_at(wl)
        beta_m = params.mie_scattering_at(wl)
        ozone = params.ozone_absorption_at(wl)
        albedo = params.ground_albedo_at(wl)
        solar = params.solar_irradiance_at(wl)
        nl = wl.size
        timings: dict[str, float] = {}
        t_start = time.perf_counter()

        t0 = time.perf_counter()
        lengths = np.zeros((*sz.transmittance_shape, 3))
        parallel_for(kernels.optical_length_kernel, lengths.shape[0] * lengths.shape[1], bottom, top, profiles,
                     counts, sz.transmittance_samples, lengths, grain=64)
        coef = np.stack([beta_r, beta_m_ext, ozone])  # (3 profiles, nl)
        transmittance = np.exp(-(lengths @ coef)).astype(np.float32)
        timings["transmittance"] = time.perf_counter() - t0

        n_r, n_mu, n_s, n_n = sz.scattering_shape
        single_rayleigh = np.zeros((*sz.scattering_shape, nl), dtype=np.float32)
        single_mie = np.zeros((*sz.scattering_shape, nl), dtype=np.float32)
        multiple = np.zeros((*sz.scattering_shape, nl), dtype=np.float32)
        irradiance = np.zeros((*sz.irradiance_shape, nl), dtype=np.float32)
        n_irr = sz.irradiance_r * sz.irradiance_mu_s

        def single(t_tab, ch, b_m):
            e_dir = np.zeros((*sz.irradiance_shape, ch.size), dtype=np.float32)
            kernels.direct_irradiance_kernel(t_tab, bottom, top, alpha, e_dir, 0, n_irr)
            e_dir *= solar[ch].astype(np.float32)
            s_r = np.zeros((*sz.scattering_shape, ch.size), dtype=np.float32)
            s_m = np.zeros((*sz.scattering_shape, ch.size), dtype=np.float32)
            parallel_for(kernels.single_scattering_kernel, n_r * n_mu, t_tab, bottom, top, mu_s_min, alpha,
                         profiles, counts, sz.ray_samples, s_r, s_m)
            s_r *= (solar[ch] * beta_r[ch]).astype(np.float32)
            s_m *= (solar[ch] * b_m[ch]).astype(np.float32)
            return e_dir, s_r, s_m

        chunks = [np.arange(i, min(i + chunk_size, nl)) for i in range(0, nl, chunk_size)]
        with tqdm(total=orders * len(chunks), desc="scattering orders", unit="order",
                  disable=not _progress_enabled(progress), leave=False) as bar:
            for ch in chunks:
                t_c = np.ascontiguousarray(transmittance[..., ch])
                t0 = time.perf_counter()
                nc = ch.size
                e_direct, s1_r, s1_m = single(t_c, ch, beta_m)
                mult_c = np.zeros((*sz.scattering_shape, nc), dtype=np.float32)
                irr_c = np.zeros((*sz.irradiance_shape, nc), dtype=np.float32)
                dt = time.perf_counter() - t0
                timings["single scattering"] = timings.get("single scattering", 0.0) + dt
                bar.set_postfix_str(f"order 1: {dt:.1f} s")
                bar.update(1)
                prev_a, prev_b, first, e_prev = s1_r, s1_m, True, e_direct
                sums: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []
                for k in range(2, orders + 1):
                    t0 = time.perf_counter()
                    dens = np.zeros((*sz.scattering_shape, nc), dtype=np.float32)
                    parallel_for(kernels.scattering_density_kernel, n_r, t_c, prev_a, prev_b, first, e_prev,
                                 albedo[ch], beta_r[ch], beta_m[ch], g, mie_kind, profiles, counts, bottom, top,
                                 mu_s_min, sz.density_sphere_samples, dens)
                    t1 = time.perf_counter()
                    d_irr = np.zeros((*sz.irradiance_shape, nc), dtype=np.float32)
                    parallel_for(kernels.indirect_irradiance_kernel, n_irr, prev_a, prev_b, first, g, mie_kind,
                                 bottom, top, mu_s_min, sz.irradiance_sphere_samples, d_irr, grain=16)
                    irr_c += d_irr
                    t2 = time.perf_counter()
                    d_scat = np.zeros((*sz.scattering_shape, nc), dtype=np.float32)
                    parallel_for(kernels.multiple_scattering_kernel, n_r * n_mu, t_c, dens, beta_r[ch],
                                 beta_m[ch], profiles, counts, bottom, top, mu_s_min, sz.ray_samples, d_scat)
                    del dens
                    mult_c += d_scat
                    sums.append((d_scat.sum(axis=(0, 1, 2, 3), dtype=np.float64),
                                 d_irr.sum(axis=(0, 1), dtype=np.float64)))
                    t3 = time.perf_counter()
                    for label, dt in ((f"order {k} density", t1 - t0), (f"order {k} irradiance", t2 - t1),
                                      (f"order {k} multiple", t3 - t2)):
                        timings[label] = timings.get(label, 0.0) + dt
                    bar.set_postfix_str(f"order {k}: {t3 - t0:.1f} s")
                    bar.update(1)
                    prev_a, prev_b, first, e_prev = d_scat, d_scat, False, d_irr
                if orders >= 3:
                    # The orders beyond the last: geometric tail (module docstring, "Orders").
                    for table, last, (now, before) in ((mult_c, d_scat, (sums[-1][0], sums[-2][0])),
                                                       (irr_c, d_irr, (sums[-1][1], sums[-2][1]))):
                        ratio = np.clip(np.divide(now, before, out=np.zeros_like(now), where=before > 0), 0.0,
                                        MAX_ORDER_RATIO)
                        table += last * (ratio / (1.0 - ratio)).astype(np.float32)
                single_rayleigh[..., ch] = s1_r
                single_mie[..., ch] = s1_m
                multiple[..., ch] = mult_c
                irradiance[..., ch] = irr_c
        timings["total"] = time.perf_counter() - t_start
        tables = {"transmittance": transmittance, "irradiance": irradiance, "single_rayleigh": single_rayleigh,
                  "single_mie": single_mie, "multiple": multiple}
        return cls(params, wl, sz, orders, tables, timings)

    # ------------------------------------------------------------------ identity

    @property
    def cache_key(self) -> str:
        """Hash of parameters, orders, wavelengths, sizes, library version and format (hex SHA-256)."""
        return cache_key(self.parameters, self.orders, self.wavelengths, self.sizes)

    def __repr__(self) -> str:
        wl = ", ".join(f"{w:g}" for w in self.wavelengths[:5]) + (", ..." if self.wavelengths.size > 5 else "")
        return (f"PrecomputedAtmosphere(orders={self.orders}, wavelengths=[{wl}] nm, "
                f"scattering={self.sizes.scattering_shape})")

    # ------------------------------------------------------------------ colour

    @property
    def spectral_mode(self) -> bool:
        """True when XYZ is integrated directly from the samples (>= 15 wavelengths)."""
        from .conversion import SPECTRAL_MODE_MIN_WAVELENGTHS

        return self.wavelengths.size >= SPECTRAL_MODE_MIN_WAVELENGTHS

    @property
    def xyz_matrix(self) -> NDArray[np.float64]:
        """(3, n_wavelengths) matrix from table radiance to CIE XYZ [cd m^-2] (see :mod:`.conversion`)."""
        if self._xyz_matrix is None:
            from .conversion import xyz_matrix

            self._xyz_matrix = xyz_matrix(self.wavelengths, self.parameters)
        return self._xyz_matrix

    @property
    def colour(self):
        """The :class:`.conversion.ColourConversion` of these tables (built once)."""
        if self._colour is None:
            from .conversion import ColourConversion

            self._colour = ColourConversion(self.wavelengths, self.parameters)
        return self._colour

    def to_xyz(self, radiance: ArrayLike) -> NDArray[np.float64]:
        """CIE XYZ [cd m^-2] of spectral radiance (..., n_wavelengths) at the table wavelengths."""
        return self.colour.to_xyz(radiance)

    def luminance(self, radiance: ArrayLike) -> NDArray[np.float64]:
        """Luminance [cd m^-2] of spectral radiance (..., n_wavelengths) at the table wavelengths."""
        return self.to_xyz(radiance)[..., 1]

    def resample(self, radiance: ArrayLike, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Radiance (..., n_table) at the table wavelengths to (..., n) at ``wavelengths`` [nm], never negative
        (see :class:`.conversion.ColourConversion`)."""
        return self.colour.resample(radiance, wavelengths)

    # ------------------------------------------------------------------ lookups

    @property
    def _mie_kind(self) -> int:
        """Integer code of the aerosol phase function for the numba kernels."""
        return aerosol_phase_kind(self.parameters.mie_phase_function)

    def _geometry(self) -> tuple[float, float, float]:
        p = self.parameters
        return p.bottom_radius, p.top_radius, p.mu_s_min

    def transmittance(self, r: ArrayLike, mu: ArrayLike) -> NDArray[np.float64]:
        """Transmittance from radius ``r`` [m] along direction cosine ``mu`` to the top of the atmosphere, or to
        the ground for rays that meet it; shape broadcast(r, mu) + (n_wavelengths,)."""
        r_a, mu_a = np.broadcast_arrays(np.asarray(r, dtype=float), np.asarray(mu, dtype=float))
        bottom, top, _ = self._geometry()
        if not (np.all(np.isfinite(r_a)) and np.all(np.isfinite(mu_a))):
            raise InvalidParameterError("r and mu must be finite")
        if np.any((r_a < bottom * (1 - 1e-12)) | (r_a > top * (1 + 1e-12))):
            raise InvalidParameterError(f"r must lie in [{bottom:g}, {top:g}] m (inside the atmosphere)")
        if np.any(np.abs(mu_a) > 1.0 + 1e-12):
            raise InvalidParameterError("mu must be in [-1, 1]")
        shape = r_a.shape
        pos = np.zeros((r_a.size, 3))
        pos[:, 2] = np.clip(r_a.ravel(), bottom, top)
        mu_f = np.clip(mu_a.ravel(), -1.0, 1.0)
        dirs = np.stack([np.sqrt(1.0 - mu_f**2), np.zeros_like(mu_f), mu_f], axis=-1)
        _, t = self._sky(pos, dirs, np.tile([0.0, 0.0, 1.0], (r_a.size, 1)), None, False)
        return t.reshape(*shape, -1)

    def _broadcast_rays(self, positions: ArrayLike, directions: ArrayLike, sun_direction: ArrayLike,
                        extra: ArrayLike | None, direction_name: str = "directions"):
        pos = _as_points("positions", positions)
        if direction_name == "points":
            dirs = _as_points("points", directions)
        else:
            dirs = _as_dirs(direction_name, directions)
        sun = _as_dirs("sun_direction", sun_direction)
        arrays = [pos[..., 0], dirs[..., 0], sun[..., 0]]
        if extra is not None:
            ex = np.asarray(extra, dtype=float)
            if not np.all(np.isfinite(ex)) or np.any(ex < 0):
                raise InvalidParameterError("shadow_length must be finite and >= 0 [m]")
            arrays.append(ex)
        try:
            shape = np.broadcast_shapes(*(a.shape for a in arrays))
        except ValueError:
            raise InvalidParameterError(
                f"positions {pos.shape}, {direction_name} {dirs.shape} and sun_direction {sun.shape} do not broadcast"
            ) from None

        def flat(a: NDArray[np.float64], last: int | None) -> NDArray[np.float64]:
            full = np.broadcast_to(a, (*shape, last) if last else shape)
            return np.ascontiguousarray(full.reshape(-1, last) if last else full.reshape(-1))

        sh = flat(np.asarray(extra, dtype=float), None) if extra is not None else None
        return shape, flat(pos, 3), flat(dirs, 3), flat(sun, 3), sh

    def _check_above_ground(self, pos: NDArray[np.float64], name: str = "positions") -> None:
        """Refuse points below the surface (the tables start at ``bottom_radius``); 1 m tolerance for rounding."""
        bottom = self.parameters.bottom_radius
        r = np.sqrt(np.einsum("ij,ij->i", pos, pos))
        if r.size and r.min() < bottom - 1.0:
            raise InvalidParameterError(
                f"{name} must be on or above the planet's surface (distance from its centre >= bottom_radius "
                f"= {bottom:.7g} m); got one at {r.min():.7g} m, {bottom - r.min():.4g} m below the surface"
            )

    def _sky(self, pos, dirs, sun, shadow, include_ground):
        from .lookup import sky_kernel
        from .parallel import parallel_for

        bottom, top, mu_s_min = self._geometry()
        n = pos.shape[0]
        sh = np.zeros(n) if shadow is None else shadow
        rad = np.zeros((n, self.wavelengths.size))
        tr = np.ones((n, self.wavelengths.size))
        parallel_for(sky_kernel, n, pos, dirs, sun, sh, self.tables["transmittance"],
                     self.tables["single_rayleigh"], self.tables["single_mie"], self.tables["multiple"],
                     self.tables["irradiance"], self._albedo, self._solar, bottom, top,
                     mu_s_min, self.parameters.mie_phase_g, self._mie_kind, self.parameters.sun_angular_radius,
                     include_ground, rad, tr,
                     grain=2048)
        return rad, tr

    def sky_xyz(self, positions: ArrayLike, directions: ArrayLike, sun_direction: ArrayLike, *,
                include_ground: bool = True) -> NDArray[np.float64]:
        """CIE 1931 XYZ [cd m^-2] of :meth:`sky_radiance` (no light shafts), shape broadcast + (3,).

        In the spectral mode, for one position inside the atmosphere and one sun direction (a sky seen by one
        observer), the lookups run on 2D slices of the tables projected to XYZ (:func:`.lookup.observer_slices`):
        the same values as ``to_xyz(sky_radiance(...))`` to rounding, several times faster. Otherwise this is
        ``to_xyz(sky_radiance(...))`` (with fewer wavelengths the colour rule is not linear in the spectrum: the
        negative-lobe guard of :mod:`.conversion`).
        """
        if self.spectral_mode:
            fast = self._observer(positions, directions, sun_direction, include_ground, self.xyz_matrix)
            if fast is not None:
                return fast
        return self.to_xyz(self.sky_radiance(positions, directions, sun_direction, include_ground=include_ground))

    def sky_luminance(self, positions: ArrayLike, directions: ArrayLike, sun_direction: ArrayLike, *,
                      include_ground: bool = True) -> NDArray[np.float64]:
        """Luminance [cd m^-2] of :meth:`sky_radiance` (no light shafts), shape broadcast: the Y of
        :meth:`sky_xyz`, with one projected channel instead of three on the observer's fast path."""
        if self.spectral_mode:
            fast = self._observer(positions, directions, sun_direction, include_ground, self.xyz_matrix[1:2])
            if fast is not None:
                return fast[..., 0]
        return self.sky_xyz(positions, directions, sun_direction, include_ground=include_ground)[..., 1]

    def _observer(self, positions, directions, sun_direction, include_ground, projection):
        """The observer fast path of :meth:`sky_xyz`, :meth:`sky_luminance` and :meth:`sky_radiance` (radiance
        projected with ``projection`` (C, n_wavelengths)), or None where it does not apply."""
        # Anything unusual (several positions or suns, bad values, an observer outside the atmosphere, whose rays
        # the general kernel first moves to the top) goes the general way, which also says what is wrong.
        try:
            pos = np.asarray(positions, dtype=float)
            sun = np.asarray(sun_direction, dtype=float)
            d = np.asarray(directions)
        except (ValueError, TypeError):
            return None
        if (pos.shape != (3,) or sun.shape != (3,)
                or not (np.all(np.isfinite(pos)) and np.all(np.isfinite(sun)) and np.any(sun))
                or d.dtype.kind not in "fiu" or d.ndim == 0 or d.shape[-1] != 3):
            return None
        bottom, top, mu_s_min = self._geometry()
        r = float(np.linalg.norm(pos))
        if not (bottom - 1.0 <= r <= top):
            return None
        from .lookup import observer_kernel, observer_slices
        from .parallel import parallel_for

        shape = d.shape[:-1]
        dirs = np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float64)
        s = sun / np.linalg.norm(sun)
        mu_s = float(np.clip(pos @ s / r, -1.0, 1.0))
        projection = np.ascontiguousarray(projection, dtype=np.float64)
        slices = observer_slices(self.tables["single_rayleigh"], self.tables["single_mie"], self.tables["multiple"],
                                 min(max(r, bottom), top), mu_s, bottom, top, mu_s_min, projection)
        out = np.empty((dirs.shape[0], projection.shape[0]))
        bad = np.zeros(dirs.shape[0], dtype=np.bool_)
        # Directions are normalised (and zero, NaN or infinite ones flagged) inside the kernel: no extra passes.
        parallel_for(observer_kernel, dirs.shape[0], pos, s, slices, self.tables["transmittance"],
                     self.tables["irradiance"], self._albedo, self._solar, projection,
                     bottom, top, self.parameters.mie_phase_g, self._mie_kind, self.parameters.sun_angular_radius,
                     bool(include_ground), dirs, out, bad, grain=2048)
        if bad.any():
            return None
        return out.reshape(*shape, projection.shape[0])

    def sky_radiance(self, positions: ArrayLike, directions: ArrayLike, sun_direction: ArrayLike, *,
                     shadow_length: ArrayLike | None = None, include_ground: bool = True,
                     return_transmittance: bool = False):
        """Spectral radiance [W m^-2 sr^-1 nm^-1] seen from ``positions`` along ``directions`` (Eq. 16).

        Parameters
        ----------
        positions : array_like, shape (..., 3)
            Observer positions [m] from the planet centre; on or above the surface (1 m tolerance), also
            outside the atmosphere.
        directions : array_like, shape (..., 3)
            View directions (unit vectors, same frame).
        sun_direction : array_like, shape (3,) or (..., 3)
            Direction towards the sun.
        shadow_length : array_like, optional
            Length [m] of the shadowed part at the near end of each ray (light shafts, Eq. 18).
        include_ground : bool
            Add the ground (albedo of the parameters, lit by the sun and the sky) for rays that meet it.
        return_transmittance : bool
            Also return the transmittance to the end of each ray (1 for rays that miss the atmosphere).

        Returns
        -------
        ndarray, shape broadcast + (n_wavelengths,)
            The solar disc is not included (see :meth:`sun_radiance`); rays that miss the atmosphere give 0.
        """
        if shadow_length is None and not return_transmittance:
            fast = self._observer(positions, directions, sun_direction, include_ground,
                                  np.eye(self.wavelengths.size))
            if fast is not None:
                return fast
        shape, pos, dirs, sun, sh = self._broadcast_rays(positions, directions, sun_direction, shadow_length)
        self._check_above_ground(pos)
        rad, t = self._sky(pos, dirs, sun, sh, bool(include_ground))
        rad = rad.reshape(*shape, -1)
        if return_transmittance:
            return rad, t.reshape(*shape, -1)
        return rad

    def aerial_perspective(self, positions: ArrayLike, points: ArrayLike, sun_direction: ArrayLike, *,
                           shadow_length: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Transmittance and inscattered radiance between observers and points (Eq. 16; Eq. 17 with shadows).

        Parameters
        ----------
        positions, points : array_like, shape (..., 3)
            Observer and object positions [m] from the planet centre.
        sun_direction : array_like, shape (3,) or (..., 3)
            Direction towards the sun.
        shadow_length : array_like, optional
            Total shadowed length [m] along each ray, moved to the object's end (Eq. 17).

        Returns
        -------
        transmittance, inscatter : ndarray, shape broadcast + (n_wavelengths,)
            The object's radiance ``L_obj`` reaches the observer as ``transmittance * L_obj + inscatter``
            [W m^-2 sr^-1 nm^-1].
        """
        from .lookup import aerial_kernel
        from .parallel import parallel_for

        shape, cam, pts, sun, sh = self._broadcast_rays(positions, points, sun_direction, shadow_length,
                                                        direction_name="points")
        bottom, top, mu_s_min = self._geometry()
        n = cam.shape[0]
        sh = np.zeros(n) if sh is None else sh
        t = np.ones((n, self.wavelengths.size))
        s = np.zeros((n, self.wavelengths.size))
        tab = self.tables
        parallel_for(aerial_kernel, n, cam, pts, sun, sh, tab["transmittance"], tab["single_rayleigh"],
                     tab["single_mie"], tab["multiple"], bottom, top, mu_s_min, self.parameters.mie_phase_g,
                     self._mie_kind, t, s, grain=2048)
        return t.reshape(*shape, -1), s.reshape(*shape, -1)

    def sun_transmittance(self, positions: ArrayLike, sun_direction: ArrayLike) -> NDArray[np.float64]:
        """Transmittance from ``positions`` [m] to the sun, times the fraction of its disc above the horizon."""
        from .lookup import sun_kernel
        from .parallel import parallel_for

        shape, pos, _, sun, _ = self._broadcast_rays(positions, sun_direction, sun_direction, None)
        self._check_above_ground(pos)
        bottom, top, _ = self._geometry()
        t = np.ones((pos.shape[0], self.wavelengths.size))
        parallel_for(sun_kernel, pos.shape[0], pos, sun, self.tables["transmittance"], bottom, top,
                     self.parameters.sun_angular_radius, t, grain=4096)
        return t.reshape(*shape, -1)

    def sun_radiance(self, positions: ArrayLike, sun_direction: ArrayLike) -> NDArray[np.float64]:
        """Mean spectral radiance of the solar disc [W m^-2 sr^-1 nm^-1] seen from ``positions`` (Eq. 9)."""
        from ..sun.disc import solar_disc_solid_angle

        omega = solar_disc_solid_angle(self.parameters.sun_angular_radius)
        return self.sun_transmittance(positions, sun_direction) * (self._solar / omega)

    def ground_irradiance(self, points: ArrayLike, normals: ArrayLike,
                          sun_direction: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Sun and sky spectral irradiance [W m^-2 nm^-1] on surfaces at ``points`` [m] with ``normals``.

        The sky part is the precomputed irradiance on a horizontal surface times ``(1 + n . up) / 2`` (Eq. 14).
        """
        from .lookup import irradiance_kernel
        from .parallel import parallel_for

        shape, pts, nrm, sun, _ = self._broadcast_rays(points, normals, sun_direction, None,
                                                       direction_name="normals")
        self._check_above_ground(pts, "points")
        bottom, top, _ = self._geometry()
        e_sun = np.zeros((pts.shape[0], self.wavelengths.size))
        e_sky = np.zeros((pts.shape[0], self.wavelengths.size))
        parallel_for(irradiance_kernel, pts.shape[0], pts, nrm, sun, self.tables["transmittance"],
                     self.tables["irradiance"], self._solar, bottom, top, self.parameters.sun_angular_radius, e_sun,
                     e_sky, grain=4096)
        return e_sun.reshape(*shape, -1), e_sky.reshape(*shape, -1)

    # ------------------------------------------------------------------ files

    def _metadata(self) -> dict[str, Any]:
        from .. import __version__

        return {
            "format": "skyscatter-bruneton-tables",
            "format_version": FORMAT_VERSION,
            "library_version": __version__,
            "key": self.cache_key,
            "parameters": self.parameters.to_dict(),
            "orders": self.orders,
            "wavelengths": [float(w) for w in self.wavelengths],
            "sizes": dataclasses.asdict(self.sizes),
            "checksums": {name: _checksum(self.tables[name]) for name in _TABLE_NAMES},
            "timings": self.timings,
        }

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the tables and their description to an .npz file, atomically; returns the path."""
        target = Path(path)
        meta = json.dumps(self._metadata(), sort_keys=True)
        with atomic_path(target) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, metadata=np.array(meta), **self.tables)
        return target

    @classmethod
    def load(cls, path: str | os.PathLike[str], *, expected_key: str | None = None) -> PrecomputedAtmosphere:
        """Read tables written by :meth:`save`, verifying format, shapes and checksums.

        Raises
        ------
        FileFormatError
            If the file is not a skyscatter table file, is damaged, was written by another format version, or
            (with ``expected_key``) holds other parameters.
        """
        p = Path(path)
        try:
            with np.load(p, allow_pickle=False) as data:
                meta = json.loads(str(data["metadata"][()]))
                arrays = {name: np.array(data[name]) for name in _TABLE_NAMES}
        except FileNotFoundError:
            raise
        except KeyError as exc:
            raise FileFormatError(f"{p}: not a skyscatter table file (no table {exc})") from None
        except Exception:  # OSError, ValueError (NumPy's pickle advice), zipfile.BadZipFile, JSON errors...
            # NumPy's messages (e.g. "allow_pickle=True") would mislead: say what the file should be instead.
            raise FileFormatError(
                f"{p}: not a readable skyscatter table file (damaged, or not an .npz written by "
                "'skyscatter precompute --out' or PrecomputedAtmosphere.save)"
            ) from None
        if meta.get("format") != "skyscatter-bruneton-tables":
            raise FileFormatError(f"{p}: not a skyscatter table file")
        if meta.get("format_version") != FORMAT_VERSION:
            raise FileFormatError(
                f"{p}: table format version {meta.get('format_version')} (this library reads {FORMAT_VERSION})"
            )
        for name in _TABLE_NAMES:
            if _checksum(arrays[name]) != meta["checksums"].get(name):
                raise FileFormatError(f"{p}: checksum mismatch in table {name!r} (file damaged)")
        try:
            params = AtmosphereParameters.from_dict(meta["parameters"])
            sizes = TableSizes(**meta["sizes"])
            atm = cls(params, meta["wavelengths"], sizes, meta["orders"], arrays, meta.get("timings"))
        except (KeyError, TypeError, InvalidParameterError) as exc:
            raise FileFormatError(f"{p}: inconsistent table description ({exc})") from None
        if atm.cache_key != meta.get("key"):
            raise FileFormatError(f"{p}: the stored key does not match the stored parameters")
        if expected_key is not None and meta.get("key") != expected_key:
            raise FileFormatError(f"{p}: tables were computed for other parameters, sizes or library version")
        return atm

    def export(self, folder: str | os.PathLike[str]) -> Path:
        """Write raw float32 textures and a JSON description for real-time engines; returns the JSON path.

        See :mod:`skyscatter.precomputed.export` for the layout.
        """
        from .export import export_tables

        return export_tables(self, Path(folder))
