"""The precomputed tables at low sun against stored Monte Carlo values (docs/accuracy.md, "Low sun").

Reference: tests/data/low_sun_montecarlo.json, made by ``benchmarks/low_sun_montecarlo_reference.py`` (the seed
and path count of each case are stored in it; rerun the script to regenerate them): the spectral Monte Carlo
(:mod:`skyscatter.montecarlo`, validated against DISORT, QUADPACK and energy conservation, docs/montecarlo.md) for
Earth defaults, turbidity 3 and aerosol optical depth 0.5, the sun at +10, +3, 0, -3 and -6 deg (the issue's) and
at -2.3 and -5.1 deg (between two sun-zenith texels of the default tables: the issue's twilight suns sit within
0.12 deg of a texel, so only these measure the read between texels below the horizon), an observer on
the ground, view elevations 2, 5 and 15 deg at azimuths 0-180 deg from the sun, 16 wavelengths.

The tables here are the default sizes and orders computed at three of the stored wavelengths (400, 560 and
700 nm: radiance at a table wavelength does not depend on the others). Target (the issue's): within 5 % or 2
Monte Carlo standard errors, whichever is larger.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from skyscatter.precomputed import AtmosphereParameters, cached_atmosphere

DATA = Path(__file__).parent / "data" / "low_sun_montecarlo.json"
WAVELENGTHS = [400.0, 560.0, 700.0]
ATMOSPHERES = {
    "earth": AtmosphereParameters,
    "turbidity3": lambda: AtmosphereParameters.from_turbidity(3.0),
    "aod05": lambda: AtmosphereParameters.from_aerosol_optical_depth(0.5),
}


@pytest.fixture(scope="module")
def reference():
    return json.loads(DATA.read_text())


@pytest.fixture(scope="module")
def tables():
    """Default-size tables at the three compared wavelengths, per atmosphere, computed once per session: through
    the session's table cache, so that parallel workers running tests of this module share one build."""
    return {name: cached_atmosphere(make(), wavelengths=WAVELENGTHS, progress=False)
            for name, make in ATMOSPHERES.items()}


def _directions(views):
    out = []
    for e, a in views:
        er, ar = math.radians(e), math.radians(a)
        out.append([math.cos(er) * math.sin(ar), math.cos(er) * math.cos(ar), math.sin(er)])
    return np.array(out)


def _errors(reference, tables, name, sun_elev):
    """(tables / MC - 1, MC relative standard error), (n_views, 3), for one stored case."""
    case = next(c for c in reference["cases"] if c["atmosphere"] == name and c["sun_elevation_deg"] == sun_elev)
    cols = [reference["wavelengths_nm"].index(w) for w in WAVELENGTHS]
    atm = tables[name]
    s = math.radians(sun_elev)
    tab = atm.sky_radiance(np.array([0.0, 0.0, atm.parameters.bottom_radius]), _directions(reference["views_deg"]),
                           np.array([0.0, math.cos(s), math.sin(s)]))
    mc = np.array(case["radiance"])[:, cols]
    se = np.array(case["radiance_stderr"])[:, cols]
    return tab / mc - 1.0, se / mc


def test_reference_records_how_it_was_made(reference):
    """Every case names its seed and path count, and the generator script exists (so the values can be remade)."""
    assert (Path(__file__).parents[1] / reference["generator"]).is_file()
    assert len(reference["cases"]) == 21
    for c in reference["cases"]:
        assert c["paths"] >= 1048576  # every case remade with at least this many (2026-12-06)
        assert np.all(np.array(c["radiance"]) > 0.0) and np.all(np.array(c["radiance_stderr"]) > 0.0)
    # one random stream per case and run (the same seed in every case repeated a direction's draw at every sun); a
    # pooled case lists its later runs (benchmarks/low_sun_montecarlo_reference.py --pool), whose paths add up
    seeds = [c["seed"] for c in reference["cases"]]
    for c in reference["cases"]:
        runs = c.get("pooled_runs", [])
        seeds += [r["seed"] for r in runs]
        assert c["paths"] > sum(r["paths"] for r in runs)
    assert len(set(seeds)) == len(seeds)


