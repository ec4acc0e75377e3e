"""Sun-zenith texels per table: would the three 4D tables read better with their own sun-zenith resolutions at the
same memory? (docs/accuracy.md, "Low sun": "Sun-zenith texels per table").

The default tables share one sun-zenith axis of 32 texels (single Rayleigh, single Mie, multiple scattering). This
script emulates tables in which each of the three has its own count ``n`` of sun-zenith texels on the same mapping
(:func:`skyscatter.precomputed.geometry.scattering_mu_s_coord` at ``n`` texels) and is read linearly between them,
from tables of 94 sun-zenith texels (``--sizes scattering_mu_s=94``, three times the default's density):

* a table of ``n`` texels holds at its texel ``k`` (coordinate ``x_k = k / (n - 1)``) the 94-texel table at
  ``x_k``: the 94-texel value where the texel is shared (``n`` = 32, 94), else the four-point Lagrange formula in
  the logarithm over the nearest 94-texel texels ([Abramowitz1964] Eq. 25.2.13), kept between the two nearest
  values (linear where a value is not positive);
* at the sun ``mu_s`` the table's read is ``(1 - w) S_k + w S_{k + 1}`` with ``k + w`` the coordinate of ``mu_s``
  at ``n`` texels (the lookups' linear rule);
* that read (the whole (r, mu, nu, wavelength) slice of each table) is put into tables with **two** sun-zenith
  texels holding the same slice, and the sky is computed from them by the library's own lookups: a read along the
  sun zenith of a constant is the constant, and every other part of the lookup (the azimuth's weights from the
  values, the shadow rule, the multiple scattering's lobe at the query's ``nu``, the ground, the transmittance)
  is the library's at the query's ``mu_s``. So the emulation is the lookups of per-table tables exactly, up to
  the texel values (the precomputation of a table of ``n`` texels reads the orders' densities along its own
  sun-zenith axis; the texel values here are the 94-texel precomputation's).

``n`` = 94 for all three reproduces the 94-texel tables' lookups at their texels; ``n`` = 32 for all three
reproduces the default tables' read from the 94-texel precomputation's texel values (against the default tables
themselves: the precomputation's own share).

Outputs, per atmosphere (Earth defaults, turbidity 3, aerosol optical depth 0.5; 400 / 560 / 700 nm; the 15 views
of ``benchmarks/low_sun_montecarlo_reference.py`` from the ground):

1. against the 94-texel tables at the suns of the 94-texel axis, per band of sun elevation: median / 90th
   percentile / largest ``100 |x / x_94 - 1|`` [%] over views, wavelengths and suns (all suns of the band; the
   default tables' lookup ``default`` in the same cells);
2. (``--montecarlo``) against the stored Monte Carlo (tests/data/low_sun_montecarlo.json; the counting rule of
   ``tests/test_precomputed_low_sun.py``: a direction is outside when it misses 5 % or 2 standard errors, whichever
   is larger, at some wavelength): directions outside per case and in all (of 315).

``python benchmarks/low_sun_mu_s_split.py [--splits 32/32/32,40/40/16,...] [--montecarlo]`` (a split is
``n_rayleigh/n_mie/n_multiple``; a count ending in ``c``, e.g. ``32/32/32c``, reads that table with the sun below
the horizon by the four-point Lagrange formula in the logarithm over its texels ``k - 1 .. k + 2``, kept between
the cell's two values, instead of linearly, and ``C`` at every sun; the tables from the cache or computed at the
three wavelengths: a few minutes each for the 94-texel ones).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from skyscatter.precomputed import cached_atmosphere
from skyscatter.precomputed.geometry import scattering_mu_s_coord
from skyscatter.precomputed.kernels import mu_s_texels
from skyscatter.precomputed.sizes import TableSizes
from skyscatter.precomputed.tables import PrecomputedAtmosphere

sys.path.insert(0, str(Path(__file__).resolve().parent))
from low_sun_montecarlo_reference import ATMOSPHERES, directions  # noqa: E402  (sibling script)

DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "low_sun_montecarlo.json"
WAVELENGTHS = [400.0, 560.0, 700.0]
FINE = 94
#: Sun-zenith texels and the read of each scattering table, in SCATTERING's order: "" linear, "c" the logarithmic
#: four-point read with the sun below the horizon (linear above), "C" that read at every sun
Split = tuple[tuple[int, str], ...]
SCATTERING = ("single_rayleigh", "single_mie", "multiple")
BANDS = [(-12.0, -7.0), (-7.0, -4.5), (-4.5, -2.0), (-2.0, -0.5), (-0.5, 1.5), (1.5, 4.0), (4.0, 8.0), (8.0, 16.5),
         (16.5, 61.0)]
DEFAULT_SPLITS = ("94/94/94,32/32/32,94/94/16,16/16/94,94/94/32,32/32/94,40/40/16,36/36/24,24/24/48,16/16/64,"
                  "48/32/16,32/48/16,40/32/24,32/40/24")


def knot(fine: np.ndarray, p: float) -> np.ndarray:
    """The table ``fine`` (n_r, n_mu, FINE, n_nu, n_wavelengths) at the fine index position ``p`` along its sun-zenith
    axis: the texel where ``p`` is one, else the four-point Lagrange formula in the logarithm, kept between the two
    nearest texels (module docstring); (n_r, n_mu, n_nu, n_wavelengths) float64."""
    n = fine.shape[2]
    i = int(math.floor(p + 1e-9))
    t = p - i
    if t < 1e-9 or i >= n - 1:
        return fine[:, :, min(i, n - 1)].astype(np.float64)
    a = fine[:, :, i].astype(np.float64)
    b = fine[:, :, i + 1].astype(np.float64)
    j0 = min(max(i - 1, 0), n - 4)
    ys = [fine[:, :, j0 + m].astype(np.float64) for m in range(4)]
    xs = [j0 + m - p for m in range(4)]  # nodes relative to p
    ok = np.all([y > 0 for y in ys], axis=0)
    with np.errstate(all="ignore"):
        logq = np.zeros_like(a)
        for m in range(4):
            w = 1.0
            for q in range(4):
                if q != m:
                    w *= (0.0 - xs[q]) / (xs[m] - xs[q])
            logq += w * np.log(np.where(ok, ys[m], 1.0))
        cubic = np.clip(np.exp(logq), np.minimum(a, b), np.maximum(a, b))
    return np.where(ok, cubic, (1.0 - t) * a + t * b)


class Emulator:
    """Per-table sun-zenith reads from one atmosphere's 94-texel tables (module docstring)."""

    def __init__(self, fine: PrecomputedAtmosphere) -> None:
        self.fine = fine
        p = fine.parameters
        self.geom = (p.bottom_radius, p.top_radius, p.mu_s_min)
        self.tables = fine.tables
        self.sizes2 = TableSizes(**{**fine.sizes.__dict__, "scattering_mu_s": 2})
        self._knots: dict[tuple[str, int, int], np.ndarray] = {}

    def _knot(self, name: str, n: int, k: int) -> np.ndarray:
        key = (name, n, k)
        if key not in self._knots:
            # float32 as the tables (the cache holds up to a few hundred slices of 0.4 MB)
            self._knots[key] = knot(self.tables[name], k * (FINE - 1) / (n - 1)).astype(np.float32)
        return self._knots[key]

    def slice(self, name: str, n: int, mu_s: float, cubic: bool = False) -> np.ndarray:
        """Table ``name`` read between its ``n`` sun-zenith texels at ``mu_s``: (n_r, n_mu, n_nu, n_l); linearly, or
        (``cubic``) by the four-point Lagrange formula in the logarithm over the texels ``k - 1 .. k + 2``, kept
        between the cell's two values (linear where a value is not positive)."""
        pc = scattering_mu_s_coord(mu_s, *self.geom, n)
        k = min(max(int(math.floor(pc)), 0), n - 2)
        w = min(max(pc - k, 0.0), 1.0)
        if not cubic:
            return (1.0 - w) * self._knot(name, n, k) + w * self._knot(name, n, k + 1)
        j0 = min(max(k - 1, 0), n - 4)
        nodes = np.stack([self._knot(name, n, j0 + m) for m in range(4)], axis=2)
        return knot(nodes, k + w - j0)

    def atmosphere(self, split: Split, mu_s: float) -> PrecomputedAtmosphere:
        """Tables of two sun-zenith texels, each holding every scattering table's read at ``mu_s``."""
        t = {name: v for name, v in self.tables.items() if name not in SCATTERING}
        for name, (n, cubic) in zip(SCATTERING, split, strict=True):
            s = self.slice(name, n, mu_s, cubic == "C" or (cubic == "c" and mu_s < 0.0)).astype(np.float32)
            t[name] = np.ascontiguousarray(np.stack([s, s], axis=2))
        f = self.fine
        return PrecomputedAtmosphere(f.parameters, f.wavelengths, self.sizes2, f.orders, t)

    def sky(self, split: Split, sun_elev: float) -> np.ndarray:
        """Sky radiance (n_views, n_wavelengths) from the ground at the sun elevation [deg]."""
        s = math.radians(sun_elev)
        atm = self.atmosphere(split, math.sin(s))
        pos = np.array([0.0, 0.0, atm.parameters.bottom_radius])
        return atm.sky_radiance(pos, directions(), np.array([0.0, math.cos(s), math.sin(s)]))


