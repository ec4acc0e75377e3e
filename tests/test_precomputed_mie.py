"""The precomputed tables with a tabulated (Mie) aerosol phase (issue 20).

* Single scattering against the independent integral of tests/precomputed_reference.py, which evaluates
  the aerosol's phase table with numpy (no table, no kernel): within 0.8 % for a Mie aerosol (OPAC
  continental-average, optical depth 0.2; measured 0.61 % worst) at the small test sizes, the same as the default
  Cornette-Shanks aerosol there (0.80 % at 550 nm: the interpolation between the 16 radii, not the phase);
  at the default sizes within the issue's 0.5 % (measured 0.32 % worst); 5 deg from the sun included.
* The aerial perspective reads the same table: at the default sizes, single scattering only, the inscattered
  radiance between the ground and points 5-30 km away (5-30 deg up, towards and away from the sun) against the
  same integral as S(camera) - T S(point), within 1 % (measured 0.63 % worst; the analytic default 1.45 % there),
  its transmittance within 0.5 % (0.2 %).
* Multiple scattering against DISORT with the same phase table's Legendre moments and its intensity correction
  with the table itself (tests/disort_reference.py): benchmarks/validate_disort_mie.py (docs/aerosols.md); here
  one case, continental-average, optical depth 0.2, sun at 30 deg, within 3 %; and coarse sea salt alone, whose
  diffraction peak is the hardest for the delta-M orders and the TMS single scattering, within 3 % plus the
  sphericity allowance.
* Multiple scattering against the Monte Carlo reference, which samples the full phase table (never truncated):
  benchmarks/compare_montecarlo_mie.py (docs/aerosols.md: within 1.2 % for two types); here the same case in the
  principal plane, view zenith 0-70 deg (not within 5 deg of the sun), within 3 % + 3 standard errors.
  At sun 70 deg both airs against stored Monte Carlo values (tests/data/montecarlo_mie_low_sun.json), the same
  bound; and maritime-clean at optical depth 0.5 against DISORT with 32 radius rows.
* The default aerosol's tables are unchanged (tests/test_precomputed_tables.py and the cache keys).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from precomputed_reference import SMALL_SIZES, optical_depth, single_scattering
from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.precomputed import PrecomputedAtmosphere


@pytest.fixture(scope="module")
def mie_params():
    return AtmosphereParameters.with_aerosol_type("continental-average", 0.2, 50.0, ozone_column=0.0,
                                                  solar_irradiance=1.0, ground_albedo=0.1)


@pytest.mark.parametrize(("sizes", "rtol"), [(SMALL_SIZES, 8e-3), (None, 5e-3)], ids=["small", "default"])
def test_single_scattering_is_exact_to_the_phase_table(mie_params, sizes, rtol):
    p = mie_params
    kw = {} if sizes is None else dict(sizes=sizes)
    atm = PrecomputedAtmosphere.compute(p, orders=1, wavelengths=[450.0, 650.0], progress=False, **kw)
    ts = math.radians(30.0)
    sun = np.array([math.sin(ts), 0.0, math.cos(ts)])
    r = p.bottom_radius + 1.0
    for vz_deg, side in ((0.0, 1), (25.0, 1), (35.0, 1), (60.0, 1), (10.0, -1), (40.0, -1), (70.0, -1)):
        vz = math.radians(vz_deg)
        d = np.array([side * math.sin(vz), 0.0, math.cos(vz)])
        ref = single_scattering(r, math.cos(vz), math.cos(ts), float(d @ sun), p, np.array([450.0, 650.0]))
        np.testing.assert_allclose(atm.sky_radiance([0.0, 0.0, r], d, sun), ref, rtol=rtol)
    # the observer fast path steps aside for a wavelength-dependent phase: XYZ is that of the spectrum
    d = np.array([[0.3, 0.0, 0.95]])
    np.testing.assert_allclose(atm.sky_xyz([0.0, 0.0, r], d, sun), atm.to_xyz(atm.sky_radiance([0.0, 0.0, r], d, sun)))


def test_aerial_perspective_reads_the_phase_table(mie_params):
    """The aerial perspective from a camera 10 m up (the cell of table rows touching the ground, 0-62.7 m) over
    5-30 km paths, single scattering of the phase table: its inscatter against the independent integral of
    tests/precomputed_reference.py as S(camera) - T S(point) within the issue's 0.5 % (measured 0.38 % worst, 5 km
    10 deg up towards the sun, 650 nm; until table format 16, which reads each row of that cell at its own mu
    coordinate with the altitude weight, 1.00 % 5 deg up away from the sun: a strict expected failure of the 1 %
    bound then), its transmittance within 0.5 % (measured 0.2 %)."""
    p, wl = mie_params, np.array([450.0, 650.0])
    atm = PrecomputedAtmosphere.compute(p, orders=1, wavelengths=wl, progress=False)
    ts = math.radians(30.0)
    sun = np.array([math.sin(ts), 0.0, math.cos(ts)])
    cam = np.array([0.0, 0.0, p.bottom_radius + 10.0])
    for el, az, dist in ((10, 0, 5e3), (10, 0, 20e3), (20, 180, 10e3), (30, 90, 30e3), (15, 20, 8e3), (5, 180, 15e3)):
        e, a = math.radians(el), math.radians(az)
        d = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])  # azimuth 0: the sun's
        pt = cam + dist * d
        r0, r1 = float(np.linalg.norm(cam)), float(np.linalg.norm(pt))
        nu = float(d @ sun)
        ss0 = single_scattering(r0, float(cam @ d) / r0, float(cam @ sun) / r0, nu, p, wl)
        ss1 = single_scattering(r1, float(pt @ d) / r1, float(pt @ sun) / r1, nu, p, wl)
        tr = np.exp(-optical_depth(np.array([r0]), np.array([float(cam @ d) / r0]), np.array([dist]), p, wl))[0]
        t, inscatter = atm.aerial_perspective(cam, pt, sun)
        np.testing.assert_allclose(t, tr, rtol=5e-3)
        np.testing.assert_allclose(inscatter, ss0 - tr * ss1, rtol=5e-3)


@pytest.fixture(scope="module")
def mie_tables(mie_params):
    from disort_reference import TABLE_SIZES as SIZES

    return PrecomputedAtmosphere.compute(mie_params, orders=6, wavelengths=[550.0], sizes=SIZES, progress=False)


@pytest.mark.slow
def test_multiple_scattering_against_disort(mie_params, mie_tables):
    pytest.importorskip("disortpp")
    from disort_reference import disort_radiance

    p, atm = mie_params, mie_tables
    ts = math.radians(30.0)
    vz = np.radians([0.0, 20.0, 50.0, 70.0])
    ref = disort_radiance(p, 550.0, ts, vz, np.radians([0.0, 180.0]), n_layers=100, n_streams=32, n_moments=400)
    for j, side in enumerate((1.0, -1.0)):
        d = np.stack([side * np.sin(vz), 0 * vz, np.cos(vz)], axis=-1)
        ours = atm.sky_radiance([0.0, 0.0, p.bottom_radius], d, [math.sin(ts), 0.0, math.cos(ts)])[:, 0]
        np.testing.assert_allclose(ours, ref[:, j], rtol=0.03)


@pytest.mark.slow
def test_sea_salt_against_disort_with_its_intensity_correction():
    """OPAC coarse sea salt alone (sscm, optical depth 0.2, diffraction peak a few tenths of a degree wide), sun at
    30 deg, principal plane, view zenith 0-70 deg (not the sun itself) against DISORT with the intensity
    correction of the phase table (tests/disort_reference.py): within 3 % plus the sphericity allowance of
    tests/test_precomputed_disort.py. Measured 2.1 % worst, +1.2 % 10 deg from the sun; against DISORT without
    the correction (its single scattering with the 32-term delta-M phase, the reference until 2026-12-02) the
    tables were +13 % 10 deg from the sun and -7.5 % 40 deg from it."""
    pytest.importorskip("disortpp")
    from disort_reference import TABLE_SIZES
    from skyscatter.atmosphere.aerosol_types import OpacAerosol

    p = AtmosphereParameters(ozone_column=0.0, ground_albedo=0.1, solar_irradiance=1.0)
    p = p.replace(aerosol=OpacAerosol.mixture((("sscm", 0.2),), column_height=p.thickness))
    atm = PrecomputedAtmosphere.compute(p, orders=6, wavelengths=[550.0], sizes=TABLE_SIZES, progress=False)
    _assert_principal_plane_against_disort(p, atm, 30.0)


@pytest.mark.slow
def test_maritime_clean_at_a_low_sun_against_disort():
    """OPAC maritime-clean, optical depth 0.5, sun at 70 deg, principal plane, view zenith 0-70 deg (not the sun
    itself) against DISORT with the intensity correction of the phase table, within 3 % plus the sphericity
    allowance, with 32 radius rows (the default tables' number; the other sizes the DISORT tests'). With the tests'
    16 rows the orders' scattering density, read linearly between rows along the view rays, misses its curvature in
    altitude in the sea-salt layer (0.86 km) and the tables are -5.8 % away from the sun at view zenith 70 deg,
    0.7 point beyond the allowance there; with 32 rows -3.9 % (docs/aerosols.md, "Tables vs DISORT")."""
    pytest.importorskip("disortpp")
    from disort_reference import TABLE_SIZES

    p = AtmosphereParameters.with_aerosol_type("maritime-clean", 0.5, 50.0, ozone_column=0.0, ground_albedo=0.1,
                                               solar_irradiance=1.0)
    atm = PrecomputedAtmosphere.compute(p, orders=6, wavelengths=[550.0], sizes=dict(TABLE_SIZES, scattering_r=32),
                                        progress=False)
    _assert_principal_plane_against_disort(p, atm, 70.0)


@pytest.mark.slow
def test_multiple_scattering_against_the_monte_carlo(mie_params, mie_tables):
    pytest.importorskip("dask")
    from skyscatter.montecarlo import sky_radiance

    p, atm = mie_params, mie_tables
    ts = math.radians(30.0)
    vz = np.radians(np.arange(0.0, 71.0, 10.0))
    for side in (1.0, -1.0):
        keep = np.abs(np.degrees(vz) * side - 30.0) > 5.0  # not the sun itself
        d = np.stack([side * np.sin(vz), 0 * vz, np.cos(vz)], axis=-1)[keep]
        ours = atm.sky_radiance([0.0, 0.0, p.bottom_radius], d, [math.sin(ts), 0.0, math.cos(ts)])[:, 0]
        # ENU directions; the tables' sun vector lies along +x: azimuth 90 deg (east)
        mc = sky_radiance(p, d, [550.0], sun_zenith=ts, sun_azimuth=math.pi / 2, samples=8192, seed=5,
                          scheduler="synchronous")
        rel = np.abs(ours / mc.radiance[:, 0] - 1)
        assert np.all(rel < 0.03 + 3 * mc.relative_stderr[:, 0]), (side, rel, mc.relative_stderr[:, 0])


@pytest.mark.slow
@pytest.mark.parametrize("aerosol_type", ["continental-average", "maritime-clean"])
def test_multiple_scattering_against_the_monte_carlo_at_a_low_sun(mie_params, mie_tables, aerosol_type):
    """Sun at 70 deg, optical depth 0.2, principal plane, view zenith 0-70 deg (not within 5 deg of the sun): the
    tables at the DISORT tests' sizes against the stored Monte Carlo values of tests/data/montecarlo_mie_low_sun.json
    (benchmarks/montecarlo_mie_low_sun.py: its seeds and path counts there; the full phase table sampled) within
    the issue's 3 % + 3 standard errors (docs/aerosols.md has the measured differences)."""
    import json
    from pathlib import Path

    data = json.loads((Path(__file__).parent / "data" / "montecarlo_mie_low_sun.json").read_text())
    case = next(c for c in data["cases"] if c["type"] == aerosol_type)
    if aerosol_type == "continental-average":
        p, atm = mie_params, mie_tables  # the same air as the stored values'
    else:
        from disort_reference import TABLE_SIZES

        p = AtmosphereParameters.with_aerosol_type(aerosol_type, case["aod_550"], case["relative_humidity"],
                                                   ozone_column=0.0, solar_irradiance=1.0, ground_albedo=0.1)
        atm = PrecomputedAtmosphere.compute(p, orders=6, wavelengths=[550.0], sizes=TABLE_SIZES, progress=False)
    assert p.to_dict() == AtmosphereParameters.with_aerosol_type(
        aerosol_type, case["aod_550"], case["relative_humidity"], ozone_column=0.0, solar_irradiance=1.0,
        ground_albedo=0.1).to_dict()
    ts = math.radians(data["sun_zenith_deg"])
    vz, side = np.radians(np.array(data["views"])[:, 0]), np.array(data["views"])[:, 1]
    d = np.stack([side * np.sin(vz), 0 * vz, np.cos(vz)], axis=-1)
    ours = atm.sky_radiance([0.0, 0.0, p.bottom_radius], d, [math.sin(ts), 0.0, math.cos(ts)])[:, 0]
    mc, se = np.array(case["radiance"]), np.array(case["relative_stderr"])
    rel = ours / mc - 1.0
    assert np.all(np.abs(rel) < 0.03 + 3 * se), (np.round(100 * rel, 2), np.round(100 * se, 2))


