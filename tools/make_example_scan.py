"""Write docs/examples/sky_scan.csv: a synthetic sky scan for the README's fit-atmosphere example.

81 directions (9 elevations 10-85 deg x 9 azimuths), radiance at 440, 550 and 670 nm of a known air (aerosol
optical depth 0.25 at 550 nm, Angstrom exponent 1.3, Cornette-Shanks g 0.7, ground albedo 0.2; sun 50 deg high in
the south) from precomputed tables of larger sizes and 6 orders, with 2 % log-normal noise (seed 1).

    PYTHONPATH=src python tools/make_example_scan.py
"""

import math
from pathlib import Path

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.conventions import direction_from_angles
from skyscatter.fit.atmosphere import FIT_SIZES
from skyscatter.precomputed import PrecomputedAtmosphere


def main() -> None:
    air = AtmosphereParameters.from_aerosol_optical_depth(0.25, 1.3, mie_phase_g=0.7, ground_albedo=0.2)
    wl = np.array([440.0, 550.0, 670.0])
    el, az = np.meshgrid(np.linspace(10.0, 85.0, 9), np.arange(0.0, 360.0, 40.0))
    el, az = el.ravel(), az.ravel()
    sun_el, sun_az = 50.0, 180.0
    atm = PrecomputedAtmosphere.compute(air, orders=6, wavelengths=wl, progress=False,
                                        sizes=dict(FIT_SIZES, scattering_r=16, scattering_mu=64))
    rad = atm.sky_radiance(np.array([0.0, 0.0, air.bottom_radius]),
                           direction_from_angles(np.radians(90.0 - el), np.radians(az)),
                           direction_from_angles(math.radians(90.0 - sun_el), math.radians(sun_az)))
    rad *= np.exp(0.02 * np.random.default_rng(1).standard_normal(rad.shape))
    lines = ["# Synthetic sky scan (tools/make_example_scan.py): aerosol optical depth 0.25, Angstrom 1.3, g 0.7,",
             "# ground albedo 0.2, sun 50 deg high at azimuth 180 deg; radiance [W m^-2 sr^-1 nm^-1], 2 % noise.",
             "kind,sun_elevation_deg,sun_azimuth_deg,azimuth_deg,elevation_deg,wavelength_nm,value"]
    for k, w in enumerate(wl):
        for i in range(el.size):
            lines.append(f"radiance,{sun_el:g},{sun_az:g},{az[i]:g},{el[i]:g},{w:g},{rad[i, k]:.6e}")
    out = Path(__file__).resolve().parents[1] / "docs" / "examples" / "sky_scan.csv"
    out.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
