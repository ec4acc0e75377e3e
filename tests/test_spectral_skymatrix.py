"""Spectral sky matrices from weather files (issue 24): broadband pieces, retrieval, matrix, outputs, sites, CLI.

The weather file is made here (tests/weather_synth.py): a clear day from pvlib's SPECTRL2 (an independent
clear-sky model) at a known aerosol optical depth, a broken and an overcast day. The tables are the "coarse"
preset over a 3 x 2 grid (six small builds, shared by the tests of the session).
"""

from __future__ import annotations

import itertools
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from skyscatter.errors import FileFormatError, InvalidParameterError  # noqa: E402
from weather_synth import CLEAR_AOD, FILE_AOD_BROADBAND, write_epw  # noqa: E402

pytest.importorskip("xarray")
pvlib = pytest.importorskip("pvlib")
from spectrl2_clear import clear_ground_spectra, spectrl2_air  # noqa: E402

AOD_NODES = (0.0, 0.2, 0.5)


def dark_below_cloud_table(rows):
    """``write_epw`` tweak: no light in the hours whose sun is below 3 deg (the cloud table's last zenith, 87 deg).
    A clear day then has no cloudy hour, so its retrieval needs no cloud table: the clear-day files of the tests
    below would otherwise each build one for their own aerosol (108 DISORT solves, about a minute)."""
    from skyscatter.sun.position import sun_position_unix
    from weather_synth import SITE

    for r in rows:
        t = (np.datetime64(f"{r[0]}-{int(r[1]):02d}-{int(r[2]):02d}T00:00").astype("datetime64[s]").astype(np.int64)
             + (int(r[3]) - 0.5) * 3600.0 - SITE["timezone"] * 3600.0)
        z = float(sun_position_unix(np.radians(SITE["latitude"]), np.radians(SITE["longitude"]), np.array([t]),
                                    apparent=False).zenith[0])
        if np.degrees(z) > 87.0:
            r[13] = r[14] = r[15] = "0"


def clear_day(path, tweak=None):
    """The clear day of ``write_epw`` without light below 3 deg (:func:`dark_below_cloud_table`), then ``tweak``."""
    def both(rows):
        dark_below_cloud_table(rows)
        if tweak is not None:
            tweak(rows)

    return write_epw(path, days=((6, 20, "clear"),), tweak=both)


@pytest.fixture(scope="module")
def options():
    from skyscatter.fit.weather import RetrievalOptions

    return RetrievalOptions(aerosol_optical_depth_nodes=AOD_NODES, tables="coarse")


@pytest.fixture(scope="module")
def epw(tmp_path_factory):
    return write_epw(tmp_path_factory.mktemp("weather") / "synth.epw")


@pytest.fixture(scope="module")
def hourly(epw, options):
    import warnings

    from skyscatter.fit.weather import retrieve_hourly_atmosphere

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return retrieve_hourly_atmosphere(epw, options)


@pytest.fixture(scope="module")
def matrix(hourly):
    from skyscatter.fit.spectral_matrix import spectral_sky_matrix

    return spectral_sky_matrix(None, scheme="tregenza", samples=1, atmosphere=hourly)


# ------------------------------------------------------------------ broadband pieces


def test_slant_masses_against_kasten_and_the_tables():
    """The medium's optical masses: within 0.6 % of Kasten (1966; with refraction) up to 80 deg, and the
    transmittance exp(-sum tau m) equal to the precomputed tables' (independent numba quadrature) within 0.3 %."""
    from skyscatter.atmosphere import AtmosphereParameters
    from skyscatter.atmosphere.airmass import relative_optical_mass
    from skyscatter.atmosphere.gas_absorption import slant_optical_masses
    from skyscatter.fit.weather import COARSE_SIZES
    from skyscatter.precomputed import cached_atmosphere

    p = AtmosphereParameters.from_aerosol_optical_depth(0.3, 1.3)
    z = np.radians([0.0, 30.0, 60.0, 75.0, 80.0])
    m = slant_optical_masses(p, z)
    assert m.rayleigh[0] == pytest.approx(1.0, abs=1e-9)
    np.testing.assert_allclose(m.rayleigh, relative_optical_mass(z), rtol=6e-3)
    assert np.all(np.diff(m.aerosol) > 0) and m.aerosol[-1] > m.rayleigh[-1]  # low layer: longer slant path
    wl = np.array([450.0, 550.0, 700.0])
    atm = cached_atmosphere(p, wavelengths=wl, sizes=dict(COARSE_SIZES, transmittance_mu=256, transmittance_r=64),
                            orders=1, progress=False)
    th = p.thickness
    tau = (np.outer(m.rayleigh, p.rayleigh_scattering_at(wl) * p.rayleigh_density.column(th))
           + np.outer(m.aerosol, p.mie_extinction_at(wl) * p.mie_density.column(th))
           + np.outer(m.ozone, p.ozone_absorption_at(wl) * p.ozone_density.column(th)))
    ours = np.exp(-tau)
    tables = atm.transmittance(np.full(z.size, p.bottom_radius), np.cos(z))
    np.testing.assert_allclose(ours, tables, rtol=3e-3)


def test_precipitable_water_matches_pvlib():
    """Gueymard (1994) against pvlib's implementation (same published formula)."""
    from skyscatter.fit.weather import precipitable_water_gueymard1994

    t = np.array([-10.0, 5.0, 20.0, 35.0])
    rh = np.array([80.0, 50.0, 60.0, 30.0])
    np.testing.assert_allclose(precipitable_water_gueymard1994(t, rh),
                               pvlib.atmosphere.gueymard94_pw(t, rh), rtol=1e-12)


def test_gas_transmittance_published_behaviour():
    """Bird & Riordan (1986) band transmittances: no absorption outside the bands (550 nm), the 940 nm water band
    and the 760 nm O2 band absorb, more water absorbs more."""
    from skyscatter.atmosphere.gas_absorption import mixed_gas_transmittance, water_vapour_transmittance

    tw = water_vapour_transmittance([550.0, 940.0], np.array([0.5, 3.0]), np.array([1.5, 1.5]))
    assert tw[:, 0] == pytest.approx([1.0, 1.0])
    assert 0.2 < tw[1, 1] < tw[0, 1] < 0.8
    tu = mixed_gas_transmittance([550.0, 762.5], np.array([1.0]))
    assert tu[0, 0] == pytest.approx(1.0) and tu[0, 1] < 0.8


def test_diffuse_ozone_counted_once(options):
    """The tables already absorb by the medium's ozone column: the broadband diffuse of tables with 300 DU equals
    that of tables of the same air without ozone, with the 300 DU applied along the sun's ozone path (Bird &
    Riordan's assumption), within 0.75 % (measured 0.09-0.46 % at sun zeniths 20-75 deg; the two differ only by
    the diffuse light's own ozone path). Counting the column twice made it 1.0-3.5 % low."""
    import warnings

    from skyscatter.conventions import direction_from_angles
    from skyscatter.fit.weather import BroadbandClearSky, default_family
    from skyscatter.precomputed.cache import cached_atmosphere

    fam = default_family(options)
    zen = np.radians([20.0, 40.0, 60.0, 75.0])
    one = np.ones(zen.size)
    ground, up = np.array([0.0, 0.0, fam.base.bottom_radius]), np.array([0.0, 0.0, 1.0])
    dhi = {}
    for o3 in (300.0, 0.0):
        atm = fam.parameters((1, 1, 1)).replace(ozone_column=o3)  # AOD 0.2, albedo 1, phase g 0.8
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tab = cached_atmosphere(atm, orders=fam.orders, wavelengths=fam.wavelengths, sizes=fam.sizes,
                                    progress=False)
        spec = np.stack([np.asarray(tab.ground_irradiance(ground, up, s)[1]).reshape(-1)
                         for s in direction_from_angles(zen, np.zeros(zen.size))])
        dhi[o3] = BroadbandClearSky(atm, options.angstrom_alpha).broadband_diffuse(
            spec, zen, 1.4 * one, 101325.0 * one, 300.0 * one, one, fam.wavelengths)
    np.testing.assert_allclose(dhi[300.0], dhi[0.0], rtol=0.0075)


@pytest.fixture(scope="module")
def spectrl2_tables():
    """Coarse tables (the module's preset) of :func:`spectrl2_air` at the test cases' optical depths (about 1 CPU-s
    each once compiled)."""
    import warnings

    from skyscatter.fit.weather import TABLE_PRESETS
    from skyscatter.precomputed.cache import cached_atmosphere

    p = TABLE_PRESETS["coarse"]
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for aod in (0.1, 0.2, 0.3):
            atm = spectrl2_air(aod)
            out[aod] = atm, cached_atmosphere(atm, orders=p["orders"], wavelengths=p["wavelengths"], sizes=p["sizes"],
                                              progress=False)
    return out




def _rel(a, b):
    """Mean, RMS and largest |.| of a / b - 1 [-]."""
    r = np.asarray(a) / np.asarray(b) - 1.0
    return float(np.mean(r)), float(np.sqrt(np.mean(r**2))), float(np.max(np.abs(r)))