def test_pooled_runs_are_the_mean_of_all_their_paths():
    """``pool_runs`` of two independent runs: the mean of all their samples, its standard error that of all the
    samples together (within the spread of the runs' own estimates: 3 % here), and a seed used twice refused."""
    import sys

    sys.path.insert(0, str(Path(__file__).parents[1] / "benchmarks"))
    try:
        from low_sun_montecarlo_reference import pool_runs
    finally:
        sys.path.pop(0)
    rng = np.random.default_rng(5)
    x = rng.lognormal(0.0, 1.0, (3000, 2))
    y = rng.lognormal(0.0, 1.0, (9000, 2))

    def run(v, seed):
        return {"paths": len(v), "seed": seed, "seconds": 1.0, "radiance": v.mean(0).tolist(),
                "radiance_stderr": (v.std(0, ddof=1) / math.sqrt(len(v))).tolist()}

    pooled = pool_runs(run(x, 1), run(y, 2))
    both = np.concatenate([x, y])
    np.testing.assert_allclose(pooled["radiance"], both.mean(0), rtol=1e-12)
    np.testing.assert_allclose(pooled["radiance_stderr"], both.std(0, ddof=1) / math.sqrt(len(both)), rtol=0.03)
    assert pooled["paths"] == 12000 and pooled["seed"] == 1 and pooled["pooled_runs"][0]["seed"] == 2
    with pytest.raises(ValueError, match="seed 2 was already used"):
        pool_runs(pooled, run(y, 2))


