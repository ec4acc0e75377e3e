"""Radiance's cloud blend (genssky at full cloud cover) against the Monte Carlo under cloud layers, beside the
cloudy sky: ground diffuse irradiance at 450 / 550 / 650 nm, radiance 10 deg or more above the horizon, CCT
(docs/clouds.md, "Genssky's blend against the same Monte Carlo").

The Monte Carlo values are those of ``tests/data/cloudy_montecarlo.json`` (``cloudy_montecarlo_reference.py``:
water cloud 1000-1500 m, r_e 10 um, Earth air, ground albedo 0.2) and their reference diffuse irradiance is the
one ``compare_cloudy_montecarlo.py`` uses (forward photons at sun 30 and 60 deg, backward paths at 2 deg).

genssky (pyradiance's build of Radiance 6) is run twice per sun elevation at 45 deg N on June 21 in solar time
(``+H``, the hour giving that elevation), cloud cover 1 (``-c 1``), ground reflectance 0.2:

* alone: its sky is then the CIE overcast ``(1 + 2 sin h) / 3`` with the zenith brightness
  ``(8.6 sin(h_sun) + 0.123) / 0.203 W m^-2 sr^-1`` (Krochmann's zenith luminance in kcd m^-2 over genssky's
  efficacy of 203 lm/W) and the fixed spectrum ``D6415`` (genssky.c; it does not depend on the cloud);
* scaled: ``-L 0 E_v`` with ``E_v`` the Monte Carlo's diffuse illuminance (the cloudy model's diffuse spectrum
  380-780 nm times the Monte Carlo / model ratio interpolated between the three wavelengths), the way a user
  matches genssky to a measured diffuse illuminance.

The 20-band sky picture (``<name>_sky.hsr``: equirectangular, rows at altitudes ``90 - 180 j / (rows - 1)`` deg,
samples in the order of its ``WAVELENGTH_SPLITS`` header, values spectral radiance times ``WVLSPAN`` = 400 nm) is
read here directly (uncompressed 21-byte spectral colours), its azimuth mean integrated into the horizontal
irradiance, read at the Monte Carlo's view elevations and converted to a CCT (Hernandez 1999 through
colour-science). Checked against genssky's own formula (the alone run's irradiance equals ``7 pi / 9`` times the
zenith radiance within the picture's 1 % mantissa steps).

``python benchmarks/genssky_montecarlo.py [--data FILE] [--keep DIR]`` (first run: genssky precomputes its
clear-sky tables, 2-5 min; ``--keep`` reuses them).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).parents[1]
LATITUDE = 45.0
WVLSPAN = 400.0  # genssky's spectral span [nm] (atmos.c)
D6415_MEAN = 1.03133  # the mean of genssky.c's 20-band overcast spectrum D6415


def solar_hour(elevation_deg: float, latitude_deg: float = LATITUDE, declination_deg: float = 23.44) -> float:
    """Morning solar hour at which the sun stands ``elevation_deg`` high (the sunrise-side root)."""
    la, de = math.radians(latitude_deg), math.radians(declination_deg)
    c = (math.sin(math.radians(elevation_deg)) - math.sin(la) * math.sin(de)) / (math.cos(la) * math.cos(de))
    return 12.0 - math.degrees(math.acos(max(-1.0, min(1.0, c)))) / 15.0


def read_hsr(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(altitudes [deg] (rows,), wavelengths [nm] (n,), spectral radiance [W m^-2 sr^-1 nm^-1] (rows, cols, n))."""
    raw = path.read_bytes()
    end = raw.index(b"\n\n")
    header = raw[:end].decode("ascii", "replace").splitlines()
    ncomp = next(int(h.split("=")[1]) for h in header if h.startswith("NCOMP="))
    split = next([float(x) for x in h.split("=")[1].split()] for h in header if h.startswith("WAVELENGTH_SPLITS="))
    rest = raw[end + 2:]
    eol = rest.index(b"\n")
    res = rest[:eol].decode().split()
    if res[0] != "-Y" or res[2] != "+X":
        raise ValueError(f"unexpected resolution string {res}")
    rows, cols = int(res[1]), int(res[3])
    data = np.frombuffer(rest[eol + 1:eol + 1 + rows * cols * (ncomp + 1)], dtype=np.uint8)
    data = data.reshape(rows, cols, ncomp + 1).astype(float)
    expo = data[..., -1:]
    vals = np.where(expo > 0, (data[..., :-1] + 0.5) * np.ldexp(1.0, (expo - 136).astype(int)), 0.0)
    step = (split[3] - split[0]) / ncomp  # Radiance's setscolor(): sample i at split[0] + (i + 1/2) step
    wl = split[0] + (np.arange(ncomp) + 0.5) * step
    order = np.argsort(wl)
    alt = 90.0 - 180.0 * np.arange(rows) / (rows - 1)
    return alt, wl[order], vals[..., order] / WVLSPAN


