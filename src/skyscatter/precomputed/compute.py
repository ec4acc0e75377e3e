"""Computing the tables: Algorithm 4.1 of Bruneton & Neyret (2008).

:func:`compute_tables` runs the paper's steps, one function each (the numba kernels that fill the tables are in
:mod:`.kernels`):

1. :func:`transmittance_table` - ``T(r, mu)`` to the top of the atmosphere (Eq. 5);
2. :func:`direct_irradiance` ``DE = E[L0]`` and :func:`single_scattering` ``DS = S[L0]``, Rayleigh and Mie
   apart (Sec. 4); with a tabulated aerosol phase, in the delta-M scaled medium (:meth:`Medium.delta_m_scaled`),
   in which the following steps run too;
3. for each further order: :func:`scattering_density` ``DJ = J[(a / pi) T DE + DS]`` (Eqs. 6, 7),
   :func:`indirect_irradiance` ``DE = E[DS]`` (Eq. 15) and :func:`multiple_scattering` ``DS = integral T DJ``
   (Eq. 11), summed into the irradiance table ``E`` and the scattering table ``S``;
4. :func:`add_geometric_tail` - the orders beyond the last (below, "Orders").

What the tables hold (single scattering apart, without its phase functions) is described in :mod:`.tables`.
Wavelengths are computed in chunks (:func:`compute_tables`, ``chunk_size``; all 16 default wavelengths are one):
most of the work is geometry shared by the wavelengths of a chunk, so each step runs over all of a chunk's
wavelengths at once. Memory is bounded by streaming (:func:`_orders`): one whole 4D float32 table of the chunk is
in memory at a time, the working tables go to scratch files by blocks of radii (:class:`ScratchTable`) and the
finished scattering tables to disk in half precision (:class:`SpillTables`). Timings and the progress
bar are kept by :class:`Bookkeeping`, apart from the steps.

Orders. Each order of the radiance field is, after a few orders, close to the previous one times a constant
``lambda < 1`` (the dominant eigenvalue of the scattering operator with the ground's reflection: successive
orders settle on its eigenfunction), so the orders after the last computed one ``K`` sum to
``DS_K lambda / (1 - lambda)``. From ``orders >= 3`` on this tail is added to the scattering and to the irradiance
table, with ``lambda`` the ratio of the sums of the last two orders' tables (at most :data:`MAX_ORDER_RATIO`), per
wavelength and, for the scattering table (format 12), per sun zenith texel: the orders' ratio differs between sun
zeniths, and with one ratio for the whole table the 3-order tail was larger than order 4 plus its own tail at the
zenith with the sun 0.5 deg up on the tiny test tables (there the ratio of order 4 to 3 is 0.222 with every order
positive; ``tests/test_precomputed_tables.py::test_each_order_adds_less_light``). Measured with one ratio per
wavelength against 16 orders computed one by one (400 and 550 nm, largest error over sky and ground, sun 60 / 10 /
-3 deg): Earth defaults, 4 orders without the tail 4.3 / 6.7 / 13.8 %, 6 orders with
it 0.00 / 0.01 / 0.26 %; turbidity 3 over albedo 0.3, 23 / 34 / 43 % and 0.15 / 0.22 / 2.2 %; against DISORT,
aerosol optical depth 0.5 over albedo 0.8, 6 orders with the tail are within 0.9 % of 16 orders
(``docs/bruneton.md``). Four orders are too few for the tail (the shape has not settled: +10 % in that case).
Six (the default until 2026-12-05) are too few in hazy air at short wavelengths: with aerosol optical depth 0.5 at
400 nm the ratio of successive orders' sums is still rising at the sixth order (sun-zenith texels from -12 to +9.5
deg: orders 4 / 3 0.33-0.51, 5 / 4 0.42-0.58, 8 / 7 0.61-0.64), so the tail from the last two is too small, most so
where the later orders carry the light: near the ground in twilight. Against 20 orders (default sizes, 400 / 560 nm,
radius rows 0-3, suns -12 to -0.4 deg, every view and azimuth texel; median / 90th percentile / largest) the
multiple-scattering table with 6 orders was 3.6 / 14.8 / 17.6 % and 0.3 / 2.3 / 4.3 % short, with 8 orders 0.2 / 1.4
/ 2.5 % and 0.1 / 0.3 / 0.6 % (sun -0.4 to +6 deg: 400 nm 2.7 / 3.6 / 4.3 % -> 0.1 / 0.3 / 0.6 %; 10 orders 0.1 /
0.5 / 1.1 % in twilight): :data:`.sizes.DEFAULT_ORDERS` is 8
(``tests/test_precomputed_tables.py::test_geometric_tail_in_hazy_twilight``; docs/accuracy.md, "Low sun"). A ratio
per radius row as well, tried first, overshoots there instead (5.5 / 18.6 / 27.5 %): close to the ground in twilight
the light of the last orders is still spreading into the shadow, faster than it will decay.

Reference: [Bruneton2008].
"""

from __future__ import annotations

import dataclasses
import math
import os
import sys
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from tqdm.auto import tqdm

from ..atmosphere.phase import aerosol_phase_kind
from ..atmosphere.phase_table import PhaseTable
from ..errors import InvalidParameterError
from ..validation import whole_number
from . import conversion, kernels
from .parallel import parallel_for
from .parameters import SOLAR_BAND_WIDTH, AtmosphereParameters
from .sampling import TABLE_PHASE, lobe_weight
from .sizes import DEFAULT_ORDERS, TableSizes, table_wavelengths
from .storage import HALF_TABLES, HalfTable, encode_half

