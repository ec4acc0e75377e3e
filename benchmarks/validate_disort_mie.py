"""Precomputed tables with a tabulated Mie aerosol phase vs DISORT (issue 20, "Checks").

The OPAC aerosol types continental-average and maritime-clean (Hess et al. 1998; Mie optics of their components,
:mod:`skyscatter.atmosphere.aerosol_types`) scaled to an aerosol optical depth of 0.2 or 0.5 at 550 nm, over ground
albedo 0.1, sun zenith 30 and 70 deg; radiance at the ground in the solar principal plane, view zenith 0-70 deg.
The last column is the diffuse horizontal irradiance against DISORT's diffuse flux. ``--types`` also takes single
OPAC components (``waso``, ``sscm``, ...; with continental-average's profile).
DISORT (disortpp, plane-parallel, tests/disort_reference.py) gets the same layers and 400 Legendre moments of the same
phase table (``PhaseTable.legendre_moments``, exact for the table), 32 streams, its own delta-M and its intensity
correction with the phase table itself (Buras, Dowling & Emde 2011; tests/disort_reference.py). The tables handle the
diffraction peak by computing the orders in the delta-M scaled medium
(:meth:`skyscatter.precomputed.compute.Medium.delta_m_scaled`); ``--no-delta-m`` sets the forward fraction to 0 (the
full table as the scaled phase: on the density quadrature, normalised per view) to measure what
the scaling brings.

    PYTHONPATH=src python benchmarks/validate_disort_mie.py [--default-sizes] [--no-delta-m]
"""

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from disort_reference import disort_diffuse_irradiance, disort_radiance  # noqa: E402
from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.atmosphere.aerosol_types import OPAC_COMPONENTS, OpacAerosol  # noqa: E402
from skyscatter.precomputed import PrecomputedAtmosphere  # noqa: E402
from skyscatter.precomputed import compute as compute_module  # noqa: E402
from test_precomputed_disort import SIDES, SIZES, VIEW_ZENITH, sphericity_allowance  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--default-sizes", action="store_true")
    ap.add_argument("--no-delta-m", action="store_true")
    ap.add_argument("--types", default="continental-average,maritime-clean",
                    help="OPAC types or single components (waso, sscm, ...), comma-separated")
    ap.add_argument("--aod", default="0.2,0.5")
    args = ap.parse_args()
    sizes = None if args.default_sizes else SIZES
    if args.no_delta_m:
        original = compute_module.aerosol_phase_arrays

        def no_delta(params, wavelengths, sizes=None):
            kind, g, (mu, full, _trunc, f) = original(params, wavelengths, sizes)
            even = np.linspace(-1.0, 1.0, compute_module.TRUNCATED_PHASE_NODES)
            whole = np.ascontiguousarray(params.aerosol_phase_table(wavelengths).evaluate(even).T)
            return kind, g, (mu, full, whole, np.zeros_like(f))

        compute_module.aerosol_phase_arrays = no_delta
    print("| type | AOD | sun zenith | side | error at view zenith 0, 10, ..., 70 deg [%] | max | allowed at 70 "
          "| DHI [%] |")
    print("|---|---|---|---|---|---|---|---|")
    for name in args.types.split(","):
        for aod in (float(a) for a in args.aod.split(",")):
            if name in OPAC_COMPONENTS:  # one component alone, with continental-average's profile
                p = AtmosphereParameters(ozone_column=0.0, ground_albedo=0.1, solar_irradiance=1.0)
                p = p.replace(aerosol=OpacAerosol.mixture(((name, aod),), column_height=p.thickness))
            else:
                p = AtmosphereParameters.with_aerosol_type(name, aod, 50.0, ozone_column=0.0, ground_albedo=0.1,
                                                           solar_irradiance=1.0)
            atm = PrecomputedAtmosphere.compute(p, orders=6, wavelengths=[550.0], sizes=sizes, progress=False)
            for sz in (30.0, 70.0):
                ts = math.radians(sz)
                ref = disort_radiance(p, 550.0, ts, VIEW_ZENITH, SIDES, n_layers=100, n_streams=32, n_moments=400)
                tol = 0.03 + sphericity_allowance(p, ts, VIEW_ZENITH)
                sun = [math.sin(ts), 0.0, math.cos(ts)]
                dhi = atm.ground_irradiance([0.0, 0.0, p.bottom_radius], [0.0, 0.0, 1.0], sun)[1][0]
                dhi_err = 100 * (dhi / disort_diffuse_irradiance(p, 550.0, ts) - 1)
                for j, (side, label) in enumerate(((1.0, "towards sun"), (-1.0, "away"))):
                    d = np.stack([side * np.sin(VIEW_ZENITH), 0 * VIEW_ZENITH, np.cos(VIEW_ZENITH)], axis=-1)
                    ours = atm.sky_radiance([0.0, 0.0, p.bottom_radius], d, sun)[:, 0]
                    err = 100 * (ours / ref[:, j] - 1)
                    print(f"| {name} | {aod} | {sz:.0f} | {label} | {' '.join(f'{e:+.1f}' for e in err)} | "
                          f"{np.abs(err).max():.1f} | {100 * tol[-1]:.1f} | {dhi_err:+.1f} |", flush=True)


if __name__ == "__main__":
    main()