def genssky(tmp: Path, elevation: float, name: str, difhor: float | None = None) -> tuple[float, Path]:
    """Run genssky; (the sun's elevation it used [deg], the sky picture)."""
    import pyradiance

    root = Path(pyradiance.__file__).parent
    env = dict(os.environ, RAYPATH=f".{os.pathsep}{root / 'lib'}")
    cmd = [str(root / "bin" / "genssky"), "6", "21", f"+{solar_hour(elevation):.5f}", "-a", f"{LATITUDE:g}",
           "-c", "1.0", "-g", "0.2", "-n", "1", "-f", name]
    if difhor is not None:
        cmd += ["-L", "0", f"{difhor:.6g}"]
    out = subprocess.run(cmd, cwd=tmp, env=env, capture_output=True, text=True, check=True).stdout
    sun = next(line for line in out.splitlines() if line.startswith("4 "))
    dz = float(sun.split()[3])
    return math.degrees(math.asin(dz)), tmp / f"{name}_sky.hsr"


def picture_quantities(path: Path, wl_out, view_elevations):
    """Diffuse irradiance on the ground [W m^-2 nm^-1] at ``wl_out``, radiance at ``view_elevations`` [deg]
    (azimuth means: the blend at cover 1 has no azimuth dependence), the full irradiance spectrum and its
    wavelengths, the zenith radiance spectrum."""
    alt, wl, rad = read_hsr(path)
    mean = rad.mean(axis=1)  # (rows, n)
    up = alt >= 0
    h = np.radians(np.linspace(0.0, 90.0, 901))
    prof = np.array([np.interp(np.degrees(h), alt[up][::-1], mean[up][::-1, k]) for k in range(wl.size)]).T
    w = np.sin(h) * np.cos(h)
    irr = 2.0 * math.pi * np.trapezoid(prof * w[:, None], h, axis=0)  # (n,)
    e_out = np.interp(wl_out, wl, irr)
    l_views = np.array([[np.interp(v, alt[up][::-1], mean[up][::-1, k]) for k in range(wl.size)]
                        for v in view_elevations]).reshape(len(view_elevations), wl.size)
    l_out = np.array([np.interp(wl_out, wl, row) for row in l_views]).reshape(len(view_elevations), len(wl_out))
    return e_out, l_out, irr, wl, mean[0]