__all__ = ["MAX_ORDER_RATIO", "Bookkeeping", "Medium", "Order", "add_geometric_tail", "compute_tables",
           "density_profiles", "direct_irradiance", "indirect_irradiance", "multiple_scattering",
           "scattering_density", "single_scattering", "single_scattering_source", "stored_single_scattering",
           "transmittance_table"]

#: Largest ratio of successive orders used for the tail (a bound against a noisy estimate: 1 would be infinite).
MAX_ORDER_RATIO = 0.95
#: Memory [bytes] of the one whole 4D float32 table of a wavelength chunk that :func:`_orders` holds at a time;
#: it sets the default chunk size: all 16 default wavelengths in one chunk (32 x 128 x 32 x 8 texels: 67 MB).
#: A chunk costs about the same CPU time for 5 or 16 wavelengths (most of each kernel's work is per texel, ray
#: sample and sun, shared by the chunk's wavelengths), so chunks are as large as this allows.
CHUNK_MEMORY = 70e6
#: Radii per block of the 4D tables streamed to and from scratch files (:class:`ScratchTable`): 8 MiB per block
#: of 4 of the default 32 radii at 16 wavelengths.
ROW_BLOCK = 4
#: Sub-chunks of the wavelengths for the first order's scattering density, which reads two whole tables (single
#: Rayleigh and Mie): in halves they take the memory of one.
FIRST_ORDER_SPLIT = 2

F32 = NDArray[np.float32]
F64 = NDArray[np.float64]


def density_profiles(atmosphere: AtmosphereParameters) -> tuple[F64, NDArray[np.int64]]:
    """The Rayleigh, Mie and ozone density profiles as one (3, n_layers, 5) array for the kernels (layers of
    :meth:`.DensityProfile.as_array`, zero-padded) and the number of layers of each."""
    profs = [atmosphere.rayleigh_density.as_array(), atmosphere.aerosol_component.density.as_array(),
             atmosphere.ozone_density.as_array()]
    n_max = max(p.shape[0] for p in profs)
    arr = np.zeros((3, n_max, 5))
    for i, p in enumerate(profs):
        arr[i, : p.shape[0]] = p
    return arr, np.array([p.shape[0] for p in profs], dtype=np.int64)


#: Streams of the delta-M truncation of a tabulated aerosol phase for the scattering-density quadrature, per
#: polar sample of that quadrature (:attr:`.TableSizes.density_sphere_samples`): 2 x 16 = 32 Legendre moments.
DELTA_M_STREAMS_PER_SAMPLE = 2
#: Cosines (evenly spaced from -1 to 1) at which the truncated phase is given to the scattering-density kernel.
TRUNCATED_PHASE_NODES = 2049


@dataclass(frozen=True)
class Medium:
    """The atmosphere as the kernels read it: its geometry and phase function, and its coefficients [m^-1],
    albedo and solar irradiance [W m^-2 nm^-1] at the wavelengths being computed (trailing axis).

    The aerosol phase is analytic (``mie_kind`` of :func:`skyscatter.atmosphere.phase.aerosol_phase_kind` with
    ``mie_phase_g``: the formula, bit for bit the tables of before) or tabulated (``mie_kind`` =
    :data:`.sampling.TABLE_PHASE`): ``phase_mu`` (n,) ascending cosines, ``phase_full`` (n_wl, n) the aerosol's
    phase table at the wavelengths. For either, ``phase_trunc`` (n_wl, :data:`TRUNCATED_PHASE_NODES`) is its
    delta-M truncation ``p*`` at even cosines and ``forward`` (n_wl,) the truncated forward fraction ``f``: a
    tabulated phase's orders after the first run in :meth:`delta_m_scaled` (``p*`` the phase, ``f`` in the
    coefficients); an analytic phase's split serves only its first-order irradiance
    (:func:`.kernels.indirect_irradiance_kernel`).
    """

    bottom: float
    top: float
    mu_s_min: float
    sun_angular_radius: float
    mie_phase_g: float
    mie_kind: int
    phase_mu: F64
    phase_full: F64
    phase_trunc: F64
    forward: F64
    profiles: F64
    counts: NDArray[np.int64]
    rayleigh_scattering: F64
    mie_extinction: F64
    mie_scattering: F64
    ozone_absorption: F64
    ground_albedo: F64
    solar_irradiance: F64
    lobe: float = 0.0

    @classmethod
    def of(cls, atmosphere: AtmosphereParameters, wavelengths: F64, sizes: TableSizes | None = None,
           phase: tuple[F64, F64] | None = None) -> Medium:
        """``atmosphere`` sampled at ``wavelengths`` [nm] (``sizes`` set the delta-M truncation of a tabulated
        phase; ``phase``, if given, the tabulated aerosol phase there as ascending cosines and values, as
        :meth:`.PhaseTable.numba_arrays` gives them, instead of computing it)."""
        profiles, counts = density_profiles(atmosphere)
        kind, g, phase_arrays = aerosol_phase_arrays(atmosphere, wavelengths, sizes, phase)
        return cls(atmosphere.bottom_radius, atmosphere.top_radius, atmosphere.mu_s_min, atmosphere.sun_angular_radius,
                   g, kind, *phase_arrays, profiles, counts,
                   atmosphere.rayleigh_scattering_at(wavelengths), atmosphere.mie_extinction_at(wavelengths),
                   atmosphere.mie_scattering_at(wavelengths), atmosphere.ozone_absorption_at(wavelengths),
                   atmosphere.ground_albedo_at(wavelengths), atmosphere.solar_irradiance_at(wavelengths),
                   lobe_weight(atmosphere))

    @property
    def extinction(self) -> F64:
        """Extinction coefficients at relative density 1 [m^-1] of the three profiles of :func:`density_profiles`
        (Rayleigh, aerosol, ozone absorption), (3, n_wavelengths): the kernels' optical depths along their rays."""
        return np.ascontiguousarray(np.stack([self.rayleigh_scattering, self.mie_extinction, self.ozone_absorption]))

    def delta_m_scaled(self) -> Medium:
        """The delta-M scaled medium of the orders after the first, for a tabulated aerosol phase
        ([Wiscombe1977] Eqs. 5-7 and 13): the phase ``P_M = (1 - f) p* + f delta(1 - nu) / (2 pi)`` with the
        forward peak as a delta, which scatters light on in its own direction, so that light is never removed
        from the beam: the aerosol's extinction coefficient becomes ``beta_ext - f beta_sca``, its scattering
        coefficient ``(1 - f) beta_sca``, its phase the truncated ``p*`` (tabulated at the even cosines of
        ``phase_trunc``) and its forward fraction 0. Every table the orders read (transmittance, the sunlight
        on the ground, single scattering as their source) and every order's density and ray integral use it,
        so no table carries the diffraction peak but the exact single scattering (which keeps the full phase,
        applied at the exact view-sun angle at lookup): the TMS correction of [NakajimaTanaka1988], as DISORT
        does it."""
        f = self.forward
        return dataclasses.replace(
            self, mie_kind=TABLE_PHASE, phase_mu=np.linspace(-1.0, 1.0, self.phase_trunc.shape[1]),
            phase_full=self.phase_trunc, forward=np.zeros_like(f),
            mie_extinction=self.mie_extinction - f * self.mie_scattering,
            mie_scattering=(1.0 - f) * self.mie_scattering)

    def channels(self, ch: NDArray[np.intp]) -> Medium:
        """The same medium at the wavelengths of indices ``ch`` (a chunk)."""
        table = self.mie_kind == TABLE_PHASE
        return Medium(self.bottom, self.top, self.mu_s_min, self.sun_angular_radius, self.mie_phase_g,
                      self.mie_kind, self.phase_mu,
                      np.ascontiguousarray(self.phase_full[ch]) if table else self.phase_full,
                      np.ascontiguousarray(self.phase_trunc[ch]), np.ascontiguousarray(self.forward[ch]),
                      self.profiles, self.counts, self.rayleigh_scattering[ch],
                      self.mie_extinction[ch], self.mie_scattering[ch], self.ozone_absorption[ch],
                      self.ground_albedo[ch], self.solar_irradiance[ch], self.lobe)


