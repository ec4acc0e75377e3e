"""CPU time of the table lookups with the observer in the cell of rows touching the ground (table format 16 reads
each row of that cell at its own mu coordinate: two mu cells, and the observer slices two gathers) and elsewhere.

Tables of the default sizes (32 x 128 x 32 x 8, 16 wavelengths) filled with a smooth synthetic field (the lookup's
cost does not depend on the values), Earth defaults; 2 x 10^5 random directions from 0, 10 m (the ground cell) and
1 km, sun 40 deg: the general 4D kernel (one position per ray, ``sky_radiance``), the observer slices
(``sky_xyz``, ``sky_luminance``: one position) and ``aerial_perspective`` (5 km paths). Prints the best CPU time
per call (time.process_time, single thread: NUMBA_NUM_THREADS=1 is set here) of --repeat calls, as ns per ray.
Run the trees to compare one after the other, alternated, with the load average stated:
PYTHONPATH=src python benchmarks/lookup_ground_cell_cost.py [--repeat N]
"""

from __future__ import annotations

import argparse
import math
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.precomputed.sizes import TableSizes  # noqa: E402
from skyscatter.precomputed.tables import PrecomputedAtmosphere  # noqa: E402


def synthetic(p, sizes, wl):
    s = sizes
    n_l = wl.size
    x = np.linspace(0.0, 1.0, n_l, dtype=np.float32)
    shape4 = (s.scattering_r, s.scattering_mu, s.scattering_mu_s, s.scattering_nu)
    grid = np.meshgrid(*[np.linspace(0.0, 1.0, n, dtype=np.float32) for n in shape4], indexing="ij")
    base = (1.0 + grid[0] + 0.5 * grid[1] + 2.0 * grid[2] + 0.3 * grid[3])[..., None] * (1.0 + x)
    tables = {
        "transmittance": np.broadcast_to(np.linspace(0.2, 1.0, s.transmittance_mu, dtype=np.float32)[None, :, None],
                                         (s.transmittance_r, s.transmittance_mu, n_l)).copy(),
        "irradiance": np.full((s.irradiance_r, s.irradiance_mu_s, n_l), 0.1, dtype=np.float32),
        "single_rayleigh": (1e-2 * base).astype(np.float32),
        "single_mie": (3e-3 * base).astype(np.float32),
        "multiple": (1e-3 * base).astype(np.float32),
    }
    return PrecomputedAtmosphere(p, wl, sizes, 4, tables)


def best(fn, repeat):
    fn()
    out = math.inf
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        out = min(out, time.process_time() - t0)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    p = AtmosphereParameters()
    atm = synthetic(p, TableSizes(), np.linspace(400.0, 700.0, 16))
    n = 200_000
    d = np.random.default_rng(1).normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    up = d.copy()
    up[:, 2] = np.abs(up[:, 2])
    ts = math.radians(40.0)
    sun = np.array([math.sin(ts), 0.0, math.cos(ts)])
    print(f"load average {os.getloadavg()[0]:.1f}")
    for h in (0.0, 10.0, 1000.0):
        pos = np.array([0.0, 0.0, p.bottom_radius + h])
        many = np.ascontiguousarray(np.broadcast_to(pos, d.shape))
        figures = {
            "4D sky_radiance, sphere": best(lambda m=many: atm.sky_radiance(m, d, sun), args.repeat),
            "observer sky_xyz, sphere": best(lambda q=pos: atm.sky_xyz(q, d, sun), args.repeat),
            "observer sky_luminance, upper": best(lambda q=pos: atm.sky_luminance(q, up, sun), args.repeat),
            "aerial_perspective 5 km, upper": best(lambda m=many: atm.aerial_perspective(m, m + 5e3 * up, sun),
                                                   args.repeat),
        }
        for name, t in figures.items():
            print(f"h {h:6.0f} m  {name:32s} {t * 1e9 / n:7.1f} ns/ray (CPU)")


if __name__ == "__main__":
    main()