SPECTRL2_60_MISS = (
    "SPECTRL2 (pvlib, Bird & Riordan 1986) at zenith 60 deg, AOD 0.2, through its own aerosol: our global "
    "horizontal spectrum measured +2.5 % mean, RMS 3.3 %, max +8.6 % (400 nm) above it; direct within 0.4 % RMS, "
    "diffuse +6.0 % mean (+15 % at 400 nm). The Monte Carlo through the same air (test below) sides with us: ours "
    "within 0.8 % RMS of it, SPECTRL2 3.6 % RMS below it (its diffuse 15 % below at 400 nm, 2.5 % at 550 nm: "
    "the empirical blue factor Cs = ((lambda + 550) / 1000)^1.8 below 450 nm, Eq. 3-17, and the plane-parallel "
    "Eqs. 3-5/3-6 at slant sun)")


@pytest.mark.parametrize("zenith_deg, aod550", [
    (30.0, 0.1), (20.0, 0.3),
    pytest.param(60.0, 0.2, marks=pytest.mark.xfail(strict=True, reason=SPECTRL2_60_MISS))])
def test_clear_sky_model_against_spectrl2(spectrl2_tables, zenith_deg, aod550):
    """Issue 24's check: the ground spectrum of a clear hour within 3 % of SPECTRL2 (pvlib, Bird & Riordan 1986)
    over 400-700 nm for the same aerosol and water: our medium with SPECTRL2's own aerosol (:func:`spectrl2_air`:
    its Angstrom optical depth, albedo spectrum and asymmetry 0.65), water 1.4 cm, ozone 300 DU, at SPECTRL2's
    wavelengths: global horizontal transmittance RMS < 3 % and mean within 2 %, direct RMS < 1 % (source
    SPECTRL2; coarse tables). Measured 2026-12-03: zenith 30 deg AOD 0.1 mean +1.2 %, RMS 1.6 %, max 4.3 % (400
    nm); zenith 20 deg AOD 0.3 +1.0 %, 1.8 %, 5.7 % (400 nm); direct RMS 0.2 %. Zenith 60 deg misses (xfail:
    SPECTRL2's diffuse, by the Monte Carlo of the next test)."""
    atm, tables = spectrl2_tables[aod550]
    _, ours, theirs, _ = clear_ground_spectra(atm, tables, zenith_deg, aod550)
    assert _rel(ours["direct"], theirs["direct"])[1] < 0.01
    mean, rms, _ = _rel(ours["global"], theirs["global"])
    assert rms < 0.03, (mean, rms)
    assert abs(mean) < 0.02, (mean, rms)


def test_clear_sky_model_against_monte_carlo_where_spectrl2_misses(spectrl2_tables):
    """Which of us is right at zenith 60 deg, AOD 0.2 (the xfail above): the spherical Monte Carlo
    (``montecarlo.ground_irradiance``, an independent solver) through the same air (:func:`spectrl2_air`), its
    diffuse times the same gas transmittance, plus the same direct beam (the Monte Carlo's direct equals the
    tables' medium's to 1e-3 outside gas bands): our global spectrum within 1.5 % RMS of it over SPECTRL2's
    400-700 nm wavelengths (measured 0.8 %, the tables' diffuse -2.6 % at 400 nm to +4.8 % at 593 nm, the coarse
    tables' 100 nm steps across ozone's Chappuis band; the default tables 0.2 %), and SPECTRL2 more than twice as
    far (measured RMS 3.6 %; its diffuse -15 % at 400 nm to -0.5 % at 668 nm). 16384 paths, standard error of the
    diffuse about 1 %."""
    from skyscatter.montecarlo.domain import ground_irradiance

    atm, tables = spectrl2_tables[0.2]
    w, ours, theirs, gas = clear_ground_spectra(atm, tables, 60.0, 0.2)
    mc = ground_irradiance(atm, w, sun_zenith=np.radians(60.0), samples=16384, seed=7)
    mc_global = ours["direct"] + np.asarray(mc.diffuse)[0] / atm.solar_irradiance_at(w) * gas
    _, rms_ours, _ = _rel(ours["global"], mc_global)
    _, rms_spectrl2, _ = _rel(theirs["global"], mc_global)
    assert rms_ours < 0.015, rms_ours
    assert rms_spectrl2 > 2 * rms_ours, (rms_spectrl2, rms_ours)


def test_horizontal_sky_irradiance_against_disort(options):
    """The one DHI of retrieval and matrix: the tables' radiance over the hemisphere (``horizontal_sky_irradiance``,
    tabulated in sun zenith) equals the direct Gauss-Legendre sum off its nodes within 0.05 %, the rule a 4x denser
    one within 0.05 %, and it is closer to
    DISORT (plane-parallel, independent) than the tables' irradiance texture: coarse tables, AOD 0.5, albedo 1,
    g 0.8, sun 30 deg, 550 nm: within 1.5 % (measured +0.84 %; the texture -2.93 %)."""
    pytest.importorskip("disortpp")
    import warnings

    from disort_reference import disort_diffuse_irradiance
    from skyscatter.fit.weather import default_family
    from skyscatter.precomputed.evaluation import HORIZONTAL_SKY_NODES
    from skyscatter.quadrature import plane_quadrature

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fam = default_family(options)
        index = (2, 1, 1)
        atm, p = fam.node(index), fam.parameters(index)
    assert p.mie_phase_g == pytest.approx(0.8)
    ground = np.array([0.0, 0.0, p.bottom_radius])
    z = np.radians([37.3, 84.2])
    suns = [np.array([np.sin(zk), 0.0, np.cos(zk)]) for zk in z]
    rule = plane_quadrature(0.0, 0.0, nodes=HORIZONTAL_SKY_NODES)
    fine = plane_quadrature(0.0, 0.0, nodes=(192, 384))
    direct, dense = (np.stack([w @ atm.sky_radiance(ground, d, s) for s in suns]) for d, w in (rule, fine))
    np.testing.assert_allclose(atm.horizontal_sky_irradiance(z), direct, rtol=5e-4)  # the tabulation
    np.testing.assert_allclose(direct, dense, rtol=5e-4)  # the rule (measured within 0.04 %)
    zs = np.radians(30.0)
    k = list(fam.wavelengths).index(550.0)
    ref = disort_diffuse_irradiance(p, 550.0, zs) * float(p.solar_irradiance_at([550.0])[0])
    hemi = atm.horizontal_sky_irradiance([zs])[0, k]
    texture = atm.ground_irradiance(ground, [0.0, 0.0, 1.0], [np.sin(zs), 0.0, np.cos(zs)])[1][k]
    assert hemi == pytest.approx(ref, rel=0.015)
    assert abs(hemi / ref - 1) < abs(texture / ref - 1)


# ------------------------------------------------------------------ retrieval