#: Cases (atmosphere, sun elevation [deg]) with directions outside the target with table format 19 (the rendering
#: lookups interpolate log-linearly along the view-sun azimuth, the multiple scattering as its ratio to the lobe of
#: ``sampling.multiple_lobe``, as the precomputation's reads do; except the single scattering seen from a point in the
#: Earth's shadow, which they read with weights that follow the shadow, as the second order's density does; the
#: orders' ray integrals interpolate the scattering density log-linearly along the sun zenith and azimuth; the
#: irradiance table is read log-quadratically along the sun zenith below the horizon; the lookups' shadow factors up
#: to ``sampling.SHADOW_RATIO_MAX``; since 2026-12-05 the lookups read the 4D tables refined along the sun zenith in
#: the cells wholly below the horizon, ``lookup.refine_sun_zenith``; measured against the regenerated reference
#: (4x the paths, one seed per case, 2026-12-03), ``benchmarks/compare_low_sun_tables.py``; docs/accuracy.md, "Low
#: sun"): how many directions, and the one furthest outside (largest excess over the target; the cell's worst of
#: 400/560/700 nm), as measured against the stored values. Held as strict expected failures, so that a fix shows
#: (and must then move the case out of this table). 64 of 315 directions (120 before the refined read); turbidity 3
#: at -2.3 deg passes since (12 of 15 before), turbidity 3 at -3 deg does not (0 before: 5/45 deg -5.1 -> -5.9 +-
#: 2.7 %, the sun 0.05 deg below a texel, where the refined read is a little darker than the linear one). Since
#: the default orders went from 6 to 8 (2026-12-05: the tail after 6 was short in hazy twilight at 400 nm), 53 of
#: 315: optical depth 0.5 34 -> 24 (-5.1 deg 10 -> 3, -6 deg 5 -> 3), turbidity 3 14 -> 13, Earth 16 unchanged.
#: Since the cell across the horizon is split too and the single scattering's sub-texels are computed at their suns
#: (2026-12-05, ``compute.stored_single_scattering``; the multiple scattering's sub-texels keep the four-point
#: rule), 40 of 315: Earth 16 -> 10 (0 deg, -2.3 deg pass; -5.1 deg 7 -> 5), turbidity 3 13 -> 9 (0 deg passes: 5
#: outside before, worst 2/0 deg +19.5 %; -6 deg 2 -> 3), optical depth 0.5 24 -> 21 (0 deg 5 -> 3, -5.1 deg 3 -> 2).
#: Since the lookups read the multiple scattering through four azimuth texels (2026-12-06,
#: ``sampling.lookup4_cell_azimuth``), 27 of 315: turbidity 3 9 -> 4 (+3, -3 deg pass; -5.1 deg 4 -> 1), optical
#: depth 0.5 21 -> 13 (+10 deg passes; +3 deg 6 -> 3, -3 deg 5 -> 3), Earth 10. The same day the -6 deg cases of the
#: reference were made again with 8 times the paths (8388608 per direction, seeds 305, 310, 315; standard errors
#: median 1.0-2.0 %, the old values within them: |z| median 0.62-0.77): 31 of 315 (the two-texel read: 42), Earth
#: at -6 deg 5 -> 7 and turbidity 3 2 -> 4, now 6-11 % dark 90-180 deg from the sun where the noise hid it.
#: Table format 20 (2026-12-06: the scattering density's sphere integral reads the previous order through the same
#: four azimuth texels, ``sampling.scattering_lookup``): 25 of 315, optical depth 0.5 14 -> 8 (+3 deg passes: its
#: 400 nm cells towards the sun; 0 deg 2 -> 1, -3 deg 3 -> 2, -2.3 deg passes, -5.1 deg 2 -> 1; -6 deg 3 -> 4).
#: Table format 21 (2026-12-06: the second order's scattering density reads the single scattering from the Earth's
#: shadow with the lookups' shadow factors, up to ``sampling.SHADOW_RATIO_MAX``, not 1): 15 of 315, the twilight
#: multiple scattering 1.2-2.7 % brighter on average at -5.1 and -6 deg; turbidity 3 -6 deg passes (4 -> 0), Earth -6
#: deg 7 -> 4 and -5.1 deg 5 -> 4, optical depth 0.5 -6 deg 4 -> 1, -5.1 deg 1 -> 2.
#: Every case of the reference but -6 deg made again with 4 to 8 times the paths (2026-12-06; at least 1048576 per
#: direction, 8388608 at -5.1 deg; seeds 401-421 and 501-520; standard errors median 0.06-1.1 %, the old values
#: within them): 9 of 315, the same tables. Optical depth 0.5 at 0, -3 and -5.1 deg pass (their cells outside were the
#: old reference's noise: 0 deg 5/0 +6.4 +- 1.8 -> +1.9 +- 0.7 %, -3 deg 15/180 -8.6 +- 3.5 -> -1.5 +- 0.5 %, -5.1 deg
#: 2/45 -9.5 +- 3.5 -> -2.6 +- 1.8 %); Earth at -5.1 deg 4 -> 3 (2/45 -9.3 +- 2.7 -> -1.5 +- 1.4 %; 2/90 -7.8 +- 0.4 %,
#: the single scattering read across the Earth's shadow, as at -6 deg), turbidity 3 at -5.1 deg 1 (15/180 +7.0 +-
#: 0.8 %, was +5.9 +- 1.8 % at 15/135).
#: The observer's single scattering computed at its own sun in twilight (2026-12-06, the lookups; the tables the same:
#: ``PrecomputedAtmosphere._twilight_singles``, the sun's disc in chords near the horizon, 29 azimuth texels): 3 of
#: 315. Earth at -5.1 deg and turbidity 3 at -5.1 deg pass, Earth at -6 deg 4 -> 2 (2/90 -9.0 +- 0.8 -> +3.0 +- 1.4 %;
#: left: 2/180 -9.1 +- 3.6 %, 15/180 -5.3 +- 1.0 %, the multiple scattering's twilight deficit).
#: The -6 deg cases outside pooled with more paths (2026-12-06, ``low_sun_montecarlo_reference.py --pool``; table
#: format 22): 0 of 315. Earth, 4 times the paths (33554432 per direction, seeds 315 and 615; standard errors median
#: 1.0 -> 0.5 %): 2/180 -9.1 +- 3.6 -> -3.3 +- 1.8 % (the 400 nm value of the earlier run was high by 2.3 of its
#: standard errors), 15/180 -5.3 +- 1.0 -> -4.9 +- 0.5 % (inside by 0.1 point: the anti-solar twilight deficit of the
#: multiple scattering, 3-5 % there, is real, 10 standard errors at 700 nm); optical depth 0.5, 3 times the paths
#: (25165824, seeds 305 and 605; 2.0 -> 1.1 %): 5/0 +5.4 +- 1.5 -> +2.8 +- 0.9 %. Kept as a mapping (empty) so that
#: a case found outside later goes back in as a strict expected failure with its worst cell.
OUTSIDE: dict[tuple[str, float], str] = {}

CASES = [(a, s) for a in ATMOSPHERES for s in (10.0, 3.0, 0.0, -3.0, -6.0, -2.3, -5.1)]


@pytest.mark.slow
@pytest.mark.parametrize(("name", "sun_elev"), [
    pytest.param(a, s, marks=pytest.mark.xfail(strict=True, reason=OUTSIDE[a, s])) if (a, s) in OUTSIDE
    else (a, s) for a, s in CASES])
