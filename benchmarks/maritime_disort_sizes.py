"""Maritime-clean at optical depth 0.5, sun at 70 deg, against DISORT for table sizes varied one at a time: which
resolution of the precomputed tables the error away from the sun comes from (docs/aerosols.md, "Not done").

OPAC maritime-clean (Hess et al. 1998) at 550 nm, ozone-free, albedo 0.1, 6 orders; radiance at the ground in the
solar principal plane, view zenith 0-70 deg, against DISORT (tests/disort_reference.py: 100 layers, 32 streams,
400 moments, its intensity correction with the phase table), as benchmarks/validate_disort_mie.py. Prints tables /
DISORT - 1 [%] towards and away from the sun, and the precompute's CPU time, per variant.

Variants are named on the command line: ``test`` (the DISORT tests' sizes, tests/disort_reference.py
TABLE_SIZES), ``default`` (the default sizes), each optionally followed by ``:`` and a JSON object of size
fields to change, e.g. ``'test:{"scattering_r": 32}'``. ``DMS=1`` in the environment truncates the phase at
1 (not 2) delta-M stream per density sample (:data:`skyscatter.precomputed.compute.DELTA_M_STREAMS_PER_SAMPLE`).
``SZ`` sets the sun zenith [deg] (70).

    PYTHONPATH=src python benchmarks/maritime_disort_sizes.py test 'test:{"scattering_r": 32}' default
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from disort_reference import TABLE_SIZES, disort_radiance  # noqa: E402
from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.precomputed import PrecomputedAtmosphere  # noqa: E402
from skyscatter.precomputed import compute as compute_module  # noqa: E402
from skyscatter.precomputed.sizes import TableSizes  # noqa: E402
from test_precomputed_disort import SIDES, VIEW_ZENITH  # noqa: E402


def main() -> None:
    if os.environ.get("DMS"):
        compute_module.DELTA_M_STREAMS_PER_SAMPLE = int(os.environ["DMS"])
    p = AtmosphereParameters.with_aerosol_type("maritime-clean", 0.5, 50.0, ozone_column=0.0, ground_albedo=0.1,
                                               solar_irradiance=1.0)
    ts = math.radians(float(os.environ.get("SZ", "70")))
    sun = [math.sin(ts), 0.0, math.cos(ts)]
    ref = disort_radiance(p, 550.0, ts, VIEW_ZENITH, SIDES, n_layers=100, n_streams=32, n_moments=400)
    default = {k: getattr(TableSizes(), k) for k in TABLE_SIZES}
    for name in sys.argv[1:] or ["test", "default"]:
        base, _, extra = name.partition(":")
        sizes = dict(default if base == "default" else TABLE_SIZES)
        if extra:
            sizes.update(json.loads(extra))
        t = time.process_time()
        atm = PrecomputedAtmosphere.compute(p, orders=6, wavelengths=[550.0], sizes=sizes, progress=False)
        cpu = time.process_time() - t
        out = []
        for j, side in enumerate((1.0, -1.0)):
            d = np.stack([side * np.sin(VIEW_ZENITH), 0 * VIEW_ZENITH, np.cos(VIEW_ZENITH)], axis=-1)
            ours = atm.sky_radiance([0.0, 0.0, p.bottom_radius], d, sun)[:, 0]
            out.append(" ".join(f"{e:+.2f}" for e in 100 * (ours / ref[:, j] - 1)))
        print(f"{name}: precompute CPU {cpu:.1f} s; towards {out[0]} | away {out[1]}", flush=True)


if __name__ == "__main__":
    main()