def test_retrieval_recovers_spectrl2_aerosol(hourly):
    """Clear hours of the SPECTRL2 day: AOD within 0.03 of the truth (the two models' Rayleigh, gas and aerosol
    descriptions differ; measured 0.131-0.135 for 0.15), DNI closure exact (Newton), DHI closed by an aerosol
    albedo between the grid's 0.8 and SPECTRL2's 0.945 (at 400 nm): our aerosol's phase (Cornette-Shanks g 0.8,
    mean cosine 0.84) is more forward than SPECTRL2's (asymmetry 0.65), so the same diffuse needs more absorption;
    DISORT puts the albedo our medium needs at 0.80-0.88 (test_spectrl2_albedo_premise_by_disort; measured
    retrieval 0.849-0.908). The DNI retrieval wins over the file's field.
    Cloudy days: the cloud optical depth from GHI (retrieve_clouds)."""
    from skyscatter.fit.weather import BROKEN, CLEAR, CLOUDY, CLOUDY_OPEN, ENHANCED, LOW_SUN, NIGHT

    st = hourly.status
    clear = np.flatnonzero(st == CLEAR)
    assert clear.size >= 12 and np.all(clear < 24)
    np.testing.assert_allclose(hourly.aerosol_optical_depth[clear], CLEAR_AOD, atol=0.03)
    assert np.nanmax(np.abs(hourly.dni_closure[clear])) < 1e-6
    assert np.nanmax(np.abs(hourly.dhi_closure[clear])) < 1e-6
    assert np.all((hourly.single_scattering_albedo[clear] > 0.8) & (hourly.single_scattering_albedo[clear] < 0.945))
    assert np.all(hourly.aerosol_source[clear] == "dni")
    assert np.all(np.isfinite(hourly.aerosol_optical_depth_file[clear]))
    # broken and overcast days: cloudy, with the file's AOD (no clear hour that day); the cloud optical depth
    # retrieved from GHI where the sun is high enough, else a reason
    later = np.arange(st.size) >= 24
    cloudy = np.flatnonzero(np.isin(st, (CLOUDY, CLOUDY_OPEN, BROKEN, LOW_SUN, ENHANCED)) & later)
    assert cloudy.size >= 28
    np.testing.assert_allclose(hourly.aerosol_optical_depth[cloudy], FILE_AOD_BROADBAND * (700 / 550) ** 1.3)
    done = np.flatnonzero(np.isin(st, (CLOUDY, BROKEN)) & later)
    open_ = np.flatnonzero((st == CLOUDY_OPEN) & later)
    assert done.size >= 20
    assert np.all((hourly.cloud_optical_depth[done] >= 0.5) & (hourly.cloud_optical_depth[done] <= 60))
    assert np.all(np.isnan(hourly.cloud_optical_depth[open_]))
    assert all("not retrieved" in str(r) for r in hourly.reason[open_])
    # the fit is to GHI: the retrieved sky's GHI (DHI + DNI cos z) reproduces it to the inversion's 400-point grid
    g_model = hourly.dhi_model[done] + hourly.dni_model[done] * np.cos(hourly.sun_zenith[done])
    np.testing.assert_allclose(g_model, hourly.ghi[done], rtol=2e-3)
    # broken day (cover 5 tenths, DNI 0.4 of SPECTRL2's clear beam): a clear / overcast blend fitted to GHI and DNI
    # (DNI exact, DHI within the 400-point grid's 0.2 % of GHI); overcast day: no flag, and (no beam in the record)
    # the layer is thick enough that DHI closes with GHI
    broken = np.flatnonzero(st == BROKEN)
    overcast = done[done >= 48]
    assert broken.size >= 10 and np.all((broken >= 24) & (broken < 48))
    assert all("blend" in str(r) for r in hourly.reason[broken])
    f = hourly.cloud_fraction[broken]
    assert np.all((f > 0.5) & (f < 0.8)), f  # our clear beam (the file's AOD) is brighter than SPECTRL2's
    np.testing.assert_allclose(hourly.dni_model[broken], hourly.dni[broken], rtol=1e-6)
    np.testing.assert_allclose(hourly.dhi_model[broken], hourly.dhi[broken], rtol=0.01)
    np.testing.assert_allclose((1 - f) * hourly.clear_dhi[broken] + f * hourly.cloud_dhi[broken],
                               hourly.dhi_model[broken])
    assert np.all(hourly.cloud_cover[broken] == 0.5) and np.all(hourly.cloud_cover[overcast] == 1.0)
    # the broken day's low suns (elevations 6-15 deg): twice the clear diffuse with 0.4 of its beam is more light
    # than any clear / overcast blend gives: the stated enhanced-diffuse rule, DHI by construction, DNI exact
    enh = np.flatnonzero(st == ENHANCED)
    assert enh.size >= 2 and np.all((enh >= 24) & (enh < 48))
    assert all("enhanced-diffuse rule" in str(r) for r in hourly.reason[enh])
    np.testing.assert_allclose(hourly.dhi_model[enh], hourly.dhi[enh], rtol=1e-12)
    np.testing.assert_allclose(hourly.dni_model[enh], hourly.dni[enh], rtol=1e-6)
    f = hourly.cloud_fraction[enh]
    np.testing.assert_allclose((1 - f) * hourly.clear_dhi[enh] + hourly.cloud_dhi[enh], hourly.dhi[enh], rtol=1e-12)
    # every daylit hour has a sky and a status that says which rule made it
    assert not np.any(st == CLOUDY_OPEN), hourly.reason[st == CLOUDY_OPEN]
    # suns below 3 deg with light: the stated fallback, not a silently wrong hour
    low = np.flatnonzero(st == LOW_SUN)
    assert low.size >= 2 and np.all(np.degrees(hourly.sun_zenith[low]) > 87.0)
    assert all("fallback" in str(r) for r in hourly.reason[low])
    assert overcast.size >= 8 and all(str(r) == "" for r in hourly.reason[overcast])
    assert np.all(hourly.cloud_optical_depth[overcast] > 5)
    np.testing.assert_allclose(hourly.dhi_model[overcast], hourly.dhi[overcast], rtol=0.01)
    assert np.all(st[(hourly.ghi == 0) & (hourly.dhi == 0)] == NIGHT)


def test_spectrl2_albedo_premise_by_disort(hourly):
    """What the SPECTRL2 day implies for our medium, by an independent solver (DISORT, plane-parallel, disortpp):
    at the clear hours with the sun 30 and 60 deg up, the aerosol albedo at which DISORT through our medium (the
    hour's retrieved AOD, Cornette-Shanks g 0.8, the same broadband conversion) gives the record's DHI is below
    0.9 (measured 0.82 and 0.88), not SPECTRL2's 0.945: DISORT with SPECTRL2's own aerosol (albedo 0.945 exp(-0.095
    ln^2(lambda / 400 nm)), asymmetry 0.65 as a Cornette-Shanks g of 0.585) reproduces the record within 1.5 %
    at 60 deg (measured: DISORT 0.2 % above it) and 4 % at 30 deg (2.5 % above): the difference is the phase,
    not SPECTRL2's diffuse. The retrieval (the tables' radiance over the hemisphere) at 60 deg within 0.04 of
    DISORT's albedo (measured +0.027: the coarse tables' diffuse 2-3 % below DISORT there); at 30 deg above it
    (the coarse tables' diffuse further below DISORT with the sun low, docs/sky_matrices.md)."""
    pytest.importorskip("disortpp")
    from disort_reference import disort_diffuse_irradiance
    from skyscatter.fit.weather import CLEAR, BroadbandClearSky
    from skyscatter.precomputed.family import AXIS_SETTERS

    fam, o = hourly.family, hourly.options
    model = BroadbandClearSky(fam.base, o.angstrom_alpha)
    wl = fam.wavelengths
    e0 = fam.base.solar_irradiance_at(wl)
    clear = np.flatnonzero(hourly.status == CLEAR)
    el = 90 - np.degrees(hourly.sun_zenith[clear])

    def medium(aod, albedo, g):
        p = AXIS_SETTERS["aerosol_phase_g"](AXIS_SETTERS["aerosol_optical_depth"](fam.base, aod), g)
        return AXIS_SETTERS["aerosol_single_scattering_albedo"](p, albedo)

    def dhi(i, albedo, g):
        """DISORT's broadband DHI [W m^-2] of hour i; ``albedo`` a number or one per table wavelength."""
        a = np.broadcast_to(albedo, wl.shape)
        media = {float(ak): medium(hourly.aerosol_optical_depth[i], float(ak), g) for ak in np.unique(a)}
        spec = np.array([disort_diffuse_irradiance(media[float(ak)], w, float(hourly.sun_zenith[i]))
                         for w, ak in zip(wl, a, strict=True)])
        h = [i]
        return model.broadband_diffuse((spec * e0)[None], hourly.sun_zenith[h], hourly.precipitable_water[h],
                                       hourly.pressure[h], hourly.ozone[h], hourly.eccentricity[h], wl)[0]

    spectrl2_albedo = 0.945 * np.exp(-0.095 * np.log(wl / 400.0) ** 2)  # Bird & Riordan 1986, Eq. 3-16
    for elevation, tol_spectrl2 in ((60.0, 0.015), (30.0, 0.04)):
        i = int(clear[np.argmin(np.abs(el - elevation))])
        d08, d09 = dhi(i, 0.8, 0.8), dhi(i, 0.9, 0.8)
        albedo_disort = 0.8 + 0.1 * (hourly.dhi[i] - d08) / (d09 - d08)
        assert 0.75 < albedo_disort < 0.9, (elevation, albedo_disort)
        assert dhi(i, spectrl2_albedo, 0.585) == pytest.approx(hourly.dhi[i], rel=tol_spectrl2)
        if elevation == 60.0:
            assert hourly.single_scattering_albedo[i] == pytest.approx(albedo_disort, abs=0.04)
        else:
            assert hourly.single_scattering_albedo[i] > albedo_disort


def test_bad_records(tmp_path, options):
    """DNI above the extraterrestrial value, DHI > GHI and light at night are errors naming the line, or flagged
    hours with bad_hours='flag'; a missing DNI is rebuilt from GHI and DHI; a time zone 9 h off is an error."""
    from skyscatter.fit.weather import INVALID, RetrievalOptions, retrieve_hourly_atmosphere

    def dni_high(rows):
        rows[12][14] = "1450"

    def dhi_high(rows):
        rows[12][15], rows[12][13] = "500", "300"

    def night(rows):
        rows[1][13] = "200"

    flag = RetrievalOptions(**{**vars(options), "bad_hours": "flag"})
    # the EPW reader itself refuses these two, with the line, whatever bad_hours says (issue 18's checks)
    for tweak, what in ((dni_high, "extraterrestrial"), (dhi_high, "diffuse")):
        path = clear_day(tmp_path / f"{tweak.__name__}.epw", tweak)
        for o in (options, flag):
            with pytest.raises(FileFormatError, match=f"line 21: .*{what}"):
                retrieve_hourly_atmosphere(path, o)
    path = clear_day(tmp_path / "night.epw", night)
    with pytest.raises(FileFormatError, match="line 10: .*below the horizon"):
        retrieve_hourly_atmosphere(path, options)
    flagged = retrieve_hourly_atmosphere(path, flag)
    assert flagged.status[1] == INVALID and "below the horizon" in flagged.reason[1]

    def missing(rows):
        rows[12][14] = "9999"

    h = retrieve_hourly_atmosphere(clear_day(tmp_path / "m.epw", missing), options)
    assert "rebuilt" in h.reason[12] and h.dni[12] > 800
    far = write_epw(tmp_path / "tz.epw", days=((6, 20, "clear"),),
                    site={"latitude": 48.1, "longitude": 2.35, "timezone": -8.0, "elevation": 0.0})
    with pytest.raises(FileFormatError, match="time zone"):
        retrieve_hourly_atmosphere(far, options)
    with pytest.raises(InvalidParameterError):
        RetrievalOptions(bad_hours="ignore")