def test_low_sun_against_stored_monte_carlo(reference, tables, name, sun_elev):
    """Every direction of the case within 5 % or 2 Monte Carlo standard errors, whichever is larger, at each of
    the three wavelengths."""
    rel, rse = _errors(reference, tables, name, sun_elev)
    bad = np.abs(rel) > np.maximum(0.05, 2.0 * rse)
    assert not bad.any(), (np.round(100 * rel, 1), np.round(100 * rse, 1))


SINGLE = Path(__file__).parent / "data" / "low_sun_single_montecarlo.json"


@pytest.fixture(scope="module")
def single_tables():
    """Single-scattering tables (``orders=1``) at the compared wavelengths, per atmosphere."""
    return {name: cached_atmosphere(make(), wavelengths=WAVELENGTHS, orders=1, progress=False)
            for name, make in ATMOSPHERES.items()}


@pytest.mark.slow
def test_observer_single_scattering_in_twilight_against_monte_carlo(reference, single_tables):
    """The observer's single scattering with the sun at or below the horizon (computed at the sun itself on 29
    azimuth texels, the sun's disc in chords near the horizon: ``_twilight_singles``) against the Monte Carlo's first
    order (``orders=1``, 1048576 paths per direction, tests/data/low_sun_single_montecarlo.json, made by
    benchmarks/low_sun_single_reference.py): every direction and wavelength within 3 % of the whole sky there (the
    stored all-orders Monte Carlo) plus 2 standard errors of the first order. Measured 2026-12-06: at most 0.2-2.6 %
    of the whole sky (Earth 0.19 / 0.67 / 0.81 / 1.85 / 2.61 % at 0 / -2.3 / -3 / -5.1 / -6 deg); the stored texels
    read by the lookups' rules (the general kernel's way, and this path before) up to 9.4 % (Earth -6 deg; -5.1 deg
    7.5 %, -2.3 deg 4.7 %; turbidity 3 at -5.1 deg 5.0 %), which this test refuses."""
    doc = json.loads(SINGLE.read_text())
    assert doc["wavelengths_nm"] == WAVELENGTHS and doc["orders"] == 1
    assert (Path(__file__).parents[1] / doc["generator"]).is_file()
    cols = [reference["wavelengths_nm"].index(w) for w in WAVELENGTHS]
    checked = 0
    for case in doc["cases"]:
        name, sun = case["atmosphere"], case["sun_elevation_deg"]
        if sun > 0.0:
            continue
        assert case["paths"] >= 1048576
        whole = next(c for c in reference["cases"] if c["atmosphere"] == name and c["sun_elevation_deg"] == sun)
        atm = single_tables[name]
        s = math.radians(sun)
        tab = atm.sky_radiance(np.array([0.0, 0.0, atm.parameters.bottom_radius]),
                               _directions(doc["views_deg"]), np.array([0.0, math.cos(s), math.sin(s)]))
        mc, se = np.array(case["radiance"]), np.array(case["radiance_stderr"])
        allowed = 0.03 * np.array(whole["radiance"])[:, cols] + 2.0 * se
        assert np.all(np.abs(tab - mc) <= allowed), (name, sun, np.round(100 * (tab - mc) / allowed, 1))
        checked += 1
    assert checked == 15


