"""Radiance's genssky at full cloud cover (its blend with the CIE overcast sky): the luminance gradation and the
correlated colour temperature of the spectral sky picture it writes, beside the fast cloudy sky (docs/clouds.md).

Runs pyradiance's ``genssky 6 21 12 -y 2024 -a 45 -o 0 -m 0 -c 1.0`` in a temporary folder (its own tables are
precomputed there: about 2 min), reads the 20-band sky picture (``genssky_montecarlo.read_hsr``: 32 rows of
altitude 90 to -90 deg, 64 columns of azimuth, 380-780 nm in the header's order), and prints L(h) / L(zenith row)
averaged over azimuth with the CIE overcast ``(1 + 2 sin h) / 3`` and its CCT (Hernandez 1999 through
colour-science) per elevation; then the cloudy sky's gradation at h = 10, 30, 60 deg under optical depths 15-60.
"""

from __future__ import annotations

import math
import os
import subprocess
import tempfile
from pathlib import Path

import numpy as np


def main() -> None:
    import colour
    import pyradiance

    from genssky_montecarlo import read_hsr
    from skyscatter.sky.cloudy import CloudySky
    from skyscatter.spectral import spectrum_to_xyz, xyz_to_chromaticity

    root = Path(pyradiance.__file__).parent
    env = dict(os.environ, RAYPATH=f".{os.pathsep}{root / 'lib'}")
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [str(root / "bin" / "genssky"), "6", "21", "12", "-y", "2024", "-a", "45", "-o", "0", "-m", "0", "-c",
               "1.0", "-n", "1", "-f", "oc"]
        out = subprocess.run(cmd, cwd=tmp, env=env, capture_output=True, text=True, check=True).stdout
        print(out.strip().splitlines()[0:4])
        # the picture read with its header's sample order (Radiance stores spectral samples from the long
        # wavelengths to the short: WAVELENGTH_SPLITS= 780 588 480 380); read in the other order its spectrum
        # gave 4330-4350 K instead of D6415's 6430 K
        alt, bands, rad = read_hsr(Path(tmp) / "oc_sky.hsr")
    fine = np.arange(380.0, 781.0, 5.0)
    rows = np.nonzero(alt > 0)[0]
    spec = np.array([np.interp(fine, bands, m) for m in rad[rows].mean(axis=1)])
    xyz = spectrum_to_xyz(spec, fine)
    cct = [float(np.squeeze(colour.temperature.xy_to_CCT(np.asarray(xyz_to_chromaticity(x))[:2],
                                                          method="Hernandez 1999"))) for x in xyz]
    h = alt
    cie = (1 + 2 * np.sin(np.radians(h[rows]))) / (1 + 2 * np.sin(np.radians(h[rows][0])))
    for k in range(rows.size):
        print(f"genssky h {h[rows][k]:5.1f} deg: L / L_top {xyz[k, 1] / xyz[0, 1]:.3f} (CIE {cie[k]:.3f}), "
              f"CCT {cct[k]:.0f} K")
    hs = np.radians([10.0, 30.0, 60.0])
    az = np.radians(np.arange(0.0, 360.0, 15.0))
    print(f"CIE overcast at h = 10, 30, 60 deg: {np.round((1 + 2 * np.sin(hs)) / 3, 3)}")
    for sun in (60.0, 30.0, 10.0):
        for tau in (15.0, 30.0, 60.0):
            sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau, ground_albedo=0.2)
            z = sky.luminance([[0.0, 0.0, 1.0]])[0]
            g = [np.mean(sky.luminance(np.stack([np.cos(x) * np.sin(az), np.cos(x) * np.cos(az),
                                                 np.full(az.size, np.sin(x))], -1))) / z for x in hs]
            print(f"cloudy sun {sun:g} deg, optical depth {tau:g}: {np.round(g, 3)}")


if __name__ == "__main__":
    main()