def aerosol_phase_arrays(atmosphere: AtmosphereParameters, wavelengths: F64, sizes: TableSizes | None = None,
                         phase: tuple[F64, F64] | None = None) -> tuple[int, float, tuple[F64, F64, F64, F64]]:
    """``(mie_kind, g, (phase_mu, phase_full, phase_trunc, forward))`` of the aerosol for the kernels.

    An analytic phase (:attr:`.AtmosphereParameters.aerosol_component` ``.analytic_phase``) gives its kind and
    ``g`` and a placeholder full table (the kernels evaluate the formula); a tabulated one
    :data:`.sampling.TABLE_PHASE` and its table at ``wavelengths``. Both give the delta-M truncation for
    :data:`DELTA_M_STREAMS_PER_SAMPLE` x ``sizes.density_sphere_samples`` streams (Medium's docstring), an
    analytic phase's from the formula tabulated (:meth:`.PhaseTable.from_analytic`): one way to split off the
    forward peak for the first-order irradiance whatever the phase. ``phase`` (ascending cosines, values), if given,
    is the tabulated phase at ``wavelengths`` already known (a table file's: :meth:`.PhaseTable.from_cosines`), so
    that the Mie sums are not made again.
    """
    sz = TableSizes() if sizes is None else sizes
    analytic = atmosphere.aerosol_component.analytic_phase
    if analytic is not None:
        table = PhaseTable.from_analytic(analytic.kind, analytic.g, wavelengths)
        kind, g, mu, full = aerosol_phase_kind(analytic.kind), analytic.g, np.array([-1.0, 1.0]), np.zeros((1, 2))
    else:
        table = (atmosphere.aerosol_phase_table(wavelengths) if phase is None
                 else PhaseTable.from_cosines(wavelengths, *phase))
        arr = table.numba_arrays()
        kind, g, mu, full = TABLE_PHASE, 0.0, arr.mu, arr.values
    trunc, f = table.delta_m(DELTA_M_STREAMS_PER_SAMPLE * sz.density_sphere_samples)
    # the truncated phase on an even cosine grid (the kernel indexes it without a search; linear between
    # 2049 nodes of a 32-term Legendre series)
    trunc_even = np.ascontiguousarray(trunc.evaluate(np.linspace(-1.0, 1.0, TRUNCATED_PHASE_NODES)).T)
    return kind, g, (mu, full, trunc_even, np.ascontiguousarray(f))


@dataclass(frozen=True)
class Order:
    """One scattering order's light, the input of the next order: the radiance ``rayleigh P_R + mie P_M`` of
    single scattering (``single``) or the table ``rayleigh`` (phase included; ``mie`` is the same table), and the
    irradiance it puts on the ground."""

    rayleigh: F32
    mie: F32
    single: bool
    irradiance: F32


# ------------------------------------------------------------------ the steps of Algorithm 4.1


def transmittance_table(medium: Medium, sizes: TableSizes) -> F32:
    """Step 1: ``T(r, mu)`` to the top of the atmosphere (Eq. 5), (n_r, n_mu, n_wavelengths) float32.

    The optical length of each density profile is integrated once for all wavelengths, then multiplied by the
    extinction coefficients (Rayleigh, aerosol extinction, ozone absorption).
    """
    lengths = np.zeros((*sizes.transmittance_shape, 3))
    parallel_for(kernels.optical_length_kernel, lengths.shape[0] * lengths.shape[1], medium.bottom, medium.top,
                 medium.profiles, medium.counts, sizes.transmittance_samples, lengths, grain=64)
    return np.exp(-(lengths @ medium.extinction)).astype(np.float32)