def test_family_interpolation_is_linear_in_the_nodes(options):
    """Family interpolation: at a node it returns the node's value; between two nodes the weighted mean."""
    import warnings

    from skyscatter.fit.weather import default_family

    fam = default_family(options)
    ground = np.array([0.0, 0.0, fam.base.bottom_radius])
    sun = np.array([[0.5, 0.0, np.sqrt(0.75)]])

    def f(atm, sub):
        return atm.sky_radiance(ground, [[0.0, 0.6, 0.8]], sun[0])[None, 0]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        at_node = fam.interpolate([[0.2, 1.0, 0.8]], f)
        mid = fam.interpolate([[0.1, 0.9, 0.65]], f)
        corners = [f(fam.node(i), np.arange(1)) for i in itertools.product((0, 1), repeat=3)]
    np.testing.assert_allclose(at_node, corners[-1], rtol=1e-12)
    np.testing.assert_allclose(mid, np.mean(corners, axis=0), rtol=1e-12)
    lower, frac, outside = fam.cells([[0.7, 0.5, 0.9]])
    assert outside.tolist() == [[True, True, True]] and frac[0, 0] == 1.0


def test_sky_radiance_of_many_suns_is_the_one_sun_lookup(options):
    """``sky_radiance_suns`` (one compiled call for all the suns of a patch pass) against ``sky_radiance`` called
    per sun (the observer's per-sun path, independent code: slices formed by numpy): the same values to 1e-12
    relative (measured 3e-13: the suns are normalised row-wise), suns from the zenith to 6 deg below the horizon
    (the tables' last sun), patch cells of the Tregenza sky and rays to the ground."""
    import warnings

    from skyscatter.conventions import direction_from_angles
    from skyscatter.fit.weather import default_family
    from skyscatter.patches import patch_scheme

    fam = default_family(options)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        atm = fam.node((1, 0, 1))
    ground = np.array([0.0, 0.0, fam.base.bottom_radius])
    dirs = np.concatenate([patch_scheme("tregenza").sample_directions(1).reshape(-1, 3), [[0.6, 0.0, -0.8]]])
    zen = np.radians([0.0, 35.0, 80.0, 87.0, 90.0, 93.0, 96.0])
    suns = direction_from_angles(zen, np.radians([0.0, 40.0, 100.0, 180.0, 250.0, 300.0, 10.0]))
    got = atm.sky_radiance_suns(ground, dirs, 2.0 * suns)
    want = np.stack([atm.sky_radiance(ground, dirs, s) for s in suns])
    assert got.shape == want.shape and np.all(want[:4] > 0)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * want.max())


# ------------------------------------------------------------------ the matrix


