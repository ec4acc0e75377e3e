"""Sky pattern and colour of the OPAC aerosol types against the analytic aerosol phase functions (issue 20).

Every air has the same aerosol optical depth at 550 nm (0.2) over ground albedo 0.1, sun 40 deg high; the analytic
airs take the Angstrom exponent 1.3 of the default description. For each air: its aerosol's single-scattering
albedo and asymmetry g at 550 nm, the Angstrom exponent 440/870 nm; the precomputed sky (tables of 3 wavelengths,
450/550/650 nm, 6 orders, the sizes of benchmarks/validate_disort_mie.py) on an 81-direction scan (9 elevations
x 9 azimuths); the RMS difference of its pattern (radiance at 550 nm normalised by its scan mean) from the
default air's (Cornette-Shanks g = 0.8), its zenith radiance at 550 nm relative to that air's, and the colour
ratio L(450) / L(550) at the zenith and 10 deg from the sun.

    PYTHONPATH=src python benchmarks/compare_aerosol_presets.py
"""

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.atmosphere.aerosol_types import AEROSOL_TYPES  # noqa: E402
from skyscatter.conventions import direction_from_angles  # noqa: E402
from skyscatter.precomputed import PrecomputedAtmosphere  # noqa: E402
from test_precomputed_disort import SIZES  # noqa: E402

WL = np.array([450.0, 550.0, 650.0])
SUN = (math.radians(50.0), math.radians(180.0))


def _scan():
    zz, aa = np.meshgrid(np.radians(np.linspace(0.0, 80.0, 9)), np.radians(np.arange(0.0, 360.0, 40.0)))
    z, a = zz.ravel(), aa.ravel()
    # the zenith and a direction 10 deg from the sun, towards the zenith
    z = np.concatenate([z, [0.0, SUN[0] - math.radians(10.0)]])
    a = np.concatenate([a, [0.0, SUN[1]]])
    return direction_from_angles(z, a)


def main() -> None:
    airs = {"cornette-shanks g=0.8 (default)": AtmosphereParameters.from_aerosol_optical_depth(0.2, 1.3),
            "cornette-shanks g=0.7": AtmosphereParameters.from_aerosol_optical_depth(0.2, 1.3, mie_phase_g=0.7),
            "henyey-greenstein g=0.7": AtmosphereParameters.from_aerosol_optical_depth(
                0.2, 1.3, mie_phase_g=0.7, mie_phase_function="henyey-greenstein")}
    for name in AEROSOL_TYPES:
        airs[name] = AtmosphereParameters.with_aerosol_type(name, 0.2, 50.0)
    dirs = _scan()
    pos = np.array([0.0, 0.0, 6_360_000.0])
    sun = direction_from_angles(*SUN)
    ref = None
    print("| air | albedo 550 | g 550 | Angstrom 440/870 | pattern RMS vs default [%] | zenith L vs default | "
          "L450/L550 zenith | L450/L550 10 deg from sun |")
    print("|---|---|---|---|---|---|---|---|")
    for name, p in airs.items():
        comp = p.aerosol_component
        ssa = float(comp.single_scattering_albedo_at([550.0])[0])
        g = float(p.aerosol_phase_table([550.0]).asymmetry[0])
        e = comp.extinction_at([440.0, 870.0])
        alpha = -math.log(e[0] / e[1]) / math.log(440.0 / 870.0)
        atm = PrecomputedAtmosphere.compute(p.replace(ground_albedo=0.1), orders=6, wavelengths=WL, sizes=SIZES,
                                            progress=False)
        rad = atm.sky_radiance(pos, dirs, sun)
        scan = rad[:81, 1] / rad[:81, 1].mean()
        if ref is None:
            ref = (scan, rad[81, 1])
        rms = 100 * math.sqrt(np.mean((scan / ref[0] - 1) ** 2))
        print(f"| {name} | {ssa:.3f} | {g:.3f} | {alpha:.2f} | {rms:.1f} | {rad[81, 1] / ref[1]:.3f} | "
              f"{rad[81, 0] / rad[81, 1]:.3f} | {rad[82, 0] / rad[82, 1]:.3f} |", flush=True)


if __name__ == "__main__":
    main()
