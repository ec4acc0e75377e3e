"""Clear-hour ground spectrum against pvlib's SPECTRL2 through SPECTRL2's own aerosol, with the Monte Carlo verdict
(issue 24, docs/sky_matrices.md "Clear hours against SPECTRL2 through SPECTRL2's own aerosol").

Our medium (the retrieval's base) with SPECTRL2's aerosol (Bird & Riordan 1986: Angstrom alpha 1.3, albedo
0.945 exp(-0.095 ln^2(lambda / 400 nm)), Eq. 3-16; asymmetry 0.65 as a Henyey-Greenstein phase, or with ``cs`` a
Cornette-Shanks g of 0.585, the same mean cosine; ``old``: the family's aerosol, Cornette-Shanks g 0.8, albedo 0.9).
Three cases (sun zenith, AOD at 550 nm): (30, 0.1), (20, 0.3), (60, 0.2); water 1.4 cm, ozone 300 DU, sea level,
ground albedo 0.2. Ours: the broadband model's direct beam plus the tables' radiance over the hemisphere times the
water and mixed-gas transmittance along the sun's path. Mean / RMS / largest of ours / SPECTRL2 - 1 over SPECTRL2's
wavelengths in 400-700 nm, global, direct and diffuse; with a number of paths the spherical Monte Carlo
(``montecarlo.ground_irradiance``) through the same air at the same wavelengths against both. ``--phase-effect``:
the sky of the retrieval's fixed aerosol (Cornette-Shanks g 0.8, the albedo giving the same horizontal diffuse at
550 nm) against SPECTRL2's aerosol at AOD 0.2, radiance ratio by scattering angle.

    PYTHONPATH=src python benchmarks/compare_spectrl2_own_aerosol.py [coarse|default] [hg|cs|old] [paths]
    PYTHONPATH=src python benchmarks/compare_spectrl2_own_aerosol.py --phase-effect
    PYTHONPATH=src python benchmarks/compare_spectrl2_own_aerosol.py --retrieval

``--retrieval``: the retrieval (coarse tables, AOD nodes 0, 0.2, 0.5) on the SPECTRL2 clear day of
tests/weather_synth.py (20 June, no light below 3 deg) with the default base (Cornette-Shanks g 0.8) and with a base
of Cornette-Shanks g 0.585 (SPECTRL2's mean cosine 0.65): the retrieved albedo, g and DHI closure per clear hour.
"""

import json
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from skyscatter.atmosphere.phase_table import PhaseTable
from skyscatter.fit.weather import TABLE_PRESETS, RetrievalOptions
from skyscatter.montecarlo.domain import ground_irradiance
from skyscatter.precomputed.cache import cached_atmosphere

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from spectrl2_clear import SPECTRL2_ALPHA as ALPHA  # noqa: E402  (shared with the test)
from spectrl2_clear import clear_ground_spectra, spectrl2_air  # noqa: E402

CASES = ((30.0, 0.1), (20.0, 0.3), (60.0, 0.2))
BASE = RetrievalOptions(angstrom_alpha=ALPHA).base_atmosphere()


def medium(aod550: float, phase: str = "hg"):
    """Our medium with SPECTRL2's aerosol (module docstring; tests/spectrl2_clear.py); ``phase`` "hg", "cs" (a
    Cornette-Shanks of the same mean cosine) or "old" (the analytic aerosol the comparison used before)."""
    if phase == "old":
        return BASE.replace(mie_angstrom_beta=aod550 * 0.55**ALPHA, mie_single_scattering_albedo=0.9, mie_phase_g=0.8)
    return spectrl2_air(aod550, None if phase == "hg" else PhaseTable.cornette_shanks(0.585, [300.0, 1300.0]))


def tables(atm, preset: str):
    p = TABLE_PRESETS[preset]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return cached_atmosphere(atm, orders=p["orders"], wavelengths=p["wavelengths"], sizes=p["sizes"],
                                 progress=False)


def stats(a, b, wl):
    rel = np.asarray(a) / np.asarray(b) - 1
    j = int(np.argmax(np.abs(rel)))
    return {"mean": round(100 * rel.mean(), 2), "rms": round(100 * np.sqrt(np.mean(rel**2)), 2),
            "max": round(100 * rel[j], 2), "at_nm": float(wl[j])}


def compare(preset: str, phase: str, paths: int) -> dict:
    out = {}
    for zdeg, aod in CASES:
        atm = medium(aod, phase)
        z = np.radians([zdeg])
        w, me, th, gas_w = clear_ground_spectra(atm, tables(atm, preset), zdeg, aod)
        row = {k: stats(me[k], th[k], w) for k in ("global", "direct", "diffuse")}
        if paths:
            mc = ground_irradiance(atm, w, sun_zenith=float(z[0]), samples=paths, seed=7)
            t_mc = np.asarray(mc.diffuse)[0] / atm.solar_irradiance_at(w)
            mc_d = t_mc * gas_w
            mc_g = me["direct"] + mc_d
            row["monte_carlo"] = {
                "diffuse_stderr_median": round(100 * float(np.median(np.asarray(mc.diffuse_stderr)[0]
                                                                     / np.asarray(mc.diffuse)[0])), 2),
                "ours_global": stats(me["global"], mc_g, w), "ours_diffuse": stats(me["diffuse"], mc_d, w),
                "spectrl2_global": stats(th["global"], mc_g, w), "spectrl2_diffuse": stats(th["diffuse"], mc_d, w),
                "spectrl2_diffuse_per_wavelength": dict(zip(
                    w.tolist(), np.round(100 * (th["diffuse"] / mc_d - 1), 1).tolist(), strict=True))}
        out[f"zenith {zdeg:g} deg, AOD {aod:g}"] = row
        print(f"zenith {zdeg:g} deg, AOD {aod:g}:", json.dumps(row), flush=True)
    return out