def test_saved_tables_carry_the_phase_table(mie_params, tmp_path, monkeypatch):
    """A table file of a Mie aerosol stores the lookups' phase table: loading it and evaluating does not compute
    the aerosol's phase again (miepython's import and the Mie sums cost 4-8 s of CPU per process), and the sky is
    bit for bit the one of the tables that were saved. A damaged phase table is refused; a file written without
    it (before it was stored) still loads and computes it."""
    import zipfile

    from skyscatter.errors import FileFormatError
    from skyscatter.precomputed import storage

    atm = PrecomputedAtmosphere.compute(mie_params, orders=1, wavelengths=[450.0, 650.0], sizes=SMALL_SIZES,
                                        progress=False)
    r = atm.parameters.bottom_radius
    d = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [-0.8, 0.0, 0.6], [0.0, 0.99, 0.141]])
    sun = np.array([0.5, 0.0, math.sqrt(0.75)])
    expected = atm.sky_radiance([0.0, 0.0, r], d, sun)
    path = atm.save(tmp_path / "mie.npz")
    with zipfile.ZipFile(path) as zf:
        assert {f"{n}.npy" for n in storage.PHASE_NAMES} <= set(zf.namelist())

    def no_phase(*args, **kwargs):
        raise AssertionError("the phase table was computed again")

    with monkeypatch.context() as mp:
        mp.setattr(AtmosphereParameters, "aerosol_phase_table", no_phase)
        loaded = PrecomputedAtmosphere.load(path)
        np.testing.assert_array_equal(loaded.sky_radiance([0.0, 0.0, r], d, sun), expected)
        # in twilight the lookups compute the single scattering's sub-texels from the stored phase table (no Mie
        # sums either), as the tables that were saved do, observer and per-ray paths; the stored arrays stay
        # writable (a frozen array would make numba compile the lookups again for it)
        dusk = np.array([0.0, math.cos(math.radians(-3.0)), math.sin(math.radians(-3.0))])
        many = np.broadcast_to([0.0, 0.0, r + 5.0], d.shape)
        for where in ([0.0, 0.0, r], many):
            np.testing.assert_array_equal(loaded.sky_radiance(where, d, dusk), atm.sky_radiance(where, d, dusk))
        assert loaded.computed and all(a.flags.writeable for a in loaded._aerosol_phase[2:])

    damaged = tmp_path / "damaged.npz"
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(damaged, "w", zipfile.ZIP_STORED) as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename == "aerosol_phase_values.npy":
                data = data[:-8] + np.float64(1.0).tobytes()
            dst.writestr(info, data)
    with pytest.raises(FileFormatError, match="checksum mismatch in table 'aerosol_phase_values'"):
        PrecomputedAtmosphere.load(damaged)

    older = tmp_path / "older.npz"
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(older, "w", zipfile.ZIP_STORED) as dst:
        for info in src.infolist():
            if info.filename[:-4] not in storage.PHASE_NAMES:
                dst.writestr(info, src.read(info))
    np.testing.assert_array_equal(PrecomputedAtmosphere.load(older).sky_radiance([0.0, 0.0, r], d, sun), expected)


