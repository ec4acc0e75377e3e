"""The tables' second order of scattering against an independent integral, at low sun (docs/accuracy.md, "Low sun").

The second order seen from an observer on the ground along ``v`` with the sun along ``s`` (point sun, ground albedo
0 in both, so that no light comes from the ground):

``L2(v) = int_0^D T(x, y) sum_i sigma_i(y) int_4pi P_i(w . v) L1(y, w) dw dt``,
``L1(y, w) = int_0^D' T(y, z) sum_i sigma_i(z) P_i(w . s) T_sun(z) E_sun dt'``

(Bruneton & Neyret 2008, Eqs. 7-9 with the order-1 radiance in the density), integrated here directly along every
ray with no table: the view ray on Gauss-Legendre pieces growing geometrically from the observer, the sphere at
each of its points on a double-Gauss (in the cosine of the local zenith) times uniform azimuth rule, each secondary
ray on the union of a uniform and a geometric grid (trapezoid, with its transmittance accumulated along the same
points), and the transmittance to the sun from each of those points on composite Gauss-Legendre (its ray blocked
where it meets the ground). The densities are the parameter object's profiles on a 1 m grid. Written with numba
(1-2 G density reads per case); it shares no code with :mod:`skyscatter.precomputed`.

The tables: ``PrecomputedAtmosphere.compute(orders=2)`` (no tail below 3 orders) at one wavelength, their
multiple-scattering table alone (the second order), read with the rendering lookups; and ``orders=1``'s single
scattering against ``L1`` of the same integrator along the view ray (a check of the integrator itself).

``--irradiance=-6,-3,0,10`` instead: the first order's sky irradiance on a horizontal surface on the ground (the
irradiance table of ``orders=2``, read by ``ground_irradiance``) against ``L1`` of the same integrator summed over
the upper hemisphere (32 Gauss-Legendre cosines x 64 azimuths), at the given sun elevations [deg].

``python benchmarks/second_order_low_sun.py [--atm turbidity3] [--suns=-6,10] [--wavelength 560]
[--n-mu 48 --n-phi 48] [--irradiance=-6,-3,0,10]``
"""

from __future__ import annotations

import argparse
import math
import time

import numba
import numpy as np

from skyscatter.precomputed import AtmosphereParameters, PrecomputedAtmosphere

ATMOSPHERES = {
    "earth": lambda **k: AtmosphereParameters(**k),
    "turbidity3": lambda **k: AtmosphereParameters.from_turbidity(3.0, **k),
    "aod05": lambda **k: AtmosphereParameters.from_aerosol_optical_depth(0.5, **k),
}
VIEWS = [(2, 0), (15, 0), (5, 45), (2, 90), (15, 90), (2, 135), (5, 135), (15, 135), (2, 180), (5, 180),
         (15, 180)]


@numba.njit(cache=False, fastmath=False)
def _ext(h, dens, sig):
    """(extinction, Rayleigh scattering, aerosol scattering) [m^-1] at altitude h [m] (1 m density grid)."""
    if h < 0.0:
        h = 0.0
    n = dens.shape[0] - 1
    if h >= n:
        return 0.0, 0.0, 0.0
    i = int(h)
    f = h - i
    dr = (1 - f) * dens[i, 0] + f * dens[i + 1, 0]
    dm = (1 - f) * dens[i, 1] + f * dens[i + 1, 1]
    do = (1 - f) * dens[i, 2] + f * dens[i + 1, 2]
    return dr * sig[0] + dm * sig[2] + do * sig[3], dr * sig[0], dm * sig[1]


@numba.njit(cache=False)
def _ray_length(px, py, pz, ux, uy, uz, rb, rt):
    """(distance to the end, meets the ground) of the ray from p along the unit u."""
    r2 = px * px + py * py + pz * pz
    b = px * ux + py * uy + pz * uz
    dg = b * b - r2 + rb * rb
    if b < 0.0 and dg >= 0.0:
        return -b - math.sqrt(dg), True
    return -b + math.sqrt(max(b * b - r2 + rt * rt, 0.0)), False