def test_twilight_single_switch_continuity_and_many_suns(tables):
    """The observer's computed single scattering in twilight (``compute_twilight_single``): by day nothing changes
    (the same bits either way); at the top of the twilight cells (+0.78 deg at the default sizes) the sky steps by at
    most 1.5 % between just below (computed) and just above (the texels' read) (measured 0.20 / 0.44 / 0.25 % at 400 /
    560 / 700 nm, Earth; turbidity 3 0.07 / 0.55 / 0.75 %); below it the switch changes the sky; and
    ``sky_radiance_suns`` gives ``sky_radiance`` of each sun, twilight suns included."""
    d = _directions([(e, a) for e in (2.0, 5.0, 15.0, 60.0) for a in (0.0, 45.0, 90.0, 135.0, 180.0)])
    for name in ("earth", "turbidity3"):
        atm = tables[name]
        pos = np.array([0.0, 0.0, atm.parameters.bottom_radius])

        def sun(mu):
            return np.array([0.0, math.sqrt(1.0 - mu * mu), mu])

        day = atm.sky_radiance(pos, d, sun(math.sin(math.radians(10.0))))
        atm.compute_twilight_single = False
        try:
            assert np.array_equal(atm.sky_radiance(pos, d, sun(math.sin(math.radians(10.0)))), day)
            read = atm.sky_radiance(pos, d, sun(math.sin(math.radians(-3.0))))
        finally:
            atm.compute_twilight_single = True
        computed = atm.sky_radiance(pos, d, sun(math.sin(math.radians(-3.0))))
        assert np.max(np.abs(computed / read - 1.0)) > 1e-3
        top = atm._twilight_top()
        below, above = (atm.sky_radiance(pos, d, sun(top + eps)) for eps in (-1e-9, 1e-9))
        assert np.max(np.abs(below / above - 1.0)) < 0.015, name
        suns = np.array([sun(math.sin(math.radians(e))) for e in (20.0, 0.5, -2.0, -5.5)])
        many = atm.sky_radiance_suns(pos, d, suns)
        for k in range(suns.shape[0]):
            np.testing.assert_allclose(many[k], atm.sky_radiance(pos, d, suns[k]), rtol=1e-12, atol=0.0)


def test_sun_disc_chords_against_uniform_points():
    """The sun's disc in chords (``kernels._sun_disc_cells``, near the horizon) against the mean over
    200000 points uniform on the disc of the same transmittance table's value and the planet's blocking of each
    point's own ray: within 0.5 % of the visible disc's mean; the shares sum to the visible fraction of the disc
    (``sampling.sun_visible_fraction``) and by day the centre alone is used."""
    from skyscatter.precomputed import kernels, sampling

    atm = cached_atmosphere(AtmosphereParameters(), wavelengths=[700.0], orders=1, progress=False)
    t = np.ascontiguousarray(atm.stored["transmittance"], dtype=np.float32)
    bottom, top = atm.parameters.bottom_radius, atm.parameters.top_radius
    alpha = atm.parameters.sun_angular_radius
    n_tr, n_tmu = t.shape[0], t.shape[1]
    x, w = np.empty(kernels.DISC_NODES), np.empty(kernels.DISC_NODES)
    kernels.gauss_legendre_unit(kernels.DISC_NODES, x, w)
    rng = np.random.default_rng(5)
    n = 50000
    rad, ang = np.sqrt(rng.random(n)), 2 * np.pi * rng.random(n)
    up = rad * np.sin(ang)  # each point's height on the disc [disc radii]

    def table(r, mu):
        p_r, p_mu = kernels.transmittance_coord(r, mu, bottom, top, n_tr, n_tmu)
        i, a = kernels.lerp_index(p_r, 0, n_tr - 1)
        j, b = kernels.lerp_index(p_mu, 0, n_tmu - 1)
        return ((1 - a) * ((1 - b) * t[i, j, 0] + b * t[i, j + 1, 0])
                + a * ((1 - b) * t[i + 1, j, 0] + b * t[i + 1, j + 1, 0]))

    for alt, elev_radii in ((3000.0, -0.6), (3000.0, 0.4), (12000.0, 2.5), (30000.0, 12.0), (30000.0, 40.0)):
        r = bottom + alt
        mu_h = -math.sqrt(1 - (bottom / r) ** 2)
        mu_s = math.cos(math.acos(mu_h) - elev_radii * alpha)
        cell = np.empty(kernels.DISC_NODES, dtype=np.int64)
        wc, frac = np.empty(kernels.DISC_NODES), np.empty(kernels.DISC_NODES)
        kernels._sun_disc_cells(r, 0.0, r, np.array([mu_s]), np.array([0.0]), bottom, top, alpha, n_tmu, cell, wc,
                                frac, x, w)
        cell, wc, frac = cell[None], wc[None], frac[None]  # (one sun, its nodes)
        visible = sampling.sun_visible_fraction(r, mu_s, bottom, alpha)
        assert frac.sum() == pytest.approx(visible, rel=1e-12)
        if elev_radii >= kernels.DISC_HORIZON_RADII:
            assert frac[0, 0] == visible and np.all(frac[0, 1:] == 0.0)
        # the chords' rule: each node's cell of the table's mu axis, at the sample's radius
        p_r, _ = kernels.transmittance_coord(r, 1.0, bottom, top, n_tr, n_tmu)
        i, a = kernels.lerp_index(p_r, 0, n_tr - 1)
        chords = 0.0
        for k in np.flatnonzero(frac[0] > 0):
            j, b = cell[0, k], wc[0, k]
            chords += frac[0, k] * ((1 - a) * ((1 - b) * t[i, j, 0] + b * t[i, j + 1, 0])
                                    + a * ((1 - b) * t[i + 1, j, 0] + b * t[i + 1, j + 1, 0]))
        mus = np.cos(math.acos(mu_s) - up * alpha)
        points = sum(table(r, m) for m in mus[mus > mu_h]) / n  # blocked points add nothing
        assert chords == pytest.approx(points, rel=5e-3), (alt, elev_radii, chords, points)


