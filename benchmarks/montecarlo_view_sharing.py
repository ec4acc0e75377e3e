"""Would one walk serve every view? The weight of sharing a walk among the views of a horizontally uniform layer.

In a plane-parallel layer a backward path's walk after its first vertex depends on the view only through that
vertex's altitude and the direction it leaves in, so one walk could serve all N views: draw a view j, its first
vertex and a direction w from its phase function, and weight view k's estimate by its own density over the mixture
of all views' (one-sample MIS, [Veach1997] Sec. 9.2.4). The direction part of that weight is ``P_k(w) / p_mix(w)``
with ``p_mix = mean_j P_j``; its second moment under the mixture, ``E_mix[(P_k / p_mix)^2] = E_{P_k}[P_k / p_mix]``
(1 for a view's own paths), is the factor by which the shared estimate's variance grows before anything else. This
script computes it for the issue's overcast (Mie droplets r_e 10 um, the cloud's phase table) over the 200
equal-area views of ``bench_montecarlo.py --overcast``, for the full phase function and for the rest without the
forward peak (``driver.forward_peak`` at ``PEAK_ANGLE``), by Monte Carlo over ``w ~ P_k`` (20000 directions per
view, numpy, seed 0). Usage: ``python benchmarks/montecarlo_view_sharing.py [--wavelength 550]``.
"""

from __future__ import annotations

import argparse

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.atmosphere.clouds import CloudLayer
from skyscatter.montecarlo.dataset import equal_area_directions
from skyscatter.montecarlo.driver import PEAK_ANGLE, forward_peak, prepare_medium


def second_moment(phase, dirs: np.ndarray, k: int, rng: np.random.Generator, n: int = 20000) -> float:
    """``E_{w ~ P_k}[P_k(w) / mean_j P_j(w)]`` for view ``k`` of ``dirs``; ``phase(mu)`` [sr^-1]."""
    grid = np.linspace(-1.0, 1.0, 200001)
    cdf = np.cumsum(phase(grid))
    cdf /= cdf[-1]
    mu = np.interp(rng.random(n), cdf, grid)
    phi = 2.0 * np.pi * rng.random(n)
    d = dirs[k]
    e1 = np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(d, e1)
    s = np.sqrt(1.0 - mu**2)
    w = mu[:, None] * d + (s * np.cos(phi))[:, None] * e1 + (s * np.sin(phi))[:, None] * e2
    mix = phase(np.clip(w @ dirs.T, -1.0, 1.0)).mean(axis=1)
    return float(np.mean(phase(mu) / mix))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--wavelength", type=float, default=550.0, help="nm")
    args = ap.parse_args()
    atm = AtmosphereParameters(particles=(CloudLayer(1000.0, 1500.0, 15.0, effective_radius=10e-6),))
    m = prepare_medium(atm, np.array([args.wavelength]))
    table = m.tval[m.lobe_tab[m.peak_lobe]]  # the cloud's table, (1, m)
    tmu, tval = m.tmu, table[0]
    peak, _, frac = forward_peak(tmu, table, PEAK_ANGLE)
    rest = (tval - frac[0] * peak[0]) / (1.0 - frac[0])
    dirs = equal_area_directions(200)
    views = [0, 50, 100, 150, 199]
    rng = np.random.default_rng(0)
    print(f"{args.wavelength:.0f} nm, 200 views, views {views} (zenith to horizon); peak fraction {frac[0]:.3f}")
    for name, vals in (("full phase function", tval), (f"without the forward peak ({np.degrees(PEAK_ANGLE):.0f} deg)",
                                                        rest)):
        def phase(mu, vals=vals):
            return np.interp(mu, tmu, vals)
        moments = [second_moment(phase, dirs, k, rng) for k in views]
        print(f"  {name}: E[(P_k / p_mix)^2] = {', '.join(f'{v:.1f}' for v in moments)}")


if __name__ == "__main__":
    main()
