"""Forward photons through the whole spherical atmosphere: ground irradiance and sky radiance by local sun elevation.

:func:`sphere_ground_fluxes` is the reference for a horizontally uniform medium (air, aerosol, cloud layers as
spherical shells) under a low sun, where neither of the other estimators serves: backward paths from the ground
(:func:`~skyscatter.montecarlo.domain.ground_irradiance`, :func:`~skyscatter.montecarlo.sky_radiance`) are
heavy-tailed where the sun grazes a cloud top, and the forward photons of
:func:`~skyscatter.montecarlo.domain.domain_quantities` run in a periodic flat domain whose error in a sphere grows
as the sun sinks (docs/clouds.md).

Method. A horizontally uniform atmosphere lit by a parallel sun is symmetric about the axis through the planet's
centre along the sun direction: a ground point's irradiance and radiance depend only on its local sun elevation
``e`` (``sin e = cos`` of its angle from the axis). Photons are launched from the sun over an annulus of impact
parameters ``b`` (distance from the axis) uniform in area, each carrying ``E_sun A / N`` (``A = pi (b_hi^2 -
b_lo^2)``, ``N`` photons; ``E_sun`` the solar irradiance at normal incidence), traced exactly through the spherical
shells with the Monte Carlo's own medium, free paths, lobes and Lambertian ground (:func:`.kernels.sphere_block`),
and every downward arrival at the ground is tallied by the ring of ``e`` it lands in: a ring ``e1 <= e < e2`` of the
ground sphere has the area ``2 pi R^2 (sin e2 - sin e1)`` exactly, so its mean irradiance is ``E_sun A sum(w) /
(N 2 pi R^2 (sin e2 - sin e1))`` (the analogue estimator of a boundary flux, [SpanierGelbard1969] Ch. 3; the
same counting as the I3RC forward codes' pixel fluxes, [Cahalan2005]). Arrivals never scattered nor reflected are
the direct part, the rest the diffuse part. The radiance arriving in a bin of view zenith ``theta`` and azimuth
``phi`` from the local sun's vertical plane (folded into [0, pi]: the field is symmetric about that plane) is
``E_sun A sum(w / cos theta) / (N area solid_angle)`` with the bin's solid angle ``2 dphi (cos theta1 - cos
theta2)``: the mean of the radiance over the bin's solid angle and the ring's area, so a bin's finite size is a
bias of second order in its width where the radiance is smooth (measured by halving the bins, docs/clouds.md).

The annulus. A ray with impact parameter ``b <= R`` meets the ground where the sun stands at ``e = acos(b / R)``;
before that it passes over the ground points of higher sun (at radius ``r`` it is above the point ``e'`` with ``b =
r cos e'``), so the air above a ring is crossed by every ray from the one landing at the ring's upper edge, ``b = R
cos e_hi``, to the one crossing the top of the atmosphere above its lower edge, ``b = r_top cos e_lo`` (all rays up
to ``r_top`` when ``e_lo <= 0``, those grazing past the planet included): at a low sun most of a ring's sky light
is scattered out of rays that land far down-sun of it or miss the ground (sun 2 deg, clear air, 450 nm: the rays
landing between 0.75 and 3.25 deg give 7 % of it). The annulus must hold those rays, plus a margin for the light
scattered sideways and back, carried through the air and the clouds; that the default margin of 3 deg costs nothing
measurable is checked by widening it (tests; docs/clouds.md).

Standard errors from the spread between batches of photons (as :mod:`.domain`); the photons of a task are a run of
batches of one wavelength group, distributed through Dask like the other drivers and added in task order, so the
result depends only on the seed, not on the scheduler.
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
from ..errors import InvalidParameterError
from ..validation import whole_number
from .driver import (
    _readonly,
    batch_layout,
    check_wavelengths,
    count_tasks,
    direct_transmittance,
    iter_tasks,
    prepare_medium,
    run_tasks,
    wavelength_groups,
)

__all__ = ["SphereGroundFluxes", "sphere_ground_fluxes", "sphere_direct_irradiance"]

#: Added to the seed of these photons' streams, so that they never share numbers with the backward paths or the
#: domain's forward photons.
_SPHERE_SEED_OFFSET = 0x5F1E
#: Default margin [rad] of the launch annulus beyond the rings on each side.
DEFAULT_MARGIN = math.radians(3.0)


@dataclass(frozen=True)
class SphereGroundFluxes:
    """Result of :func:`sphere_ground_fluxes`; irradiances [W m^-2 nm^-1], radiances [W m^-2 sr^-1 nm^-1].

    Attributes
    ----------
    elevation_edges : (nr + 1,) local sun elevations [rad] of the rings' edges; ``elevations`` their centres.
    direct, direct_stderr : (nr, n_wl) downward irradiance of the never-scattered photons, ring mean.
    diffuse, diffuse_stderr : (nr, n_wl) downward irradiance of the photons scattered or reflected at least once.
    radiance, radiance_stderr : (nr, nz, na, n_wl) mean radiance arriving in each bin of view zenith
        (``view_zenith_edges`` (nz + 1,) [rad]) and azimuth from the sun's vertical plane (``azimuth_edges`` (na + 1,)
        [rad] over [0, pi]).
    ground_fraction, escaped_fraction, absorbed_fraction : (n_wl,) the launched energy arriving at the ground
        (every arrival, reflections included, anywhere), leaving through the top, absorbed in the medium.
    launch : (2,) the annulus' impact parameters [m].
    wavelengths : (n_wl,) [nm]; photons : launched per wavelength group; mean_vertices; seconds (wall);
    cpu_seconds (process CPU time of the call).
    """

    elevation_edges: NDArray[np.float64]
    direct: NDArray[np.float64]
    direct_stderr: NDArray[np.float64]
    diffuse: NDArray[np.float64]
    diffuse_stderr: NDArray[np.float64]
    radiance: NDArray[np.float64]
    radiance_stderr: NDArray[np.float64]
    view_zenith_edges: NDArray[np.float64]
    azimuth_edges: NDArray[np.float64]
    ground_fraction: NDArray[np.float64]
    escaped_fraction: NDArray[np.float64]
    absorbed_fraction: NDArray[np.float64]
    launch: NDArray[np.float64]
    wavelengths: NDArray[np.float64]
    photons: int
    mean_vertices: float
    seconds: float
    cpu_seconds: float

    @property
    def elevations(self) -> NDArray[np.float64]:
        """Centres of the rings [rad]."""
        return 0.5 * (self.elevation_edges[1:] + self.elevation_edges[:-1])


def _sphere_task(medium, launch, sedges, muedges, na, group, wl_index, batch0, n_batches, batch_size, seed):
    from . import kernels

    m = medium.subset(wl_index)
    nw = wl_index.size
    nr = sedges.size - 1
    direct = np.zeros((nr, nw, 2))
    diffuse = np.zeros_like(direct)
    rad = np.zeros((nr, muedges.size - 1, na, nw, 2))
    totals = np.zeros((3, nw, 2))
    verts = np.zeros(1)
    f = m.field
    inputs = [_readonly(a) for a in (  # one compile whatever the arrays' origin (driver._readonly)
        m.bottom_radius, m.top_radius, m.edges, m.layers, m.nlay, m.coef, m.scat, m.lobe, m.lobe_g, m.lobe_tab,
        m.tmu, m.tval, m.tcdf, m.albedo, f.vf, f.vi, f.rho, f.bmax, f.bmin, f.xe, f.ye, f.re, m.fs, m.fss, launch,
        sedges, muedges)]
    kernels.sphere_block(*inputs, seed, group, batch0, n_batches, batch_size, direct, diffuse, rad, totals, verts)
    return direct, diffuse, rad, totals, verts


def _stats(s1: NDArray[np.float64], s2: NDArray[np.float64], n_batches: int, batch_size: int
           ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Mean tally per photon and its standard error from per-batch sums ``s1`` and sums of squares ``s2``."""
    mean_b = s1 / n_batches
    var_b = np.maximum(s2 / n_batches - mean_b ** 2, 0.0) * (n_batches / (n_batches - 1))
    return mean_b / batch_size, np.sqrt(var_b / n_batches) / batch_size