def test_sphere_quadrature_is_double_gauss():
    """The density grid's zenith nodes are Gauss-Legendre in cos(theta) on each hemisphere (numpy's leggauss as
    the reference); the solid angles sum to 4 pi (2 pi on the hemisphere) and integrate mu^2 exactly."""
    from skyscatter.precomputed.kernels import sphere_quadrature

    for n, hemisphere in ((16, False), (7, False), (32, True)):
        om, dom = sphere_quadrature(n, hemisphere)
        n_up = n if hemisphere else n - n // 2
        x, _ = np.polynomial.legendre.leggauss(n_up)
        up = np.unique(om[:, 2][om[:, 2] > 0])
        np.testing.assert_allclose(up, np.sort(0.5 * (x + 1.0)), rtol=0, atol=1e-13)
        np.testing.assert_allclose(dom.sum(), (2.0 if hemisphere else 4.0) * np.pi, rtol=1e-13)
        np.testing.assert_allclose(np.sum(om[:, 2] ** 2 * dom), (2.0 if hemisphere else 4.0) * np.pi / 3, rtol=1e-13)
        np.testing.assert_allclose(np.linalg.norm(om, axis=1), 1.0, rtol=1e-14)


def test_single_scattering_of_grazing_rays_near_the_ground():
    """The single-scattering kernel's texels for view rays within 1 deg of the horizon at 0-500 m, the sun 2-10 deg
    up, against the independent integral of ``tests/precomputed_reference.py`` (its own optical depths along the
    view and sun paths), turbidity 3 at 550 nm: within 3 %.

    The view transmittance ``T(x, y)`` was the table ratio ``T(x, v) / T(y, v)`` (Bruneton & Neyret 2008, Sec. 4),
    two bilinear reads of a table that falls by orders of magnitude between its radius rows along grazing paths:
    -23 % at the horizon on the ground and -15 % just above it at 250 m (docs/accuracy.md, "Low sun"). Now it is
    integrated along the ray's own samples (measured: within 1.9 % at the default transmittance table; the rest is
    the sun's transmittance, read from the table)."""
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    import precomputed_reference as ref
    from skyscatter.precomputed.compute import Medium, single_scattering, transmittance_table
    from skyscatter.precomputed.geometry import scattering_params
    from skyscatter.precomputed.kernels import mu_s_texels
    from skyscatter.precomputed.sizes import TableSizes

    params = AtmosphereParameters.from_turbidity(3.0)
    wl = np.array([550.0])
    sizes = TableSizes(scattering_r=32, scattering_mu=128, scattering_mu_s=32, scattering_nu=8)
    medium = Medium.of(params, wl, sizes)
    rows = range(0, 5)
    ray, mie = single_scattering(medium, sizes, transmittance_table(medium, sizes), rows)
    rb, rt = params.bottom_radius, params.top_radius
    n_r, n_mu, n_s, n_nu = sizes.scattering_shape
    elevations = np.degrees(np.arcsin(mu_s_texels(rb, rt, params.mu_s_min, n_s)))
    suns = [i for i in range(n_s) if 1.5 <= elevations[i] <= 10.0]
    worst = 0.0
    checked = 0
    for i_r in (0, 2, 4):
        for i_mu in range(n_mu - 6, n_mu):
            for i_s in suns[::2]:
                for i_n in (0, 4, 7):
                    r, mu, mu_s, nu, _ = scattering_params(i_r, i_mu, i_s, i_n, rb, rt, params.mu_s_min, n_r, n_mu,
                                                           n_s, n_nu)
                    if r - rb > 500.0 or abs(90.0 - math.degrees(math.acos(mu))) > 1.0 + math.degrees(
                            math.acos(rb / r)):
                        continue
                    want_r, want_m = ref.single_scattering_integrals(r, mu, mu_s, nu, params, wl, n=960, pieces=40,
                                                                     first=1e-5)
                    got_r = ray[i_r, i_mu, i_s, i_n, 0] / (medium.solar_irradiance[0] * medium.rayleigh_scattering[0])
                    got_m = mie[i_r, i_mu, i_s, i_n, 0] / (medium.solar_irradiance[0] * medium.mie_scattering[0])
                    worst = max(worst, abs(got_r / want_r[0] - 1.0), abs(got_m / want_m[0] - 1.0))
                    checked += 1
    assert checked >= 40
    assert worst < 0.03, worst