def sky(atm: PrecomputedAtmosphere, sun_elev: float) -> np.ndarray:
    """Sky radiance (n_views, n_wavelengths) of ``atm``'s own lookups from the ground at the sun elevation [deg]."""
    s = math.radians(sun_elev)
    pos = np.array([0.0, 0.0, atm.parameters.bottom_radius])
    return atm.sky_radiance(pos, directions(), np.array([0.0, math.cos(s), math.sin(s)]))


def spread(e: np.ndarray) -> str:
    """``median / 90th percentile / largest`` of the relative differences ``e`` [%]."""
    e = e[np.isfinite(e)]
    if e.size == 0:
        return "-"
    return f"{np.median(e):.1f} / {np.percentile(e, 90):.1f} / {e.max():.1f}"


def outside(cases: list[dict], values: list[np.ndarray], cols: list[int]) -> list[int]:
    """Directions outside the target per case (the rule of ``tests/test_precomputed_low_sun.py``: 5 % or 2 Monte
    Carlo standard errors, whichever is larger, at some wavelength); ``values`` (n_views, n_wavelengths) per case."""
    out = []
    for c, v in zip(cases, values, strict=True):
        mc = np.array(c["radiance"])[:, cols]
        limit = np.maximum(0.05, 2.0 * np.array(c["radiance_stderr"])[:, cols] / mc)
        out.append(int((np.abs(v / mc - 1.0) > limit).any(axis=1).sum()))
    return out