def direct_irradiance(medium: Medium, sizes: TableSizes, transmittance: F32) -> F32:
    """Step 2: ``DE = E[L0]``, the sun's irradiance on a horizontal surface (Eq. 15 for the sun), (n_r, n_mu_s,
    n_wavelengths) float32."""
    out = np.zeros((*sizes.irradiance_shape, transmittance.shape[-1]), dtype=np.float32)
    kernels.direct_irradiance_kernel(transmittance, medium.bottom, medium.top, medium.sun_angular_radius, out, 0,
                                     sizes.irradiance_r * sizes.irradiance_mu_s)
    out *= medium.solar_irradiance.astype(np.float32)
    return out


def _disc_nodes(n: int) -> F64 | None:
    """The single-scattering kernel's ``disc``: None for the disc's centre (``n`` 1), else ``n`` Gauss-Legendre nodes
    and weights on [0, 1], (2, n)."""
    if n <= 1:
        return None
    out = np.empty((2, n))
    kernels.gauss_legendre_unit(n, out[0], out[1])
    return out


def single_scattering(medium: Medium, sizes: TableSizes, transmittance: F32, rows: range | None = None,
                      mu_s: F64 | None = None, disc_nodes: int = 1) -> tuple[F32, F32]:
    """Step 2: ``DS = S[L0]`` (Eq. 11 with the sun's light), Rayleigh and Mie apart and without their phase
    functions (Sec. 4, "Angular precision"): two (n_rows, n_mu, n_mu_s, n_nu, n_wavelengths) float32 tables of
    the radius indices ``rows`` (default all), at the suns of zenith cosines ``mu_s`` (default the tables' sun
    zenith texels; others give the tables' values at those suns, each with its own view-sun azimuth texels).
    ``disc_nodes``: the solar disc's transmittance at its centre (1, the tables') or by chords near the horizon
    (:func:`.kernels.single_scattering_kernel`)."""
    n_r, n_mu = sizes.scattering_r, sizes.scattering_mu
    rows = range(n_r) if rows is None else rows
    if mu_s is None:
        mu_s = kernels.mu_s_texels(medium.bottom, medium.top, medium.mu_s_min, sizes.scattering_mu_s)
    mu_s = np.ascontiguousarray(mu_s, dtype=np.float64)
    shape = (len(rows), n_mu, mu_s.size, sizes.scattering_nu, transmittance.shape[-1])
    rayleigh = np.zeros(shape, dtype=np.float32)
    mie = np.zeros_like(rayleigh)
    parallel_for(kernels.single_scattering_kernel, rows.stop * n_mu, transmittance, medium.bottom, medium.top,
                 mu_s, medium.sun_angular_radius, medium.profiles, medium.counts, medium.extinction,
                 sizes.ray_samples, n_r, _disc_nodes(disc_nodes), rayleigh, mie, rows.start,
                 begin=rows.start * n_mu)
    rayleigh *= (medium.solar_irradiance * medium.rayleigh_scattering).astype(np.float32)
    mie *= (medium.solar_irradiance * medium.mie_scattering).astype(np.float32)
    return rayleigh, mie


def single_scattering_source(medium: Medium, sizes: TableSizes, orders: int,
                             transmittance: F32) -> tuple[Medium, F32, F32]:
    """The medium and transmittance table (n_r, n_mu, n_wavelengths) float32 whose single scattering the tables
    store, and the factor per wavelength it is stored with: ``medium`` itself, ``transmittance`` and 1; for a
    tabulated aerosol phase with ``orders`` >= 2 the delta-M scaled medium (:meth:`Medium.delta_m_scaled`), its
    own transmittance (computed here) and ``1 / (1 - f)``: its single scattering is the orders' source and, per unit
    scattering coefficient, the stored single scattering (the full phase applied at lookup: the TMS correction)."""
    if medium.mie_kind == TABLE_PHASE and orders >= 2:
        scaled = medium.delta_m_scaled()
        return scaled, transmittance_table(scaled, sizes), (1.0 / (1.0 - medium.forward)).astype(np.float32)
    return medium, transmittance, np.ones(medium.solar_irradiance.shape, dtype=np.float32)


def stored_single_scattering(source: tuple[Medium, F32, F32], sizes: TableSizes, mu_s: ArrayLike,
                             rows: range | None = None, disc_nodes: int = 1) -> tuple[F32, F32]:
    """The single-scattering tables (Rayleigh, aerosol) as :func:`compute_tables` stores them, at the suns of zenith
    cosines ``mu_s`` instead of the sun-zenith texels: two (n_rows, n_mu, len(mu_s), n_nu, n_wavelengths) float32
    arrays for the radius indices ``rows`` (default all). ``source``: :func:`single_scattering_source` of the
    tables' medium (:meth:`Medium.of` their atmosphere and wavelengths; a tabulated phase as the tables' lookups
    hold it, ``phase``, spares the Mie sums), orders and transmittance table; ``sizes`` the tables'.

    The rendering lookups' sub-texels of the single scattering (:func:`.lookup.refine_sun_zenith`): computed, not
    interpolated, because the single scattering has a kink in the sun zenith wherever the sun sets for a point of
    the ray (the Earth's shadow), which no rule through the stored texels follows (the four-point rule in the
    logarithm -52 to +18 %, the linear read +8 to +18 %, against tables of three times the texels opposite a sun on
    the horizon, clear air, views 0.2-2 deg; docs/accuracy.md, "Low sun"). Also the observer's single scattering
    in twilight (:meth:`.PrecomputedAtmosphere._twilight_singles`: one sun, finer azimuths, ``disc_nodes``
    :data:`.kernels.DISC_NODES`)."""
    medium, transmittance, per_beta = source
    rayleigh, mie = single_scattering(medium, sizes, np.ascontiguousarray(transmittance, dtype=np.float32), rows,
                                      np.asarray(mu_s, dtype=np.float64), disc_nodes)
    mie *= per_beta
    return rayleigh, mie