def main() -> None:
    import sys

    sys.path.insert(0, str(HERE / "benchmarks"))
    from compare_cloudy_montecarlo import cct, reference_diffuse
    from skyscatter.sky.cloudy import CloudySky
    from skyscatter.spectral import spectrum_to_xyz

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(HERE / "tests" / "data" / "cloudy_montecarlo.json"))
    ap.add_argument("--keep", default=None, help="folder for genssky's tables and pictures (kept)")
    a = ap.parse_args()
    data = json.loads(Path(a.data).read_text())
    wl = np.array(data["wavelengths_nm"])
    fine = np.arange(380.0, 781.0, 5.0)
    tmp = Path(a.keep) if a.keep else Path(tempfile.mkdtemp(prefix="genssky_mc_"))
    tmp.mkdir(parents=True, exist_ok=True)
    cases = [c for c in data["cases"] if c["tau"] > 0]
    alone = {}
    print("| optical depth | sun | genssky alone: E_d vs MC (450 / 550 / 650 nm) | genssky -L E_v(MC): E_d vs MC | "
          "radiance >= 10 deg vs MC, -L (MC median stderr) | cloudy model: E_d vs MC | CCT genssky / model / MC |")
    print("|---|---|---|---|---|---|---|")
    for case in sorted(cases, key=lambda c: (-c["sun_elevation_deg"], c["tau"])):
        tau, sun = case["tau"], case["sun_elevation_deg"]
        mc_e, mc_ee, kind = reference_diffuse(case)
        if mc_e is None:
            continue
        if sun not in alone:
            used, pic = genssky(tmp, sun, f"alone{sun:g}")
            alone[sun] = (used, picture_quantities(pic, wl, []))
            e_alone, _, irr, gwl, zen = alone[sun][1]
            zb = (8.6 * math.sin(math.radians(used)) + 0.123) / 0.203  # genssky.c's zenith brightness [W m^-2 sr^-1]
            print(f"<!-- genssky sun {used:.2f} deg (asked {sun:g}): irradiance / (7 pi / 9 zenith) = "
                  f"{np.sum(irr) / np.sum(zen) / (7 * math.pi / 9):.4f}; zenith broadband "
                  f"{np.sum(zen) * 20.0:.3f} W m^-2 sr^-1 vs the formula times mean(D6415) {zb * D6415_MEAN:.3f} -->")
        used, (e_alone, _, _, _, _) = alone[sun]
        sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau, cloud_base=data["cloud_base_m"],
                        cloud_top=data["cloud_top_m"], ground_albedo=data["ground_albedo"])
        model_e = sky.diffuse_fluxes(wl)[0]
        s_model = sky.diffuse_fluxes(fine)[0]
        s_mc = s_model * np.interp(fine, wl, mc_e / model_e)
        ev = float(spectrum_to_xyz(s_mc, fine)[1])
        views = [v for v in case.get("views_deg", []) if v[0] >= 10.0]
        keep = [i for i, v in enumerate(case.get("views_deg", [])) if v[0] >= 10.0]
        _, pic = genssky(tmp, sun, f"t{tau:g}s{sun:g}", difhor=ev)
        e_l, l_l, irr_l, gwl, _ = picture_quantities(pic, wl, [v[0] for v in views])
        rad_text = "-"
        if keep:
            mc_l = np.array(case["radiance"])[keep]
            mc_le = np.array(case["radiance_stderr"])[keep]
            d_l = l_l / mc_l - 1.0
            rad_text = (f"median {np.median(d_l) * 100:+.0f} %, range {d_l.min() * 100:+.0f}..{d_l.max() * 100:+.0f} % "
                        f"({np.median(mc_le / mc_l) * 100:.0f} %)")
        gs_fine = np.interp(fine, gwl, irr_l)
        fmt = lambda d: " / ".join(f"{100 * v:+.0f}" for v in d)  # noqa: E731
        print(f"| {tau:g} | {sun:g} ({kind}) | {fmt(e_alone / mc_e - 1)} % | {fmt(e_l / mc_e - 1)} % "
              f"(E_v {ev / 1000:.2f} klx) | {rad_text} | {' / '.join(f'{100 * v:+.1f}' for v in model_e / mc_e - 1)} % "
              f"| {cct(gs_fine, fine):.0f} / {cct(s_model, fine):.0f} / {cct(s_mc, fine):.0f} K |", flush=True)
    print(f"<!-- load average {os.getloadavg()} -->")


if __name__ == "__main__":
    main()
