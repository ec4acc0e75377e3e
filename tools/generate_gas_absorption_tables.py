# ruff: noqa: E501  (the data files' header lines are written as they appear in the files)
"""Write the data files of the broadband clear-sky transmittance (skyscatter.atmosphere.gas_absorption).

1. ``bird_riordan1986_gas_absorption.csv``: the water vapour, ozone and uniformly mixed gas absorption
   coefficients of Bird & Riordan (1986), "Simple solar spectral model for direct and diffuse irradiance on
   horizontal and tilted planes at the Earth's surface for cloudless atmospheres", J. Climate Appl. Meteor.
   25(1), 87-97, doi:10.1175/1520-0450(1986)025<0087:SSSMFD>2.0.CO;2 (their Table 1, after Leckner 1978), at
   their 122 wavelengths 300-4000 nm. Read from the copy pvlib-python distributes (pvlib/spectrum/spectrl2.py,
   BSD 3-clause); the numbers are the paper's.
2. ``solar_spectrum_astm_g173_nir.csv``: the ASTM G173-03 extraterrestrial spectrum above 1100 nm (the part
   the medium's ``solar_spectrum_astm_g173.csv`` leaves out), from pvlib/data/ASTMG173.csv, native sampling.

Usage: ``python tools/generate_gas_absorption_tables.py`` (needs pvlib).
"""

from __future__ import annotations

import csv
import importlib
from pathlib import Path

import numpy as np
import pvlib

s2 = importlib.import_module("pvlib.spectrum.spectrl2")

DATA = Path(__file__).resolve().parents[1] / "src" / "skyscatter" / "data"


def main() -> None:
    c = s2._SPECTRL2_COEFFS  # data table (Bird & Riordan 1986, Table 1), not code
    with open(DATA / "bird_riordan1986_gas_absorption.csv", "w", encoding="utf-8") as fh:
        fh.write(
            "# Absorption coefficients of water vapour, ozone and the uniformly mixed gases (O2, CO2) at 122 wavelengths.\n"
            "# Source: R. E. Bird & C. Riordan (1986), 'Simple solar spectral model for direct and diffuse irradiance on\n"
            "# horizontal and tilted planes at the Earth's surface for cloudless atmospheres', J. Climate Appl. Meteor.\n"
            "# 25(1), 87-97, doi:10.1175/1520-0450(1986)025<0087:SSSMFD>2.0.CO;2, Table 1 (after Leckner 1978).\n"
            "# Transcribed from the copy distributed with pvlib-python (pvlib/spectrum/spectrl2.py, BSD-3-Clause) by\n"
            "# tools/generate_gas_absorption_tables.py.\n"
            "# Columns: wavelength [nm]; water vapour a_w [cm^-1] (Eq. 2-8, precipitable water in cm); ozone a_o [cm^-1]\n"
            "# (Eq. 2-9, ozone column in atm-cm); uniformly mixed gases a_u [km^-1] (Eq. 2-11).\n"
            "wavelength_nm,water_vapour_cm-1,ozone_cm-1,mixed_gas_km-1\n"
        )
        for row in c:
            fh.write(f"{row['wavelength']:g},{row['water_vapor_absorption']:g},{row['ozone_absorption']:g},"
                     f"{row['mixed_absorption']:g}\n")
    src = Path(pvlib.__file__).parent / "data" / "ASTMG173.csv"
    rows = list(csv.reader(src.read_text().splitlines()[2:]))
    wl = np.array([float(r[0]) for r in rows])
    etr = np.array([r[1] for r in rows])
    keep = wl > 1100.0
    with open(DATA / "solar_spectrum_astm_g173_nir.csv", "w", encoding="utf-8") as fh:
        fh.write(
            "# Extraterrestrial solar spectral irradiance, ASTM G173-03 reference spectra (ETR column), above 1100 nm.\n"
            "# Source: ASTM G173-03(2012), 'Standard Tables for Reference Solar Spectral Irradiances: Direct Normal and\n"
            "# Hemispherical on 37 deg Tilted Surface', derived from SMARTS v2.9.2 (C. A. Gueymard, Solar Energy 76 (2004)\n"
            "# 423-453). Transcribed from the copy distributed with pvlib-python (pvlib/data/ASTMG173.csv), 1100-4000 nm\n"
            "# (the 280-1100 nm part is solar_spectrum_astm_g173.csv), native sampling, by\n"
            "# tools/generate_gas_absorption_tables.py. Mean Sun-Earth distance.\n"
            "# Columns: wavelength [nm], spectral irradiance at the top of the atmosphere, normal to the sun [W m^-2 nm^-1].\n"
            "wavelength_nm,irradiance_W_m2_nm\n"
        )
        for w, e in zip(wl[keep], etr[keep], strict=True):
            fh.write(f"{w:g},{e}\n")


if __name__ == "__main__":
    main()
