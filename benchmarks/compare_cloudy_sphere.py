"""The cloudy sky (``CloudySky``, default coupling) against the spherical forward photons and the pooled backward paths.

Reads ``tests/data/cloudy_sphere_forward.json`` (``benchmarks/cloudy_sphere_reference.py``) and prints, per case,
the model's diffuse irradiance on the ground against the photons' centre ring (450 / 550 / 650 nm) with their
standard error, the ring's width as a bias bound (the curvature of ``E`` over the three rings, ``(de)^2 / 24
E''/E``), the photons against the pooled backward paths where they exist (``tests/cloudy_cct_reference.py``: sun 2
deg, optical depths 1, 5, 15) and at sun 10 deg and higher against the pooled forward photons of the periodic
domain, the radiance in each stored bin >= 10 deg above the horizon (the model averaged over the bin's solid angle,
6 x 6 points, against the photons' bin mean; per run set, and the run sets of the same bins pooled: their mean
difference per wavelength, as tests/test_cloudy_sphere.py holds it), and the CCT of the model against that of the
photons (``monte_carlo_cct``: the model's spectrum times the Monte Carlo / model ratio; Hernandez 1999). ``python
benchmarks/compare_cloudy_sphere.py [--json out.json]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

from skyscatter.sky.cloudy import CloudySky

HERE = Path(__file__).parents[1]
DEFAULT_DATA = str(HERE / "tests" / "data" / "cloudy_sphere_forward.json")
sys.path.insert(0, str(HERE / "tests"))
import cloudy_cct_reference as ref_mod  # noqa: E402


def bin_mean(sky: CloudySky, z0: float, z1: float, a0: float, a1: float, wl: list[float], n: int = 6) -> np.ndarray:
    """The model's radiance averaged over the solid angle of a bin of view zenith [z0, z1] and azimuth from the sun
    [a0, a1] (rad): ``tests/cloudy_cct_reference.py`` (``model_bin_mean``, which the tests use too)."""
    return ref_mod.model_bin_mean(sky, (z0, z1), (a0, a1), wl, n)


def _centre(z0: float, z1: float, a0: float, a1: float) -> np.ndarray:
    """The direction at a bin's centre (mid cosine, mid azimuth), (1, 3)."""
    mu = 0.5 * (np.cos(z0) + np.cos(z1))
    a = 0.5 * (a0 + a1)
    s = math.sqrt(1.0 - mu * mu)
    return np.array([[s * math.sin(a), s * math.cos(a), mu]])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=DEFAULT_DATA)
    ap.add_argument("--json", default=None, help="also write the figures here")
    a = ap.parse_args()
    data = json.loads(Path(a.data).read_text())
    fine = ref_mod.FINE
    rows = []
    keys = sorted({(c["tau"], c["sun_elevation_deg"]) for c in data["cases"]}, key=lambda k: (-k[1], k[0]))
    for tau, sun in keys:
        sets = [c for c in data["cases"] if (c["tau"], c["sun_elevation_deg"]) == (tau, sun)]
        case = sets[0]
        wl = ref_mod.WAVELENGTHS
        # the diffuse irradiance pooled over the runs of every seed (photon-weighted; tests/cloudy_cct_reference.py;
        # a run set may hold some of the wavelengths only)
        pooled = [ref_mod.pooled([(np.array(r["diffuse_irradiance"]), np.array(r["diffuse_irradiance_stderr"]),
                                   r["photons"]) for c in sets for r in c["runs"] if r["wavelength_nm"] == w])
                  for w in wl]
        three = np.array([p[0] for p in pooled])                    # (wl, 3 rings)
        mc = three[:, 1]
        mce = np.array([p[1][1] for p in pooled])
        photons = [p[2] for p in pooled]
        de = math.radians(case["ring_edges_deg"][2] - case["ring_edges_deg"][1])
        curv = (three[:, 0] - 2 * three[:, 1] + three[:, 2]) / de ** 2 / three[:, 1]
        width_bias = de ** 2 / 24 * np.abs(curv)
        sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau, cloud_base=data["cloud_base_m"],
                        cloud_top=data["cloud_top_m"], ground_albedo=data["ground_albedo"])
        model = sky.diffuse_fluxes(wl)[0]
        spectrum = sky.diffuse_fluxes(fine)[0]
        t_model, t_mc, t_sig = ref_mod.monte_carlo_cct(spectrum, model, mc, mce)
        row = {"tau": tau, "sun": sun, "mc": mc.tolist(), "mc_stderr": mce.tolist(), "model": model.tolist(),
               "diff": (model / mc - 1).tolist(), "width_bias": width_bias.tolist(),
               "cct_model": t_model, "cct_mc": t_mc, "cct_sigma": t_sig, "photons": photons,
               "seeds": [c["seed"] for c in sets],
               "cpu_seconds": sum(r["cpu_seconds"] for c in sets for r in c["runs"])}
        ref = ref_mod.reference(tau, sun) if (sun < 5.0 and tau in (1.0, 5.0, 15.0)) or sun >= 10.0 else None
        if ref is not None:
            row["backward"] = ref[0].tolist()
            row["backward_stderr"] = ref[1].tolist()
            row["photons_vs_backward"] = (mc / ref[0] - 1).tolist()
            row["photons_vs_backward_sigma"] = ((mc - ref[0]) / np.hypot(mce, ref[1])).tolist()
        bins = []
        for c in sets:   # the radiance per run (each run its own bins)
            ze = np.radians(c["view_zenith_edges_deg"])
            na = c["azimuth_bins"]
            ae = np.linspace(0.0, math.pi, na + 1)
            if c["wavelengths_nm"] != wl:
                continue   # the radiance is compared for the run sets of all three wavelengths
            rad = np.array([r["radiance"] for r in c["runs"]])            # (wl, nz, na)
            rade = np.array([r["radiance_stderr"] for r in c["runs"]])
            for j in range(ze.size - 1):
                if math.degrees(math.pi / 2 - ze[j + 1]) < 10.0 - 1e-9:
                    continue
                for k in range(na):
                    lm = bin_mean(sky, ze[j], ze[j + 1], ae[k], ae[k + 1], wl)
                    # the bin's size as a bias of its mean read as the radiance at its centre: the model's own
                    lc = sky.spectral_radiance(
                        _centre(ze[j], ze[j + 1], ae[k], ae[k + 1]), wl)[0]
                    bins.append({"seed": c["seed"], "zenith_deg": [math.degrees(ze[j]), math.degrees(ze[j + 1])],
                                 "azimuth_deg": [math.degrees(ae[k]), math.degrees(ae[k + 1])],
                                 "mc": rad[:, j, k].tolist(), "mc_stderr": rade[:, j, k].tolist(),
                                 "model": lm.tolist(), "diff": (lm / rad[:, j, k] - 1).tolist(),
                                 "size_effect": (lm / lc - 1).tolist()})
        row["radiance_bins"] = bins
        # the run sets of the same bins pooled (tests/cloudy_cct_reference.py, as tests/test_cloudy_sphere.py reads
        # them): the bins' relative differences per wavelength, mean and largest abs
        pooled_bins = ref_mod.sphere_radiance_bins(tau, sun) if a.data == DEFAULT_DATA else []
        pd = np.array([ref_mod.model_bin_mean(sky, z, az, wl) / m - 1 for z, az, m, _, _ in pooled_bins])
        row["radiance_pooled_diff"] = pd.tolist()
        rows.append(row)
        dl = np.array([b["diff"] for b in bins])
        rel = np.array([np.array(b["mc_stderr"]) / np.array(b["mc"]) for b in bins])
        size = np.max(np.abs([b["size_effect"] for b in bins]))
        kind = ref[3] if ref is not None else ""
        bw = (f" | photons vs pooled {kind} " + " / ".join(f"{100 * v:+.1f}" for v in row["photons_vs_backward"])
              + " % (" + " / ".join(f"{v:+.1f}" for v in row["photons_vs_backward_sigma"]) + " sigma)") \
            if "backward" in row else ""
        print(f"| {tau:g} | {sun:g} | {' / '.join(f'{100 * v:+.1f}' for v in row['diff'])} % | "
              f"{' / '.join(f'{100 * v:.1f}' for v in mce / mc)} % | "
              f"{' / '.join(f'{100 * v:.2f}' for v in width_bias)} % | "
              f"{np.median(np.abs(dl)) * 100:.1f} %, {np.max(np.abs(dl)) * 100:.1f} % ({np.median(rel) * 100:.1f} %; "
              f"bin size {size * 100:.1f} %) | "
              f"{t_model:.0f} / {t_mc:.0f} +- {t_sig:.0f} K ({t_model - t_mc:+.0f}) |{bw}", flush=True)
        if pd.size:
            print(f"    pooled bins ({len(pooled_bins)}): mean per wavelength "
                  + " / ".join(f"{100 * v:+.1f}" for v in pd.mean(axis=0)) + " %, largest abs "
                  + " / ".join(f"{100 * v:.1f}" for v in np.abs(pd).max(axis=0)) + " %", flush=True)
    print(f"load average {os.getloadavg()}")
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