def _edges(name: str, value: ArrayLike, lo: float, hi: float) -> NDArray[np.float64]:
    e = np.asarray(value, dtype=float).ravel()
    if e.size < 2 or not np.all(np.isfinite(e)) or np.any(np.diff(e) <= 0) or e[0] < lo or e[-1] > hi:
        raise InvalidParameterError(
            f"{name} must be at least two strictly ascending angles [rad] within [{lo:.6g}, {hi:.6g}]; got {value!r}")
    return e


def sphere_ground_fluxes(atmosphere: AtmosphereParameters, wavelengths: ArrayLike, *, elevation_edges: ArrayLike,
                         photons: int, launch: ArrayLike | None = None, margin: float = DEFAULT_MARGIN,
                         view_zenith_edges: ArrayLike = (0.0, math.pi / 2), azimuth_bins: int = 1, seed: int = 0,
                         scheduler: Any = None, group_size: int = 1,
                         progress: Callable[[int, int], None] | None = None) -> SphereGroundFluxes:
    """Ground irradiance (direct, diffuse) and sky radiance by local sun elevation from forward photons through the
    spherical atmosphere (module docstring).

    Parameters
    ----------
    atmosphere : AtmosphereParameters
        A horizontally uniform medium (air, aerosol, cloud layers; no 3D cloud field), Lambertian ground of its
        albedo.
    wavelengths : array_like [nm]
    elevation_edges : array_like [rad]
        Edges of the rings of local sun elevation (ascending, within [-pi/2, pi/2]), e.g. 0.5 deg wide.
    photons : int
        Photons launched (per wavelength group), >= 1000 (rounded up to whole batches of 512).
    launch : (2,) array_like [m], optional
        The annulus' impact parameters (distance of a sun ray from the axis). It must hold every ray through the
        air above the rings (module docstring). Default: from the ray that lands ``margin`` above the rings'
        upper edge (``b = R cos(e_hi + margin)``) to the one that crosses the top of the atmosphere ``margin``
        below their lower edge (``b = r_top cos(e_lo - margin)``, every ray to the top when that is <= 0).
    margin : float [rad]
        The default annulus' margin (>= 0; unused with ``launch``).
    view_zenith_edges : array_like [rad]
        Edges of the radiance's view zenith bins (ascending, within [0, pi/2]).
    azimuth_bins : int
        Equal bins of the azimuth from the sun's vertical plane over [0, pi] (>= 1).
    seed : int
        The result depends only on it (and on the photons, wavelengths and group size), not on the scheduler.
    scheduler : None, 'synchronous', a dask.distributed Client or address, as for ``sky_radiance``.
    group_size : int
        Wavelengths sharing photons (hero wavelengths, [Wilkie2014]); 1 (default): one wavelength at a time.

    Raises
    ------
    InvalidParameterError
        On a bad argument: rings outside the launched annulus or [-pi/2, pi/2], too few photons, bad bins.
    """
    t0 = time.perf_counter()
    c0 = time.process_time()
    wl = check_wavelengths(wavelengths)
    n_photons = whole_number("photons", photons, 1000)
    se = _edges("elevation_edges", elevation_edges, -math.pi / 2, math.pi / 2)
    mz = _edges("view_zenith_edges", view_zenith_edges, 0.0, math.pi / 2)
    na = whole_number("azimuth_bins", azimuth_bins, 1)
    if not (math.isfinite(float(margin)) and float(margin) >= 0.0):
        raise InvalidParameterError(f"margin must be an angle >= 0 [rad]; got {margin!r}")
    medium = prepare_medium(atmosphere, wl)
    rb, rt = medium.bottom_radius, medium.top_radius
    e_lo, e_hi = float(se[0]), float(se[-1])
    if e_hi <= 0.0:
        raise InvalidParameterError("the rings must reach the sunlit ground (their upper edge above 0)")
    # every ray through the air above the rings: from the ray that lands at their upper edge to the ray that
    # crosses the top of the atmosphere above their lower edge
    need = (rb * math.cos(e_hi), rt * math.cos(e_lo) if e_lo > 0.0 else rt)
    if launch is None:
        m = float(margin)
        b_lo = rb * math.cos(min(e_hi + m, math.pi / 2))
        b_hi = rt * math.cos(e_lo - m) if e_lo - m > 0.0 else rt
    else:
        lb = np.asarray(launch, dtype=float).ravel()
        if lb.size != 2 or not np.all(np.isfinite(lb)) or not 0.0 <= lb[0] < lb[1] <= rt:
            raise InvalidParameterError(
                f"launch must be two ascending impact parameters [m] from 0 to the top radius ({rt:.8g} m); "
                f"got {launch!r}")
        b_lo, b_hi = float(lb[0]), float(lb[1])
    if not (b_lo <= need[0] * (1.0 + 1e-12) and b_hi >= need[1] * (1.0 - 1e-12)):
        raise InvalidParameterError(
            f"the launched annulus ({b_lo:.8g} to {b_hi:.8g} m from the axis) must hold every ray through the air "
            f"above the rings ({math.degrees(e_lo):.4g} to {math.degrees(e_hi):.4g} deg): {need[0]:.8g} to "
            f"{need[1]:.8g} m")
    launch_b = np.array([b_lo, b_hi])
    sedges = np.ascontiguousarray(np.sin(se))
    # view zenith edges as ascending cosines (from the largest zenith to the smallest)
    muedges = np.ascontiguousarray(np.cos(mz[::-1]))

    batch_size, n_batches = batch_layout(n_photons)
    n_batches = max(n_batches, 8)
    groups = wavelength_groups(wl.size, whole_number("group_size", group_size, 1))
    nr, nm, nw = se.size - 1, mz.size - 1, wl.size
    acc_dir = np.zeros((nr, nw, 2))
    acc_dif = np.zeros((nr, nw, 2))
    acc_rad = np.zeros((nr, nm, na, nw, 2))
    acc_tot = np.zeros((3, nw, 2))
    verts = [0.0]
    sizes = dict(directions_per_task=1, batches_per_task=max(1, 16384 // batch_size))
    specs: dict[int, Any] = {}
    waiting: dict[int, tuple] = {}
    nxt = [0]

    def calls():
        for k, sp in enumerate(iter_tasks(1, len(groups), n_batches, batch_size, **sizes)):
            specs[k] = sp
            yield (medium, launch_b, sedges, muedges, na, sp.group, groups[sp.group], sp.batch0, sp.n_batches,
                   batch_size, int(seed) + _SPHERE_SEED_OFFSET)

    def add(k: int, result: tuple) -> None:
        # added in task order (results may arrive in any order on a cluster): the same bits on any scheduler
        waiting[k] = result
        while nxt[0] in waiting:
            d, f, r, tt, v = waiting.pop(nxt[0])
            sp = specs.pop(nxt[0])
            gi = slice(int(groups[sp.group][0]), int(groups[sp.group][-1]) + 1)
            acc_dir[:, gi] += d
            acc_dif[:, gi] += f
            acc_rad[..., gi, :] += r
            acc_tot[:, gi] += tt
            verts[0] += float(v[0])
            nxt[0] += 1

    total = count_tasks(1, len(groups), n_batches, batch_size, **sizes)
    run_tasks(_sphere_task, calls(), scheduler, on_result=add, progress=progress, total=total)
    used = batch_size * n_batches
    # each photon carries E_sun * A_launch / N; a ring's area 2 pi R^2 (sin e2 - sin e1)
    area_launch = math.pi * (b_hi * b_hi - b_lo * b_lo)
    ring = 2.0 * math.pi * rb * rb * np.diff(sedges)
    scale = medium.esun[None, :] * area_launch / ring[:, None]
    d, d_err = _stats(acc_dir[..., 0], acc_dir[..., 1], n_batches, batch_size)
    f, f_err = _stats(acc_dif[..., 0], acc_dif[..., 1], n_batches, batch_size)
    r, r_err = _stats(acc_rad[..., 0], acc_rad[..., 1], n_batches, batch_size)
    tt, _ = _stats(acc_tot[..., 0], acc_tot[..., 1], n_batches, batch_size)
    az = np.linspace(0.0, math.pi, na + 1)
    omega = 2.0 * np.diff(az)[None, :] * (np.cos(mz[:-1]) - np.cos(mz[1:]))[:, None]  # both sides of the plane
    # the kernel's view bins run in ascending cosine (descending zenith): reverse them to ascending zenith
    r, r_err = r[:, ::-1], r_err[:, ::-1]
    rscale = scale[:, None, None, :] / omega[None, :, :, None]
    return SphereGroundFluxes(se, d * scale, d_err * scale, f * scale, f_err * scale, r * rscale, r_err * rscale,
                              mz, az, tt[0], tt[1], tt[2], launch_b, wl, used,
                              verts[0] / (used * len(groups)), time.perf_counter() - t0, time.process_time() - c0)


def sphere_direct_irradiance(atmosphere: AtmosphereParameters, wavelengths: ArrayLike, elevation_edges: ArrayLike,
                             points: int = 16) -> NDArray[np.float64]:
    """Exact direct irradiance [W m^-2 nm^-1] of a parallel sun (its disc's centre) on each ring of local sun
    elevation, (nr, n_wl): ``E_sun sin e T(e)`` with the Beer-Lambert transmittance ``T`` along the sun's chord
    (the Monte Carlo's column integrator, :func:`.driver.direct_transmittance`), averaged over the ring's area
    (uniform in ``sin e``) by ``points``-point Gauss-Legendre quadrature in ``sin e`` ([Abramowitz1964] 25.4.30)."""
    wl = check_wavelengths(wavelengths)
    se = _edges("elevation_edges", elevation_edges, -math.pi / 2, math.pi / 2)
    medium = prepare_medium(atmosphere, wl)
    x, w = np.polynomial.legendre.leggauss(whole_number("points", points, 1))
    out = np.zeros((se.size - 1, wl.size))
    sun = np.array([0.0, 0.0, 1.0])
    for k in range(se.size - 1):
        s1, s2 = math.sin(se[k]), math.sin(se[k + 1])
        s = 0.5 * (s1 + s2) + 0.5 * (s2 - s1) * x
        for sk, wk in zip(s, w, strict=True):
            if sk <= 0.0:
                continue
            pt = np.array([[math.sqrt(1.0 - sk * sk) * medium.bottom_radius, 0.0, sk * medium.bottom_radius]])
            out[k] += 0.5 * wk * medium.esun * sk * direct_transmittance(medium, pt, sun, point=True)[0]
    return out
