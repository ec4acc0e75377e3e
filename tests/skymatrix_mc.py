"""The spectral sky matrix's patches against the Monte Carlo through the same air and clouds (shared by the test
``tests/test_skymatrix_montecarlo.py`` and ``benchmarks/compare_spectral_skymatrix_montecarlo.py``).

What the Monte Carlo (``skyscatter.montecarlo.sky_radiance``, all orders, the sun's direct beam excluded) is run
through, per hour kind (the retrieval's status):

* clear: the family's base medium with the hour's retrieved aerosol optical depth and the matrix's closed aerosol
  albedo (``single_scattering_albedo`` of the Dataset: the value off the table nodes, not a node);
* overcast: the cloud table's air (its aerosol node) with the retrieved water layer (``CloudLayer`` 1000-1500 m,
  10 um droplets, the hour's optical depth at 550 nm: the layer ``CloudySky`` builds the table from);
* broken: ``(1 - f) MC_clear + f MC_overcast`` with the retrieved cloud fraction f: the same independent-pixel
  blend as the matrix, so the Monte Carlo checks the blend's two skies, not the blend as a model of a broken sky
  (a 3D cloud field of the file's cover would need a cloud size, shape and position that the record does not
  hold: every choice gives another sky per patch, so it cannot serve as a per-patch reference for the hour).

Everything is compared as reduced radiance (radiance over the extraterrestrial irradiance each one uses, per unit
eccentricity), at the points where the matrix evaluates its patches (``samples=1``: one equal-area cell per
patch, at mid sin(altitude) and mid azimuth; :func:`matrix_directions`). Those are not the patch centres of
``PatchScheme.centre_directions`` (mid altitude; the zenith for the cap): 1.4 deg lower in Tregenza's row at
78 deg, 3.4 deg off the zenith in the cap, which moves a clear sky's radiance by up to 13 % near the aureole.
"""

from __future__ import annotations

import time

import numpy as np

#: Relative sun-frame targets of the patch subset: altitudes [deg] x azimuths from the sun [deg], and the zenith.
PATCH_ALTITUDES = (6.0, 18.0, 30.0, 42.0, 54.0, 66.0)
PATCH_RELATIVE_AZIMUTHS = (0.0, 90.0, 180.0)


def patch_subset(dirs: np.ndarray, sun_azimuth: float) -> np.ndarray:
    """Indices of the patches nearest the targets (altitude x azimuth from the sun [deg], and the zenith): up to
    19 patches spread over the sky in the sun's frame (the principal plane towards and away from the sun and the
    plane across it); ``sun_azimuth`` [rad] from north towards east, ``dirs`` ENU unit vectors."""
    from skyscatter.conventions import direction_from_angles

    tz, ta = [0.0], [0.0]
    for alt in PATCH_ALTITUDES:
        for raz in PATCH_RELATIVE_AZIMUTHS:
            tz.append(np.radians(90.0 - alt))
            ta.append(sun_azimuth + np.radians(raz))
    targets = direction_from_angles(np.array(tz), np.array(ta))
    idx = np.argmax(targets @ dirs.T, axis=1)
    return np.array(sorted(set(int(k) for k in idx)))


def matrix_directions(scheme: str = "tregenza") -> np.ndarray:
    """Where the matrix evaluates each patch with ``samples=1`` (n_patches, 3) ENU unit vectors."""
    from skyscatter.patches import patch_scheme

    return patch_scheme(scheme).sample_directions(1)[:, 0]


def clear_air(h, i: int, ssa: float, phase_g: float | None = None):
    """The family's base medium with hour ``i``'s aerosol optical depth, albedo ``ssa`` and phase g (default:
    the base's)."""
    from skyscatter.precomputed.family import AXIS_SETTERS

    tau = float(h.aerosol_optical_depth[i])
    air = AXIS_SETTERS["aerosol_single_scattering_albedo"](AXIS_SETTERS["aerosol_optical_depth"](h.family.base, tau),
                                                          ssa)
    return air if phase_g is None or not np.isfinite(phase_g) else air.replace(mie_phase_g=float(phase_g))


def cloudy_air(h, i: int):
    """The cloud table's air with hour ``i``'s retrieved water layer."""
    from skyscatter.atmosphere.clouds import CloudLayer

    air = h.cloud_table.atmosphere
    layer = CloudLayer(1000.0, 1500.0, float(h.cloud_optical_depth[i]), effective_radius=10e-6)
    return air.replace(particles=(*air.particles, layer))


def mc_reduced(air, dirs, wl, sun_zenith, sun_azimuth, samples, seed, scheduler="synchronous"):
    """Reduced Monte Carlo radiance and standard error (n_dirs, n_wl) [sr^-1], paths run, CPU seconds."""
    from skyscatter.montecarlo import sky_radiance

    c0 = time.process_time()
    r = sky_radiance(air, dirs, wl, sun_zenith=float(sun_zenith), sun_azimuth=float(sun_azimuth), samples=int(samples),
                     seed=int(seed), scheduler=scheduler)
    e0 = air.solar_irradiance_at(wl)
    return r.radiance / e0, r.stderr / e0, int(np.min(r.samples) if np.ndim(r.samples) else r.samples), \
        time.process_time() - c0


def pool(a: tuple, b: tuple) -> tuple:
    """Pool two independent Monte Carlo estimates (mean, stderr, paths): weights by paths."""
    (m1, s1, n1), (m2, s2, n2) = a, b
    n = n1 + n2
    return (n1 * m1 + n2 * m2) / n, np.sqrt((n1 * s1) ** 2 + (n2 * s2) ** 2) / n, n


def parts_of(h, ds, i: int, kind: str):
    """[(weight, air)] of hour ``i``: the Monte Carlo skies whose weighted sum is the hour's sky."""
    f = float(h.cloud_fraction[i]) if kind == "broken" else (1.0 if kind == "overcast" else 0.0)
    out = []
    if f < 1.0:
        g = float(ds["aerosol_phase_g"].values[i]) if "aerosol_phase_g" in ds else None
        out.append((1.0 - f, "clear", clear_air(h, i, float(ds["single_scattering_albedo"].values[i]), g)))
    if f > 0.0:
        out.append((f, "overcast", cloudy_air(h, i)))
    return out


def ours_reduced(ds, i: int, patches: np.ndarray, band_index, e0_bands: np.ndarray, eccentricity: float):
    """The matrix's patch radiances of hour ``i`` over the band means of the extraterrestrial sun (n_p, n_wl)."""
    return ds["sky_radiance"].values[i][patches][:, band_index] / (e0_bands * eccentricity)


def band_e0(edges: np.ndarray, band_index) -> np.ndarray:
    """Band means of the 1 nm ASTM extraterrestrial spectrum [W m^-2 nm^-1] (the matrix's E0)."""
    from skyscatter.atmosphere.gas_absorption import broadband_solar_spectrum

    fw, fe = broadband_solar_spectrum()
    return np.array([np.interp(np.linspace(edges[b], edges[b + 1], 21), fw, fe).mean() for b in band_index])


def away_from_sun(dirs: np.ndarray, sun: np.ndarray, kind: str) -> np.ndarray:
    """Patches more than 5 deg (overcast parts: 10 deg, where the matrix puts the forward peak in the sun's patch)
    from the sun."""
    return (dirs @ sun) < np.cos(np.radians(5.0 if kind == "clear" else 10.0))