def scattering_density(medium: Medium, sizes: TableSizes, transmittance: F32, previous: Order,
                       rows: range | None = None) -> F32:
    """Step 3: ``DJ = J[(a / pi) T DE + DS]`` (Eqs. 6, 7) from the previous order's light, per unit scattering
    coefficient (:func:`.kernels.scattering_density_kernel`), (n_rows, n_mu, n_mu_s, n_nu, n_wavelengths) float32
    at the radius indices ``rows`` (default all). Call it with OpenBLAS limited to one thread
    (:func:`_one_blas_thread`)."""
    rows = range(sizes.scattering_r) if rows is None else rows
    out = np.zeros((len(rows), *sizes.scattering_shape[1:], transmittance.shape[-1]), dtype=np.float32)
    args = (kernels.scattering_density_kernel, rows.stop, transmittance, previous.rayleigh,
            previous.mie, previous.single, previous.irradiance, medium.ground_albedo,
            medium.rayleigh_scattering, medium.mie_scattering, medium.mie_phase_g, medium.mie_kind, medium.lobe,
            medium.phase_mu, medium.phase_full, medium.phase_trunc, medium.profiles, medium.counts, medium.bottom,
            medium.top, medium.mu_s_min, sizes.density_sphere_samples, out, rows.start)
    parallel_for(*args, begin=rows.start)
    return out


def _one_blas_thread() -> Any:
    """A context in which OpenBLAS runs on one thread. The scattering density's kernel runs on all cores
    (parallel_for); OpenBLAS's own threads on top of it only spin: one BLAS thread per pool thread. Measured: a
    tabulated phase's density step took 32.8 s instead of 7.3 s with them (default sizes, 16 wavelengths, busy
    2-core machine); the default precomputation (analytic phase, one product per radius) 22.0 s of CPU instead of
    17.9 s, whole process, load 10. The products are the same (OpenBLAS splits the output among its threads, not
    the sums). Entered once per computation: each entry scans the process's libraries (0.1 s of CPU for the 64
    density calls of a default precomputation, 2026-12-06)."""
    from threadpoolctl import threadpool_limits

    return threadpool_limits(1, user_api="blas")


def indirect_irradiance(medium: Medium, sizes: TableSizes, previous: Order) -> F32:
    """Step 3: ``DE = E[DS]`` (Eq. 15), the previous order's sky light on a horizontal surface, (n_r, n_mu_s,
    n_wavelengths) float32."""
    out = np.zeros((*sizes.irradiance_shape, previous.rayleigh.shape[-1]), dtype=np.float32)
    parallel_for(kernels.indirect_irradiance_kernel, sizes.irradiance_r * sizes.irradiance_mu_s, previous.rayleigh,
                 previous.mie, previous.single, medium.mie_phase_g, medium.mie_kind, medium.lobe,
                 medium.phase_trunc, medium.forward, medium.bottom, medium.top,
                 medium.mu_s_min, sizes.irradiance_sphere_samples, out, grain=16)
    return out


def multiple_scattering(medium: Medium, sizes: TableSizes, transmittance: F32, density: F32,
                        rows: range | None = None) -> F32:
    """Step 3: ``DS = integral T DJ`` (Eq. 11) along each texel's view ray, (n_rows, n_mu, n_mu_s, n_nu,
    n_wavelengths) float32 at the radius indices ``rows`` (default all)."""
    rows = range(sizes.scattering_r) if rows is None else rows
    out = np.zeros((len(rows), *density.shape[1:]), dtype=np.float32)
    parallel_for(kernels.multiple_scattering_kernel, rows.stop * sizes.scattering_mu, transmittance,
                 density, medium.rayleigh_scattering, medium.mie_scattering, medium.profiles, medium.counts,
                 medium.extinction, medium.bottom, medium.top, medium.mu_s_min, sizes.ray_samples, out, rows.start,
                 begin=rows.start * sizes.scattering_mu)
    return out


def add_geometric_tail(table: F32, last: F32, last_sum: F64, before_sum: F64) -> None:
    """Step 4: add the orders after the last one to ``table`` in place: ``last lambda / (1 - lambda)`` with
    ``lambda`` the ratio ``last_sum / before_sum`` of the last two orders' sums, in [0, :data:`MAX_ORDER_RATIO`],
    per wavelength (sums (n_wavelengths,)) or per sun zenith texel and wavelength (sums (n_mu_s, n_wavelengths) for
    a 4D table) (module docstring, "Orders")."""
    ratio = np.clip(np.divide(last_sum, before_sum, out=np.zeros_like(last_sum), where=before_sum > 0), 0.0,
                    MAX_ORDER_RATIO)
    factor = (ratio / (1.0 - ratio)).astype(np.float32)
    table += last * (factor[:, None, :] if factor.ndim == 2 else factor)