@numba.njit(cache=False)
def _tau_sun(px, py, pz, sx, sy, sz, rb, rt, dens, sig, gx, gw, pieces):
    """Optical depth from p to the top towards the sun (composite Gauss-Legendre); inf if the ground blocks it."""
    d, ground = _ray_length(px, py, pz, sx, sy, sz, rb, rt)
    if ground:
        return math.inf
    tau = 0.0
    h = d / pieces
    for k in range(pieces):
        for q in range(gx.shape[0]):
            t = h * (k + 0.5 + 0.5 * gx[q])
            x, y, z = px + t * sx, py + t * sy, pz + t * sz
            e, _, _ = _ext(math.sqrt(x * x + y * y + z * z) - rb, dens, sig)
            tau += 0.5 * h * gw[q] * e
    return tau


@numba.njit(cache=False)
def _single(px, py, pz, ux, uy, uz, sx, sy, sz, rb, rt, dens, sig, g, grid, gx, gw, pieces):
    """L1 / E_sun seen from p looking along u (point sun), trapezoid on ``grid`` (fractions of the ray)."""
    d, _ = _ray_length(px, py, pz, ux, uy, uz, rb, rt)
    nu = ux * sx + uy * sy + uz * sz
    p_r = 3.0 / (16.0 * math.pi) * (1.0 + nu * nu)
    p_m = 3.0 / (8.0 * math.pi) * (1 - g * g) * (1 + nu * nu) / ((2 + g * g) * (1 + g * g - 2 * g * nu) ** 1.5)
    tau = 0.0
    acc = 0.0
    prev_e = 0.0
    prev_s = 0.0
    prev_t = 0.0
    for k in range(grid.shape[0]):
        t = d * grid[k]
        x, y, z = px + t * ux, py + t * uy, pz + t * uz
        e, sr, sm = _ext(math.sqrt(x * x + y * y + z * z) - rb, dens, sig)
        if k > 0:
            tau += 0.5 * (t - prev_t) * (e + prev_e)
        src = 0.0
        if sr + sm > 0.0:
            ts = _tau_sun(x, y, z, sx, sy, sz, rb, rt, dens, sig, gx, gw, pieces)
            if ts < 700.0:
                src = (sr * p_r + sm * p_m) * math.exp(-tau - ts)
        if k > 0:
            acc += 0.5 * (t - prev_t) * (src + prev_s)
        prev_e, prev_s, prev_t = e, src, t
    return acc


@numba.njit(cache=False, parallel=True)
def second_order(vx, vy, vz, sx, sy, sz, rb, rt, dens, sig, g, vt, vw, mus, muw, n_phi, grid, gx, gw, pieces):
    """(L2 / E_sun, L1 / E_sun) seen from (0, 0, rb) along the unit v; ``vt``, ``vw`` the view ray's nodes and
    weights [m], ``mus``, ``muw`` the zenith rule (cosines, weights summing to 2)."""
    n_v = vt.shape[0]
    contrib = np.zeros(n_v)
    for i in numba.prange(n_v):
        t = vt[i]
        px, py, pz = t * vx, t * vy, rb + t * vz
        r = math.sqrt(px * px + py * py + pz * pz)
        upx, upy, upz = px / r, py / r, pz / r
        # a local frame: e1 horizontal, e2 = up x e1
        ax, ay, az = (1.0, 0.0, 0.0)
        d = ax * upx + ay * upy + az * upz
        e1x, e1y, e1z = ax - d * upx, ay - d * upy, az - d * upz
        n1 = math.sqrt(e1x * e1x + e1y * e1y + e1z * e1z)
        e1x, e1y, e1z = e1x / n1, e1y / n1, e1z / n1
        e2x, e2y, e2z = upy * e1z - upz * e1y, upz * e1x - upx * e1z, upx * e1y - upy * e1x
        e, sr, sm = _ext(r - rb, dens, sig)
        j = 0.0
        for a in range(mus.shape[0]):
            m = mus[a]
            st = math.sqrt(max(1.0 - m * m, 0.0))
            for b in range(n_phi):
                ph = 2.0 * math.pi * (b + 0.5) / n_phi
                c, s = math.cos(ph), math.sin(ph)
                ux = m * upx + st * (c * e1x + s * e2x)
                uy = m * upy + st * (c * e1y + s * e2y)
                uz = m * upz + st * (c * e1z + s * e2z)
                l1 = _single(px, py, pz, ux, uy, uz, sx, sy, sz, rb, rt, dens, sig, g, grid, gx, gw, pieces)
                cw = ux * vx + uy * vy + uz * vz
                p_r = 3.0 / (16.0 * math.pi) * (1.0 + cw * cw)
                p_m = 3.0 / (8.0 * math.pi) * (1 - g * g) * (1 + cw * cw) / (
                    (2 + g * g) * (1 + g * g - 2 * g * cw) ** 1.5)
                j += muw[a] * (2.0 * math.pi / n_phi) * (sr * p_r + sm * p_m) * l1
        contrib[i] = j
    # transmittance from the observer to each view node: its own Gauss rule from 0 to t
    out = 0.0
    for i in range(n_v):
        t = vt[i]
        tau = 0.0
        for q in range(gx.shape[0]):
            for k in range(4):
                tt = t * (k + 0.5 + 0.5 * gx[q]) / 4.0
                x, y, z = tt * vx, tt * vy, rb + tt * vz
                ee, _, _ = _ext(math.sqrt(x * x + y * y + z * z) - rb, dens, sig)
                tau += 0.5 * t / 4.0 * gw[q] * ee
        out += vw[i] * math.exp(-tau) * contrib[i]
    l1 = _single(0.0, 0.0, rb, vx, vy, vz, sx, sy, sz, rb, rt, dens, sig, g, grid, gx, gw, pieces)
    return out, l1