def phase_effect(aod: float = 0.2) -> None:
    spl = tables(medium(aod), "coarse")
    ours = {a: tables(BASE.replace(mie_angstrom_beta=aod * 0.55**ALPHA, mie_single_scattering_albedo=a,
                                   mie_phase_g=0.8), "coarse") for a in (0.8, 1.0)}
    k = list(np.asarray(spl.wavelengths)).index(550.0)
    ground = np.array([0.0, 0.0, BASE.bottom_radius])
    alt, az = np.radians(np.arange(6.0, 90.0, 6.0)), np.radians(np.arange(0.0, 181.0, 15.0))
    a_, z_ = np.meshgrid(alt, az, indexing="ij")
    d = np.stack([np.cos(a_) * np.cos(z_), np.cos(a_) * np.sin(z_), np.sin(a_)], -1).reshape(-1, 3)
    d = np.vstack([d, [0.0, 0.0, 1.0]])
    for zdeg in (30.0, 60.0):
        z = np.radians([zdeg])
        hs = spl.horizontal_sky_irradiance(z)[0]
        h8, h10 = (ours[a].horizontal_sky_irradiance(z)[0] for a in (0.8, 1.0))
        f = (hs[k] - h8[k]) / (h10[k] - h8[k])  # linear in albedo between the nodes, as the family interpolates
        sun = np.array([np.sin(z[0]), 0.0, np.cos(z[0])])
        lo = (1 - f) * ours[0.8].sky_radiance(ground, d, sun)[:, k] + f * ours[1.0].sky_radiance(ground, d, sun)[:, k]
        r = lo / spl.sky_radiance(ground, d, sun)[:, k]
        scat = np.degrees(np.arccos(np.clip(d @ sun, -1, 1)))
        ratio = np.round((h8 + f * (h10 - h8)) / hs, 3).tolist()
        print(f"sun zenith {zdeg:g} deg: albedo {0.8 + 0.2 * f:.3f}; horizontal diffuse ours / SPECTRL2's aerosol "
              f"at {np.asarray(spl.wavelengths).tolist()} nm: {ratio}; zenith {r[-1]:.3f}")
        for lo_deg, hi_deg in ((0, 10), (10, 20), (20, 35), (35, 60), (60, 90), (90, 120), (120, 180)):
            m = (scat >= lo_deg) & (scat < hi_deg)
            if m.any():
                print(f"  {lo_deg}-{hi_deg} deg from the sun: median {np.median(r[m]):.3f}, "
                      f"{r[m].min():.3f}-{r[m].max():.3f} ({m.sum()} directions)")


def retrieval() -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from skyscatter.fit.weather import CLEAR, CLEAR_OPEN, retrieve_hourly_atmosphere
    from skyscatter.sun.position import sun_position_unix
    from weather_synth import SITE, write_epw

    def dark(rows):  # no light below 3 deg (no cloud table needed), as the tests' clear_day
        for r in rows:
            t = (np.datetime64(f"{r[0]}-{int(r[1]):02d}-{int(r[2]):02d}T00:00").astype("datetime64[s]")
                 .astype(np.int64) + (int(r[3]) - 0.5) * 3600.0 - SITE["timezone"] * 3600.0)
            z = float(sun_position_unix(np.radians(SITE["latitude"]), np.radians(SITE["longitude"]), np.array([t]),
                                        apparent=False).zenith[0])
            if np.degrees(z) > 87.0:
                r[13] = r[14] = r[15] = "0"

    with tempfile.TemporaryDirectory() as tmp:
        path = write_epw(Path(tmp) / "june.epw", days=((6, 20, "clear"),), tweak=dark)
        for g in (0.8, 0.585):
            o = RetrievalOptions(aerosol_optical_depth_nodes=(0.0, 0.2, 0.5), tables="coarse",
                                 base=BASE.replace(mie_phase_g=g))
            t0 = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                h = retrieve_hourly_atmosphere(path, o)
            c = np.flatnonzero(h.status == CLEAR)
            print(f"base g {g}: {c.size} clear hours closed of {np.sum(np.isin(h.status, [CLEAR, CLEAR_OPEN]))} "
                  f"({time.process_time() - t0:.0f} CPU-s)")
            for i in c:
                print(f"  sun {90 - np.degrees(h.sun_zenith[i]):5.1f} deg: AOD {h.aerosol_optical_depth[i]:.3f}, "
                      f"albedo {h.single_scattering_albedo[i]:.3f}, g {h.aerosol_phase_g[i]:.3f}, "
                      f"DHI closure {h.dhi_closure[i]:.1e}")


if __name__ == "__main__":
    if "--phase-effect" in sys.argv:
        phase_effect()
    elif "--retrieval" in sys.argv:
        retrieval()
    else:
        args = sys.argv[1:]
        compare(args[0] if args else "coarse", args[1] if len(args) > 1 else "hg",
                int(args[2]) if len(args) > 2 else 16384)