def test_matrix_closure_and_sun(matrix, hourly, options):
    """The matrix's own broadband DHI within 1 % of the record in every clear hour; the sun's band spectrum equal
    to the tables' sun transmittance x E0 (independent lookups) within 1.5 % at the bands' table wavelengths;
    night 0, cloudy not retrieved NaN; the 380-780 nm horizontal diffuse of the patches within 2 % of the tables'
    irradiance. Cloudy, broken and low-sun hours have a sky: the matrix's DHI within 1 % of the record where the
    retrieval converged (overcast: measured 5e-14, the GHI fit with no beam; broken: measured 0.41 %, the clear
    part's albedo closure), exactly (by construction) in the low-sun fallback; the sun's band spectrum integrates
    to the model's DNI."""
    import warnings

    from skyscatter.conventions import direction_from_angles
    from skyscatter.fit.weather import BROKEN, CLEAR, CLOUDY, LOW_SUN

    st = matrix["status"].values
    clear = np.flatnonzero(st == CLEAR)
    assert clear.size >= 10
    assert np.nanmax(np.abs(matrix["dhi_closure"].values[clear])) < 0.01
    assert np.nanmax(np.abs(matrix["dni_closure"].values[clear])) < 1e-6
    sky = matrix["sky_radiance"].values
    assert np.all(sky[st == 0] == 0) and np.all(np.isnan(sky[st == 3]))
    for k, tol in ((CLOUDY, 0.01), (BROKEN, 0.01), (LOW_SUN, 1e-9)):
        sel = np.flatnonzero(st == k)
        assert sel.size >= 2, k
        assert np.all(np.isfinite(sky[sel])) and np.all(sky[sel] >= 0) and np.all(sky[sel].max(axis=(1, 2)) > 0)
        assert np.max(np.abs(matrix["dhi_closure"].values[sel])) < tol, (k, matrix["dhi_closure"].values[sel])
    broken = st == BROKEN
    assert np.max(np.abs(matrix["dni_closure"].values[broken])) < 1e-6
    # the overcast sky's scale to the retrieval's DHI is an interpolation difference (linear vs monotone cubic in
    # ln tau): within 1.5 % (measured 0.995-1.011)
    scale = matrix["cloud_dhi_scale"].values[np.isin(st, (CLOUDY, BROKEN))]
    assert np.all(np.abs(scale - 1) < 0.015), scale
    assert np.all(sky[clear] > 0)
    assert matrix["sky_radiance"].attrs["units"] == "W m-2 sr-1 nm-1"
    assert matrix.sizes["wavelength"] == 20 and matrix["wavelength"].values[0] == 390.0
    # sun against the tables (no gases there: compare at 550 nm, 450 nm where water and O2 do not absorb)
    fam = hourly.family
    i = clear[len(clear) // 2]
    pos = np.array([0.0, 0.0, fam.base.bottom_radius])
    s = direction_from_angles(hourly.sun_zenith[i], hourly.sun_azimuth[i])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = fam.interpolate([[hourly.aerosol_optical_depth[i], hourly.single_scattering_albedo[i],
                              hourly.aerosol_phase_g[i]]],
                            lambda atm, sub: atm.sun_transmittance(pos, s)[None])
    e0 = fam.base.solar_irradiance_at(fam.wavelengths)
    for wl in (450.0, 550.0):
        k = list(fam.wavelengths).index(wl)
        b = int(np.argmin(np.abs(matrix["wavelength"].values - wl)))
        ours = matrix["sun_irradiance"].values[i, b] / hourly.eccentricity[i]
        # band mean vs point: compare transmittances (E0 band-mean vs E0 at the table wavelength)
        band_e0 = np.mean(fam.base.solar_irradiance_at(np.linspace(wl - 10, wl + 10, 41)))
        assert ours / band_e0 == pytest.approx(t[0, k], rel=0.015)
        assert e0[k] > 0
    # patches vs the tables' irradiance over 380-780 nm (the patch quadrature of Tregenza, 1 sample)
    g = np.cos(matrix["patch_zenith"].values) * matrix["patch_solid_angle"].values
    e_patch = np.einsum("tpw,p->tw", sky[clear], g).sum(axis=1) * 20.0
    assert np.all(e_patch > 0) and np.all(np.isfinite(e_patch))


def test_cloudy_patches_against_cloudy_sky(matrix, hourly):
    """Overcast hours' patches (the cloud table's radiance grid interpolated in optical depth and sun zenith, the
    forward peak in the sun's patch, scaled to the retrieval's DHI) against CloudySky solved by DISORT at the
    hour's exact optical depth and sun, at the patch centres (Tregenza, one sample), 540-560 nm band: median
    within 1 %, 95th percentile within 2.5 % more than 10 deg from the sun (measured with 2 x 2 cells:
    -0.7 to +0.1 %, <= 2.0 %); the sun's patch within 5 % (measured 0.1-4 %)."""
    from skyscatter.fit.weather import CLOUDY
    from skyscatter.sky.cloudy import CloudySky

    st = matrix["status"].values
    b = int(np.argmin(np.abs(matrix["wavelength"].values - 550.0)))
    geom_dirs = np.stack([np.sin(matrix["patch_zenith"].values) * np.sin(matrix["patch_azimuth"].values),
                          np.sin(matrix["patch_zenith"].values) * np.cos(matrix["patch_azimuth"].values),
                          np.cos(matrix["patch_zenith"].values)], axis=-1)
    hours = [i for i in np.flatnonzero(st == CLOUDY) if i >= 48 and np.degrees(hourly.sun_zenith[i]) < 60][:2]
    assert len(hours) == 2
    for i in hours:
        z, az, tau = float(hourly.sun_zenith[i]), float(hourly.sun_azimuth[i]), float(hourly.cloud_optical_depth[i])
        sky = CloudySky(z, az, cloud_optical_depth=tau, atmosphere=hourly.cloud_table.atmosphere)
        exact = sky.spectral_radiance(geom_dirs, np.linspace(541.0, 559.0, 7)).mean(axis=-1)
        ours = matrix["sky_radiance"].values[i, :, b] / hourly.eccentricity[i]
        rel = ours / exact - 1.0
        s = np.array([np.sin(z) * np.sin(az), np.sin(z) * np.cos(az), np.cos(z)])
        far = np.degrees(np.arccos(np.clip(geom_dirs @ s, -1, 1))) > 10.0
        assert abs(np.median(rel[far])) < 0.01, (i, np.median(rel[far]))
        assert np.percentile(np.abs(rel[far]), 95) < 0.025, (i, np.percentile(np.abs(rel[far]), 95))
        from skyscatter.patches import patch_scheme

        p_sun = patch_scheme("tregenza").patch_index(s[None])[0]
        assert abs(rel[p_sun]) < 0.05, rel[p_sun]


def test_broken_sky_blend_recovers_its_parts(hourly):
    """fit_broken_sky on hours made as a blend of a clear sky (a given DHI, the model's clear beam) and the cloud
    table's overcast sky at a node optical depth (exact there): cloud fraction and optical depth recovered,
    GHI, DNI and DHI reproduced; a DNI above the clear beam is refused with the reason."""
    from skyscatter.fit.weather import BroadbandClearSky, cloud_irradiance, fit_broken_sky

    table = hourly.cloud_table
    model = BroadbandClearSky(table.atmosphere, hourly.options.angstrom_alpha)
    z = np.radians([20.0, 40.0, 55.0, 70.0])
    n = z.size
    k = 6  # optical depth node
    tau = table.optical_depths[k]
    aod = np.full(n, 0.1)
    f_true = np.array([0.3, 0.5, 0.7, 0.9])
    d_clear = np.array([110.0, 95.0, 80.0, 60.0])
    d_nodes, n_nodes = cloud_irradiance(table, model, z, aod, 1.4, 101325.0, 300.0, 1.0)
    n_clear = model.direct_normal(z, aod, np.full(n, 1.4), np.full(n, 101325.0), np.full(n, 300.0), np.ones(n))
    dhi = (1 - f_true) * d_clear + f_true * d_nodes[:, k]
    dni = (1 - f_true) * n_clear + f_true * n_nodes[:, k]
    ghi = dhi + dni * np.cos(z)
    fit = fit_broken_sky(ghi, dni, z, aod, d_clear, table=table, model=model)
    assert np.all(fit.retrieved)
    np.testing.assert_allclose(fit.cloud_fraction, f_true, rtol=2e-3)
    np.testing.assert_allclose(fit.optical_depth, tau, rtol=0.02)
    np.testing.assert_allclose(fit.dni_model, dni, rtol=1e-6)
    np.testing.assert_allclose(fit.dhi_model, dhi, rtol=5e-3)
    bad = fit_broken_sky(ghi[:1], n_clear[:1] * 1.01, z[:1], aod[:1], d_clear[:1], table=table, model=model)
    assert not bad.retrieved[0] and "no cloud in the beam" in bad.reason[0]
    # thin cloud, low sun (sun elevations 14-25 deg, the thinnest node): the cloud passes a large share of the
    # beam, and a fixed-point iteration between f and tau stopped 0.3-0.7 % off in DNI here (4-19 % on the made
    # year); solved together, the blend is exact
    z = np.radians([65.3, 71.4, 73.0, 76.1])
    f_true = np.array([0.8, 0.7, 0.65, 0.6])
    d_clear = np.array([100.0, 85.0, 76.0, 64.0])
    d_nodes, n_nodes = cloud_irradiance(table, model, z, aod, 1.4, 101325.0, 300.0, 1.0)
    n_clear = model.direct_normal(z, aod, np.full(n, 1.4), np.full(n, 101325.0), np.full(n, 300.0), np.ones(n))
    for k in (0, 1):
        dhi = (1 - f_true) * d_clear + f_true * d_nodes[:, k]
        dni = (1 - f_true) * n_clear + f_true * n_nodes[:, k]
        fit = fit_broken_sky(dhi + dni * np.cos(z), dni, z, aod, d_clear, table=table, model=model)
        assert np.all(fit.retrieved)
        np.testing.assert_allclose(fit.dni_model, dni, rtol=1e-6)
        np.testing.assert_allclose(fit.dhi_model, dhi, rtol=5e-3)
        # two blends can reproduce GHI and DNI here; the thinner cloud is taken and the reason says so (measured:
        # the first hour at node 1 gives tau 0.60 and f 0.88 against 0.77 and 0.8); elsewhere the parts are
        # recovered
        two = np.array(["two blends" in str(r) for r in fit.reason])
        other = fit.optical_depth < table.optical_depths[k] / 1.02
        assert not np.any(other & ~two)
        np.testing.assert_allclose(fit.cloud_fraction[~other], f_true[~other], rtol=2e-3)
        np.testing.assert_allclose(fit.optical_depth[~other], table.optical_depths[k], rtol=0.02)
    # brighter than every blend (twice the diffuse of the exact blend): the enhanced-diffuse rule with the record's
    # DHI, stated; without the record's DHI the hour is not fitted, with the reason
    dhi = (1 - f_true) * d_clear + f_true * d_nodes[:, 3]
    dni = (1 - f_true) * n_clear + f_true * n_nodes[:, 3]
    ghi = 2 * dhi + dni * np.cos(z)
    fit = fit_broken_sky(ghi, dni, z, aod, d_clear, table=table, model=model, dhi=2 * dhi)
    assert not np.any(fit.retrieved) and np.all(fit.enhanced)
    np.testing.assert_allclose(fit.dhi_model, 2 * dhi, rtol=1e-12)
    np.testing.assert_allclose(fit.dni_model, dni, rtol=1e-6)
    np.testing.assert_allclose((1 - fit.cloud_fraction) * d_clear + fit.cloud_dhi, 2 * dhi, rtol=1e-12)
    assert np.all(fit.enhancement > 1)
    plain = fit_broken_sky(ghi, dni, z, aod, d_clear, table=table, model=model)
    assert not np.any(plain.retrieved | plain.enhanced) and all("brighter" in str(r) for r in plain.reason)


def test_cloud_table_disk_cache(hourly, monkeypatch):
    """The cloud table is stored beside the precomputed tables: a process without it in memory (Dask's workers)
    loads the same arrays instead of redoing its DISORT solves."""
    import skyscatter.fit.weather as weather

    t = hourly.cloud_table
    # stored again (the session's cache folder) so that the test does not rely on how the fixture was built
    weather._save_cloud_table(t)
    monkeypatch.setattr(weather, "_CLOUD_TABLES", {})
    again = weather.cloud_table(t.atmosphere, t.optical_depths, t.zeniths)
    assert again is not t and again.build_seconds == 0.0
    for name in ("diffuse", "slant", "field", "peak", "optical_depths", "zeniths", "wavelengths"):
        np.testing.assert_array_equal(getattr(again, name), getattr(t, name))


def test_outputs_roundtrip_and_radiance(matrix, tmp_path):
    """NetCDF and Zarr round trips; Radiance's rmtxop reads our matrix back to the same numbers, and dctimestep
    with a horizontal-irradiance coefficient row gives our horizontal diffuse + ground-free sky irradiance."""
    import xarray as xr

    from skyscatter.errors import OutputError
    from skyscatter.fit.spectral_matrix import ground_radiance, save_dataset, write_radiance_matrix

    nc = save_dataset(matrix, tmp_path / "m.nc")
    back = xr.open_dataset(nc, engine="h5netcdf")
    np.testing.assert_array_equal(back["sky_radiance"].values, matrix["sky_radiance"].values)
    assert back["status"].attrs["flag_meanings"].startswith("night clear")
    zr = save_dataset(matrix, tmp_path / "m.zarr")
    np.testing.assert_array_equal(xr.open_zarr(zr, consolidated=False)["sun_irradiance"].values,
                                  matrix["sun_irradiance"].values)
    with pytest.raises(OutputError):
        save_dataset(matrix, tmp_path / "m.zarr")
    with pytest.raises(InvalidParameterError):
        save_dataset(matrix, tmp_path / "m.txt")
    pyradiance = pytest.importorskip("pyradiance")
    bindir = Path(pyradiance.__file__).parent / "bin"
    day = matrix.isel(time=slice(0, 24))  # the clear day: no NaN
    mtx = write_radiance_matrix(day, tmp_path / "sky.mtx")
    out = subprocess.run([str(bindir / "rmtxop"), "-fa", str(mtx)], capture_output=True, text=True, check=True)
    body = out.stdout.split("\n\n", 1)[1].split()
    vals = np.array(body, dtype=float).reshape(day.sizes["patch"] + 1, 24, 20)
    np.testing.assert_allclose(vals[1:, :, ::-1].transpose(1, 0, 2), day["sky_radiance"].values, rtol=1e-6,
                               atol=1e-12)
    np.testing.assert_allclose(vals[0, :, ::-1], ground_radiance(day), rtol=1e-5, atol=1e-12)
    # dctimestep (3 components only) on the RGB matrix: one sensor, a coefficient per patch = Omega cos(zenith)
    # (ground patch 0) gives the horizontal sky irradiance in Radiance RGB; its luminance 179 (.265 R + .670 G +
    # .065 B) equals our photometric integral of the bands
    from skyscatter.fit.spectral_matrix import radiance_rgb

    rgb = write_radiance_matrix(day, tmp_path / "sky_rgb.mtx", rgb=True)
    g = np.cos(day["patch_zenith"].values) * day["patch_solid_angle"].values
    dc = tmp_path / "dc.mtx"
    coef = np.concatenate([[0.0], g])
    dc.write_text(f"#?RADIANCE\nNROWS=1\nNCOLS={coef.size}\nNCOMP=3\nFORMAT=ascii\n\n"
                  + " ".join(f"{c:.9g} {c:.9g} {c:.9g}" for c in coef) + "\n")
    res = subprocess.run([str(bindir / "dctimestep"), str(dc), str(rgb)], capture_output=True, text=True, check=True)
    got = np.array(res.stdout.split("\n\n", 1)[1].split(), dtype=float).reshape(24, 3)
    e_h = np.einsum("tpw,p->tw", day["sky_radiance"].values.astype(float), g)
    np.testing.assert_allclose(got, radiance_rgb(day, e_h), rtol=1e-4, atol=1e-9)
    from skyscatter.spectral.colorimetry import spectrum_to_luminance

    lum = 179.0 * got @ np.array([0.265, 0.670, 0.065])
    width = day["wavelength_high"].values - day["wavelength_low"].values
    from skyscatter.spectral.colorimetry import cie_cmfs

    ev = 683.0 * e_h @ (cie_cmfs(day["wavelength"].values)[:, 1] * width)
    lit = ev > 100
    np.testing.assert_allclose(lum[lit], ev[lit], rtol=3e-3)
    assert callable(spectrum_to_luminance)


def test_plane_irradiance(matrix):
    """Tilt 0: sky = sum_p L_p int_p cos dOmega with the exact patch integral (sin^2 alt_hi - sin^2 alt_lo) / 2
    x azimuth width, no ground; vertical planes see half the ground; the direct part is the sun's normal
    irradiance times the cosine of incidence."""
    from skyscatter.fit.spectral_matrix import ground_radiance, plane_irradiance
    from skyscatter.patches import patch_scheme

    day = matrix.isel(time=np.flatnonzero(matrix["status"].values[:24] != 3))  # the clear day's retrieved hours
    flat = plane_irradiance(day, 0.0, 0.0, samples=1)
    geom = patch_scheme(day.attrs["scheme"])
    g = (np.sin(geom.altitude_high) ** 2 - np.sin(geom.altitude_low) ** 2) / 2 * geom.azimuth_width
    np.testing.assert_allclose(flat["sky"].values, np.einsum("tpw,p->tw", day["sky_radiance"].values, g),
                               rtol=1e-5)
    assert np.all(flat["ground"].values == 0)
    np.testing.assert_allclose(flat["direct"].values, day["sun_irradiance"].values
                               * np.maximum(np.cos(day["sun_zenith"].values), 0)[:, None], rtol=1e-9, atol=1e-12)
    south = plane_irradiance(day, np.pi / 2, np.pi)
    north = plane_irradiance(day, np.pi / 2, 0.0)
    np.testing.assert_allclose(south["ground"].values, ground_radiance(day) * np.pi / 2, rtol=1e-9)
    noon = int(np.argmin(day["sun_zenith"].values))
    assert south["direct"].values[noon].sum() > 0 and north["direct"].values[noon].sum() == 0
    assert south["global"].values[noon].sum() > north["global"].values[noon].sum()
    with pytest.raises(InvalidParameterError):
        plane_irradiance(day, 4.0, 0.0)


def test_sites_store_resumes_to_identical_bytes(tmp_path, options):
    """Two sites into one Zarr store; a rerun with one site's flag cleared and its chunk damaged recomputes it and
    gives the same bytes as the first run; another job on the same store is refused. (One clear day a site.)"""
    from skyscatter.errors import OutputError
    from skyscatter.fit.spectral_matrix import spectral_sky_matrix_sites

    epw = clear_day(tmp_path / "a.epw")
    b = tmp_path / "b.epw"
    shutil.copy(epw, b)
    store = tmp_path / "sites.zarr"
    ds = spectral_sky_matrix_sites([epw, b], store, scheme="tregenza", samples=1, options=options)
    assert ds.sizes["site"] == 2 and bool(ds["done"].all())
    np.testing.assert_array_equal(ds["sky_radiance"].values[0], ds["sky_radiance"].values[1])

    def snapshot():
        return {p.relative_to(store): p.read_bytes() for p in sorted(store.rglob("*")) if p.is_file()}

    first = snapshot()
    chunk = next(p for p in sorted((store / "sky_radiance").rglob("*"))
                 if p.is_file() and p.relative_to(store / "sky_radiance").parts[:2] == ("c", "1"))
    chunk.write_bytes(b"damaged" + chunk.read_bytes()[7:])
    spectral_sky_matrix_sites([epw, b], store, scheme="tregenza", samples=1, options=options)
    assert snapshot() == first
    with pytest.raises(OutputError, match="another multi-site job"):
        spectral_sky_matrix_sites([epw], store, scheme="tregenza", samples=1, options=options)


def test_cli_spectral(epw, tmp_path, capsys):
    """`skyscatter skymatrix --spectral` for one site (NetCDF, Radiance matrix, report) and for two (Zarr)."""
    import xarray as xr

    from skyscatter.cli import main

    out = tmp_path / "s.nc"
    rad = tmp_path / "s.mtx"
    rep = tmp_path / "r.csv"
    common = ["--tables", "coarse", "--aod-nodes", ",".join(map(str, AOD_NODES)), "--patches", "tregenza",
              "--samples", "1", "--no-progress"]
    rgb = tmp_path / "s_rgb.mtx"
    assert main(["skymatrix", "--spectral", str(epw), "--out", str(out), "--radiance", str(rad), "--radiance-rgb",
                 str(rgb), "--report", str(rep), "--bad-hours", "flag", *common]) == 0
    assert b"NCOMP=3" in rgb.read_bytes()[:400]
    text = capsys.readouterr().out
    assert "clear" in text and "DHI closure" in text
    ds = xr.open_dataset(out, engine="h5netcdf")
    assert ds.sizes["time"] == 72 and int((ds["status"] == 1).sum()) >= 10
    # cloudy, broken (blend or enhanced diffuse) and low-sun hours written with a sky (no NaN) that closes DHI
    # within 1 %
    cloudy = np.isin(ds["status"].values, (4, 6, 7, 8))
    assert cloudy.sum() >= 25 and np.all(np.isfinite(ds["sky_radiance"].values[cloudy]))
    assert np.all(np.isfinite(ds["sun_irradiance"].values[cloudy]))
    assert np.max(np.abs(ds["dhi_closure"].values[cloudy])) < 0.01
    assert rad.read_bytes().startswith(b"#?RADIANCE\n") and b"NCOMP=20" in rad.read_bytes()[:400]
    lines = rep.read_text().splitlines()
    assert lines[0].startswith("time,status,reason") and len(lines) == 73
    # the options below need no cloudy hour: one clear day (24 hours, no cloud table)
    day = clear_day(tmp_path / "day.epw")
    store = tmp_path / "two.zarr"
    b = tmp_path / "b.epw"
    shutil.copy(day, b)
    assert main(["skymatrix", "--spectral", str(day), str(b), "--out", str(store), "--workers", "1", *common]) == 0
    assert bool(xr.open_zarr(store, consolidated=False)["done"].all())
    local = tmp_path / "local.zarr"
    assert main(["skymatrix", "--spectral", str(day), str(b), "--out", str(local), "--scheduler", "local",
                 "--workers", "1", *common]) == 0
    assert bool(xr.open_zarr(local, consolidated=False)["done"].all())
    wide = tmp_path / "w.zarr"
    assert main(["skymatrix", "--spectral", str(day), "--out", str(wide), "--bands", "41", *common]) == 0
    assert xr.open_zarr(wide, consolidated=False).sizes["wavelength"] == 41
    assert main(["skymatrix", "--spectral", str(epw), "--out", str(tmp_path / "x.npz"), *common]) == 2
    assert main(["skymatrix", str(epw), str(b), "--out", str(tmp_path / "y.npz")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and ".nc or .zarr" in err


def test_ground_only_family_equals_full_tables(options):
    """The ground-level nodes give the full tables' sky radiance, sun and irradiance for an observer on the ground
    (to float32 rounding of the same table values)."""
    import warnings

    from skyscatter.fit.weather import default_family
    from skyscatter.precomputed import cached_atmosphere

    fam = default_family(options)
    assert fam.ground_only
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        small = fam.node((1, 0, 0))
        full = cached_atmosphere(fam.parameters((1, 0, 0)), orders=fam.orders, wavelengths=fam.wavelengths,
                                 sizes=fam.sizes, progress=False)
    assert small.tables["multiple"].shape[0] == 2 and full.tables["multiple"].shape[0] == fam.sizes.scattering_r
    pos = np.array([0.0, 0.0, fam.base.bottom_radius])
    rng = np.random.default_rng(3)
    d = rng.normal(size=(500, 3))
    d[:, 2] = np.abs(d[:, 2])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    for sun in ([0.3, 0.1, 0.95], [0.9, 0.0, 0.1], [0.0, 0.99, -0.05]):
        s = np.array(sun) / np.linalg.norm(sun)
        np.testing.assert_allclose(small.sky_radiance(pos, d, s), full.sky_radiance(pos, d, s), rtol=1e-6, atol=1e-12)
        np.testing.assert_allclose(small.ground_irradiance(pos, [0, 0, 1.0], s)[1],
                                   full.ground_irradiance(pos, [0, 0, 1.0], s)[1], rtol=1e-12)


@pytest.mark.slow
def test_cli_spectral_takes_the_air_options(tmp_path):
    """`skymatrix --spectral --aerosol maritime-clean` on the clear day: the optical depth is still retrieved from DNI
    (closure kept), but through the type's own spectral shape, and the sky it gives is less blue.

    Expected from physics, not from the code: a broadband DNI weighs the aerosol's optical depth at roughly 600-900 nm,
    so the two aerosols must agree there: maritime-clean (nearly flat, Angstrom exponent 0.13) retrieves a 550 nm
    optical depth between the default's (Angstrom 1.3) times ``(900/550)^-1.3 / s(900)`` and times
    ``(600/550)^-1.3 / s(600)`` (``s`` its optical depth relative to 550 nm); its albedo is its Mie albedo (0.996 at
    550 nm, no albedo axis). Colour: with the sun high the aerosol's own scattered light decides, and the flatter
    aerosol adds relatively more red: the sky's 390/670 nm radiance ratio falls (docs/aerosols.md: zenith 450/550
    1.63 against 1.88 at optical depth 0.2); with the sun low the beam's path decides, and the default aerosol,
    whose optical depth at 390 nm is about twice maritime's here (steep spectrum), reddens the sunlight more: the
    ratio rises. Measured: 390/670 maritime / default 0.89-0.97 for sun elevations 29-65 deg, 1.17 and 1.31 at 15
    and 10 deg; optical depth ratio 0.68-0.80. The DHI closure is no longer fitted (no albedo axis): -7 to +16 %
    against this SPECTRL2 file, whose aerosol is the Angstrom one."""
    import xarray as xr

    from skyscatter.atmosphere import AtmosphereParameters
    from skyscatter.cli import main
    from skyscatter.fit.weather import particle_aerosol_shape

    epw = clear_day(tmp_path / "clear.epw")
    # optical depth nodes 0 and 0.2 (the clear day's: 0.13 retrieved): two builds for maritime-clean's family
    common = ["--tables", "coarse", "--aod-nodes", "0,0.2", "--patches", "tregenza",
              "--samples", "1", "--no-progress"]
    assert main(["skymatrix", "--spectral", str(epw), "--out", str(tmp_path / "d.nc"), *common]) == 0
    assert main(["skymatrix", "--spectral", str(epw), "--out", str(tmp_path / "m.nc"), "--aerosol", "maritime-clean",
                 "--ground-albedo", "0.2", *common]) == 0
    d = xr.open_dataset(tmp_path / "d.nc", engine="h5netcdf")
    m = xr.open_dataset(tmp_path / "m.nc", engine="h5netcdf")
    clear = (d["status"].values == 1) & (m["status"].values == 1)
    assert clear.sum() >= 8
    assert np.all(np.abs(m["dni_closure"].values[clear]) < 1e-3)
    air = AtmosphereParameters.with_aerosol_type("maritime-clean", 0.1)
    s600, s900 = particle_aerosol_shape(air.aerosol, [600.0, 900.0])
    ratio = m["aerosol_optical_depth"].values[clear] / d["aerosol_optical_depth"].values[clear]
    assert np.all(ratio > (900 / 550) ** -1.3 / s900) and np.all(ratio < (600 / 550) ** -1.3 / s600), ratio
    ssa = float(air.aerosol.single_scattering_albedo_at([550.0])[0])
    np.testing.assert_allclose(m["single_scattering_albedo"].values[clear], ssa, rtol=1e-12)
    # the file's broadband AOD (700 nm) is brought to 550 nm with each aerosol's own spectrum: maritime-clean's Mie
    # extinction ratio (its particles' extinction_at, not the retrieval's log-log shape), the default's Angstrom law
    e550, e700 = air.aerosol.extinction_at([550.0, 700.0])
    broadband = m["aerosol_optical_depth_file"].values[clear] * (e700 / e550)
    assert np.all(np.isfinite(broadband)) and np.all(broadband > 0)
    np.testing.assert_allclose(broadband, d["aerosol_optical_depth_file"].values[clear] * (700 / 550) ** -1.3,
                               rtol=1e-9)
    wl = d["wavelength"].values
    blue, red = int(np.argmin(np.abs(wl - 390))), int(np.argmin(np.abs(wl - 670)))

    def colour(ds):
        rad = ds["sky_radiance"].values[clear]  # (hours, patches, bands)
        return rad[..., blue].mean(axis=1) / rad[..., red].mean(axis=1)

    elevation = 90.0 - np.degrees(d["sun_zenith"].values[clear])
    ratio = colour(m) / colour(d)
    assert np.all(ratio[elevation >= 29.0] < 1.0) and np.all(ratio[elevation <= 16.0] > 1.0), (elevation, ratio)
    assert (elevation >= 29.0).sum() >= 6 and (elevation <= 16.0).sum() >= 1


def test_air_options_go_with_spectral(epw, tmp_path, capsys):
    """The atmosphere options belong to the physical sky (--spectral): with the Perez luminance matrix they are
    refused in one line, nothing written."""
    from skyscatter.cli import main

    out = tmp_path / "x.npz"
    assert main(["skymatrix", str(epw), "--aerosol", "urban", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "go with --spectral" in err and "Traceback" not in err and not out.exists()



def test_clear_hours_not_closed_state_why(tmp_path, options):
    """Every clear hour whose DHI the sky cannot close (status 'clear, DHI not closed') of a SPECTRL2 clear day
    (no cloud: a model difference, not thin cloud; 1 March: its sun at 3.6 deg; the one at 4.7 deg, open with the
    albedo alone, closes on the phase leg since 2026-12-02) has a sky giving more
    diffuse light than the record even at the closure path's end (aerosol albedo 0.8, phase g 0.5), and its reason
    gives the sun's elevation and the phase g the record would need (the phase leg extrapolated), below the grid's
    0.5. Made year (coarse tables): 75 such hours (63 beyond 1 %), sun 3.1-5.9 deg (docs/sky_matrices.md, "One
    diffuse horizontal irradiance"); on the irradiance texture 108, sun 3-8 deg; with the albedo alone 471."""
    import warnings

    from skyscatter.fit.spectral_matrix import spectral_sky_matrix
    from skyscatter.fit.weather import CLEAR_OPEN, retrieve_hourly_atmosphere

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h = retrieve_hourly_atmosphere(write_epw(tmp_path / "march.epw", days=((3, 1, "clear"),),
                                                 tweak=dark_below_cloud_table), options)
    g_low = options.phase_g_min
    ds = spectral_sky_matrix(None, scheme="tregenza", samples=1, atmosphere=h)
    st = ds["status"].values
    open_ = np.flatnonzero(st == CLEAR_OPEN)
    assert open_.size >= 1
    for i in open_:
        why = str(ds["reason"].values[i])
        m = re.search(r"the record's DHI is ([0-9.]+) % below the physical minimum \(the clear sky of the beam's "
                      r"aerosol optical depth with the most absorbing, least forward-scattering aerosol within "
                      r"bounds: albedo 0.8, phase g 0.5; sun ([0-9.]+) deg up\): no aerosol within bounds reproduces "
                      r"it \(the phase line at albedo 0.8 through the grid's g nodes reaches the record's DHI at g "
                      r"(-?[0-9.]+), below the published range\)", why)
        assert m is not None, why
        assert float(m.group(2)) == pytest.approx(90 - np.degrees(h.sun_zenith[i]), abs=0.06)
        assert float(m.group(3)) < g_low
        assert ds["dhi_closure"].values[i] > 0  # the sky's diffuse above the record's
        # the deficit stated is the matrix's closure seen from the other side: 1 - record / sky
        assert float(m.group(1)) / 100 == pytest.approx(1 - 1 / (1 + ds["dhi_closure"].values[i]), abs=6e-4)
        assert ds["aerosol_phase_g"].values[i] == pytest.approx(g_low)
        assert ds["single_scattering_albedo"].values[i] == pytest.approx(options.single_scattering_albedo_nodes[0])


def test_low_sun_spectrl2_diffuse_below_the_physical_minimum(options):
    """Why a SPECTRL2 record's clear hours with the sun 3-6 deg up cannot close DHI (docs/sky_matrices.md, "Why
    those hours"): with the sun 4 deg up, AOD 0.2 at 550 nm (a node: no interpolation), at 550 nm,

    1. the tables' horizontal sky irradiance at the closure path's end (albedo 0.8, phase g 0.5: the least diffuse
       light any aerosol within the bounds gives) is the spherical Monte Carlo's through the same medium (an
       independent solver) within 3 % plus 4 standard errors (measured -2.2 to +0.6 % at 450-650 nm, suns 3.1-5.7
       deg, 32768 paths; here -0.1 %, standard error 1.2 %): the minimum is physical, not a coarse-table artefact
       at low sun;
    2. SPECTRL2 (pvlib, Bird & Riordan 1986) gives a diffuse transmittance DHI / (E0 cos z) at least 10 % below
       the Monte Carlo through SPECTRL2's own aerosol (its albedo 0.945 exp(-0.095 ln^2(l / 400 nm)), asymmetry
       0.65 as a Cornette-Shanks g of 0.585; here 23 % below, 17-25 % over suns 3-6 deg), and below the Monte Carlo
       at the bounds too (here 13 % below): its low-sun diffuse is below radiative transfer through its own atmosphere
       and below any aerosol within the bounds, so no retrieval within them can close it."""
    from skyscatter.fit.weather import default_family
    from skyscatter.montecarlo.domain import ground_irradiance

    fam = default_family(options)
    names = [a.name for a in fam.axes]
    assert names == ["aerosol_optical_depth", "aerosol_single_scattering_albedo", "aerosol_phase_g"]
    z = np.radians(86.0)
    aod = 0.2
    k_aod = list(fam.axes[0].values).index(aod)
    i550 = list(fam.wavelengths).index(550.0)
    bounds = fam.parameters((k_aod, 0, 0))
    assert bounds.mie_single_scattering_albedo == 0.8 and bounds.mie_phase_g == 0.5
    tables = fam.interpolate(np.array([[aod, 0.8, 0.5]]),
                             lambda atm, sub: atm.horizontal_sky_irradiance(np.array([z])))[0, i550]
    mc = ground_irradiance(bounds, [550.0], sun_zenith=z, samples=16384, seed=11)
    e_mc, se = float(mc.diffuse[0, 0]), float(mc.diffuse_stderr[0, 0])
    assert abs(tables / e_mc - 1) < 0.03 + 4 * se / e_mc, (tables, e_mc, se)

    ssa550 = 0.945 * np.exp(-0.095 * np.log(550.0 / 400.0) ** 2)  # Bird & Riordan 1986, Eq. 3-16
    own = bounds.replace(mie_single_scattering_albedo=float(ssa550), mie_phase_g=0.585)
    mc_own = ground_irradiance(own, [550.0], sun_zenith=z, samples=16384, seed=12)
    e0 = float(bounds.solar_irradiance_at([550.0])[0]) * np.cos(z)
    t_own, t_bounds = float(mc_own.diffuse[0, 0]) / e0, e_mc / e0
    assert t_own > t_bounds  # the ordering of the path: more albedo, more forward phase, more diffuse light
    s = pvlib.spectrum.spectrl2(apparent_zenith=86.0, aoi=86.0, surface_tilt=0.0, ground_albedo=0.2,
                                surface_pressure=101325.0,
                                relative_airmass=pvlib.atmosphere.get_relative_airmass(86.0, model="kasten1966"),
                                precipitable_water=1.5, ozone=0.3, aerosol_turbidity_500nm=aod * (500 / 550) ** -1.3,
                                dayofyear=172, alpha=1.3)
    k = int(np.argmin(np.abs(s["wavelength"] - 550.0)))
    t_spl = float(s["dhi"][k, 0] / (s["dni_extra"][k, 0] * np.cos(z)))
    assert t_spl < 0.9 * t_own, (t_spl, t_own)
    assert t_spl < t_bounds, (t_spl, t_bounds)


def test_clear_hours_close_on_the_phase_leg(tmp_path, options):
    """The second aerosol parameter recovers a known phase: clear hours of the SPECTRL2 day whose DHI is replaced by
    the sky's at the hour's optical depth (from DNI), aerosol albedo 0.8 and a Cornette-Shanks g of 0.55, 0.65 or
    0.75 (the family interpolated there directly, not through the closure path) are retrieved clear with that g
    (within 0.005: the record's DHI is written to 1 mW m^-2) and albedo 0.8, DHI closed by the retrieval (1e-9);
    with the albedo alone (``phase_g_min=None``) the same hours stay open. The DHI is made from the tables'
    radiance over the hemisphere (``horizontal_sky_irradiance``), what the retrieval and the matrix close on: the
    matrix keeps the retrieved g and closes all three (the patches scaled to the hemisphere's irradiance)."""
    import dataclasses
    import warnings

    from skyscatter.fit.spectral_matrix import spectral_sky_matrix
    from skyscatter.fit.weather import CLEAR, CLEAR_OPEN, BroadbandClearSky, retrieve_hourly_atmosphere

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h0 = retrieve_hourly_atmosphere(clear_day(tmp_path / "june.epw"), options)
        fam = h0.family
        clear = np.flatnonzero(h0.status == CLEAR)
        el = 90 - np.degrees(h0.sun_zenith[clear])
        picks = [int(clear[np.argmin(np.abs(el - e))]) for e in (12.0, 35.0, 60.0)]
        truth = dict(zip(picks, (0.55, 0.65, 0.75), strict=True))
        rows = np.array(picks)
        vals = np.column_stack([h0.aerosol_optical_depth[rows], np.full(rows.size, 0.8), [truth[i] for i in picks]])
        zen = h0.sun_zenith[rows]
        spec = fam.interpolate(vals, lambda atm, sub: atm.horizontal_sky_irradiance(zen[sub]))
        dhi = BroadbandClearSky(fam.base, options.angstrom_alpha).broadband_diffuse(
            spec, h0.sun_zenith[rows], h0.precipitable_water[rows], h0.pressure[rows], h0.ozone[rows],
            h0.eccentricity[rows], fam.wavelengths)

        def tweak(recs):
            for i, d in zip(picks, dhi, strict=True):
                r = recs[i]
                dni = float(r[14])
                r[15] = f"{d:.3f}"
                r[13] = f"{d + dni * np.cos(h0.sun_zenith[i]):.3f}"

        path = clear_day(tmp_path / "june_phase.epw", tweak)
        h = retrieve_hourly_atmosphere(path, options)
        h_albedo = retrieve_hourly_atmosphere(path, dataclasses.replace(options, phase_g_min=None))
    for i in picks:
        assert h.status[i] == CLEAR, h.reason[i]
        assert h.aerosol_phase_g[i] == pytest.approx(truth[i], abs=0.005)
        assert h.single_scattering_albedo[i] == pytest.approx(0.8, abs=1e-12)
        assert abs(h.dhi_closure[i]) < 1e-9
        assert h_albedo.status[i] == CLEAR_OPEN  # the albedo alone cannot
    g_retrieved = h.aerosol_phase_g[picks].copy()
    ds = spectral_sky_matrix(None, scheme="tregenza", samples=1, atmosphere=h)
    st, c, g = ds["status"].values[picks], ds["dhi_closure"].values[picks], ds["aerosol_phase_g"].values[picks]
    # one description of DHI (the tables' radiance over the hemisphere): the matrix keeps the retrieved air and
    # closes every hour the retrieval closed (float32 patches); its patches before scaling within 3 % of the
    # hemisphere (Tregenza, one sample per patch; measured +1.5 %, +0.8 %, -0.03 % at sun 12, 35, 60 deg; the made
    # year with 2 x 2 cells: +2.2 % median at 10-20 deg, docs/sky_matrices.md)
    assert np.all(st == CLEAR), (st, c)
    np.testing.assert_array_equal(g, g_retrieved)
    assert np.all(np.abs(c) < 1e-4), c  # measured 3e-7 to 2.7e-5 (float32 interpolation of the patch sums)
    assert np.all(np.abs(ds["sky_quadrature"].values[picks]) < 0.03), ds["sky_quadrature"].values[picks]


@pytest.mark.slow
def test_gensdaymtx_unit_is_radiance_per_nm_times_400(tmp_path):
    """Radiance's gensdaymtx (pyradiance's binary) writes per band the spectral radiance times 400 nm (``WVLSPAN``,
    380-780 nm; src/gen/gensdaymtx.c, src/gen/atmos.c) and scales its sky to the EPW's diffuse horizontal
    illuminance as ``DHI_lux / 179 / E_d / 1.15`` (E_d its own 380-780 nm diffuse). So its patches divided by 400 nm,
    summed over the 20 bands of 20 nm and the hemisphere (Tregenza patch centres, solid angle x cos), give
    ``DHI_lux / (179 x 1.15)``: within 0 to +10 % with the sun 15 deg or more up (the patch quadrature of its
    radiance against its irradiance table; measured +6 to +9 %). A reading per nm would be 20 times off, one in
    Radiance's luminance units 179 times. Doubling the illuminance doubles every patch. The first run precomputes
    gensdaymtx's tables (minutes) in its working folder: ``$SKYSCATTER_RADIANCE_DIR`` if set (kept between
    sessions), else the session's cache. They cannot be made smaller: their sizes, the 20 bands and the 4 scattering
    orders are compiled into gensdaymtx (src/gen/atmos.h, ``precompute(sorder=4)``); about 160 s of CPU once, then
    9 s (2026-12-03)."""
    import os

    from skyscatter.patches import patch_scheme
    from skyscatter.precomputed.cache import cache_dir
    from skyscatter.sun.position import sun_position_unix
    from weather_synth import SITE

    pyradiance = pytest.importorskip("pyradiance")
    root = Path(pyradiance.__file__).parent
    work = Path(os.environ.get("SKYSCATTER_RADIANCE_DIR") or cache_dir() / "radiance")
    work.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, RAYPATH=f".{os.pathsep}{root / 'lib'}")

    def run(lux: float) -> np.ndarray:
        def tweak(rows):
            for r in rows:
                if float(r[15]) > 0:
                    r[16], r[17], r[18] = "50000", "30000", f"{lux:.0f}"  # global, direct, diffuse illuminance
                r[29] = "0.120"  # the aerosol field gensdaymtx reads (one table set)
        epw = write_epw(tmp_path / f"lux{lux:.0f}.epw", days=((6, 20, "clear"),), tweak=tweak)
        out = subprocess.run([str(root / "bin" / "gensdaymtx"), "-m", "1", "-s", str(epw)], cwd=work, env=env,
                             capture_output=True, check=True).stdout
        head, body = out.split(b"\n\n", 1)
        text = head.decode()
        n = [int(text.split(f"{k}=")[1].split()[0]) for k in ("NROWS", "NCOLS", "NCOMP")]
        return np.array(body.split(), dtype=float).reshape(*n)[1:]  # sky patches (145, 24 hours, 20 bands)

    a, b = run(20000.0), run(40000.0)
    geom = patch_scheme("tregenza")
    weight = geom.solid_angles * geom.sample_directions(1)[:, 0, 2]
    e_vis = np.einsum("phk,p->h", a / 400.0 * 20.0, weight)
    start = np.datetime64("2023-06-20T00:00").astype("datetime64[s]").astype(np.int64)
    unix = start + (np.arange(1, 25) - 0.5) * 3600.0 - SITE["timezone"] * 3600.0
    el = 90 - np.degrees(np.asarray(sun_position_unix(np.radians(SITE["latitude"]), np.radians(SITE["longitude"]),
                                                      unix, apparent=False).zenith))
    up = el >= 15.0
    assert up.sum() >= 10
    ratio = e_vis[up] / (20000.0 / 179.0 / 1.15)
    assert np.all((ratio > 1.0) & (ratio < 1.10)), ratio
    lit = a[:, up] > 0.05  # (hours without the record's light keep 999999, missing: not calibrated)
    np.testing.assert_allclose(b[:, up][lit], 2.0 * a[:, up][lit], rtol=0.01)  # ASCII: 3 significant digits
