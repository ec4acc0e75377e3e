"""Shadow rules for the single scattering read between two azimuth texels from the Earth's shadow, on the
independent integrals' own texel values (docs/accuracy.md, "Low sun").

For an observer on the ground (Earth defaults), the sun at -6 and -3 deg, views 2, 5, 15 deg up at 45-110 deg from
the sun, 400 / 560 / 700 nm: the Rayleigh single-scattering integral of ``tests/precomputed_reference.py`` at the
query and at the two azimuth texels around it (8 texels, the default), combined by each rule, over the integral at
the query, minus 1 [%]. Rules: ``lin`` linear; ``geo2`` the rendering lookups' (each texel times the density ratio
at the exits from the geometric shadow, at most ``sampling.SHADOW_RATIO_MAX`` = 2); ``optN`` the same with the exits
from an "optical" shadow, a cylinder raised per wavelength to the tangent altitude where the grazing sunlight's
optical depth through the whole atmosphere (the reference's own optical depths: Rayleigh, aerosol and ozone) falls
to N (``c2``: ratio capped at 2, else uncapped); ``march`` each texel times the ratio of :func:`lit_march` (the
sunlit density integrated from the exit, 16 points) of the query's ray and the texel's, uncapped. The exits are
solved here (the cylinder's quadratic), the geometric one checked against ``geometry.shadow_exit_altitude``.

``python benchmarks/shadow_rule_low_sun.py`` (about 1 CPU-minute)
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from skyscatter.precomputed import AtmosphereParameters
from skyscatter.precomputed.geometry import lerp_index, scattering_nu_coord, scattering_nu_param, shadow_exit_altitude

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import precomputed_reference as ref  # noqa: E402  (the tests' independent integrals)

P = AtmosphereParameters()
RB, RT = P.bottom_radius, P.top_radius
WL = np.array([400.0, 560.0, 700.0])
H_RAYLEIGH = 8000.0  # [m], Bruneton & Neyret 2008, Eq. 1
N_NU = 8


def grazing_optical_depth(z: float) -> np.ndarray:
    """Optical depth (per wavelength) of the sunlight along the whole ray tangent to the sphere at altitude z [m]."""
    r = RB + z
    d, _ = ref.ray_end(r, 0.0, P)
    return 2.0 * ref.optical_depth(np.array([r]), np.array([0.0]), np.array([d]), P, WL, n=400)[0]


def tangent_altitude(target: float) -> np.ndarray:
    """Per wavelength, the tangent altitude [m] where :func:`grazing_optical_depth` falls to ``target`` (bisection)."""
    out = []
    for k in range(WL.size):
        lo, hi = 0.0, 60e3
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if grazing_optical_depth(mid)[k] > target else (lo, mid)
        out.append(lo)
    return np.array(out)


def exit_distance(r: float, mu: float, mu_s: float, nu: float, rc: float) -> float:
    """Distance [m] along the ray from radius r [m] (zenith cosine mu; the sun at mu_s, nu) to where it leaves the
    half cylinder of radius rc [m] behind the planet; 0 if it starts outside."""
    xs, xv = r * mu_s, r * mu
    a = 1.0 - nu * nu
    b = 2.0 * (xv - xs * nu)
    c = r * r - xs * xs - rc * rc
    if xs >= 0.0 or c >= 0.0:
        return 0.0
    t = (-b + math.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)
    return min(t, -xs / nu) if nu > 0.0 else t


def exit_altitude(r: float, mu: float, mu_s: float, nu: float, rc: float) -> float:
    """Altitude [m] above the ground of :func:`exit_distance`'s point."""
    t = exit_distance(r, mu, mu_s, nu, rc)
    return math.sqrt(t * t + 2.0 * r * mu * t + r * r) - RB


