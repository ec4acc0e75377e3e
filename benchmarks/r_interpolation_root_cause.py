"""Why the aerial perspective's single scattering from 10 m is +0.86 % (tests/test_precomputed_mie.py).

For the geometries of ``test_aerial_perspective_reads_the_phase_table`` (camera 10 m above the ground, sun at
30 deg, continental-average Mie aerosol, one order, default sizes), prints at 450 and 650 nm, against the
independent integral of tests/precomputed_reference.py [%]:

* ``S(10 m)``: the table's lookup at 10 m;
* ``S(0)``, ``S(62.5 m)``: the lookups at the two rows of the radius cell (the first row above the ground of the
  default 32 sits at rho = H / 31, 62.5 m), in the same direction (the same ``mu``);
* those two rows interpolated with the weight linear in rho (0.40 at 10 m) and linear in the height (0.16);
* the integral's own change from 0 to 62.5 m;

then the aerial perspective's inscatter and transmittance of the test's six paths against ``S(camera) - T S(point)``
of the same integral (the test's bound: 1 %, 0.5 %).

Run: PYTHONPATH=src:tests python benchmarks/r_interpolation_root_cause.py
"""

from __future__ import annotations

import math
import sys

import numpy as np

sys.path.insert(0, "tests")
from precomputed_reference import optical_depth, single_scattering  # noqa: E402
from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.precomputed import PrecomputedAtmosphere  # noqa: E402

WL = np.array([450.0, 650.0])


def main():
    p = AtmosphereParameters.with_aerosol_type("continental-average", 0.2, 50.0, ozone_column=0.0,
                                               solar_irradiance=1.0, ground_albedo=0.1)
    atm = PrecomputedAtmosphere.compute(p, orders=1, wavelengths=WL, progress=False)
    n_r = atm.single_rayleigh.shape[0] if hasattr(atm, "single_rayleigh") else 32
    big_h = math.sqrt(p.top_radius ** 2 - p.bottom_radius ** 2)
    rho1 = big_h / (n_r - 1)
    h1 = math.sqrt(rho1 ** 2 + p.bottom_radius ** 2) - p.bottom_radius
    h = 10.0
    w_rho = math.sqrt((p.bottom_radius + h) ** 2 - p.bottom_radius ** 2) / rho1
    w_h = h / h1
    print(f"first row above the ground: {h1:.2f} m; weight of that row at {h} m: linear in rho {w_rho:.3f}, "
          f"linear in height {w_h:.3f}")
    ts = math.radians(30.0)
    sun = np.array([math.sin(ts), 0.0, math.cos(ts)])
    for el, az in ((10, 0), (20, 180), (30, 90), (15, 20), (5, 180)):
        e, a = math.radians(el), math.radians(az)
        d = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
        vals, refs = {}, {}
        for hh in (0.0, h, h1):
            r = p.bottom_radius + hh
            vals[hh] = np.ravel(atm.sky_radiance([0.0, 0.0, r], d, sun, include_ground=False))
            refs[hh] = np.ravel(single_scattering(r, float(d[2]), math.cos(ts), float(d @ sun), p, WL))
        ref = refs[h]

        def pct(x, ref=ref):
            return " ".join(f"{v:+6.2f}" for v in 100 * (x / ref - 1.0))

        print(f"el {el:2d} az {az:3d}: S(10 m) {pct(vals[h])} | rows at their own height "
              f"{' '.join(f'{v:+6.2f}' for v in 100 * (vals[0.0] / refs[0.0] - 1))} / "
              f"{' '.join(f'{v:+6.2f}' for v in 100 * (vals[h1] / refs[h1] - 1))} | rows in rho "
              f"{pct((1 - w_rho) * vals[0.0] + w_rho * vals[h1])} | rows in height "
              f"{pct((1 - w_h) * vals[0.0] + w_h * vals[h1])} | integral 0 -> {h1:.1f} m "
              f"{' '.join(f'{v:+5.2f}' for v in 100 * (refs[h1] / refs[0.0] - 1))} %", flush=True)

    cam = np.array([0.0, 0.0, p.bottom_radius + h])
    worst_in, worst_t = np.zeros(2), np.zeros(2)
    for el, az, dist in ((10, 0, 5e3), (10, 0, 20e3), (20, 180, 10e3), (30, 90, 30e3), (15, 20, 8e3), (5, 180, 15e3)):
        e, a = math.radians(el), math.radians(az)
        d = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
        pt = cam + dist * d
        r0, r1 = float(np.linalg.norm(cam)), float(np.linalg.norm(pt))
        nu = float(d @ sun)
        ss0 = single_scattering(r0, float(cam @ d) / r0, float(cam @ sun) / r0, nu, p, WL)
        ss1 = single_scattering(r1, float(pt @ d) / r1, float(pt @ sun) / r1, nu, p, WL)
        tr = np.exp(-optical_depth(np.array([r0]), np.array([float(cam @ d) / r0]), np.array([dist]), p, WL))[0]
        t, inscatter = atm.aerial_perspective(cam, pt, sun)
        e_in = 100 * (np.ravel(inscatter) / (ss0 - tr * ss1) - 1)
        e_t = 100 * (np.ravel(t) / tr - 1)
        worst_in = np.maximum(worst_in, np.abs(e_in))
        worst_t = np.maximum(worst_t, np.abs(e_t))
        print(f"aerial el {el:2d} az {az:3d} {dist / 1e3:4.0f} km: inscatter {' '.join(f'{v:+6.2f}' for v in e_in)} "
              f"transmittance {' '.join(f'{v:+6.2f}' for v in e_t)} %")
    print(f"aerial worst |err| at {WL} nm: inscatter {np.round(worst_in, 2)} %, transmittance {np.round(worst_t, 2)} %")


if __name__ == "__main__":
    main()