def _assert_principal_plane_against_disort(p, atm, sun_zenith_deg):
    """The tables' radiance at 550 nm in the principal plane, view zenith 0-70 deg every 10 deg (not the sun
    itself), against DISORT (100 layers, 32 streams, 400 moments) within 3 % plus the sphericity allowance."""
    from disort_reference import disort_radiance, sphericity_allowance

    ts = math.radians(sun_zenith_deg)
    vz = np.radians(np.arange(0.0, 71.0, 10.0))
    ref = disort_radiance(p, 550.0, ts, vz, np.radians([0.0, 180.0]), n_layers=100, n_streams=32, n_moments=400)
    tol = 0.03 + sphericity_allowance(p, ts, vz)
    for j, side in enumerate((1.0, -1.0)):
        keep = np.abs(side * np.degrees(vz) - sun_zenith_deg) > 1.0  # not the sun itself
        d = np.stack([side * np.sin(vz), 0 * vz, np.cos(vz)], axis=-1)
        ours = atm.sky_radiance([0.0, 0.0, p.bottom_radius], d, [math.sin(ts), 0.0, math.cos(ts)])[:, 0]
        err = ours / ref[:, j] - 1.0
        assert np.all(np.abs(err[keep]) < tol[keep]), (side, np.round(100 * err, 2))