def parse_splits(text: str) -> list[Split]:
    """``"a/b/c,..."`` -> [((n_rayleigh, read), (n_mie, read), (n_multiple, read)), ...] (sun-zenith texels per
    table; a count ending in ``c`` reads that table by the logarithmic four-point rule with the sun below the
    horizon, ``C`` at every sun)."""
    return [tuple((int(v.rstrip("cC")), v[len(v.rstrip("cC")):]) for v in s.split("/")) for s in text.split(",")]


def label(split: Split) -> str:
    """``"32/32/44c"``: the split as given on the command line."""
    return "/".join(f"{n}{c}" for n, c in split)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--atmospheres", default=",".join(ATMOSPHERES))
    ap.add_argument("--splits", default=DEFAULT_SPLITS, help="n_rayleigh/n_mie/n_multiple, comma separated")
    ap.add_argument("--montecarlo", action="store_true", help="also count against the stored Monte Carlo")
    ap.add_argument("--no-bands", action="store_true", help="skip the comparison with the 94-texel tables")
    args = ap.parse_args()
    splits = parse_splits(args.splits)
    names = args.atmospheres.split(",")
    doc = json.loads(DATA.read_text())
    cols = [doc["wavelengths_nm"].index(w) for w in WAVELENGTHS]
    totals = {s: [0] * len(names) for s in splits}
    totals_default = [0] * len(names)
    for ia, name in enumerate(names):
        params = ATMOSPHERES[name][1]()
        fine = cached_atmosphere(params, wavelengths=WAVELENGTHS, sizes={"scattering_mu_s": FINE}, progress=False)
        default = cached_atmosphere(params, wavelengths=WAVELENGTHS, progress=False)
        emu = Emulator(fine)
        p = fine.parameters
        if not args.no_bands:
            el = np.degrees(np.arcsin(mu_s_texels(p.bottom_radius, p.top_radius, p.mu_s_min, FINE)))
            el = el[(el >= BANDS[0][0]) & (el < BANDS[-1][1])]
            ref = np.array([sky(fine, e) for e in el])
            rows = {"default (32, the lookups)": np.array([sky(default, e) for e in el])}
            for s in splits:
                rows[label(s)] = np.array([emu.sky(s, e) for e in el])
            print(f"## {name}, {WAVELENGTHS} nm: median / 90 % / largest 100 |x / x_94 - 1| [%] at the 94-texel suns")
            print("| split R/M/multiple | " + " | ".join(f"{lo:+g}..{hi:+g}" for lo, hi in BANDS) + " |")
            print("|---|" + "---|" * len(BANDS))
            for row, got in rows.items():
                err = np.abs(got / ref - 1.0) * 100.0
                cells = [spread(err[(el >= lo) & (el < hi)].ravel()) for lo, hi in BANDS]
                print(f"| {row} | " + " | ".join(cells) + " |", flush=True)
        if args.montecarlo:
            cases = sorted((c for c in doc["cases"] if c["atmosphere"] == name), key=lambda c: -c["sun_elevation_deg"])
            print(f"## {name}: directions outside of 15 against the stored Monte Carlo")
            print("| split R/M/multiple | " + " | ".join(f"{c['sun_elevation_deg']:+g}" for c in cases) + " | all |")
            print("|---|" + "---|" * (len(cases) + 1))
            got = outside(cases, [sky(default, c["sun_elevation_deg"]) for c in cases], cols)
            totals_default[ia] = sum(got)
            print("| default (32, the lookups) | " + " | ".join(map(str, got)) + f" | {sum(got)} |", flush=True)
            for s in splits:
                got = outside(cases, [emu.sky(s, c["sun_elevation_deg"]) for c in cases], cols)
                totals[s][ia] = sum(got)
                print(f"| {label(s)} | " + " | ".join(map(str, got)) + f" | {sum(got)} |", flush=True)
    if args.montecarlo:
        print(f"## all atmospheres ({', '.join(names)}): directions outside")
        print(f"| default (32, the lookups) | {' / '.join(map(str, totals_default))} | {sum(totals_default)} |")
        for s in splits:
            print(f"| {label(s)} | {' / '.join(map(str, totals[s]))} | {sum(totals[s])} |")


if __name__ == "__main__":
    main()