def _orders(medium: Medium, sizes: TableSizes, transmittance: F32, orders: int, book: Bookkeeping,
            spill: SpillTables, first_channel: int, split: int) -> F32:
    """Steps 2-4 for one group of wavelengths (all of them by default): the finished 4D tables go to ``spill``
    (its wavelengths from ``first_channel`` on) and the irradiance table is returned.

    Every step runs over all the group's wavelengths at once, because most of each kernel's work is per texel,
    ray sample and sun (cells, weights, positions) and shared by the wavelengths; only the tables it reads must be
    whole. The tables it writes are streamed by blocks of :data:`ROW_BLOCK` radii to float32 scratch files
    (:class:`ScratchTable`) and read back when the next step needs them, so one whole 4D table is in memory at
    a time: the previous order while its scattering density is computed, then that density while the next order
    is integrated. The first order's density reads two tables (single Rayleigh and Mie); it runs on ``split``
    sub-chunks of the wavelengths so that its inputs are no larger than one table.
    """
    n_l = transmittance.shape[-1]
    shape = (*sizes.scattering_shape, n_l)
    blocks = [range(a, min(a + ROW_BLOCK, sizes.scattering_r)) for a in range(0, sizes.scattering_r, ROW_BLOCK)]
    # One buffer for the whole table loaded at a time (the previous order, then the density; in the second order
    # the two single-scattering tables of a sub-chunk side by side): a new 67 MB array per load had its pages
    # zeroed by the kernel on first touch, twice per order.
    sub = max(len(c) for c in np.array_split(np.arange(n_l), min(split, n_l)))
    texels = math.prod(sizes.scattering_shape)
    whole = np.empty(texels * max(n_l, 2 * sub), dtype=np.float32)

    def buffer(n_wl: int, part: int = 0) -> F32:
        return whole[part * texels * n_wl: (part + 1) * texels * n_wl].reshape(*sizes.scattering_shape, n_wl)

    with ScratchTable(shape) as s_r, ScratchTable(shape) as s_m, ScratchTable(shape) as density, _one_blas_thread():
        # The single-scattering tables' files hold the last order and the sum of the orders once the second order's
        # density has read them: their pages are already in the file cache, and the first write of a scratch file's
        # page cost 1-2 s of system time per precomputation on ext4 (rewrites a tenth of that)
        previous, total = s_r, s_m
        with book.order(1, "single scattering"):
            e_direct = direct_irradiance(medium, sizes, transmittance)
            # A tabulated phase: the orders in the delta-M scaled medium (Medium.delta_m_scaled), whose single
            # scattering is both their source (with (1 - f) beta_sca and p*) and, per unit beta_sca, the stored
            # single scattering (with the full phase at lookup: the TMS correction, tables.py).
            scaled, t_scaled, per_beta = single_scattering_source(medium, sizes, orders, transmittance)
            e_source = e_direct if scaled is medium else direct_irradiance(scaled, sizes, t_scaled)
            for rows in blocks:
                ray, mie = single_scattering(scaled, sizes, t_scaled, rows)
                s_r.write(rows, ray)
                s_m.write(rows, mie)
                spill.put("single_rayleigh", first_channel, rows, ray)
                spill.put("single_mie", first_channel, rows, mie * per_beta)
                del ray, mie
        # The sunlight scattered into the forward peak stays in the scaled beam (e_source); on the ground it is
        # diffuse light, as DISORT counts it (its diffuse flux is the total minus the unscaled direct beam).
        irradiance = e_source - e_direct if orders >= 2 else np.zeros_like(e_direct)
        last_irradiance = e_source
        # per order: sums of its scattering table per sun zenith texel and wavelength, of its irradiance per wavelength
        sums: list[tuple[F64, F64]] = []
        for k in range(2, orders + 1):
            with book.order(k):
                d_irradiance = np.empty_like(e_direct)
                with book.timed(f"order {k} density"):
                    if k == 2:
                        for ch in np.array_split(np.arange(n_l), min(split, n_l)):
                            med = scaled.channels(ch)
                            t_ch = np.ascontiguousarray(t_scaled[..., ch])
                            light = Order(s_r.load(ch, buffer(len(ch), 0)), s_m.load(ch, buffer(len(ch), 1)), True,
                                          np.ascontiguousarray(e_source[..., ch]))
                            for rows in blocks:
                                density.write(rows, scattering_density(med, sizes, t_ch, light, rows), ch)
                            d_irradiance[..., ch] = indirect_irradiance(med, sizes, light)
                            del light
                    else:
                        table = previous.load(out=buffer(n_l))
                        light = Order(table, table, False, last_irradiance)
                        for rows in blocks:
                            density.write(rows, scattering_density(scaled, sizes, t_scaled, light, rows))
                        d_irradiance = indirect_irradiance(scaled, sizes, light)
                        del light, table
                    irradiance += d_irradiance
                with book.timed(f"order {k} multiple"):
                    dens = density.load(out=buffer(n_l))
                    order_sum = np.zeros((sizes.scattering_mu_s, n_l))
                    for rows in blocks:
                        d_scattering = multiple_scattering(scaled, sizes, t_scaled, dens, rows)
                        # over (r, mu) first, a contiguous reduction, then over nu: 8.7x quicker than the sum over
                        # the three axes at once (0.28 s of CPU per default precomputation; 2026-12-06)
                        n_rows = d_scattering.shape[0] * d_scattering.shape[1]
                        order_sum += (d_scattering.reshape(n_rows, *d_scattering.shape[2:])
                                      .sum(axis=0, dtype=np.float64).sum(axis=1))
                        previous.write(rows, d_scattering)
                        if k > 2:
                            d_scattering += total.read(rows)  # the sum of the orders
                        total.write(rows, d_scattering)
                    del dens, d_scattering
                    sums.append((order_sum, d_irradiance.sum(axis=(0, 1), dtype=np.float64)))
                last_irradiance = d_irradiance
        for rows in blocks:
            multiple = total.read(rows) if orders >= 2 else np.zeros((len(rows), *shape[1:]), dtype=np.float32)
            if orders >= 3:
                add_geometric_tail(multiple, previous.read(rows), sums[-1][0], sums[-2][0])
            spill.put("multiple", first_channel, rows, multiple)
    if orders >= 3:
        add_geometric_tail(irradiance, last_irradiance, sums[-1][1], sums[-2][1])
    return irradiance