def _shadow_exit_by_marching(r, mu, mu_s, nu, bottom):
    """Altitudes [m] of the last point in the shadow and the first that the point sun lights, of 20000 points along
    the ray (to 3000 km): the test's own search (no closed form); (inf, inf) if none is lit."""
    t = np.concatenate([[0.0], np.geomspace(0.01, 3e6, 20000)])
    ry = np.sqrt(t * t + 2 * r * mu * t + r * r)
    ms = (r * mu_s + t * nu) / ry
    lit = (ms >= 0.0) | (ry * ry * (1.0 - ms * ms) >= bottom * bottom)
    if not lit.any():
        return np.inf, np.inf
    i = int(np.argmax(lit))
    return ry[max(i - 1, 0)] - bottom, ry[i] - bottom


def test_shadow_exit_altitude_against_marching():
    """:func:`geometry.shadow_exit_altitude` against a search along the ray for the first lit point (sun 1-12 deg
    below the horizon, observers at 0, 5 and 20 km, view elevations from the planet's horizon to 60 deg, all
    azimuths): between the altitudes of the search's last shadowed and first lit points (1 m of rounding), or both
    at or above the top of the atmosphere; a start in the light gives its own altitude."""
    from skyscatter.precomputed.geometry import shadow_exit_altitude

    p = AtmosphereParameters()
    rb, rt = p.bottom_radius, p.top_radius
    rng = np.random.default_rng(3)
    checked = 0
    for _ in range(300):
        h = float(rng.choice([0.0, 5e3, 20e3]))
        lowest = -math.degrees(math.acos(rb / (rb + h))) + 0.1  # above the planet's horizon
        e, a, s = (math.radians(x) for x in (rng.uniform(lowest, 60), rng.uniform(0, 180), rng.uniform(-12, -1)))
        v = np.array([math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e)])
        sun = np.array([0.0, math.cos(s), math.sin(s)])
        r = rb + h
        lo, hi = _shadow_exit_by_marching(r, v[2], sun[2], float(v @ sun), rb)
        got = shadow_exit_altitude(r, v[2], sun[2], float(v @ sun), rb, rt)
        if min(lo, hi) >= rt - rb:
            assert got == pytest.approx(rt - rb)
        elif max(lo, hi) < rt - rb:
            assert min(lo, hi) - 1.0 <= got <= max(lo, hi) + 1.0, (h, e, a, s, got, lo, hi)
        checked += 1
    assert checked == 300
    assert shadow_exit_altitude(rb + 1e3, 0.2, 0.1, 0.3, rb, rt) == pytest.approx(1e3)