def view_nodes(rb: float, rt: float, v: np.ndarray, n_pieces: int, per: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights [m] on pieces growing geometrically from 1 m to the top."""
    b = v[2] * rb
    d = -b + math.sqrt(b * b - rb * rb + rt * rt)
    edges = np.concatenate([[0.0], np.geomspace(1.0, d, n_pieces)])
    x, w = np.polynomial.legendre.leggauss(per)
    ts = [0.5 * (e1 - e0) * x + 0.5 * (e1 + e0) for e0, e1 in zip(edges[:-1], edges[1:], strict=True)]
    ws = [0.5 * (e1 - e0) * w for e0, e1 in zip(edges[:-1], edges[1:], strict=True)]
    return np.concatenate(ts), np.concatenate(ws)


def unit(elev_deg: float, az_deg: float) -> np.ndarray:
    e, a = math.radians(elev_deg), math.radians(az_deg)
    return np.array([math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e)])


def irradiance(params: AtmosphereParameters, wl: np.ndarray, sizes: dict | None, suns: list[float], dens: np.ndarray,
               sig: np.ndarray, grid: np.ndarray, gx: np.ndarray, gw: np.ndarray) -> None:
    """The first order's sky irradiance on the ground: the tables' against the hemisphere integral of ``L1``."""
    rb, rt = params.bottom_radius, params.top_radius
    g = params.aerosol_component.analytic_phase.g
    x, w = np.polynomial.legendre.leggauss(32)
    mus, muw = 0.5 * (x + 1.0), 0.5 * w
    n_phi = 64
    two = PrecomputedAtmosphere.compute(params, orders=2, wavelengths=wl, sizes=sizes, progress=False)
    e_sun = params.solar_irradiance_at(wl)[0]
    print("| sun [deg] | integral [W m^-2 nm^-1] | tables | tables / integral - 1 [%] |")
    print("|---|---|---|---|")
    for s_deg in suns:
        s = unit(s_deg, 0.0)
        e = 0.0
        for a in range(mus.size):
            st = math.sqrt(1.0 - mus[a] ** 2)
            for b in range(n_phi):
                ph = 2.0 * math.pi * (b + 0.5) / n_phi
                e += muw[a] * mus[a] * (2.0 * math.pi / n_phi) * _single(
                    0.0, 0.0, rb, st * math.sin(ph), st * math.cos(ph), mus[a], s[0], s[1], s[2], rb, rt, dens, sig,
                    g, grid, gx, gw, 16)
        e *= e_sun
        _, sky = two.ground_irradiance(np.array([[0.0, 0.0, rb]]), np.array([[0.0, 0.0, 1.0]]), s)
        print(f"| {s_deg:+g} | {e:.4e} | {sky[0, 0]:.4e} | {100 * (sky[0, 0] / e - 1):+.1f} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--atm", default="turbidity3", choices=sorted(ATMOSPHERES))
    ap.add_argument("--suns", default="-6")
    ap.add_argument("--wavelength", type=float, default=560.0)
    ap.add_argument("--n-mu", type=int, default=48, help="zenith nodes on the sphere (double Gauss)")
    ap.add_argument("--n-phi", type=int, default=48)
    ap.add_argument("--n-grid", type=int, default=160, help="points along each secondary ray")
    ap.add_argument("--views", default="", help="elev/az pairs, e.g. 15/135,5/180")
    ap.add_argument("--sizes", default="", help="table size overrides, e.g. scattering_mu_s=64")
    ap.add_argument("--irradiance", default="", help="sun elevations [deg]: the first-order irradiance instead")
    ap.add_argument("--sun-radius", type=float, default=1e-5,
                    help="the tables' sun angular radius [rad]; default 1e-5: a point sun like the integral's "
                         "(the parameters' default 0.004675 gives the tables a soft shadow the integral has not)")
    args = ap.parse_args()
    params = ATMOSPHERES[args.atm](ground_albedo=0.0, sun_angular_radius=args.sun_radius)
    analytic = params.aerosol_component.analytic_phase
    if analytic is None or analytic.kind != "cornette-shanks":
        raise SystemExit("the integral here writes out the Cornette-Shanks phase only")
    wl = np.array([args.wavelength])
    rb, rt = params.bottom_radius, params.top_radius
    h = np.arange(0.0, rt - rb + 2.0)
    dens = np.stack([params.rayleigh_density(h), params.aerosol_component.density(h), params.ozone_density(h)], -1)
    sig = np.array([params.rayleigh_scattering_at(wl)[0], params.mie_scattering_at(wl)[0],
                    params.mie_extinction_at(wl)[0], params.ozone_absorption_at(wl)[0]])
    x, w = np.polynomial.legendre.leggauss(args.n_mu // 2)
    mus = np.concatenate([0.5 * (x - 1.0), 0.5 * (x + 1.0)])
    muw = np.concatenate([0.5 * w, 0.5 * w])
    n_u = args.n_grid * 3 // 5
    grid = np.unique(np.concatenate([[0.0], np.linspace(0.0, 1.0, n_u), np.geomspace(1e-6, 1.0, args.n_grid - n_u)]))
    gx, gw = np.polynomial.legendre.leggauss(4)
    sizes = {k: int(v) for k, v in (kv.split("=") for kv in args.sizes.split(",") if kv)} or None
    views = [tuple(float(a) for a in p.split("/")) for p in args.views.split(",")] if args.views else VIEWS
    if args.irradiance:
        irradiance(params, wl, sizes, [float(a) for a in args.irradiance.split(",")], dens, sig, grid, gx, gw)
        return
    t0 = time.process_time()
    one = PrecomputedAtmosphere.compute(params, orders=1, wavelengths=wl, sizes=sizes, progress=False)
    two = PrecomputedAtmosphere.compute(params, orders=2, wavelengths=wl, sizes=sizes, progress=False)
    print(f"# {args.atm}, {args.wavelength:g} nm, ground albedo 0; sphere {args.n_mu} x {args.n_phi}, "
          f"{grid.size} points per secondary ray; tables {time.process_time() - t0:.0f} CPU-s")
    t2 = dict(two.tables)
    mult_only = PrecomputedAtmosphere(params, two.wavelengths, two.sizes, two.orders,
                                      {**t2, "single_rayleigh": np.zeros_like(t2["single_rayleigh"]),
                                       "single_mie": np.zeros_like(t2["single_mie"])})
    e_sun = params.solar_irradiance_at(wl)[0]
    g = analytic.g
    print("| sun [deg] | view elev/az [deg] | order 2: tables / integral - 1 [%] | integral [W m^-2 sr^-1 nm^-1] "
          "| single: tables / integral - 1 [%] | CPU-s |")
    print("|---|---|---|---|---|---|")
    for s_deg in (float(a) for a in args.suns.split(",")):
        s = unit(s_deg, 0.0)
        pos = np.array([0.0, 0.0, rb])
        for el, az in views:
            v = unit(el, az)
            vt, vw = view_nodes(rb, rt, v, 12, 4)
            c0 = time.process_time()
            l2, l1 = second_order(v[0], v[1], v[2], s[0], s[1], s[2], rb, rt, dens, sig, g, vt, vw, mus, muw,
                                  args.n_phi, grid, gx, gw, 16)
            cpu = time.process_time() - c0
            tab2 = float(mult_only.sky_radiance(pos, v[None], s)[0, 0])
            tab1 = float(one.sky_radiance(pos, v[None], s)[0, 0])
            l1 *= e_sun
            l2 *= e_sun
            s1 = f"{100 * (tab1 / l1 - 1):+.1f}" if l1 > 0 else "-"
            print(f"| {s_deg:+g} | {el:g}/{az:g} | {100 * (tab2 / l2 - 1):+.1f} | {l2:.3e} | {s1} | {cpu:.0f} |",
                  flush=True)


if __name__ == "__main__":
    main()
