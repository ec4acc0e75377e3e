"""Monte Carlo sky radiance on Dask: validation, medium packing, task graph, reduction.

A job is (medium, directions, wavelengths, sun, observer altitude, samples, seed). It is cut into fixed *batches*
of paths (``batch_size`` paths, a function of ``samples`` only) and fixed *wavelength groups* (consecutive
wavelengths sharing paths, at most ``group_size``), and every (direction, group, batch) draws from its own
counter-based random stream (:mod:`.rng`). Tasks bundle direction blocks x groups x runs of batches; each returns
per-batch sums, and the reduction adds the batches of the whole job in one fixed order (batch 0, 1, 2, ... for
every direction and wavelength). The result therefore depends on the seed and the job only, not on the task
sizes, the scheduler or the number of workers. Tasks are planned and reduced lazily, a window at a time, so a job
of any number of samples needs memory for its directions and wavelengths only.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from itertools import islice
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere import AtmosphereParameters
from ..atmosphere.phase import aerosol_phase_kind
from ..conventions import direction_from_angles
from ..errors import InvalidDirectionError, InvalidParameterError, MissingDependencyError
from ..validation import whole_number
from . import kernels, tracking

__all__ = ["MonteCarloResult", "Medium", "prepare_medium", "sky_radiance", "solar_disc_radiance"]

#: Largest number of wavelengths that share one path (hero-wavelength group).
DEFAULT_GROUP_SIZE = 16
#: Largest number of paths in one batch (the unit of the random streams and of the reduction).
MAX_BATCH_SIZE = 512
#: Probability of drawing a scattering direction about the sun from the cloud's phase function in a cloudy medium
#: (directional importance sampling, ``kernels`` module docstring); cloudless media do not use it.
DDIS_PROBABILITY = 0.0
#: Optical depth [-] of the next-event shadow ray (least extinguished wavelength) below which a medium vertex draws
#: directions about the sun with :data:`DDIS_PROBABILITY` (math.inf: at every vertex). With the forward peak split
#: off, those directions are drawn from the cloud's phase function without its peak, the lobe of the next-event
#: estimates.
DDIS_DEPTH = math.inf
#: Half-angle [rad] of the forward peak split off the cloud's tabulated phase function (``kernels`` module
#: docstring, "forward peak"): next-event estimates use the phase function without it, chains of peak scatterings
#: sampled about the sun carry it. 10 deg: the efficiency measured in docs/clouds.md (2 deg: 3x lower).
PEAK_ANGLE = math.radians(10.0)
#: Optical depth (least extinguished wavelength) along a next-event shadow ray of a cloudy medium beyond which the
#: ray survives by Russian roulette only, to optical depth tau with probability exp(-(tau - depth))
#: (``kernels._sun_transmittance``; the sun's light there is below exp(-8) = 3e-4 of its value). math.inf: never.
#: Clear media do not use it.
NEE_ROULETTE_DEPTH = 8.0
#: Next-event shadow rays of a cloudy medium from below the top of its cloud layers (and field) take the shells'
#: columns above that top from a table over the cosine there (``kernels._shadow_march``, :func:`columns_above`):
#: that many nodes uniform in ln(mu) from :data:`SHADOW_TABLE_MU` to 1 (within 5e-10 relative of the march at 400
#: random cosines, docs/clouds.md; against QUADPACK in the tests). 0: off (every shadow ray marched to the top).
SHADOW_TABLE_NODES = 512
#: Smallest cosine [-] of the shadow rays' table; rays leaving the cloud tops more grazing are marched.
SHADOW_TABLE_MU = 0.005
#: Free paths and shadow rays from inside a cloud layer (a shell where a further particle component has a constant
#: density, :func:`uniform_shells`) take that component in closed form: free paths by decomposition (the layer's
#: exponential free path, the air marched up to it), shadow rays ended without a march once the layer alone passes
#: their depth (``kernels._uniform_free_path``, ``kernels._uniform_lower_bound``). False: every free path inverted
#: by the march (Newton in the Gauss-Legendre piece). Clear media do not use it.
UNIFORM_SHELLS = True
#: Splitting and roulette by importance in cloudy media (``kernels`` module docstring, "splitting"): a path's
#: medium vertex is in class ``k`` when its next-event shadow ray's optical depth (least extinguished wavelength) is
#: below ``k`` of :data:`SPLIT_DEPTHS`; a path that climbs ``k`` classes above its first medium vertex's is split
#: into ``SPLIT_FACTOR ** k`` copies (each with that fraction of the weight), and one that falls back is rouletted
#: by the same ratio. 1: off. Clear media do not use it. 2 with one class bound at optical depth 4: +7-13 % efficiency
#: under an overcast of optical depth 15 (Mie droplets, 10 um) in five alternating runs (docs/clouds.md, Speed;
#: more classes or a larger factor cost more than they gain).
SPLIT_FACTOR = 2
#: Optical depths [-] of the shadow ray that bound the classes of :data:`SPLIT_FACTOR`.
SPLIT_DEPTHS = (4.0,)


@dataclass(frozen=True)
class MonteCarloResult:
    """Result of :func:`sky_radiance`.

    Attributes
    ----------
    radiance : ndarray, shape (N, n_wavelengths)
        Sky spectral radiance without the directly transmitted sun [W m^-2 sr^-1 nm^-1].
    stderr : ndarray, shape (N, n_wavelengths)
        Standard error of ``radiance`` (sample standard deviation / sqrt(samples)) [W m^-2 sr^-1 nm^-1].
    samples : int
        Paths per direction (each path serves every wavelength of its group).
    seconds : float
        Wall-clock time of the computation [s].
    wavelengths : ndarray (n_wavelengths,) [nm]; directions : ndarray (N, 3) unit ENU vectors.
    mean_vertices : float
        Mean number of vertices (scatterings and ground reflections) per path.
    """

    radiance: NDArray[np.float64]
    stderr: NDArray[np.float64]
    samples: int
    seconds: float
    wavelengths: NDArray[np.float64]
    directions: NDArray[np.float64]
    mean_vertices: float = math.nan

    @property
    def relative_stderr(self) -> NDArray[np.float64]:
        """stderr / radiance (inf where the radiance is 0)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.radiance > 0, self.stderr / self.radiance, np.inf)


