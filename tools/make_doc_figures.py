"""Draw the skyscatter.plot figures of the documentation (docs/images/plot_*.png) again.

Usage: ``python tools/make_doc_figures.py [OUT_DIR]`` (default ``docs/images``); needs the ``plot`` extra
(matplotlib). About 10 s. Every figure is drawn by :mod:`skyscatter.plot` from the models themselves:

* ``plot_luminance_preetham.png``: the Preetham 1999 sky, turbidity 3, sun 30 deg above the horizon in the
  south-east (azimuth 135 deg), luminance on a logarithmic colour bar;
* ``plot_chromaticity_preetham.png``: the same sky's CIE 1931 chromaticity x and y;
* ``plot_error_hosek_wilkie_vs_preetham.png``: Hosek & Wilkie 2012 (turbidity 3, ground albedo 0.1) against that
  Preetham sky, relative luminance error;
* ``plot_spectra.png``: both skies' spectral radiance at the zenith and 80 deg from it opposite the sun,
  380-720 nm (Hosek-Wilkie's spectral data end at 720 nm).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")  # files only, no display

from skyscatter import plot  # noqa: E402
from skyscatter.conventions import direction_from_angles  # noqa: E402
from skyscatter.fileio import atomic_path  # noqa: E402
from skyscatter.sky import registry  # noqa: E402

SUN = (math.radians(60.0), math.radians(135.0))  # zenith, azimuth [rad]
TURBIDITY = 3.0


def save(figure, out: Path, name: str) -> Path:
    path = out / name
    with atomic_path(path) as tmp:
        figure.savefig(tmp, format="png", dpi=110, bbox_inches="tight")
    matplotlib.pyplot.close(figure)
    print(f"wrote {path}")
    return path


def main(out: Path) -> None:
    preetham = registry.build("preetham", *SUN, turbidity=TURBIDITY)
    hosek = registry.build("hosek-wilkie", *SUN, turbidity=TURBIDITY)

    m = plot.luminance_map(preetham, log=True, sun=SUN, title="Preetham 1999, turbidity 3, sun 30 deg high")
    save(m.figure, out, "plot_luminance_preetham.png")

    x, _ = plot.chromaticity_map(preetham, sun=SUN, title="Preetham 1999, turbidity 3: CIE 1931 chromaticity")
    save(x.figure, out, "plot_chromaticity_preetham.png")

    e = plot.error_map(hosek, preetham, sun=SUN,
                       title="Hosek-Wilkie 2012 / Preetham 1999 - 1, luminance (turbidity 3)")
    save(e.figure, out, "plot_error_hosek_wilkie_vs_preetham.png")

    d = direction_from_angles([0.0, math.radians(80.0)], [0.0, SUN[1] + math.pi])
    wl = np.arange(380.0, 721.0, 10.0)  # Hosek-Wilkie's spectral data end at 720 nm (zero beyond)
    s = plot.spectra([preetham, hosek], d, wl, labels=["Preetham 1999", "Hosek-Wilkie 2012"],
                     title="Sky spectral radiance, turbidity 3, sun 30 deg high")
    save(s.figure, out, "plot_spectra.png")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "docs" / "images"))
