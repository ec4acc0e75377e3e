"""How far a shader can follow the lookups' single scattering from the Earth's shadow (docs/accuracy.md, "Low sun";
docs/realtime.md).

The rendering lookups scale the single scattering read from a point in the shadow by a factor per wavelength
(``sampling.shadow_march_factors``: a march of the sunlit density times the transmittance to the sun). A shader
reads the tables folded to RGB (``realtime.export.engine_textures``) and can only form that factor per colour
channel, from the folded transmittance. This runs the lookups themselves on the folded tables (three "wavelengths":
the RGB textures' values, the transmittance weighted by the sun's spectrum as the export folds it; the multiple
scattering zeroed) against the spectral lookup's single scattering folded with ``fold_matrix``: the difference, per
direction, over the largest channel of the whole sky there (the measure of
``tests/test_realtime_export.py::test_manifest_mappings_and_textures_give_the_spectral_lookup``, bound 2e-5).

``--bands 480,590``: instead of the RGB fold, the per-wavelength lookups with the transmittance averaged over
wavelength bands (split at the given wavelengths [nm], weighted by the sun's spectrum as the export folds the
transmittance texture), i.e. a factor per band (what a band-split export could give a shader), against the
per-wavelength rule, both folded.

``python benchmarks/shadow_march_parity.py [--default] [--bands 480,590]``: the manifest test's small tables
(orders 2), or the default cached ones.
"""

from __future__ import annotations

import argparse

import numpy as np

from skyscatter.conventions import direction_from_angles
from skyscatter.precomputed import PrecomputedAtmosphere, cached_atmosphere
from skyscatter.realtime.export import _sun_weighted, fold_matrix

SMALL = dict(transmittance_mu=32, transmittance_r=8, irradiance_mu_s=8, irradiance_r=4, scattering_r=6,
             scattering_mu=16, scattering_mu_s=6, scattering_nu=4)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--default", action="store_true", help="the default cached tables")
    ap.add_argument("--bands", default="", help="band edges [nm], e.g. 480,590: a factor per band instead of RGB")
    args = ap.parse_args()
    atm = cached_atmosphere() if args.default else PrecomputedAtmosphere.compute(orders=2, sizes=SMALL,
                                                                                 progress=False)
    m = fold_matrix(atm)
    t = dict(atm.tables)
    solar = atm.parameters.solar_irradiance_at(atm.wavelengths)
    rgb = {"transmittance": _sun_weighted(t["transmittance"], solar, m)[..., :3].astype(np.float32)}
    for k in ("single_rayleigh", "single_mie", "multiple", "irradiance"):
        rgb[k] = (t[k].astype(np.float64) @ m.T).astype(np.float32)
    rgb["multiple"][:] = 0.0
    if args.bands:
        band = np.searchsorted(np.array([float(v) for v in args.bands.split(",")]), atm.wavelengths)
        tr = t["transmittance"].astype(np.float64)
        for b in np.unique(band):
            k = band == b
            tr[..., k] = ((tr[..., k] * solar[k]).sum(-1) / solar[k].sum())[..., None]
        folded = PrecomputedAtmosphere(atm.parameters, atm.wavelengths, atm.sizes, atm.orders,
                                       {**t, "transmittance": tr.astype(np.float32),
                                        "multiple": np.zeros_like(t["multiple"])})
    else:
        folded = PrecomputedAtmosphere(atm.parameters, np.array([450.0, 550.0, 650.0]), atm.sizes, atm.orders,
                                       {k: np.maximum(v, 0.0) for k, v in rgb.items()})
        folded._decoded = dict(rgb)  # the folded values as they are (a few negative: the half storage refuses them)
    single = PrecomputedAtmosphere(atm.parameters, atm.wavelengths, atm.sizes, atm.orders,
                                   {**t, "multiple": np.zeros_like(t["multiple"])})
    rng = np.random.default_rng(7)
    p = atm.parameters
    for alt in (0.0, 1500.0):
        pos = np.array([0.0, 0.0, p.bottom_radius + alt])
        for zenith in (93.0, 94.0, 96.0):
            sun = direction_from_angles(np.radians(zenith), 0.4)
            dirs = direction_from_angles(rng.uniform(0.0, np.pi / 2, 400), rng.uniform(0, 2 * np.pi, 400))
            many = np.broadcast_to(pos, dirs.shape)  # the general kernel (it reads the decoded tables)
            full = atm.sky_radiance(many, dirs, sun, include_ground=False) @ m.T
            a = single.sky_radiance(many, dirs, sun, include_ground=False) @ m.T
            b = folded.sky_radiance(many, dirs, sun, include_ground=False)
            b = b @ m.T if args.bands else b
            e = np.abs(a - b).max(1) / np.maximum(np.abs(full).max(1), 1e-6)
            print(f"altitude {alt:6.0f} m, sun {90.0 - zenith:+.0f} deg: per channel against per wavelength, over the "
                  f"sky's largest channel: median {np.median(e):.2e}, 95th percentile {np.percentile(e, 95):.2e}, "
                  f"worst {e.max():.2e}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
