"""Accuracy of the analytic aerial perspective against quadrature (the table in ``docs/aerial.md``).

``python -m skyscatter.aerial.accuracy`` prints, for view elevations -10 to +30 deg and distances 0.1 to
100 km, the largest relative error of the in-scattered radiance L_in (Preetham 1999 Eq. 8) of
``method="analytic"`` against ``method="numeric"``, over observer heights 0-3 km, turbidities 2-10, all
wavelengths 380-780 nm and three view azimuths (towards, across and away from a sun 20 deg high).
Paths that would end below sea level are left out ("-").
"""

from __future__ import annotations

import argparse

import numpy as np
from numpy.typing import NDArray

from ..conventions import direction_from_angles
from ..spectral import DEFAULT_WAVELENGTHS
from .integrals import in_scattering_integrals
from .preetham import PreethamAerialPerspective

__all__ = ["ELEVATIONS_DEG", "DISTANCES_KM", "HEIGHTS_M", "TURBIDITIES", "in_scattering_errors", "markdown_table"]

ELEVATIONS_DEG = (-10.0, -5.0, -2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 30.0)
DISTANCES_KM = (0.1, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0)
HEIGHTS_M = (0.0, 500.0, 1000.0, 2000.0, 3000.0)
TURBIDITIES = (2.0, 4.0, 6.0, 10.0)
SUN_ELEVATION_DEG = 20.0
VIEW_AZIMUTHS_DEG = (0.0, 90.0, 180.0)  # the sun is at azimuth 180 deg


def in_scattering_errors(*, segments: int | str = "auto", elevations=ELEVATIONS_DEG, distances_km=DISTANCES_KM,
                         heights=HEIGHTS_M, turbidities=TURBIDITIES, wavelengths=DEFAULT_WAVELENGTHS
                         ) -> NDArray[np.float64]:
    """Largest relative error of L_in, analytic vs numeric, shape (n_elevations, n_distances); NaN where every
    path of that cell would end below sea level."""
    from ..sky.preetham import PreethamSky

    el = np.radians(np.asarray(elevations, dtype=float))
    s = np.asarray(distances_km, dtype=float) * 1000.0
    h = np.asarray(heights, dtype=float)
    ee, ss, hh = np.meshgrid(el, s, h, indexing="ij")
    valid = hh + ss * np.sin(ee) >= 0.0
    worst = np.full(ee.shape[:2], np.nan)
    for t in turbidities:
        sky = PreethamSky(t, np.radians(90.0 - SUN_ELEVATION_DEG), np.pi)
        ap = PreethamAerialPerspective(sky)
        b1, b2 = ap.scattering_coefficients(wavelengths)
        c = np.sin(ee[valid])
        num = in_scattering_integrals(c, ss[valid], hh[valid], b1, b2, method="quadrature")
        ana = in_scattering_integrals(c, ss[valid], hh[valid], b1, b2, method="analytic", segments=segments)
        table = ap.table(wavelengths)
        err = np.zeros(c.shape)
        for az in np.radians(VIEW_AZIMUTHS_DEG):
            d = direction_from_angles(np.pi / 2 - ee[valid], az)
            s1, s2 = table.lookup(d)
            ref = s1 * num[0] + s2 * num[1]
            got = s1 * ana[0] + s2 * ana[1]
            err = np.maximum(err, np.max(np.abs(got / ref - 1.0), axis=-1))
        cell = np.full(ee.shape, np.nan)
        cell[valid] = err
        with np.errstate(invalid="ignore"):
            worst = np.fmax(worst, np.nanmax(np.where(np.isnan(cell), -np.inf, cell), axis=2))
    worst[np.isinf(worst)] = np.nan
    return worst


def markdown_table(errors: NDArray[np.float64], *, elevations=ELEVATIONS_DEG, distances_km=DISTANCES_KM) -> str:
    """The error array as a Markdown table (per cent, elevations as rows, distances as columns)."""
    head = "| elevation \\ distance | " + " | ".join(f"{d:g} km" for d in distances_km) + " |"
    rule = "|---|" + "---|" * len(distances_km)
    rows = [head, rule]
    for e, row in zip(elevations, errors, strict=True):
        cells = ["-" if np.isnan(v) else f"{100 * v:.2g} %" for v in row]
        rows.append(f"| {e:+g} deg | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--segments", default="auto", help="'auto' or a whole number (1 = the paper as published)")
    parser.add_argument("--turbidity", type=float, nargs="+", default=list(TURBIDITIES),
                        help="turbidities to include")
    args = parser.parse_args(argv)
    segments = args.segments if args.segments == "auto" else int(args.segments)
    errors = in_scattering_errors(segments=segments, turbidities=args.turbidity)
    print(markdown_table(errors))
    upto50 = errors[:, np.asarray(DISTANCES_KM) <= 50.0]
    print(f"\nlargest error up to 50 km: {100 * np.nanmax(upto50):.3g} %; "
          f"up to 100 km: {100 * np.nanmax(errors):.3g} %")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