class ScratchTable:
    """A float32 4D table (n_r, n_mu, n_mu_s, n_nu, n_wavelengths) in an unnamed temporary file, written and read
    by blocks of radii (each a contiguous run of the file): a working table of :func:`_orders` that is not needed
    whole in memory. The pages live in the operating system's file cache, not in the process."""

    def __init__(self, shape: tuple[int, ...]) -> None:
        import tempfile

        self.shape = shape
        self._row = math.prod(shape[1:]) * 4
        self._fh = tempfile.TemporaryFile(prefix="skyscatter-work-")
        self._fh.truncate(self._row * shape[0])

    def __enter__(self) -> ScratchTable:
        return self

    def __exit__(self, *exc: object) -> None:
        self._fh.close()

    def write(self, rows: range, block: F32, channels: NDArray[np.intp] | None = None) -> None:
        """Store ``block`` (len(rows), n_mu, n_mu_s, n_nu, n) as the radii ``rows``: all wavelengths, or the
        wavelengths of indices ``channels`` (n of them; the others are kept)."""
        if channels is not None:
            full = self.read(rows)
            full[..., channels] = block
            block = full
        _pwrite_all(self._fh.fileno(), np.ascontiguousarray(block, dtype=np.float32), rows.start * self._row)

    def read(self, rows: range, out: F32 | None = None) -> F32:
        """The radii ``rows``, all wavelengths (into the C-contiguous ``out`` if given)."""
        if out is None:
            out = np.empty((len(rows), *self.shape[1:]), dtype=np.float32)
        _pread_all(self._fh.fileno(), out, rows.start * self._row)
        return out

    def load(self, channels: NDArray[np.intp] | None = None, out: F32 | None = None) -> F32:
        """The whole table, at all wavelengths or at those of indices ``channels`` (read by blocks of radii),
        into the C-contiguous ``out`` if given."""
        if channels is None:
            return self.read(range(self.shape[0]), out)
        if out is None:
            out = np.empty((*self.shape[:-1], len(channels)), dtype=np.float32)
        for a in range(0, self.shape[0], ROW_BLOCK):
            rows = range(a, min(a + ROW_BLOCK, self.shape[0]))
            out[a: rows.stop] = self.read(rows)[..., channels]
        return out


def _pwrite_all(fd: int, arr: NDArray[Any], offset: int) -> None:
    """Write the bytes of the C-contiguous ``arr`` at ``offset`` of file descriptor ``fd``."""
    data = memoryview(arr).cast("B")  # type: ignore[arg-type]  # numpy arrays export the buffer protocol
    while data.nbytes:
        written = os.pwrite(fd, data, offset)
        data, offset = data[written:], offset + written


def _pread_all(fd: int, arr: NDArray[Any], offset: int) -> None:
    """Fill the C-contiguous ``arr`` with the bytes at ``offset`` of file descriptor ``fd``."""
    data = memoryview(arr).cast("B")  # type: ignore[arg-type]
    while data.nbytes:
        got = os.preadv(fd, [data], offset)
        if got <= 0:
            raise OSError(f"short read of a scratch table at byte {offset}")
        data, offset = data[got:], offset + got


class SpillTables:
    """The half-precision scattering tables of a computation (:class:`.storage.HalfTable`), written chunk by chunk
    of wavelengths to unnamed temporary files instead of being kept in memory: a wavelength chunk is one
    contiguous block of the wavelength-first layout. The tables are memory maps of those files (mapped pages are
    read only when a lookup needs them; :func:`.storage.write_tables` streams the files without mapping them)."""

    def __init__(self, sizes: TableSizes, n_wavelengths: int) -> None:
        import tempfile

        n_r, n_mu, n_s, n_nu = sizes.scattering_shape
        self._shape = (n_wavelengths, n_r, n_mu, n_s, n_nu)
        self._per_wavelength = n_r * n_mu * n_s * n_nu * 2
        self._files = {name: tempfile.TemporaryFile(prefix="skyscatter-tables-") for name in HALF_TABLES}
        for fh in self._files.values():
            fh.truncate(self._per_wavelength * n_wavelengths)
        self._scales = {name: np.ones((n_wavelengths, n_r, n_s), dtype=np.float32) for name in HALF_TABLES}

    def put(self, name: str, first: int, rows: range, table: F32) -> None:
        """Store ``table`` (len(rows), n_mu, n_mu_s, n_nu, chunk), the radii ``rows`` of the wavelengths
        ``first..first + chunk - 1`` (the half-precision scales are per radius: a block of whole radii is final)."""
        fd = self._files[name].fileno()
        row_bytes = self._per_wavelength // self._shape[1]
        values, scale = encode_half(table)  # (chunk, len(rows), ...): a block is a few MiB
        for k in range(table.shape[-1]):
            _pwrite_all(fd, values[k], (first + k) * self._per_wavelength + rows.start * row_bytes)
        self._scales[name][first: first + table.shape[-1], rows.start: rows.stop] = scale

    def tables(self) -> dict[str, HalfTable]:
        """The finished tables."""
        return {name: HalfTable(np.memmap(fh, dtype=np.float16, mode="r", shape=self._shape), self._scales[name],
                                source=(fh, 0))
                for name, fh in self._files.items()}


