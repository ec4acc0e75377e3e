"""The Monte Carlo's correlated colour temperature (CCT) of the diffuse light on the ground under a cloud layer,
with its uncertainty, from the stored Monte Carlo references (docs/clouds.md, "Accuracy against the Monte Carlo").

The Monte Carlo stores the diffuse irradiance at three wavelengths only (450 / 550 / 650 nm), so its CCT is that
of the model's diffuse spectrum ``S(lambda)`` (380-780 nm every 5 nm) times the Monte Carlo / model ratio
``r(lambda)`` interpolated linearly between the three wavelengths (constant beyond them, ``numpy.interp``); the
CCT of a spectrum is that of its CIE 1931 chromaticity by Hernandez-Andres, Lee & Romero (1999), Appl. Opt. 38,
5703 (their Eq. 2, through colour-science's ``xy_to_CCT(..., method="Hernandez 1999")``).

Its uncertainty: the three ratios are drawn independently from normal distributions with the Monte Carlo's
standard errors (``r_k = (E_k + sigma_k z_k) / M_k``, ``z_k`` standard normal; the three wavelengths of a hero
group share their paths, so this ignores their correlation, which makes the spread of the colour larger, not
smaller), and the standard deviation of the draws' CCTs is the CCT's standard error. XYZ is linear in the
ratios (``X = sum_k r_k X_k`` with ``X_k`` the XYZ of ``S`` times the k-th hat function of the interpolation),
so a draw costs a 3 x 3 product.

The references, per case (cloud optical depth, sun elevation), each pooled over its independent runs (different
seeds, the same estimator) as the photon-weighted mean ``sum n_i E_i / N`` with standard error
``sqrt(sum n_i^2 sigma_i^2) / N``:

* sun 60 deg: the forward photons of ``cloudy_montecarlo.json`` (16384, seed 2201);
* sun 30 deg: those and the two 131072-photon runs of ``cloudy_sun30_forward.json`` (seeds 31, 32);
* sun 10 deg: those and the runs of ``cloudy_low_sun.json`` at the Earth's radius (65536-photon seeds 21, 22 for
  optical depths 1 and 15; 131072-photon seeds 61-66 for 30 and 60);
* sun 2 deg: backward paths (the forward photons' periodic domain is 7-34 % off in a sphere there): the stored
  ones of ``cloudy_montecarlo.json`` (400000 paths, seed 41, for optical depths 1 and 5; 20000, seed 77, for
  15-60) and the backward runs of ``cloudy_low_sun.json`` at the Earth's radius (400000 paths each: optical depth
  5 seeds 51-63, 15 seeds 71, 72, 77, 78); fewer than 400000 paths in all is no reference (their heavy tail,
  docs/clouds.md "The sun 2 deg high").

The runs of 2026-12-02 (``cloudy_montecarlo.json``, ``cloudy_sun30_forward.json``, seeds 21 and 22) were traced
with the droplets' Mie optics on the size quadrature of then (24 nodes per e, whose aliased phase function the
model no longer has); those of 2026-12-04 (seeds 51-66) with the resolved optics. The model with the old optics
(``benchmarks/cloudy_cct.py --aliased-optics``) moves the CCT difference by 3-31 K (the current optics the bluer
against these runs), a small share of the 200 K.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

DATA_DIR = Path(__file__).parent / "data"
MONTECARLO = json.loads((DATA_DIR / "cloudy_montecarlo.json").read_text())
SUN30 = json.loads((DATA_DIR / "cloudy_sun30_forward.json").read_text())
LOW_SUN = json.loads((DATA_DIR / "cloudy_low_sun.json").read_text())
WAVELENGTHS = MONTECARLO["wavelengths_nm"]
#: the model's diffuse spectrum is taken on this grid [nm]
FINE = np.arange(380.0, 781.0, 5.0)
#: fewest backward paths that make a reference at sun 2 deg (docs/clouds.md, "The sun 2 deg high")
MIN_BACKWARD_PATHS = 400000


def pooled(runs: list[tuple[list[float], list[float], int]]) -> tuple[np.ndarray, np.ndarray, int]:
    """Photon-weighted mean of independent runs ``(values, stderr, n)``, its standard error and the total count."""
    n = np.array([r[2] for r in runs], dtype=float)
    vals = np.array([r[0] for r in runs], dtype=float)
    errs = np.array([r[1] for r in runs], dtype=float)
    total = n.sum()
    return (n[:, None] * vals).sum(axis=0) / total, np.sqrt(((n[:, None] * errs) ** 2).sum(axis=0)) / total, \
        int(total)


def _earth_cases(data: dict, tau: float, sun: float) -> list[dict]:
    return [c for c in data["cases"] if (c["air"], c["tau"], c["sun_elevation_deg"], c["radius_scale"])
            == ("earth", tau, sun, 1.0)]


def reference_runs(tau: float, sun: float) -> tuple[list[tuple[list[float], list[float], int]], str]:
    """The independent Monte Carlo runs of the diffuse irradiance [W m^-2 nm^-1] of a case and the estimator."""
    stored = next(c for c in MONTECARLO["cases"] if (c["tau"], c["sun_elevation_deg"]) == (tau, sun))
    if sun < 5.0:
        runs = [(stored["diffuse_irradiance_backward"], stored["diffuse_irradiance_backward_stderr"],
                 stored["backward_paths"])]
        for c in _earth_cases(LOW_SUN, tau, sun):
            runs += [(r["diffuse_irradiance"], r["diffuse_irradiance_stderr"], r["paths"])
                     for r in c.get("backward", [])]
        return runs, "backward"
    runs = [(stored["diffuse_irradiance"], stored["diffuse_irradiance_stderr"], stored["photons"])]
    extra = SUN30 if sun == 30.0 else LOW_SUN if sun == 10.0 else None
    if extra is not None:
        for c in _earth_cases(extra, tau, sun):
            runs += [(r["diffuse_irradiance"], r["diffuse_irradiance_stderr"], r["photons"]) for r in c["forward"]]
    return runs, "forward"


def between_runs_stderr(runs: list[tuple[list[float], list[float], int]]) -> np.ndarray:
    """Standard error of the pooled mean from the scatter of the runs' means about it (three or more runs).

    ``sqrt(k / (k - 1) * sum w_i^2 (E_i - E)^2)`` with ``w_i = n_i / N``: unlike the runs' own standard errors it
    sees the rare large contributions that most runs of a heavy-tailed estimator miss (docs/clouds.md, "The sun
    2 deg high")."""
    mean, _, total = pooled(runs)
    w = np.array([r[2] for r in runs], dtype=float) / total
    dev = np.array([r[0] for r in runs], dtype=float) - mean[None, :]
    k = len(runs)
    return np.sqrt(k / (k - 1) * ((w[:, None] * dev) ** 2).sum(axis=0))


def reference(tau: float, sun: float) -> tuple[np.ndarray, np.ndarray, int, str] | None:
    """Pooled reference (mean, standard error, photons or paths, estimator), or None where there is none.

    Backward paths (heavy-tailed at a grazing sun): the standard error is the larger of the pooled one and the
    runs' scatter (:func:`between_runs_stderr`) where there are three runs or more."""
    runs, kind = reference_runs(tau, sun)
    mean, err, n = pooled(runs)
    if kind == "backward" and n < MIN_BACKWARD_PATHS:
        return None
    if kind == "backward" and len(runs) >= 3:
        err = np.maximum(err, between_runs_stderr(runs))
    return mean, err, n, kind


def cct_from_xy(xy: np.ndarray) -> np.ndarray:
    """CCT [K] of CIE 1931 chromaticities ``xy`` (..., 2), Hernandez-Andres, Lee & Romero (1999), Eq. 2."""
    import colour

    return np.asarray(colour.temperature.xy_to_CCT(xy, method="Hernandez 1999"), dtype=float)


def monte_carlo_cct(spectrum: np.ndarray, model: np.ndarray, mc: np.ndarray, mc_stderr: np.ndarray,
                    draws: int = 4000, seed: int = 0) -> tuple[float, float, float]:
    """(CCT of the model, CCT of the Monte Carlo, its standard error) [K] (module docstring).

    Parameters
    ----------
    spectrum : (len(FINE),) ndarray
        The model's diffuse irradiance on the ground at :data:`FINE` [W m^-2 nm^-1].
    model, mc, mc_stderr : (3,) ndarray
        The model's and the Monte Carlo's diffuse irradiance and the latter's standard error at
        :data:`WAVELENGTHS` [W m^-2 nm^-1].
    draws : int
        Normal draws of the three ratios for the standard error.
    seed : int
        Seed of those draws (the result is reproducible).
    """
    from skyscatter.spectral import spectrum_to_xyz, xyz_to_chromaticity

    hats = np.array([np.interp(FINE, WAVELENGTHS, np.eye(3)[k]) for k in range(3)])   # sum over k is 1
    basis = spectrum_to_xyz(spectrum[None, :] * hats, FINE)                             # (3 ratios, XYZ)
    ratio = mc / model
    z = np.random.default_rng(seed).standard_normal((draws, 3))
    drawn = (mc[None, :] + z * mc_stderr[None, :]) / model[None, :]
    xy_model = np.asarray(xyz_to_chromaticity(spectrum_to_xyz(spectrum, FINE)))[:2]
    xy_mc = np.asarray(xyz_to_chromaticity(ratio @ basis))[:2]
    xy_draws = np.asarray(xyz_to_chromaticity(drawn @ basis))[..., :2]
    return float(cct_from_xy(xy_model)), float(cct_from_xy(xy_mc)), float(np.std(cct_from_xy(xy_draws)))


#: forward photons through the whole sphere (benchmarks/cloudy_sphere_reference.py), the low sun's reference
SPHERE = json.loads((DATA_DIR / "cloudy_sphere_forward.json").read_text())


def sphere_reference(tau: float, sun: float) -> tuple[np.ndarray, np.ndarray, int] | None:
    """The spherical forward photons' diffuse irradiance [W m^-2 nm^-1] at :data:`WAVELENGTHS` on the ring centred
    on the sun's elevation, pooled over the stored seeds (:func:`pooled`), its standard error and the fewest photons
    of a wavelength; None where none is stored."""
    sets = [c for c in SPHERE["cases"] if (c["tau"], c["sun_elevation_deg"]) == (tau, sun)]
    if not sets:
        return None
    per_wl = []
    for w in WAVELENGTHS:   # a stored run set may hold some of the wavelengths only
        runs = [(r["diffuse_irradiance"], r["diffuse_irradiance_stderr"], r["photons"]) for c in sets
                for r in c["runs"] if r["wavelength_nm"] == w]
        per_wl.append(pooled(runs))
    return (np.array([p[0][1] for p in per_wl]), np.array([p[1][1] for p in per_wl]), int(min(p[2] for p in per_wl)))


def sphere_radiance_bins(tau: float, sun: float, min_elevation_deg: float = 10.0
                         ) -> list[tuple[tuple[float, float], tuple[float, float], np.ndarray, np.ndarray, int]]:
    """The spherical forward photons' radiance [W m^-2 sr^-1 nm^-1] at :data:`WAVELENGTHS` in the stored bins of
    view zenith and azimuth from the sun's vertical plane whose lowest direction is ``min_elevation_deg`` [deg] or
    more above the horizon (the centre ring's bin means, ``benchmarks/cloudy_sphere_reference.py``).

    Run sets with the same bins and all three wavelengths are pooled (:func:`pooled`); per bin: (view zenith edges
    [rad], azimuth edges [rad], mean (3,), standard error (3,), photons of the fewest-photon wavelength)."""
    layouts: dict[tuple, list[dict]] = {}
    for c in SPHERE["cases"]:
        if (c["tau"], c["sun_elevation_deg"]) == (tau, sun) and c["wavelengths_nm"] == WAVELENGTHS:
            layouts.setdefault((tuple(c["view_zenith_edges_deg"]), c["azimuth_bins"]), []).append(c)
    out = []
    for (zenith_deg, azimuth_bins), sets in layouts.items():
        ze = np.radians(zenith_deg)
        ae = np.linspace(0.0, np.pi, azimuth_bins + 1)
        per_wl = [pooled([(np.ravel(r["radiance"]), np.ravel(r["radiance_stderr"]), r["photons"]) for c in sets
                          for r in c["runs"] if r["wavelength_nm"] == w]) for w in WAVELENGTHS]
        mean = np.array([p[0] for p in per_wl]).reshape(3, ze.size - 1, azimuth_bins)
        err = np.array([p[1] for p in per_wl]).reshape(3, ze.size - 1, azimuth_bins)
        n = min(p[2] for p in per_wl)
        for j in range(ze.size - 1):
            if 90.0 - np.degrees(ze[j + 1]) < min_elevation_deg - 1e-9:
                continue
            for k in range(azimuth_bins):
                out.append(((float(ze[j]), float(ze[j + 1])), (float(ae[k]), float(ae[k + 1])), mean[:, j, k],
                            err[:, j, k], n))
    return out


def model_bin_mean(sky, zenith: tuple[float, float], azimuth: tuple[float, float], wavelengths: list[float],
                   n: int = 6) -> np.ndarray:
    """A sky model's radiance [W m^-2 sr^-1 nm^-1] averaged over the solid angle of a bin of view zenith and
    azimuth from the sun (sun at azimuth 0, north) [rad]: ``n x n`` midpoints uniform in cos(zenith) and in
    azimuth (equal solid angles), (len(wavelengths),)."""
    mu = np.cos(zenith[0]) + (np.cos(zenith[1]) - np.cos(zenith[0])) * (np.arange(n) + 0.5) / n
    az = azimuth[0] + (azimuth[1] - azimuth[0]) * (np.arange(n) + 0.5) / n
    m, a = np.meshgrid(mu, az, indexing="ij")
    s = np.sqrt(1.0 - m * m)
    d = np.stack([s * np.sin(a), s * np.cos(a), m], axis=-1).reshape(-1, 3)
    return np.asarray(sky.spectral_radiance(d, wavelengths)).mean(axis=0)