@dataclass(frozen=True)
class Medium:
    """The medium packed for the kernels at a set of wavelengths (all SI, see ``kernels.trace_block``).

    Shell components in the order Rayleigh, aerosol, ozone, then the further particle components of the
    atmosphere (cloud layers, more aerosols); ``lobe``, ``lobe_g``, ``lobe_tab`` have one more entry, the cloud
    field's. ``field`` is the field for tracking (majorant blocks), ``field_exact`` the same field with every
    voxel its own block (exact transmittance of the direct sun); both :func:`.tracking.empty_field` without one.
    ``peak_lobe``, ``pval``, ``pcdf``, ``pa``: the lobe whose forward peak is split off the next-event estimates
    (-1: none) and the peak as :func:`forward_peak` returns it. ``sgeo``, ``stab``: the shadow rays' table of the
    columns above the cloud tops (:func:`columns_above`; ``sgeo[0] = 0``: none). ``ushell``: the uniform shells
    (:func:`uniform_shells`; no rows: none).
    """

    bottom_radius: float
    top_radius: float
    edges: NDArray[np.float64]
    layers: NDArray[np.float64]
    nlay: NDArray[np.int64]
    coef: NDArray[np.float64]
    scat: NDArray[np.float64]
    lobe: NDArray[np.int64]
    lobe_g: NDArray[np.float64]
    lobe_tab: NDArray[np.int64]
    tmu: NDArray[np.float64]
    tval: NDArray[np.float64]
    tcdf: NDArray[np.float64]
    albedo: NDArray[np.float64]
    esun: NDArray[np.float64]
    sun_angular_radius: float
    field: tracking.PackedField
    field_exact: tracking.PackedField
    fs: NDArray[np.float64]
    fss: NDArray[np.float64]
    ddis: float = 0.0
    ddis_lobe: int = 0
    peak_lobe: int = -1
    pval: NDArray[np.float64] = dataclasses.field(default_factory=lambda: np.zeros((1, 2)))
    pcdf: NDArray[np.float64] = dataclasses.field(default_factory=lambda: np.zeros((1, 2)))
    pa: NDArray[np.float64] = dataclasses.field(default_factory=lambda: np.zeros(1))
    nee_roulette: float = math.inf
    split: NDArray[np.float64] = dataclasses.field(default_factory=lambda: np.ones(1))
    dval: NDArray[np.float64] = dataclasses.field(default_factory=lambda: np.zeros((1, 2)))
    dcdf: NDArray[np.float64] = dataclasses.field(default_factory=lambda: np.zeros((1, 2)))
    ddis_gate: float = 0.0
    sgeo: NDArray[np.float64] = dataclasses.field(default_factory=lambda: np.zeros(3))
    stab: NDArray[np.float64] = dataclasses.field(default_factory=lambda: np.zeros((4, 1)))
    ushell: NDArray[np.float64] = dataclasses.field(default_factory=lambda: np.zeros((0, 2)))

    @property
    def cloud_paths(self) -> bool:
        """Whether the kernels need their cloud code (a field, a forward peak, directional sampling); without it
        they run a separate compilation with that code removed (``kernels.trace_block``'s ``cloudy``)."""
        return bool(self.field.present or self.peak_lobe >= 0 or self.ddis > 0.0 or self.nee_roulette < math.inf
                    or self.split[0] > 1.0)

    def subset(self, index: NDArray[np.int64]) -> Medium:
        """The same medium at a subset of its wavelengths."""
        def c(a):
            return np.ascontiguousarray(a)

        return dataclasses.replace(self, coef=c(self.coef[index]), scat=c(self.scat[index]),
                                   tval=c(self.tval[:, index]), tcdf=c(self.tcdf[:, index]),
                                   albedo=c(self.albedo[index]), esun=c(self.esun[index]), fs=c(self.fs[index]),
                                   fss=c(self.fss[index]), pval=c(self.pval[index]), pcdf=c(self.pcdf[index]),
                                   pa=c(self.pa[index]), dval=c(self.dval[index]), dcdf=c(self.dcdf[index]))

    @property
    def has_field(self) -> bool:
        return self.field.present


def _shell_profiles(atmosphere: AtmosphereParameters) -> list:
    """Density profiles of the shell components in the kernels' order (Rayleigh, aerosol, ozone, others)."""
    comps = atmosphere.particle_components
    return [atmosphere.rayleigh_density, comps[0].density, atmosphere.ozone_density, *(c.density for c in comps[1:])]


def quadrature_edges(atmosphere: AtmosphereParameters) -> NDArray[np.float64]:
    """Radii [m] of the quadrature shells: layer boundaries, zeros of linear layers, and two scale heights apart
    for each exponential layer (up to 12 scale heights), strictly inside the atmosphere, for every shell
    component (so a cloud layer's base and top are shell boundaries and its constant density is integrated
    exactly).

    4-point Gauss-Legendre over a piece spanning two scale heights of ``exp`` integrates it to a relative error
    of ``2^9 (4!)^4 / (9 (8!)^3) ~ 3e-7`` (Abramowitz & Stegun 25.4.30); the tests check columns against
    adaptive quadrature."""
    top = atmosphere.thickness
    alts: list[float] = []
    for prof in _shell_profiles(atmosphere):
        start = 0.0
        for k, lay in enumerate(prof.layers):
            last = k == len(prof.layers) - 1
            end = top if last else start + lay.width
            if not last:
                alts.append(end)
            if lay.exp_term != 0.0 and lay.exp_scale != 0.0:
                scale = 1.0 / abs(lay.exp_scale)
                alts.extend(np.arange(start + 2 * scale, min(end, start + 12 * scale), 2 * scale).tolist())
            if lay.linear_term != 0.0:
                z = -lay.constant_term / lay.linear_term
                if start < z < end:
                    alts.append(z)
            start = end
    a = np.unique(np.round(np.array([x for x in alts if 1.0 < x < top - 1.0]), 3))
    if a.size > 1:
        keep = np.concatenate([[True], np.diff(a) > 1.0])
        a = a[keep]
    return atmosphere.bottom_radius + a


def _lobe_of(component: Any, wavelengths: NDArray[np.float64], tables: list) -> tuple[int, float, int]:
    """(lobe code, g, table index) of a particle component; a tabulated phase is appended to ``tables``."""
    analytic = component.analytic_phase
    if analytic is not None:
        code = kernels.LOBE_HENYEY_GREENSTEIN if aerosol_phase_kind(analytic.kind) == 1 else \
            kernels.LOBE_CORNETTE_SHANKS
        return code, float(analytic.g), -1
    tables.append(component.phase_table(wavelengths))
    return kernels.LOBE_TABLE, 0.0, len(tables) - 1


