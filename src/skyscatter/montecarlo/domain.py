"""Fluxes and radiances of a cloud field's domain, per column (the I3RC quantities), and irradiance at the ground.

:func:`domain_quantities` answers, for every column ``(i, j)`` of a :class:`~skyscatter.atmosphere.clouds.CloudField`
(its pixel), what the intercomparisons of 3D radiative transfer codes ask ([Cahalan2005]; the I3RC Phase 1
output definitions):

* reflectance ``R = F_up(top) / (mu0 F0)``: the upward irradiance at the field's top averaged over the pixel;
* transmittance ``T = F_down(base) / (mu0 F0)``, direct + diffuse, at the field's base (the ground when the base
  is 0), and its direct part alone;
* reflectivities ``pi I / (mu0 F0)`` of the radiance leaving the top towards given directions (``up_views``:
  nadir reflectivity = towards the zenith), and of the radiance reaching the base from given directions
  (``down_views``: zenith transmissivity = from the zenith);
* the domain means, and the domain's absorptance ``1 - R - T (1 - A)`` for a ground of albedo ``A`` (energy
  conservation over a periodic domain, where the net horizontal fluxes cancel).

The fluxes come from forward photons (:func:`skyscatter.montecarlo.kernels.flux_block`): photons from the sun travel
on the sun rays through the field's base, uniformly over the periodic domain there, entering the top of the
atmosphere where those rays do (in a sphere, rays entering the top above the domain would reach the base where the
sun stands lower), and are tracked with the same free paths, lobes and hero-wavelength weights as the backward
paths; every upward crossing of the top, downward crossing of the base and absorbing collision adds the photon's
weight to the pixel under it (standard errors from the spread between batches of photons). With a phase function as
forward-peaked as a cloud's, this estimates fluxes with far less variance than backward paths with
cosine-distributed directions, whose next-event estimates hinge on rare scattering angles near the forward peak. The
radiances are backward paths from a point drawn uniformly over the pixel (at the top or the base) along one
direction, with next-event estimation. The direct transmittance is deterministic: the exact transmittance along the
sun direction (voxel by voxel) at a grid of points over the pixel (``direct_points`` per axis, 1 along an axis of
one voxel), along the sun's centre like the photons. In a sphere the periodic domain is an approximation: a straight
ray has the domain's sun at the base only, and diffuse light lands away from where its beam was aimed; clear air,
Earth defaults, 550 nm, the ground's diffuse irradiance against backward paths: -0.8 to -1.0 % at sun 30 deg, -3.1
to -3.4 % at 10 deg, shrinking as 1 / R (docs/clouds.md). ``mu0 F0`` is the solar irradiance on a horizontal plane
at the top, ``cos(sun_zenith) solar_irradiance_at(lambda)``.

:func:`ground_irradiance` gives the downward irradiance on the ground at the observer's foot point (or any
points): direct from the disc-mean transmittance, diffuse by the same cosine-weighted paths.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere import AtmosphereParameters
from ..conventions import direction_from_angles
from ..errors import InvalidParameterError
from ..validation import whole_number
from .driver import (
    DEFAULT_GROUP_SIZE,
    _check_clouds,
    _readonly,
    _sun_vector,
    check_wavelengths,
    direct_transmittance,
    prepare_medium,
    trace,
)

__all__ = ["DomainResult", "GroundIrradiance", "domain_quantities", "ground_irradiance"]


@dataclass(frozen=True)
class DomainResult:
    """Per-column quantities of :func:`domain_quantities`; arrays (nx, ny, n_wl) unless stated, all [-].

    Attributes
    ----------
    reflectance, reflectance_stderr : upward irradiance at the top / (mu0 F0) and its standard error.
    transmittance, transmittance_stderr : downward irradiance at the base / (mu0 F0), direct + diffuse.
    direct_transmittance : its direct part (deterministic).
    column_absorptance, column_absorptance_stderr : energy absorbed in the column between base and top / (mu0 F0
        times the pixel's area).
    up_reflectivity, up_reflectivity_stderr : (n_up, nx, ny, n_wl) ``pi I / (mu0 F0)`` of the radiance leaving
        the top towards each of ``up_views``.
    down_reflectivity, down_reflectivity_stderr : (n_down, nx, ny, n_wl) the same for the radiance reaching the
        base from each of ``down_views``.
    up_views, down_views : (n, 2) the (zenith, azimuth) [rad] of those directions.
    wavelengths : (n_wl,) [nm]; samples : backward paths per radiance; photons : forward photons in all;
    mean_vertices : vertices per path; seconds : wall time.
    ground_albedo : (n_wl,) the ground's albedo.
    levels : (L,) altitudes [m] of the flux levels (the base first, the top last); level_up, level_down and their
        ``_stderr`` (L, nx, ny, n_wl): upward and downward (direct + diffuse) irradiance / (mu0 F0) there;
        level_direct (L, nx, ny, n_wl): the direct part of level_down (deterministic).
    """

    reflectance: NDArray[np.float64]
    reflectance_stderr: NDArray[np.float64]
    transmittance: NDArray[np.float64]
    transmittance_stderr: NDArray[np.float64]
    direct_transmittance: NDArray[np.float64]
    column_absorptance: NDArray[np.float64]
    column_absorptance_stderr: NDArray[np.float64]
    up_reflectivity: NDArray[np.float64]
    up_reflectivity_stderr: NDArray[np.float64]
    down_reflectivity: NDArray[np.float64]
    down_reflectivity_stderr: NDArray[np.float64]
    up_views: NDArray[np.float64]
    down_views: NDArray[np.float64]
    wavelengths: NDArray[np.float64]
    ground_albedo: NDArray[np.float64]
    samples: int
    photons: int
    mean_vertices: float
    seconds: float
    levels: NDArray[np.float64]
    level_up: NDArray[np.float64]
    level_up_stderr: NDArray[np.float64]
    level_down: NDArray[np.float64]
    level_down_stderr: NDArray[np.float64]
    level_direct: NDArray[np.float64]

    @property
    def mean_reflectance(self) -> NDArray[np.float64]:
        """Domain-mean reflectance (n_wl,)."""
        return self.reflectance.mean(axis=(0, 1))

    @property
    def mean_transmittance(self) -> NDArray[np.float64]:
        """Domain-mean transmittance, direct + diffuse (n_wl,)."""
        return self.transmittance.mean(axis=(0, 1))

    @property
    def mean_stderr(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Standard errors of the domain-mean reflectance and transmittance (independent columns)."""
        n = self.reflectance.shape[0] * self.reflectance.shape[1]
        return (np.sqrt(np.sum(self.reflectance_stderr ** 2, axis=(0, 1))) / n,
                np.sqrt(np.sum(self.transmittance_stderr ** 2, axis=(0, 1))) / n)

    @property
    def absorptance(self) -> NDArray[np.float64]:
        """Domain-mean absorptance between base and top (n_wl,): the forward photons' absorbed weight."""
        return self.column_absorptance.mean(axis=(0, 1))

    @property
    def energy_residual(self) -> NDArray[np.float64]:
        """``1 - R - T (1 - A_ground) - absorptance`` (n_wl,): zero for a periodic domain with nothing above the
        top (what goes in comes out or is absorbed), a check of the estimator."""
        return 1.0 - self.mean_reflectance - self.mean_transmittance * (1.0 - self.ground_albedo) - self.absorptance


def _flux_task(medium, sun, dom, levels, group, wl_index, batch0, n_batches, batch_size, seed):
    from . import kernels

    m = medium.subset(wl_index)
    npix = int(dom[4]) * int(dom[5])
    up = np.zeros((levels.size, npix, wl_index.size, 2))
    down = np.zeros_like(up)
    absorbed = np.zeros((npix, wl_index.size, 2))
    verts = np.zeros(1)
    f = m.field
    inputs = [_readonly(a) for a in (  # one compile whatever the arrays' origin (driver._readonly)
        sun, m.bottom_radius, m.top_radius, m.edges, m.layers, m.nlay, m.coef, m.scat, m.lobe, m.lobe_g, m.lobe_tab,
        m.tmu, m.tval, m.tcdf, m.albedo, f.vf, f.vi, f.rho, f.bmax, f.bmin, f.xe, f.ye, f.re, m.fs, m.fss, dom, levels)]
    kernels.flux_block(*inputs, seed, group, batch0, n_batches, batch_size, up, down, absorbed, verts)
    return up, down, absorbed, verts


#: Added to the seed of the forward photons' streams, so that they never share numbers with the backward paths.
_FORWARD_SEED_OFFSET = 0x5F0D


def _batch_stats(s1: NDArray[np.float64], s2: NDArray[np.float64], n_batches: int, batch_size: int, npix: int):
    """Per-pixel estimates (tally per photon times the number of pixels) and standard errors from the per-batch
    sums of tallies ``s1`` and of their squares ``s2``."""
    mean_b = s1 / n_batches
    var_b = np.maximum(s2 / n_batches - mean_b ** 2, 0.0) * (n_batches / (n_batches - 1))
    return mean_b / batch_size * npix, np.sqrt(var_b / n_batches) / batch_size * npix


def _domain_fluxes(medium, clouds, radii, sun, n_wl, *, samples, seed, scheduler, group_size, progress):
    """Forward photons over the domain: upward and downward fluxes at the level spheres ``radii`` [m] (L, nx, ny,
    n_wl) and the column absorptance (nx, ny, n_wl), each with standard errors (batch to batch), / (mu0 F0); the
    photons used and the vertices per photon."""
    from .driver import batch_layout, count_tasks, iter_tasks, run_tasks, wavelength_groups

    batch_size, n_batches = batch_layout(int(samples))
    n_batches = max(n_batches, 8)
    groups = wavelength_groups(n_wl, group_size)
    nx, ny, _ = clouds.shape
    dx, dy, _ = clouds.voxel_size
    dom = np.array([clouds.origin[0], clouds.origin[1], dx, dy, float(nx), float(ny)])
    sizes = dict(directions_per_task=1, batches_per_task=max(1, 65536 // batch_size))
    npix = nx * ny
    nlev = radii.size
    levels = np.zeros((2, nlev, npix, n_wl, 2))
    absorbed = np.zeros((npix, n_wl, 2))
    verts = [0.0]
    specs: dict[int, Any] = {}
    waiting: dict[int, tuple] = {}
    nxt = [0]

    def calls():
        for k, sp in enumerate(iter_tasks(1, len(groups), n_batches, batch_size, **sizes)):
            specs[k] = sp
            yield (medium, sun, dom, radii, sp.group, groups[sp.group], sp.batch0, sp.n_batches, batch_size,
                   int(seed) + _FORWARD_SEED_OFFSET)

    def add(k: int, result: tuple) -> None:
        # added in task order (results may arrive in any order on a cluster): the same bits on any scheduler
        waiting[k] = result
        while nxt[0] in waiting:
            u, d, a, v = waiting.pop(nxt[0])
            sp = specs.pop(nxt[0])
            gi = slice(int(groups[sp.group][0]), int(groups[sp.group][-1]) + 1)
            levels[0, :, :, gi] += u
            levels[1, :, :, gi] += d
            absorbed[:, gi] += a
            verts[0] += float(v[0])
            nxt[0] += 1

    total = count_tasks(1, len(groups), n_batches, batch_size, **sizes)
    run_tasks(_flux_task, calls(), scheduler, on_result=add, progress=progress, total=total)
    lv, lv_err = _batch_stats(levels[..., 0], levels[..., 1], n_batches, batch_size, npix)
    ab, ab_err = _batch_stats(absorbed[..., 0], absorbed[..., 1], n_batches, batch_size, npix)
    used = batch_size * n_batches
    shape = (2, nlev, nx, ny, n_wl)
    return (lv.reshape(shape), lv_err.reshape(shape), ab.reshape(nx, ny, n_wl), ab_err.reshape(nx, ny, n_wl), used,
            verts[0] / (used * len(groups)))


def _views(name: str, views: ArrayLike | None) -> NDArray[np.float64]:
    if views is None:
        return np.zeros((0, 2))
    v = np.asarray(views, dtype=float).reshape(-1, 2)
    if not np.all(np.isfinite(v)) or np.any(v[:, 0] < 0) or np.any(v[:, 0] >= math.pi / 2):
        raise InvalidParameterError(f"{name} must be (zenith, azimuth) pairs [rad] with 0 <= zenith < pi/2")
    return v




def _on_sphere(x: NDArray[np.float64], y: NDArray[np.float64], radius: float) -> NDArray[np.float64]:
    """Planet-frame points at horizontal coordinates (x, y) [m] and distance ``radius`` [m] from the centre."""
    return np.stack([x, y, np.sqrt(radius * radius - x * x - y * y)], axis=-1)


def domain_quantities(atmosphere: AtmosphereParameters, clouds: Any, wavelengths: ArrayLike, *, sun_zenith: float,
                      sun_azimuth: float = 0.0, up_views: ArrayLike | None = ((0.0, 0.0),),
                      down_views: ArrayLike | None = None, samples: int = 4096, seed: int = 0,
                      direct_points: int = 16, scheduler: Any = None, group_size: int = DEFAULT_GROUP_SIZE,
                      progress: Callable[[int, int], None] | None = None, majorant_block: Any = None,
                      fluxes: bool = True, levels: ArrayLike | None = None) -> DomainResult:
    """R, T, direct T, absorptance and reflectivities per column of a periodic ``clouds`` (module docstring).

    Parameters
    ----------
    atmosphere : AtmosphereParameters
        The medium around the field (for a cloud alone: no Rayleigh, aerosol or ozone, e.g.
        ``AtmosphereParameters(rayleigh_scattering=0.0, mie_angstrom_beta=0.0, ozone_column=0.0, ...)``).
    clouds : CloudField
        A periodic field (its columns are the pixels; the sun lights the whole periodic domain).
    wavelengths : array_like [nm]
    sun_zenith, sun_azimuth : float
        Sun position [rad] (zenith < pi/2; azimuth from north towards east: pi/2 = the sun in the east, its light
        travelling west).
    up_views : (n, 2) array_like, optional
        Directions (zenith < pi/2, azimuth) [rad] towards which the radiance leaving the top is reported (default:
        the zenith, the nadir reflectivity).
    down_views : (n, 2) array_like, optional
        Directions (zenith < pi/2, azimuth) [rad] from which the radiance reaching the base is reported.
    samples : int
        Backward paths per column and view; the fluxes use ``samples`` forward photons per column.
    direct_points : int
        Points per pixel axis for the direct transmittance (>= 1).
    fluxes : bool
        False skips R, T and the absorptance (radiances only; their arrays are NaN).
    levels : array_like, optional
        Further altitudes [m] (between the ground and the top of the atmosphere) at which the upward and downward
        fluxes are tallied too (:attr:`DomainResult.level_up` ...); the field's base and top always are.
    seed, scheduler, group_size, progress, majorant_block
        As :func:`~skyscatter.montecarlo.sky_radiance`.
    """
    from ..atmosphere.clouds import CloudField
    from .driver import check_samples

    t0 = time.perf_counter()
    if not isinstance(clouds, CloudField):
        raise InvalidParameterError(f"clouds must be a CloudField; got {type(clouds).__name__}")
    if not clouds.periodic:
        raise InvalidParameterError("domain quantities need a periodic cloud field (CloudField(..., periodic=True))")
    wl = check_wavelengths(wavelengths)
    n_samples = check_samples(samples)
    sun = _sun_vector(sun_zenith, sun_azimuth)
    mu0 = float(sun[2])
    if not mu0 > 1e-6:
        raise InvalidParameterError("domain quantities need the sun above the horizon (sun_zenith < pi/2)")
    ups, downs = _views("up_views", up_views), _views("down_views", down_views)
    npts = whole_number("direct_points", direct_points, 1)
    medium = prepare_medium(atmosphere, wl, clouds, majorant_block)
    nx, ny, _ = clouds.shape
    dx, dy, _ = clouds.voxel_size
    xs = clouds.origin[0] + (np.arange(nx) + 0.5) * dx
    ys = clouds.origin[1] + (np.arange(ny) + 0.5) * dy
    cx, cy = (a.ravel() for a in np.meshgrid(xs, ys, indexing="ij"))
    ncol = cx.size
    r_top = atmosphere.bottom_radius + clouds.top
    r_base = atmosphere.bottom_radius + clouds.base
    top = _on_sphere(cx, cy, r_top)
    base = _on_sphere(cx, cy, r_base)
    alts = np.array([clouds.base, clouds.top], dtype=float)
    if levels is not None:
        extra = np.atleast_1d(np.asarray(levels, dtype=float))
        if extra.ndim != 1 or not np.all(np.isfinite(extra)) or np.any(extra < 0) or \
                np.any(extra >= atmosphere.thickness):
            raise InvalidParameterError(
                f"levels must be altitudes [m] from 0 to below the top of the atmosphere ({atmosphere.thickness:g} m)")
        alts = np.unique(np.concatenate([alts, extra]))
    radii = atmosphere.bottom_radius + alts
    nlev = alts.size
    nan = np.full((nlev, nx, ny, wl.size), np.nan)
    lv, lv_err = np.stack([nan, nan]), np.stack([nan, nan])
    ab, ab_err = nan[0], nan[0]
    photons, fverts = 0, math.nan
    if fluxes:
        lv, lv_err, ab, ab_err, photons, fverts = _domain_fluxes(
            medium, clouds, radii, sun, wl.size, samples=n_samples * ncol, seed=seed, scheduler=scheduler,
            group_size=group_size, progress=progress)
        # each photon carries mu0 F0 times the domain's area / photons: the tallies are already / (mu0 F0)
    origins, dirs = [], []
    for zen, azi in ups:
        origins.append(top)
        dirs.append(np.tile(-direction_from_angles(zen, azi), (ncol, 1)))
    for zen, azi in downs:
        origins.append(base)
        dirs.append(np.tile(direction_from_angles(zen, azi), (ncol, 1)))
    n_sets = len(origins)
    refl = np.zeros((n_sets, nx, ny, wl.size))
    refl_err = np.zeros_like(refl)
    used, verts = n_samples, fverts
    if n_sets:
        o = np.ascontiguousarray(np.concatenate(origins))
        d = np.ascontiguousarray(np.concatenate(dirs), dtype=float)
        jitter = np.tile([dx, dy], (o.shape[0], 1))
        mean, stderr, used, verts = trace(medium, o, jitter, d, np.zeros(o.shape[0], dtype=np.int64), sun, wl.size,
                                          samples=n_samples, seed=seed, scheduler=scheduler, group_size=group_size,
                                          progress=progress)
        # reflectivities pi I / (mu0 F0)
        scale = math.pi / (mu0 * medium.esun)
        refl = (mean * scale).reshape(n_sets, nx, ny, wl.size)
        refl_err = (stderr * scale).reshape(n_sets, nx, ny, wl.size)
    # direct transmittance: exact at npts x npts points over each pixel (1 along an axis of one voxel), each level
    frac = (np.arange(npts) + 0.5) / npts - 0.5
    qx = frac * dx if nx > 1 else np.zeros(1)
    qy = frac * dy if ny > 1 else np.zeros(1)
    ox, oy = (a.ravel() for a in np.meshgrid(qx, qy, indexing="ij"))
    direct = np.empty((nlev, nx, ny, wl.size))
    for j, radius in enumerate(radii):
        pts = _on_sphere((cx[:, None] + ox[None, :]).ravel(), (cy[:, None] + oy[None, :]).ravel(), radius)
        d = direct_transmittance(medium, pts, sun, point=True).reshape(ncol, ox.size, wl.size).mean(axis=1)
        direct[j] = d.reshape(nx, ny, wl.size)
    nu = ups.shape[0]
    top, base = nlev - 1, 0
    return DomainResult(lv[0, top], lv_err[0, top], lv[1, base], lv_err[1, base], direct[base], ab, ab_err,
                        refl[:nu], refl_err[:nu], refl[nu:], refl_err[nu:], ups, downs, wl,
                        np.asarray(medium.albedo, dtype=float), used, photons, verts, time.perf_counter() - t0,
                        alts, lv[0], lv_err[0], lv[1], lv_err[1], direct)


@dataclass(frozen=True)
class GroundIrradiance:
    """Downward irradiance on the ground [W m^-2 nm^-1], each (n_points, n_wl): ``direct`` (the sun's disc,
    deterministic), ``diffuse`` and its ``diffuse_stderr``; ``global_`` = direct + diffuse."""

    direct: NDArray[np.float64]
    diffuse: NDArray[np.float64]
    diffuse_stderr: NDArray[np.float64]
    wavelengths: NDArray[np.float64]
    samples: int
    mean_vertices: float
    seconds: float

    @property
    def global_(self) -> NDArray[np.float64]:
        return self.direct + self.diffuse


def ground_irradiance(atmosphere: AtmosphereParameters, wavelengths: ArrayLike, *, sun_zenith: float,
                      sun_azimuth: float = 0.0, points: ArrayLike | None = None, clouds: Any = None,
                      samples: int = 4096, seed: int = 0, scheduler: Any = None,
                      group_size: int = DEFAULT_GROUP_SIZE, majorant_block: Any = None,
                      progress: Callable[[int, int], None] | None = None) -> GroundIrradiance:
    """Direct and diffuse irradiance on the horizontal ground [W m^-2 nm^-1] at ``points``.

    ``points`` (N, 2): east and north offsets [m] from the observer's foot point (the field's horizontal
    coordinates; default one point at 0, 0). The diffuse part is the mean of ``pi L`` over cosine-distributed
    upward directions (paths ``samples`` per point); the direct part is ``E_sun cos(sun_zenith) T`` with the
    disc-mean transmittance ``T`` (exact through a cloud field).
    """
    t0 = time.perf_counter()
    wl = check_wavelengths(wavelengths)
    sun = _sun_vector(sun_zenith, sun_azimuth)
    pts = np.zeros((1, 2)) if points is None else np.asarray(points, dtype=float).reshape(-1, 2)
    if not np.all(np.isfinite(pts)) or np.any(np.abs(pts) > 1e7):
        raise InvalidParameterError("points must be finite (east, north) offsets within 10000 km [m]")
    medium = prepare_medium(atmosphere, wl, _check_clouds(clouds), majorant_block)
    origins = _on_sphere(pts[:, 0], pts[:, 1], atmosphere.bottom_radius)
    n = origins.shape[0]
    mean, stderr, used, verts = trace(medium, origins, np.zeros((n, 2)), np.tile([0.0, 0.0, 1.0], (n, 1)),
                                      np.ones(n, dtype=np.int64), sun, wl.size, samples=samples, seed=seed,
                                      scheduler=scheduler, group_size=group_size, progress=progress)
    direct = medium.esun * max(float(sun[2]), 0.0) * direct_transmittance(medium, origins, sun)
    return GroundIrradiance(direct, mean, stderr, wl, used, verts, time.perf_counter() - t0)