@pytest.mark.parametrize("aerosol", ["mie", "analytic"])
def test_stored_single_scattering_at_the_texels_is_the_stored_tables(mie_params, aerosol):
    """``compute.stored_single_scattering`` (the rendering lookups' single-scattering sub-texels) at the tables' own
    sun-zenith texels gives their stored single-scattering tables, within the half-precision storage (4.9e-4 where a
    value is above 1e-3 of its radius layer's largest): for a tabulated phase through the delta-M scaled medium, its
    transmittance recomputed and per unit scattering coefficient, with the phase from the lookups' arrays (a file's:
    no Mie sums); for the analytic phase directly."""
    from skyscatter.precomputed import TableSizes
    from skyscatter.precomputed.compute import Medium, single_scattering_source, stored_single_scattering
    from skyscatter.precomputed.kernels import mu_s_texels

    p = mie_params if aerosol == "mie" else AtmosphereParameters.from_turbidity(3.0)
    sizes = TableSizes(**SMALL_SIZES)
    atm = PrecomputedAtmosphere.compute(p, orders=2, wavelengths=[450.0, 650.0], sizes=sizes, progress=False)
    _, _, mu, values = atm._aerosol_phase
    medium = Medium.of(p, atm.wavelengths, sizes, (mu, values) if aerosol == "mie" else None)
    source = single_scattering_source(medium, sizes, atm.orders, np.asarray(atm.stored["transmittance"]))
    assert (source[0] is medium) == (aerosol == "analytic")  # a tabulated phase: the delta-M scaled medium
    suns = mu_s_texels(p.bottom_radius, p.top_radius, p.mu_s_min, sizes.scattering_mu_s)
    rows = range(2, 5)
    ray, mie = stored_single_scattering(source, sizes, suns, rows)
    for got, name in ((ray, "single_rayleigh"), (mie, "single_mie")):
        want = np.asarray(atm.tables[name], dtype=np.float64)[rows.start:rows.stop]
        keep = want > 1e-3 * want.max(axis=(1, 2, 3), keepdims=True)
        assert keep.sum() > 1000
        np.testing.assert_allclose(got[keep], want[keep], rtol=5e-4, err_msg=name)