def lit_march(r: float, mu: float, mu_s: float, nu: float, pieces: int = 4, per_piece: int = 4) -> np.ndarray:
    """``integral rho_R(y) T_sun(y) dy`` from the ray's exit from the geometric shadow to its end, per wavelength
    [m]: ``pieces`` Gauss-Legendre pieces growing geometrically from the exit (``per_piece`` nodes each), the sun's
    optical depth the reference's; no view transmittance (nearly common to the texels of a cell). What a rule that
    follows the sunlight beyond the exit would evaluate per ray (a short march instead of one density)."""
    t0 = exit_distance(r, mu, mu_s, nu, RB)
    t1, _ = ref.ray_end(r, mu, P)
    edges = t0 + (t1 - t0) * np.concatenate([[0.0], np.geomspace(1e-3, 1.0, pieces)])
    x, wq = np.polynomial.legendre.leggauss(per_piece)
    total = np.zeros(WL.size)
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        t = 0.5 * (b - a) * x + 0.5 * (b + a)
        ry = np.sqrt(t * t + 2 * r * mu * t + r * r)
        ms = np.clip((r * mu_s + t * nu) / ry, -1.0, 1.0)
        ends = [ref.ray_end(p, q, P) for p, q in zip(ry, ms, strict=True)]
        d = np.array([e[0] for e in ends])
        lit = ~np.array([e[1] for e in ends])
        tau = ref.optical_depth(ry, ms, d, P, WL, n=80)
        f = P.rayleigh_density(ry - RB)[:, None] * np.exp(-tau) * lit[:, None]
        total += 0.5 * (b - a) * (wq[:, None] * f).sum(axis=0)
    return total


def main() -> None:
    raised = {1.0: tangent_altitude(1.0), 3.0: tangent_altitude(3.0)}
    print(f"# tangent altitude where the grazing optical depth is 1: {np.round(raised[1.0] / 1e3, 1)} km, 3: "
          f"{np.round(raised[3.0] / 1e3, 1)} km (400/560/700 nm)")
    rules = (("geo2", np.zeros(3), 2.0), ("opt1c2", raised[1.0], 2.0), ("opt1", raised[1.0], math.inf),
             ("opt3c2", raised[3.0], 2.0))
    print("| sun | view/az | " + " | ".join(["lin"] + [r[0] for r in rules] + ["march"]) + " |")
    print("|---" * (4 + len(rules)) + "|")
    for sun in (-6.0, -3.0):
        mu_s = math.sin(math.radians(sun))
        for elev in (2.0, 5.0, 15.0):
            for az in (45.0, 70.0, 90.0, 110.0):
                mu = math.sin(math.radians(elev))
                s = math.sqrt((1 - mu * mu) * (1 - mu_s * mu_s))
                nu = mu * mu_s + s * math.cos(math.radians(az))
                i_n, w = lerp_index(scattering_nu_coord(mu, mu_s, nu, N_NU), 0, N_NU - 1)
                nus = (scattering_nu_param(i_n, mu, mu_s, N_NU), nu, scattering_nu_param(i_n + 1, mu, mu_s, N_NU))
                val = [ref.single_scattering_integrals(RB, mu, mu_s, n, P, WL, n=960, pieces=40, first=1e-5)[0]
                       for n in nus]
                if np.any(val[1] <= 0.0):
                    continue  # the query's ray never leaves the shadow
                geo = shadow_exit_altitude(RB, mu, mu_s, nu, RB, RT)
                assert geo >= RT - RB - 1.0 or abs(geo - exit_altitude(RB, mu, mu_s, nu, RB)) < 5.0
                cells = [((1 - w) * val[0] + w * val[2]) / val[1] - 1.0]
                for _, dz, cap in rules:
                    e = np.empty(WL.size)
                    for k in range(WL.size):
                        h = [exit_altitude(RB, mu, mu_s, n, RB + dz[k]) for n in nus]
                        f0 = min(math.exp((h[0] - h[1]) / H_RAYLEIGH), cap)
                        f1 = min(math.exp((h[2] - h[1]) / H_RAYLEIGH), cap)
                        e[k] = ((1 - w) * f0 * val[0][k] + w * f1 * val[2][k]) / val[1][k] - 1.0
                    cells.append(e)
                m = [lit_march(RB, mu, mu_s, n) for n in nus]
                # a texel whose ray never leaves the shadow holds 0 and keeps it
                f = [np.divide(m[1], m[i], out=np.zeros(WL.size), where=m[i] > 0.0) for i in (0, 2)]
                cells.append(((1 - w) * val[0] * f[0] + w * val[2] * f[1]) / val[1] - 1.0)
                print(f"| {sun:+.0f} | {elev:.0f}/{az:.0f} | "
                      + " | ".join("/".join(f"{100 * x:+.0f}" for x in c) for c in cells) + " |", flush=True)


if __name__ == "__main__":
    main()