def test_shadow_weights_follow_the_single_scattering_into_the_shadow():
    """:func:`sampling.shadow_nu_weights` applied to the independent single-scattering integrals of
    ``tests/precomputed_reference.py`` at two azimuth texels (77.1 and 102.9 deg from the sun) against the integral
    between them (90 deg), Rayleigh, Earth defaults, 560 nm, the sun 6 deg below the horizon, view elevations 2, 5
    and 15 deg from the ground: within 12 % (measured +10, -5, -10 %) where the linear interpolation is +219, +94
    and +16 % (the single scattering falls 200 times across the cell at 2 deg); with the sun up the weights are the
    linear ones."""
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    import precomputed_reference as ref
    from skyscatter.precomputed.compute import density_profiles
    from skyscatter.precomputed.geometry import scattering_nu_param
    from skyscatter.precomputed.sampling import shadow_nu_weights

    p = AtmosphereParameters()
    rb, rt = p.bottom_radius, p.top_radius
    profiles, counts = density_profiles(p)
    wl = np.array([560.0])
    n_nu, i_n = 8, 3  # texels 77.1 and 102.9 deg from the sun
    mu_s = math.sin(math.radians(-6.0))
    for elev, bound_linear in ((2.0, 2.0), (5.0, 0.9), (15.0, 0.15)):
        mu = math.sin(math.radians(elev))
        s = math.sqrt((1 - mu * mu) * (1 - mu_s * mu_s))
        nu = mu * mu_s + s * math.cos(math.radians(90.0))
        vals = [ref.single_scattering_integrals(rb, mu, mu_s, n, p, wl, n=960, pieces=40, first=1e-5)[0][0]
                for n in (scattering_nu_param(i_n, mu, mu_s, n_nu), nu, scattering_nu_param(i_n + 1, mu, mu_s, n_nu))]
        w = 0.5
        a, b = shadow_nu_weights(rb, mu, mu_s, nu, i_n, w, n_nu, rb, rt, profiles[0], counts[0])
        assert abs((a * vals[0] + b * vals[2]) / vals[1] - 1.0) < 0.12
        assert ((1 - w) * vals[0] + w * vals[2]) / vals[1] - 1.0 > bound_linear  # what the rule is for
    a, b = shadow_nu_weights(rb, 0.1, 0.05, 0.0, i_n, 0.3, n_nu, rb, rt, profiles[0], counts[0])
    assert (a, b) == (pytest.approx(0.7), pytest.approx(0.3))


def test_lookup_shadow_factors_between_a_lower_and_a_higher_exit():
    """The rendering lookups' shadow factors (:func:`sampling.shadow_ratios_fast`, at most
    ``sampling.SHADOW_RATIO_MAX``) applied to the independent single-scattering integrals of
    ``tests/precomputed_reference.py`` at two azimuth texels (51.4 and 25.7 deg from the sun) against the integral
    at 45 deg, Rayleigh, Earth defaults, 560 nm, sun 6 deg below the horizon, view elevations 2 and 5 deg: the rays
    leave the shadow at 17.9 / 16.7 / 14.6 km (2 deg), so one texel's factor is above 1. Within 4 % (measured -1
    and -2 %; factors capped at 1, the precomputation's until table format 21, gave -10 %). The precomputation's
    second-order density takes the same factors (:func:`sampling.shadow_nu_weights`, one rule)."""
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    import precomputed_reference as ref
    from skyscatter.precomputed.compute import density_profiles
    from skyscatter.precomputed.geometry import lerp_index, scattering_nu_coord, scattering_nu_param
    from skyscatter.precomputed.sampling import shadow_exit_altitudes, shadow_nu_weights, shadow_ratios_fast

    p = AtmosphereParameters()
    rb, rt = p.bottom_radius, p.top_radius
    profiles, counts = density_profiles(p)
    wl = np.array([560.0])
    n_nu = 8
    mu_s = math.sin(math.radians(-6.0))
    for elev in (2.0, 5.0):
        mu = math.sin(math.radians(elev))
        s = math.sqrt((1 - mu * mu) * (1 - mu_s * mu_s))
        nu = mu * mu_s + s * math.cos(math.radians(45.0))
        i_n, w = lerp_index(scattering_nu_coord(mu, mu_s, nu, n_nu), 0, n_nu - 1)
        vals = [ref.single_scattering_integrals(rb, mu, mu_s, n, p, wl, n=960, pieces=40, first=1e-5)[0][0]
                for n in (scattering_nu_param(i_n, mu, mu_s, n_nu), nu, scattering_nu_param(i_n + 1, mu, mu_s, n_nu))]
        h_q, h_0, h_1 = shadow_exit_altitudes(rb, mu, mu_s, nu, i_n, n_nu, rb, rt)
        assert min(h_0, h_1) < h_q < max(h_0, h_1)
        a, b = shadow_ratios_fast(h_q, h_0, h_1, profiles[0], counts[0])
        assert abs(((1 - w) * a * vals[0] + w * b * vals[2]) / vals[1] - 1.0) < 0.04
        assert max(a, b) > 1.0  # a factor above the old cap of 1: what the larger cap is for
        n0, n1 = shadow_nu_weights(rb, mu, mu_s, nu, i_n, w, n_nu, rb, rt, profiles[0], counts[0])
        assert n0 == pytest.approx((1 - w) * a, rel=1e-9) and n1 == pytest.approx(w * b, rel=1e-9)