def _stack_tables(tables: list, n_wl: int) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Phase tables on one ascending-mu grid (the union of their nodes, on which each interpolant is unchanged)."""
    if not tables:
        return np.array([-1.0, 1.0]), np.zeros((1, n_wl, 2)), np.zeros((1, n_wl, 2))
    angles = np.unique(np.concatenate([t.angles for t in tables]))
    same = [t if np.array_equal(t.angles, angles) else t.on_angles(angles) for t in tables]
    arrs = [t.numba_arrays() for t in same]
    return (np.ascontiguousarray(arrs[0].mu), np.ascontiguousarray(np.stack([a.values for a in arrs])),
            np.ascontiguousarray(np.stack([a.cdf for a in arrs])))


def forward_peak(tmu: NDArray[np.float64], tval: NDArray[np.float64], angle: float = PEAK_ANGLE
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]] | None:
    """The forward peak of a phase table (``tval`` (n_wl, m) [sr^-1] on ascending ``tmu``) split off at a node.

    With ``j`` the first node at or above ``cos(angle)`` ([rad], ``angle`` > 0) and ``c_i`` just below (a factor
    1 - 1e-6) the smallest value of wavelength ``i`` at the nodes ``j .. m - 1``, the peak is ``P_i - c_i`` at those
    nodes and 0 at the nodes below, linear in ``mu`` between the same nodes as the table: peak + rest reproduce the
    table's interpolant exactly, both are >= 0, and every wavelength's peak is > 0 on the same interval
    ``(tmu[j - 1], 1]`` (so the hero's peak can be sampled for every wavelength's). Returns ``(values, cdf,
    fraction)``: the peak normalised to 1 over the sphere (n_wl, m) [sr^-1], its CDF on ``tmu`` (n_wl, m) and its
    fraction of the phase function (n_wl,); None when the split node would be the last or the first, or when the
    peak holds less than 5 % of the scattering at every wavelength (a smooth phase function: nothing to gain, and
    the probes cost rays).
    """
    m = tmu.size
    j = int(np.searchsorted(tmu, math.cos(angle)))
    if j >= m - 1 or j < 1:
        return None
    floor = (1.0 - 1e-6) * tval[:, j:].min(axis=1, keepdims=True)
    val = np.where(np.arange(m)[None, :] >= j, tval - floor, 0.0)
    cdf = np.concatenate([np.zeros((val.shape[0], 1)),
                          np.cumsum(0.5 * (val[:, 1:] + val[:, :-1]) * np.diff(tmu)[None, :], axis=1)], axis=1)
    cdf *= 2.0 * math.pi
    frac = cdf[:, -1].copy()
    if not np.max(frac) >= 0.05:
        return None
    return (np.ascontiguousarray(val / frac[:, None]), np.ascontiguousarray(cdf / frac[:, None]),
            np.ascontiguousarray(frac))


def prepare_medium(atmosphere: AtmosphereParameters, wavelengths: NDArray[np.float64], clouds: Any = None,
                   block: Any = None) -> Medium:
    """Pack ``atmosphere`` (and a :class:`~skyscatter.atmosphere.clouds.CloudField` ``clouds``) for the kernels at
    ``wavelengths`` [nm]. ``block``: the field's majorant block edge in voxels (default
    :data:`.tracking.DEFAULT_BLOCK`)."""
    from ..atmosphere.clouds import REFERENCE_WAVELENGTH, CloudField

    if not isinstance(atmosphere, AtmosphereParameters):
        raise InvalidParameterError(f"atmosphere must be AtmosphereParameters; got {type(atmosphere).__name__}")
    if clouds is not None and not isinstance(clouds, CloudField):
        raise InvalidParameterError(f"clouds must be a CloudField or None; got {type(clouds).__name__}")
    atmosphere.check_wavelengths(wavelengths)
    wl = np.asarray(wavelengths, dtype=float)
    comps = atmosphere.particle_components
    profiles = _shell_profiles(atmosphere)
    arrs = [pr.as_array() for pr in profiles]
    nmax = max(a.shape[0] for a in arrs)
    layers = np.zeros((len(arrs), nmax, 5))
    for c, a in enumerate(arrs):
        layers[c, : a.shape[0]] = a
    rayleigh = atmosphere.rayleigh_scattering_at(wl)
    ozone = atmosphere.ozone_absorption_at(wl)
    zero = np.zeros_like(wl)
    coef = [rayleigh, atmosphere.mie_extinction_at(wl), ozone]
    scat = [rayleigh, atmosphere.mie_scattering_at(wl), zero]
    tables: list = []
    lobes = [(kernels.LOBE_RAYLEIGH, 0.0, -1), _lobe_of(comps[0], wl, tables), (kernels.LOBE_NONE, 0.0, -1)]
    for comp in comps[1:]:
        coef.append(comp.extinction_at(wl))
        scat.append(comp.scattering_at(wl))
        lobes.append(_lobe_of(comp, wl, tables))
    rb = atmosphere.bottom_radius
    if clouds is not None:
        ref = float(clouds.particles.extinction_at(np.array([REFERENCE_WAVELENGTH]))[0])
        if not ref > 0.0:
            raise InvalidParameterError("the cloud field's particles have no extinction at 550 nm")
        fs = clouds.particles.extinction_at(wl) / ref
        fss = clouds.particles.scattering_at(wl) / ref
        lobes.append(_lobe_of(clouds.particles, wl, tables))
        if clouds.top > atmosphere.thickness:
            raise InvalidParameterError(
                f"the cloud field's top ({clouds.top:g} m) is above the top of the atmosphere "
                f"({atmosphere.thickness:g} m)")
        geo = (clouds.extinction, clouds.size, clouds.origin, clouds.base, clouds.top, clouds.periodic, rb)
        field = tracking.pack_grid(*geo, block=block)
        field_exact = tracking.pack_grid(*geo, exact=True)
    else:
        fs = np.zeros_like(wl)
        fss = np.zeros_like(wl)
        lobes.append((kernels.LOBE_NONE, 0.0, -1))
        field = field_exact = tracking.empty_field()
    tmu, tval, tcdf = _stack_tables(tables, wl.size)
    cloudy = clouds is not None or len(comps) > 1
    # the cloud's lobe for directional sampling: the field's, else the last further particle component's
    ddis_lobe = len(lobes) - 1 if clouds is not None else (len(lobes) - 2 if len(comps) > 1 else 0)
    peak_lobe = -1
    pval = pcdf = np.zeros((wl.size, 2))
    pa = np.zeros(wl.size)
    dval = dcdf = np.zeros((wl.size, 2))
    if cloudy and lobes[ddis_lobe][0] == kernels.LOBE_TABLE:
        split = forward_peak(tmu, tval[lobes[ddis_lobe][2]], PEAK_ANGLE)
        if split is not None:
            peak_lobe = ddis_lobe
            pval, pcdf, pa = split
            dval, dcdf = _without_peak_table(tmu, tval[lobes[ddis_lobe][2]], pval, pa)
    edges = quadrature_edges(atmosphere)
    nlay = np.array([a.shape[0] for a in arrs], dtype=np.int64)
    sgeo, stab = np.zeros(3), np.zeros((4, 1))
    if cloudy and SHADOW_TABLE_NODES > 0:
        tops = [_profile_top(c.density, atmosphere.thickness) for c in comps[1:]]
        if clouds is not None:
            tops.append(clouds.top)
        top = max(tops)
        if top < atmosphere.thickness - 1.0:
            sgeo, stab = columns_above(rb, atmosphere.top_radius, edges, layers, nlay, rb + top, SHADOW_TABLE_MU,
                                       SHADOW_TABLE_NODES)
    return Medium(
        rb, atmosphere.top_radius, edges, layers,
        nlay,
        np.ascontiguousarray(np.stack(coef, axis=-1), dtype=float),
        np.ascontiguousarray(np.stack(scat, axis=-1), dtype=float),
        np.array([lo[0] for lo in lobes], dtype=np.int64), np.array([lo[1] for lo in lobes]),
        np.array([lo[2] for lo in lobes], dtype=np.int64), tmu, tval, tcdf,
        np.ascontiguousarray(atmosphere.ground_albedo_at(wl), dtype=float),
        np.ascontiguousarray(atmosphere.solar_irradiance_at(wl), dtype=float),
        atmosphere.sun_angular_radius, field, field_exact, np.ascontiguousarray(fs, dtype=float),
        np.ascontiguousarray(fss, dtype=float), DDIS_PROBABILITY if cloudy else 0.0, ddis_lobe, peak_lobe, pval,
        pcdf, pa, NEE_ROULETTE_DEPTH if cloudy else math.inf, _split_table() if cloudy else np.ones(1),
        dval, dcdf, math.exp(-DDIS_DEPTH), sgeo, stab,
        uniform_shells(atmosphere) if cloudy and UNIFORM_SHELLS else np.zeros((0, 2)),
    )


def uniform_shells(atmosphere: AtmosphereParameters) -> NDArray[np.float64]:
    """The shells where a further particle component (a cloud layer) has a constant density: rows ``r_lo, r_hi``
    [m] (planet radii of the layer's base and top) and the relative densities of the shell components there (that
    component's, 0 for every other: those are marched). Free paths and shadow rays that start inside one use the
    constant part in closed form (``kernels._uniform_free_path``, ``kernels._uniform_lower_bound``)."""
    profiles = _shell_profiles(atmosphere)
    rows = []
    for q in range(3, len(profiles)):
        start = 0.0
        layers = profiles[q].layers
        for k, lay in enumerate(layers):
            end = atmosphere.thickness if k == len(layers) - 1 else start + lay.width
            if lay.linear_term == 0.0 and (lay.exp_term == 0.0 or lay.exp_scale == 0.0):
                rho = max(lay.constant_term + lay.exp_term, 0.0)
                if rho > 0.0 and end > start:
                    row = np.zeros(2 + len(profiles))
                    row[0] = atmosphere.bottom_radius + start
                    row[1] = atmosphere.bottom_radius + end
                    row[2 + q] = rho
                    rows.append(row)
            start = end
    if not rows:
        return np.zeros((0, 2))
    return np.array(rows)


def _profile_top(profile: Any, thickness: float) -> float:
    """Altitude [m] above which ``profile`` is zero (its last layer identically 0), else ``thickness``."""
    last = profile.layers[-1]
    if len(profile.layers) < 2 or (last.exp_term, last.linear_term, last.constant_term) != (0.0, 0.0, 0.0):
        return thickness
    return float(sum(lay.width for lay in profile.layers[:-1]))


def columns_above(rb: float, rt: float, edges: NDArray[np.float64], layers: NDArray[np.float64],
                  nlay: NDArray[np.int64], rc: float, mu_min: float, nodes: int
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The shadow rays' table (``kernels._add_columns_above``): the columns [m] of every shell component along a
    ray from the sphere of radius ``rc`` [m] at the cosine ``mu`` to the local vertical up to the top ``rt`` [m],
    at ``nodes`` cosines uniform in ``ln mu`` from ``mu_min`` to 1, each by the kernels' own march
    (``kernels.column_along``: the same pieces and Gauss-Legendre sums). In spherical shells the column from a
    point to the top depends on its radius and that cosine only, so a shadow ray that leaves the cloud tops (radius
    ``rc``) needs no march above them. Returns ``sgeo`` (``rc``, ``ln mu_min``, 1 / node spacing in ``ln mu``) and
    the table (nodes, n_comp)."""
    x0 = math.log(mu_min)
    xs = np.linspace(x0, 0.0, nodes)
    nc = layers.shape[0]
    table = np.zeros((nodes, nc))
    tmp = np.empty(nc)
    kinf = np.zeros(nc)
    # the shells read-only, as the paths' kernels get them (_run_task): one compile of the march for both
    edges, layers, nlay = _readonly(edges), _readonly(layers), _readonly(nlay)
    for j, x in enumerate(xs):
        mu = math.exp(x) if j < nodes - 1 else 1.0
        sn = math.sqrt(max(1.0 - mu * mu, 0.0))
        b = rc * mu
        te = -b + math.sqrt(b * b - (rc * rc - rt * rt))
        kernels.column_along(0.0, 0.0, rc, sn, 0.0, mu, te, math.inf, kinf, rb, edges, layers, nlay, table[j], tmp)
    return np.array([rc, x0, (nodes - 1) / -x0]), table


def _without_peak_table(tmu: NDArray[np.float64], tval: NDArray[np.float64], pval: NDArray[np.float64],
                        pa: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The phase table ``tval`` (n_wl, m) [sr^-1] on ``tmu`` without the forward peak ``pa pval`` of
    :func:`forward_peak`, normalised to 1 over the sphere, and its CDF (the trapezoids of the linear interpolant,
    exact): the lobe the next-event estimates use, to draw directions about the sun from."""
    rest = np.maximum(tval - pa[:, None] * pval, 0.0)
    cdf = np.concatenate([np.zeros((rest.shape[0], 1)),
                          np.cumsum(0.5 * (rest[:, 1:] + rest[:, :-1]) * np.diff(tmu)[None, :], axis=1)], axis=1)
    total = cdf[:, -1:].copy()
    return np.ascontiguousarray(rest / (2.0 * math.pi * total)), np.ascontiguousarray(cdf / total)


def _split_table() -> NDArray[np.float64]:
    """The kernels' ``split``: :data:`SPLIT_FACTOR`, then the transmittances ``exp(-d)`` of :data:`SPLIT_DEPTHS`
    (``d`` descending, so the classes' bounds ascend)."""
    if int(SPLIT_FACTOR) < 1:
        raise InvalidParameterError(f"SPLIT_FACTOR must be a whole number >= 1; got {SPLIT_FACTOR!r}")
    if int(SPLIT_FACTOR) == 1:
        return np.ones(1)
    depths = sorted((float(d) for d in SPLIT_DEPTHS), reverse=True)
    return np.array([float(int(SPLIT_FACTOR))] + [math.exp(-d) for d in depths])


# --------------------------------------------------------------------------------------------- validation


def check_directions(directions: ArrayLike) -> NDArray[np.float64]:
    """Unit (N, 3) directions from ``(..., 3)`` input; refuses non-finite and zero-length vectors."""
    d = np.asarray(directions, dtype=float)
    if d.ndim == 0 or d.shape[-1] != 3:
        raise InvalidDirectionError(f"directions must have shape (..., 3); got {d.shape}")
    d = d.reshape(-1, 3)
    if d.shape[0] == 0:
        raise InvalidDirectionError("no directions given")
    if not np.all(np.isfinite(d)):
        raise InvalidDirectionError("directions contain NaN or infinite components")
    n = np.linalg.norm(d, axis=-1)
    if np.any(n <= 1e-12):
        raise InvalidDirectionError("directions contain zero-length vectors")
    return np.ascontiguousarray(d / n[:, None])


def check_wavelengths(wavelengths: ArrayLike) -> NDArray[np.float64]:
    wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
    if wl.ndim != 1 or wl.size == 0:
        raise InvalidParameterError("wavelengths must be a non-empty 1-D array [nm]")
    if not np.all(np.isfinite(wl)) or np.any(wl <= 0):
        raise InvalidParameterError("wavelengths must be finite and > 0 nm")
    return wl


def _check_scalar(name: str, value: Any, lo: float, hi: float, unit: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a number [{unit}]; got {value!r}") from None
    if not (math.isfinite(v) and lo <= v <= hi):
        raise InvalidParameterError(f"{name} must be in [{lo:g}, {hi:g}] {unit}; got {value!r}")
    return v


def check_samples(samples: Any) -> int:
    """Paths per direction: a whole number >= 1."""
    return whole_number("samples", samples, 1)


def check_orders(orders: Any, medium: Medium | None = None) -> tuple[int, int]:
    """The window of scattering orders ``(first, last)`` from ``None`` (every order), a whole number ``k`` (that
    order alone) or a pair ``(first, last)`` (``last`` None: no limit); 1 <= first <= last <= ``MAX_ORDER``. A medium
    with a cloud's forward peak split off takes every order only (``kernels``, "Orders")."""
    top = kernels.MAX_ORDER
    if orders is None:
        return 1, top
    if isinstance(orders, (tuple, list)):
        if len(orders) != 2:
            raise InvalidParameterError(f"orders must be None, a whole number or a pair (first, last); got {orders!r}")
        lo = whole_number("orders[0]", orders[0], 1)
        hi = top if orders[1] is None else whole_number("orders[1]", orders[1], 1)
    else:
        lo = hi = whole_number("orders", orders, 1)
    if hi < lo or hi > top:
        raise InvalidParameterError(f"orders must satisfy 1 <= first <= last <= {top}; got ({lo}, {hi})")
    if medium is not None and medium.peak_lobe >= 0 and (lo, hi) != (1, top):
        raise InvalidParameterError("orders: a window of scattering orders is not available for a cloud whose "
                                    "phase function's forward peak is split off (a tabulated cloud phase function); "
                                    "pass orders=None")
    return lo, hi


def batch_layout(samples: int) -> tuple[int, int]:
    """(batch_size, n_batches) for a number of paths per direction; the samples used are their product."""
    bs = min(samples, MAX_BATCH_SIZE)
    return bs, -(-samples // bs)


def wavelength_groups(n: int, group_size: int = DEFAULT_GROUP_SIZE) -> list[NDArray[np.int64]]:
    """Consecutive wavelength indices that share paths (even split into groups of at most ``group_size``)."""
    if group_size < 1:
        raise InvalidParameterError(f"group_size must be >= 1; got {group_size}")
    k = -(-n // group_size)
    return [np.asarray(g, dtype=np.int64) for g in np.array_split(np.arange(n), k)]


# --------------------------------------------------------------------------------------------- tasks

#: The kernels' ``cloudy`` marker for media that need the cloud code (any array; None compiles it out).
_CLOUDY = np.zeros(1)


def _run_task(medium: Medium, origins: NDArray[np.float64], jitter: NDArray[np.float64], dirs: NDArray[np.float64],
              mode: NDArray[np.int64], suns: NDArray[np.float64], sun_ptr: NDArray[np.int64],
              dir_index: NDArray[np.int64], group: int, wl_index: NDArray[np.int64], batch0: int, n_batches: int,
              batch_size: int, seed: int, orders: tuple[int, int] = (1, kernels.MAX_ORDER)
              ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """One task: per-batch sums and sums of squares per hero and wavelength, each (n_rows, n_batches,
    n_group_wavelengths, n_group_wavelengths), the paths per hero (n_rows, n_batches, n_group_wavelengths) and the
    vertices per batch (n_rows, n_batches); a row per sun of the entries (``kernels.trace_block``)."""
    m = medium.subset(wl_index)
    rows = suns.shape[0]
    sums = np.zeros((rows, n_batches, wl_index.size, wl_index.size))
    sumsq = np.zeros_like(sums)
    counts = np.zeros((rows, n_batches, wl_index.size))
    verts = np.zeros((rows, n_batches))
    f = m.field
    inputs = [_readonly(a) for a in (
        origins, jitter, dirs, mode, dir_index, suns, sun_ptr, math.cos(m.sun_angular_radius), m.bottom_radius,
        m.top_radius,
        m.edges, m.layers, m.nlay, m.sgeo, m.stab, m.ushell, m.coef, m.scat, m.lobe, m.lobe_g, m.lobe_tab, m.tmu,
        m.tval, m.tcdf, m.albedo, m.esun, f.vf, f.vi, f.rho, f.bmax, f.bmin, f.xe, f.ye, f.re, m.fs, m.fss, m.ddis,
        m.ddis_lobe, m.peak_lobe, m.pval, m.pcdf, m.pa, m.nee_roulette, m.split, m.dval, m.dcdf, m.ddis_gate,
        _CLOUDY if m.cloud_paths else None, np.int64(orders[0]), np.int64(orders[1]))]
    kernels.trace_block(*inputs, seed, group, batch0, n_batches, batch_size, sums, sumsq, counts, verts)
    return sums, sumsq, counts, verts


def _readonly(value: Any) -> Any:
    """A read-only view of an input array of the kernel (other values unchanged). Numba compiles a kernel per
    argument type, and read-only is part of an array's type: the media's arrays are read-only or not depending on
    where they came from (a frozen phase table, a cached field), which compiled up to three copies of the largest
    kernels (about 13 CPU-s each); viewed read-only they share one."""
    if isinstance(value, np.ndarray) and value.flags.writeable:
        value = value.view()
        value.flags.writeable = False
    return value


@dataclass(frozen=True)
class TaskSpec:
    """Coordinates of one task of a job."""

    dir_slice: slice
    group: int
    batch0: int
    n_batches: int


def _task_sizes(n_dirs: int, n_batches: int, batch_size: int, directions_per_task: int | None,
                batches_per_task: int | None) -> tuple[int, int]:
    dpt = int(directions_per_task or min(n_dirs, 32))
    if batches_per_task is None:
        batches_per_task = max(1, 32768 // (batch_size * dpt))
    return dpt, max(1, min(int(batches_per_task), n_batches))


def iter_tasks(n_dirs: int, n_groups: int, n_batches: int, batch_size: int, *,
               directions_per_task: int | None = None, batches_per_task: int | None = None) -> Iterator[TaskSpec]:
    """The tasks of a job (direction blocks x wavelength groups x runs of batches), generated one at a time, so
    that a job of any size is planned in constant memory; any cut gives the same result."""
    dpt, bpt = _task_sizes(n_dirs, n_batches, batch_size, directions_per_task, batches_per_task)
    for d0 in range(0, n_dirs, dpt):
        for g in range(n_groups):
            for b0 in range(0, n_batches, bpt):
                yield TaskSpec(slice(d0, min(n_dirs, d0 + dpt)), g, b0, min(bpt, n_batches - b0))


def count_tasks(n_dirs: int, n_groups: int, n_batches: int, batch_size: int, *,
                directions_per_task: int | None = None, batches_per_task: int | None = None) -> int:
    """Number of tasks :func:`iter_tasks` yields (without generating them)."""
    dpt, bpt = _task_sizes(n_dirs, n_batches, batch_size, directions_per_task, batches_per_task)
    return -(-n_dirs // dpt) * n_groups * -(-n_batches // bpt)


def plan_tasks(n_dirs: int, n_groups: int, n_batches: int, batch_size: int, *,
               directions_per_task: int | None = None, batches_per_task: int | None = None) -> list[TaskSpec]:
    """Every task of a job as a list (:func:`iter_tasks`; for small jobs)."""
    return list(iter_tasks(n_dirs, n_groups, n_batches, batch_size, directions_per_task=directions_per_task,
                           batches_per_task=batches_per_task))


def _resolve_scheduler(scheduler: Any) -> tuple[str, Any]:
    """("local", dask scheduler name) or ("distributed", Client)."""
    if scheduler is None or scheduler == "threads" or scheduler == "threaded":
        return "local", "threads"
    if scheduler in ("synchronous", "sync"):
        return "local", "sync"
    if isinstance(scheduler, str):
        if "://" not in scheduler and ":" not in scheduler:
            raise InvalidParameterError(
                "scheduler must be None (threads), 'synchronous', a dask.distributed Client or a scheduler address "
                f"such as 'tcp://host:8786'; got {scheduler!r}"
            )
        Client = _distributed().Client  # noqa: N806
        try:
            return "distributed", Client(scheduler, timeout="10s")
        except (OSError, ValueError, TimeoutError) as exc:
            raise InvalidParameterError(f"cannot connect to the dask scheduler at {scheduler!r}: {exc}") from None
    try:
        from distributed import Client
    except ImportError:  # no distributed: a Client cannot have been made
        Client = None  # noqa: N806
    if Client is not None and isinstance(scheduler, Client):
        return "distributed", scheduler
    raise InvalidParameterError(
        "scheduler must be None (threads), 'synchronous', a dask.distributed Client or its address; "
        f"got {scheduler!r}"
    )


def _distributed():
    """The ``distributed`` package, or a one-line error naming the extra that installs it."""
    try:
        import distributed
    except ImportError:
        raise MissingDependencyError(
            "a dask.distributed scheduler address needs the 'distributed' package: pip install "
            "'skyscatter[montecarlo]' (or pip install distributed)") from None
    return distributed


def check_scheduler(scheduler: Any) -> None:
    """Refuse a scheduler :func:`sky_radiance` cannot use, before any work (an address is checked for its form
    and for the ``distributed`` package, not connected to)."""
    if scheduler is None or scheduler in ("threads", "threaded", "synchronous", "sync"):
        return
    if isinstance(scheduler, str):
        if "://" not in scheduler and ":" not in scheduler:
            _resolve_scheduler(scheduler)  # raises with the allowed forms
        _distributed()
        return
    _resolve_scheduler(scheduler)


def run_tasks(fn: Callable[..., Any], calls: Iterable[tuple], scheduler: Any = None, *,
              on_result: Callable[[int, Any], None], progress: Callable[[int, int], None] | None = None,
              total: int | None = None) -> int:
    """Run ``fn(*args)`` for each tuple that ``calls`` yields as dask tasks; ``on_result(i, result)`` receives each
    result (in order on the local schedulers, in completion order on a cluster). Returns the number of tasks.

    ``calls`` is consumed lazily, a window of tasks at a time (a few per worker thread), so neither the plan nor
    the results of a job need to fit in memory. ``progress(done, total)`` is called as windows finish. On the
    threaded scheduler the tasks run in a pool owned by this call: an interrupt (Ctrl-C, SIGTERM in the command
    line) cancels the queued tasks and returns at once; the running ones (a fraction of a second each) finish
    in the background.
    """
    import dask

    from ..runtime import num_threads

    kind, sched = _resolve_scheduler(scheduler)
    it = iter(calls)
    done = 0
    if kind == "distributed":
        client = sched
        ac = _distributed().as_completed()
        in_flight: dict[Any, tuple[int, Any]] = {}  # key -> (task number, future)
        submitted = 0

        def submit(n: int) -> None:
            nonlocal submitted
            for args in islice(it, n):
                fut = client.submit(fn, *args, pure=False)
                in_flight[fut.key] = (submitted, fut)
                submitted += 1
                ac.add(fut)

        try:
            submit(max(4, 4 * sum(client.nthreads().values())))
            for fut in ac:
                i, _ = in_flight.pop(fut.key)
                on_result(i, fut.result())
                done += 1
                if progress is not None:
                    progress(done, total or done)
                submit(1)
        except BaseException:
            client.cancel([f for _, f in in_flight.values()])
            raise
        finally:
            if isinstance(scheduler, str):
                client.close()
        return done
    workers = num_threads() if sched == "threads" else 1
    window = 8 * workers
    pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="skyscatter-mc") if sched == "threads" else None
    extra = {"pool": pool} if pool is not None else {}
    finished = False
    try:
        while True:
            chunk = list(islice(it, window))
            if not chunk:
                break
            results = dask.compute(*[dask.delayed(fn, pure=False)(*a) for a in chunk], scheduler=sched, **extra)
            for r in results:
                on_result(done, r)
                done += 1
            if progress is not None:
                progress(done, total or done)
        finished = True
    finally:
        if pool is not None:
            pool.shutdown(wait=finished, cancel_futures=not finished)
    return done


def execute(fn: Callable[..., Any], calls: list[tuple], scheduler: Any = None,
            progress: Callable[[int, int], None] | None = None, on_result: Callable[[int, Any], None] | None = None
            ) -> list[Any]:
    """Run ``fn(*args)`` for each tuple of ``calls`` as dask tasks; return the results in order
    (:func:`run_tasks` collecting them; for small jobs)."""
    out: list[Any] = [None] * len(calls)

    def keep(i: int, r: Any) -> None:
        out[i] = r
        if on_result is not None:
            on_result(i, r)

    run_tasks(fn, calls, scheduler, on_result=keep, progress=progress, total=len(calls))
    return out


# --------------------------------------------------------------------------------------------- public API


def _observer_radius(atmosphere: AtmosphereParameters, altitude: float) -> float:
    alt = _check_scalar("altitude", altitude, -math.inf, math.inf, "m")
    if alt < 0.0:
        raise InvalidParameterError(f"the observer is inside the planet (altitude {alt:g} m < 0)")
    return atmosphere.bottom_radius + alt


def _sun_vector(sun_zenith: float, sun_azimuth: float) -> NDArray[np.float64]:
    zen = _check_scalar("sun_zenith", sun_zenith, 0.0, math.pi, "rad")
    azi = _check_scalar("sun_azimuth", sun_azimuth, -math.inf, math.inf, "rad")
    return np.ascontiguousarray(direction_from_angles(zen, azi), dtype=float)


def _check_clouds(clouds: Any) -> Any:
    from ..atmosphere.clouds import CloudField

    if clouds is not None and not isinstance(clouds, CloudField):
        raise InvalidParameterError(f"clouds must be a CloudField or None; got {type(clouds).__name__}")
    return clouds


def almucantars(medium: Medium, origins: NDArray[np.float64], jitter: NDArray[np.float64],
                dirs: NDArray[np.float64], mode: NDArray[np.int64], sun: NDArray[np.float64]
                ) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
    """The entries traced for N views and the suns of their next-event estimates (``kernels`` module docstring,
    "Almucantars").

    Views share paths when the kernels run their cloud code (``Medium.cloud_paths``: a forward peak, splitting or
    roulette; the clear sky's kernel takes one sun per entry), there is no cloud field, every entry is a radiance
    (mode 0) without a footprint, and every origin is the same point on the planet's axis (``sky_radiance``'s
    observer); then views whose directions have the same vertical component (within 1e-12, i.e. the same zenith
    angle within about 1e-12 rad) form one entry, traced along its first view, with for each view the sun turned
    about the vertical by minus the angle from the first view's azimuth to the view's. Otherwise every view is its
    own entry with the sun.

    Returns ``(order, ptr, suns)``: ``order`` (N,) the views in the order of the rows, entries contiguous (each
    entry's first view first; entries ordered by their first view); ``ptr`` (E + 1,) the rows of entry ``e``
    ``ptr[e] .. ptr[e + 1] - 1``; ``suns`` (N, 3) each row's sun. The entry of ``e`` is the view ``order[ptr[e]]``.
    """
    n = dirs.shape[0]
    shared = (medium.cloud_paths and not medium.has_field and bool(np.all(mode == 0)) and not np.any(jitter)
              and bool(np.all(origins[:, :2] == 0.0)) and bool(np.all(origins == origins[0])))
    if not shared:
        return np.arange(n, dtype=np.int64), np.arange(n + 1, dtype=np.int64), np.tile(sun, (n, 1))
    by_z = np.argsort(dirs[:, 2], kind="stable")
    cut = np.flatnonzero(np.diff(dirs[by_z, 2]) > 1e-12) + 1
    rings = sorted((np.sort(g) for g in np.split(by_z, cut)), key=lambda g: int(g[0]))
    order = np.concatenate(rings).astype(np.int64)
    ptr = np.concatenate([[0], np.cumsum([g.size for g in rings])]).astype(np.int64)
    first = np.repeat(order[ptr[:-1]], np.diff(ptr))
    h0, h = dirs[first, :2], dirs[order, :2]
    norm = np.hypot(h0[:, 0], h0[:, 1]) * np.hypot(h[:, 0], h[:, 1])
    ok = norm > 0.0  # a view along the vertical: no azimuth, the sun unturned
    cos_a = np.where(ok, (h0 * h).sum(axis=1) / np.where(ok, norm, 1.0), 1.0)
    sin_a = np.where(ok, (h0[:, 0] * h[:, 1] - h0[:, 1] * h[:, 0]) / np.where(ok, norm, 1.0), 0.0)
    # R turns the first view's azimuth to the view's (counter-clockwise in x-y by the angle a); the sun is turned by
    # R^-1 (the transpose)
    suns = np.stack([cos_a * sun[0] + sin_a * sun[1], -sin_a * sun[0] + cos_a * sun[1],
                     np.full(n, sun[2])], axis=-1)
    suns /= np.linalg.norm(suns, axis=-1)[:, None]
    suns[ptr[:-1]] = sun  # each traced view's own sun exactly (a view alone is traced to the bit as without rings)
    return order, ptr, np.ascontiguousarray(suns)


def trace(medium: Medium, origins: NDArray[np.float64], jitter: NDArray[np.float64], dirs: NDArray[np.float64],
          mode: NDArray[np.int64], sun: NDArray[np.float64], n_wavelengths: int, *, samples: int, seed: int,
          scheduler: Any = None, group_size: int = DEFAULT_GROUP_SIZE, directions_per_task: int | None = None,
          batches_per_task: int | None = None, progress: Callable[[int, int], None] | None = None,
          orders: tuple[int, int] = (1, kernels.MAX_ORDER)
          ) -> tuple[NDArray[np.float64], NDArray[np.float64], int, float]:
    """Run the kernels for N entries (origin, footprint, direction, mode; ``kernels.trace_block``) on dask.

    Views of one almucantar share their paths where the medium allows it (:func:`almucantars`); the tasks are
    made of whole entries (``directions_per_task`` counts entries).

    ``orders`` (first, last): the orders of scattering counted (``kernels.trace_block``; :func:`check_orders`).

    Returns ``(mean, stderr, samples_used, mean_vertices)``: per entry and wavelength the mean per-path estimate
    and its standard error, the paths per entry and the mean number of scattering and ground vertices per path.
    """
    n_samples = check_samples(samples)
    seed = int(seed)
    if seed < 0:
        raise InvalidParameterError(f"seed must be >= 0; got {seed}")
    check_scheduler(scheduler)
    batch_size, n_batches = batch_layout(n_samples)
    groups = wavelength_groups(n_wavelengths, group_size)
    n = dirs.shape[0]
    order, ptr, suns = almucantars(medium, origins, jitter, dirs, mode, sun)
    entry = order[ptr[:-1]]  # the view each entry is traced along (and whose random streams it takes)
    n_entries = entry.size
    sizes = dict(directions_per_task=directions_per_task, batches_per_task=batches_per_task)
    total = count_tasks(n_entries, len(groups), n_batches, batch_size, **sizes)
    fold = _BatchFold(n, n_wavelengths, groups)
    specs: dict[int, TaskSpec] = {}
    vertices = [0.0]

    def c(a, sl):
        return np.ascontiguousarray(a[entry[sl]])

    def calls() -> Iterator[tuple]:
        for k, sp in enumerate(iter_tasks(n_entries, len(groups), n_batches, batch_size, **sizes)):
            e0, e1 = sp.dir_slice.start, sp.dir_slice.stop
            specs[k] = dataclasses.replace(sp, dir_slice=slice(int(ptr[e0]), int(ptr[e1])))  # its rows
            yield (medium, c(origins, sp.dir_slice), c(jitter, sp.dir_slice), c(dirs, sp.dir_slice),
                   c(mode, sp.dir_slice), np.ascontiguousarray(suns[ptr[e0]:ptr[e1]]), ptr[e0:e1 + 1] - ptr[e0],
                   entry[sp.dir_slice], sp.group, groups[sp.group], sp.batch0, sp.n_batches, batch_size, seed,
                   orders)

    def add(k: int, result: tuple) -> None:
        a, b, cnt, v = result
        fold.add(specs.pop(k), a, b, cnt)
        vertices[0] += float(np.sum(v))  # whole numbers: exact in any order

    run_tasks(_run_task, calls(), scheduler, on_result=add, progress=progress, total=total)
    used = batch_size * n_batches
    mean, stderr = reduce_strata(fold.sums, fold.sumsq, fold.counts, used)
    out_mean, out_stderr = np.empty_like(mean), np.empty_like(stderr)
    out_mean[order], out_stderr[order] = mean, stderr  # the rows back in the views' order
    return out_mean, out_stderr, used, vertices[0] / (n * len(groups) * used)


def sky_radiance(atmosphere: AtmosphereParameters, directions: ArrayLike, wavelengths: ArrayLike, *,
                 sun_zenith: float, sun_azimuth: float = 0.0, altitude: float = 0.0, samples: int = 4096,
                 seed: int = 0, scheduler: Any = None, group_size: int = DEFAULT_GROUP_SIZE,
                 directions_per_task: int | None = None, batches_per_task: int | None = None,
                 progress: Callable[[int, int], None] | None = None, clouds: Any = None,
                 majorant_block: Any = None, orders: Any = None) -> MonteCarloResult:
    """Monte Carlo spectral sky radiance (all orders of scattering or a window of them, without the directly
    transmitted sun).

    Parameters
    ----------
    atmosphere : AtmosphereParameters
        The medium (spherical shells, ground albedo, solar spectrum and disc radius, the aerosol and any further
        particle components such as cloud layers, each with its analytic or tabulated phase function).
    directions : array_like, shape (..., 3)
        View directions (ENU at the observer; need not be unit length, must be finite and non-zero).
    wavelengths : array_like, shape (n,)
        [nm], inside the spectra of ``atmosphere``.
    sun_zenith, sun_azimuth : float
        Sun position at the observer [rad] (azimuth from north towards east); any zenith in [0, pi].
    altitude : float
        Observer altitude above the ground [m], >= 0 (above the top of the atmosphere is allowed): below, inside or
        above the clouds.
    samples : int
        Paths per direction (rounded up to whole batches of at most 512; the result says how many ran).
    seed : int
        Seed of the counter-based random streams; equal seeds give bit-identical results on any scheduler.
    scheduler : None, "synchronous", dask.distributed.Client or str
        None runs dask's threaded scheduler (the numba kernels release the GIL); "synchronous" runs in this
        thread; a Client or a scheduler address runs the tasks on that cluster.
    group_size : int
        Wavelengths sharing one path (hero-wavelength sampling); part of the job (changes the random numbers).
    directions_per_task, batches_per_task : int, optional
        Task sizes (do not change the result).
    progress : callable(done, total), optional
        Called as tasks finish.
    clouds : CloudField, optional
        A 3D cloud field (:class:`skyscatter.atmosphere.clouds.CloudField`) in the atmosphere; the observer is
        at the origin of its horizontal coordinates.
    majorant_block : int or (int, int, int), optional
        Block edge of the field's majorant grid in voxels (default 8; changes the random numbers, not the
        expectation).
    orders : None, int or (int, int or None), optional
        The orders of scattering counted (a ground reflection counts as one): None every order, ``k`` the ``k``-th
        alone (1: single scattering), ``(first, last)`` those from ``first`` to ``last`` (``last`` None: no limit).
        The same paths, each ending after its vertex ``last``; the windows ``1``, ``2`` and ``(3, None)`` add up to
        the whole (``kernels``, "Orders"). Not for a cloud with a tabulated phase function (its forward peak's
        probes span orders): :class:`~skyscatter.errors.InvalidParameterError`.
    """
    t_start = time.perf_counter()
    dirs = check_directions(directions)
    wl = check_wavelengths(wavelengths)
    check_samples(samples)
    sun = _sun_vector(sun_zenith, sun_azimuth)
    r_obs = _observer_radius(atmosphere, altitude)
    check_orders(orders)
    medium = prepare_medium(atmosphere, wl, _check_clouds(clouds), majorant_block)
    window = check_orders(orders, medium)
    n = dirs.shape[0]
    origins = np.tile(np.array([0.0, 0.0, r_obs]), (n, 1))
    mean, stderr, used, verts = trace(medium, origins, np.zeros((n, 2)), dirs, np.zeros(n, dtype=np.int64), sun,
                                      wl.size, samples=samples, seed=seed, scheduler=scheduler,
                                      group_size=group_size, directions_per_task=directions_per_task,
                                      batches_per_task=batches_per_task, progress=progress, orders=window)
    return MonteCarloResult(mean, stderr, used, time.perf_counter() - t_start, wl, dirs, verts)


class _BatchFold:
    """Adds per-batch sums into running totals in one fixed order: for every direction and wavelength, batch 0,
    then 1, 2, ... (tasks arriving out of order wait for their turn). The result is therefore the same bits
    whatever the task sizes, the scheduler or the order of completion, in memory independent of the samples.
    The totals are kept per hero (the strata of the standard error, :func:`reduce_strata`): ``sums``, ``sumsq``,
    ``counts`` (n_dirs, n_wl, largest group)."""

    def __init__(self, n_dirs: int, n_wl: int, groups: list[NDArray[np.int64]]) -> None:
        h = max(g.size for g in groups)
        self.sums = np.zeros((n_dirs, n_wl, h))
        self.sumsq = np.zeros((n_dirs, n_wl, h))
        self.counts = np.zeros((n_dirs, n_wl, h))
        self.groups = groups
        self.next: dict[tuple[int, int], int] = {}
        self.waiting: dict[tuple[int, int], dict[int, tuple]] = {}

    def add(self, spec: TaskSpec, sums: NDArray[np.float64], sumsq: NDArray[np.float64],
            counts: NDArray[np.float64]) -> None:
        key = (spec.dir_slice.start, spec.group)
        waiting = self.waiting.setdefault(key, {})
        waiting[spec.batch0] = (spec, sums, sumsq, counts)
        nxt = self.next.get(key, 0)
        while nxt in waiting:
            sp, a, b, c = waiting.pop(nxt)
            gi = self.groups[sp.group]
            cols = slice(int(gi[0]), int(gi[-1]) + 1)
            heroes = slice(0, gi.size)
            tot, tot2 = self.sums[sp.dir_slice, cols, heroes], self.sumsq[sp.dir_slice, cols, heroes]
            cnt = self.counts[sp.dir_slice, cols, heroes]
            for k in range(sp.n_batches):  # one batch at a time: the order of the additions is fixed
                tot += a[:, k].transpose(0, 2, 1)  # (rows, hero, wavelength) -> (rows, wavelength, hero)
                tot2 += b[:, k].transpose(0, 2, 1)
                cnt += c[:, k, None, :]  # whole numbers: exact
            nxt += sp.n_batches
        self.next[key] = nxt


def reduce_strata(sums: NDArray[np.float64], sumsq: NDArray[np.float64], counts: NDArray[np.float64], n: int
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Mean and standard error of ``n`` per-path estimates from their sums, sums of squares and counts per stratum (the
    hero; last axis; ``kernels`` module docstring, "Hero wavelengths").

    The mean is the sum over all paths over ``n``; its variance the stratified one, ``sum_h n_h s_h^2 / n^2`` with
    ``s_h^2`` the sample variance of stratum ``h``'s ``n_h`` paths ([Cochran1977] Ch. 5: the variance of the stratified
    mean, estimated with the strata's sample variances; proportional allocation). A stratum of fewer than 2 paths takes
    the strata's pooled variance; with none of 2 or more (a handful of paths) the variance of all the paths taken as one
    sample (:func:`reduce_batches`), which can only be larger in expectation."""
    mean = sums.sum(axis=-1) / n
    safe = np.maximum(counts, 1.0)
    within = np.maximum(sumsq - sums * sums / safe, 0.0)  # (n_h - 1) s_h^2
    ok = counts >= 2.0
    dof = np.where(ok, counts - 1.0, 0.0).sum(axis=-1)
    pooled = np.where(dof > 0, np.where(ok, within, 0.0).sum(axis=-1) / np.maximum(dof, 1.0), 0.0)
    s2 = np.where(ok, within / np.maximum(counts - 1.0, 1.0), pooled[..., None])
    var = (counts * s2).sum(axis=-1) / float(n) ** 2
    _, plain = reduce_batches(sums.sum(axis=-1), sumsq.sum(axis=-1), n)
    stderr = np.where(dof > 0, np.sqrt(var), plain)
    return mean, stderr


def reduce_batches(sums: NDArray[np.float64], sumsq: NDArray[np.float64], n: int
                   ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Mean and standard error from the sums and sums of squares of ``n`` per-path estimates."""
    mean = sums / n
    var = np.maximum(sumsq / n - mean * mean, 0.0) * (n / max(n - 1, 1))
    return mean, np.sqrt(var / n)


def direct_transmittance(medium: Medium, origins: NDArray[np.float64], sun: NDArray[np.float64],
                         n_radial: int = 8, n_angular: int = 16, *, point: bool = False) -> NDArray[np.float64]:
    """Mean transmittance over the solar disc from each origin (N, 3) [planet frame, m], (N, n_wl); exact through
    a cloud field (deterministic). ``point``: along the disc's centre ``sun`` alone (the beam of the forward
    photons; one ring and sector of the disc would sit off the centre, by 0.19 deg for the Sun)."""
    m = medium
    f = m.field_exact
    out = np.zeros((origins.shape[0], m.coef.shape[0]))
    radius = 0.0 if point else m.sun_angular_radius
    if point:
        n_radial = n_angular = 1
    # read-only views, as the paths' kernel gets them (_run_task): one compile of this kernel, and of the field's
    # tracking helpers it shares with trace_block, whether the field's arrays were read-only or not (compiled
    # twice in one process of tests/test_montecarlo_clouds.py before)
    inputs = [_readonly(a) for a in (sun, radius, m.bottom_radius, m.top_radius, m.edges, m.layers, m.nlay, m.coef,
                                     f.vf, f.vi, f.rho, f.bmax, f.bmin, f.xe, f.ye, f.re, m.fs)]
    for k in range(origins.shape[0]):
        kernels.disc_transmittance(_readonly(np.ascontiguousarray(origins[k])), *inputs, int(n_radial),
                                   int(n_angular), out[k])
    return out


def solar_disc_radiance(atmosphere: AtmosphereParameters, wavelengths: ArrayLike, *, sun_zenith: float,
                        altitude: float = 0.0, n_radial: int = 8, n_angular: int = 16,
                        clouds: Any = None, sun_azimuth: float = 0.0) -> NDArray[np.float64]:
    """Directly transmitted solar radiance, averaged over the solar disc [W m^-2 sr^-1 nm^-1], shape (n,).

    ``E_sun(lambda) / Omega_sun * mean_disc T(lambda)``: the transmittance ``T`` of the straight path from the
    observer to each point of a uniform disc of the parameters' angular radius (no limb darkening, as in the
    parameters), by deterministic quadrature over the disc (``n_radial`` x ``n_angular`` points equal in solid
    angle), through the cloud field ``clouds`` exactly (voxel by voxel; ``sun_azimuth`` [rad] then matters). Points
    below the planet's limb contribute 0. This is what :func:`sky_radiance` leaves out.
    """
    wl = check_wavelengths(wavelengths)
    sun = _sun_vector(sun_zenith, sun_azimuth)
    r_obs = _observer_radius(atmosphere, altitude)
    m = prepare_medium(atmosphere, wl, _check_clouds(clouds))
    out = direct_transmittance(m, np.array([[0.0, 0.0, r_obs]]), sun, n_radial, n_angular)[0]
    omega = 2.0 * math.pi * (1.0 - math.cos(m.sun_angular_radius))
    return m.esun / omega * out