def compute_tables(atmosphere: AtmosphereParameters, *, orders: int = DEFAULT_ORDERS,
                   wavelengths: ArrayLike | str | None = None, sizes: TableSizes | Mapping[str, int] | None = None,
                   progress: bool | None = None, preset: str | None = None,
                   chunk_size: int | None = None) -> tuple[F64, TableSizes, dict[str, Any], dict[str, float]]:
    """Algorithm 4.1: ``(wavelengths, sizes, tables, timings)`` after validating the arguments (those of
    :meth:`.PrecomputedAtmosphere.compute`, whose ``tables`` preset is ``preset`` here); ``tables`` maps the names
    of :data:`.storage.TABLE_NAMES` to float32 arrays with a trailing wavelength axis (transmittance, irradiance)
    and :class:`.storage.HalfTable` objects (the 4D tables, :class:`SpillTables`), ``timings`` each step's seconds
    (summed over wavelength chunks)."""
    if not isinstance(atmosphere, AtmosphereParameters):
        raise InvalidParameterError(f"atmosphere must be AtmosphereParameters; got {type(atmosphere).__name__}")
    whole_number("orders", orders, 1, 50)
    if atmosphere.particles:
        raise InvalidParameterError(
            "the precomputed tables take one aerosol (AtmosphereParameters.aerosol) and no further particle "
            "components (cloud layers): use the Monte Carlo reference for those")
    wl = table_wavelengths(wavelengths, preset)
    atmosphere.check_wavelengths(wl)
    check_colour_range(atmosphere, wl)
    sz = TableSizes.coerce(sizes)
    if chunk_size is None:
        chunk_size = max(1, int(CHUNK_MEMORY // (4 * math.prod(sz.scattering_shape))))
    whole_number("chunk_size", chunk_size, 1)
    medium = Medium.of(atmosphere, wl, sz)
    # as many chunks as needed, of nearly equal sizes (16 wavelengths by 8: two chunks of 8, not 8, 8 and 0)
    chunks = np.array_split(np.arange(wl.size), -(-wl.size // int(chunk_size)))
    spill = SpillTables(sz, wl.size)
    with Bookkeeping(orders * len(chunks), progress) as book:
        with book.timed("transmittance"):
            transmittance = transmittance_table(medium, sz)
        irradiance = np.zeros((*sz.irradiance_shape, wl.size), dtype=np.float32)
        for ch in chunks:
            irradiance[..., ch] = _orders(medium.channels(ch), sz, np.ascontiguousarray(transmittance[..., ch]),
                                          int(orders), book, spill, int(ch[0]), FIRST_ORDER_SPLIT)
    tables: dict[str, F32 | HalfTable] = {"transmittance": transmittance, "irradiance": irradiance,
                                          **spill.tables()}
    return wl, sz, tables, book.timings


# ------------------------------------------------------------------ checks and bookkeeping


def check_colour_range(atmosphere: AtmosphereParameters, wavelengths: F64) -> None:
    """Refuse a solar spectrum too narrow for the colour conversion of the few-wavelength mode.

    Below 15 wavelengths, XYZ integrates spectra rebuilt over the CIE observer's range, which needs the solar
    irradiance (a 10 nm band average) there too; the spectral mode integrates the table wavelengths only.
    """
    if wavelengths.size >= conversion.SPECTRAL_MODE_MIN_WAVELENGTHS:
        return
    grid = conversion.FINE_GRID
    try:
        atmosphere.solar_irradiance_at(grid)
    except InvalidParameterError:
        lo, hi = grid.min() - SOLAR_BAND_WIDTH / 2, grid.max() + SOLAR_BAND_WIDTH / 2
        spec = atmosphere.solar_irradiance
        covers = f"covers {spec.range[0]:g}-{spec.range[1]:g} nm" if hasattr(spec, "range") else "does not"
        raise InvalidParameterError(
            f"solar_irradiance {covers}; with fewer than {conversion.SPECTRAL_MODE_MIN_WAVELENGTHS} table "
            f"wavelengths the colour conversion rebuilds spectra over {grid.min():g}-{grid.max():g} nm, so the "
            f"solar spectrum must cover {lo:g}-{hi:g} nm. Extend it, or use 15 or more wavelengths "
            f"(spectral mode)"
        ) from None


class Bookkeeping:
    """Timings of the steps (summed over wavelength chunks, plus ``"total"``) and the progress bar (one tick per
    order and chunk; shown when ``progress`` is True, or None and stderr is a terminal)."""

    def __init__(self, total: int, progress: bool | None) -> None:
        if progress is None:
            progress = bool(getattr(sys.stderr, "isatty", lambda: False)())
        self.timings: dict[str, float] = {}
        self._bar: Any = tqdm(total=total, desc="scattering orders", unit="order", disable=not progress,
                              leave=False)
        self._start = time.perf_counter()

    def __enter__(self) -> Bookkeeping:
        return self

    def __exit__(self, *exc: object) -> None:
        self.timings["total"] = time.perf_counter() - self._start
        self._bar.close()

    @contextmanager
    def timed(self, label: str) -> Iterator[None]:
        """Add the time spent in the block to ``timings[label]``."""
        t0 = time.perf_counter()
        yield
        self.timings[label] = self.timings.get(label, 0.0) + time.perf_counter() - t0

    @contextmanager
    def order(self, k: int, label: str | None = None) -> Iterator[None]:
        """One order of one chunk: a tick of the bar with its time (and ``timings[label]`` if given)."""
        t0 = time.perf_counter()
        yield
        dt = time.perf_counter() - t0
        if label is not None:
            self.timings[label] = self.timings.get(label, 0.0) + dt
        self._bar.set_postfix_str(f"order {k}: {dt:.1f} s")
        self._bar.update(1)
