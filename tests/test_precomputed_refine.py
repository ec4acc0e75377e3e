"""The rendering lookups' sun-zenith axis refined in twilight (docs/accuracy.md, "Low sun"): the 4D tables' cells that
start below the horizon split into three (:func:`skyscatter.precomputed.geometry.refined_mu_s_cell`), their
sub-texels filled from the stored texels by the four-point Lagrange formula in the logarithm
([Abramowitz1964] Eq. 25.2.13; :func:`skyscatter.precomputed.lookup.refine_sun_zenith`) and read linearly.

Checks: the geometry of the refined axis; the rule against functions it must reproduce exactly (an exponential of a
cubic, Eq. 25.2.13 being exact for cubics) and its fall-backs at the Earth's shadow; the sub-texels against an
independent precomputation with three times the sun-zenith texels (the same mapping, so its texels are the
sub-texels' suns), against the linear read; daytime lookups unchanged to the bit.
"""

import math

import numpy as np
import pytest

from skyscatter.precomputed import AtmosphereParameters, PrecomputedAtmosphere, TableSizes, geometry, lookup
from skyscatter.precomputed.geometry import MU_S_SPLIT, refined_mu_s_cell, refined_mu_s_count, twilight_cells
from skyscatter.precomputed.kernels import mu_s_texels

EARTH = AtmosphereParameters()
RB, RT, MU_S_MIN = EARTH.bottom_radius, EARTH.top_radius, EARTH.mu_s_min


def test_twilight_cells_are_the_cells_below_and_across_the_horizon():
    """The default 32 texels: 8 cells (-12 .. +0.78 deg); for any count, the last split cell is the one across the
    horizon (its lower texel below it, its upper one not); one texel below the horizon: none."""
    assert twilight_cells(RB, RT, MU_S_MIN, 32) == 8
    for n in (4, 5, 6, 8, 12, 16, 22, 32, 64, 94):
        c = twilight_cells(RB, RT, MU_S_MIN, n)
        mu = mu_s_texels(RB, RT, MU_S_MIN, n)
        below = int(np.sum(mu < 0.0))
        assert c == (below if below >= 2 else 0)
        if c:
            assert mu[c - 1] < 0.0 <= mu[c]
    assert refined_mu_s_count(32, 8) == 48


def test_refined_cell_is_three_times_finer_below_the_split_and_the_stored_axis_above():
    """Read position of the refined axis: ``3 p`` below ``cells``, ``p + 2 cells`` above (continuous at the split);
    with no cells split it is the stored axis' :func:`lerp_index` to the bit."""
    n, cells = 32, 8
    n_f = refined_mu_s_count(n, cells)
    for p in np.concatenate([np.linspace(0.0, n - 1.0, 997), [cells - 1e-12, cells, cells + 1e-12, n - 1.0]]):
        i, w = refined_mu_s_cell(float(p), n_f, cells)
        want = MU_S_SPLIT * p if p < cells else p + (MU_S_SPLIT - 1) * cells
        assert 0 <= i <= n_f - 2 and 0.0 <= w <= 1.0
        assert i + w == pytest.approx(want, abs=1e-9)
        if p >= cells:  # daytime: the stored axis' cell and weight, shifted by the split's texels
            i0, w0 = geometry.lerp_index(float(p), 0, n - 1)
            assert (i, w) == (i0 + (MU_S_SPLIT - 1) * cells, w0)
        assert refined_mu_s_cell(float(p), n, 0) == geometry.lerp_index(float(p), 0, n - 1)


def _column_table(columns):
    """A 4D table (1, 1, n_mu_s, n_columns, 1) float32 whose columns along the sun zenith are ``columns``."""
    return np.ascontiguousarray(np.asarray(columns, dtype=np.float32).T[None, None, :, :, None])


def test_refinement_reproduces_an_exponential_of_a_cubic_and_keeps_the_texels():
    """Columns ``exp(cubic(i))`` (four-point Lagrange in the logarithm is exact for cubics, [Abramowitz1964]
    Eq. 25.2.13): every sub-texel within float32 rounding of the function (1e-5; the clamp between the cell's
    values does not act on a monotone column), the last split cell's too (its stencil takes the two texels above
    it); the stored texels copied to the bit; above the split the stored columns unchanged."""
    n, cells = 16, 5
    x = np.arange(n, dtype=float)
    cubics = [(-2.0, 0.9, -0.05, 0.001), (1.0, 0.4, 0.0, 0.0), (0.0, 1.5, -0.09, 0.002)]
    cols = [np.exp(a + b * x + c * x ** 2 + d * x ** 3) for a, b, c, d in cubics]
    table = _column_table(cols)
    fine = lookup.refine_sun_zenith(table, cells)
    n_f = refined_mu_s_count(n, cells)
    assert fine.shape == (1, 1, n_f, len(cols), 1) and fine.dtype == np.float32
    xf = np.concatenate([np.arange(MU_S_SPLIT * cells) / MU_S_SPLIT, np.arange(cells, n)])
    for k, (a, b, c, d) in enumerate(cubics):
        want = np.exp(a + b * xf + c * xf ** 2 + d * xf ** 3)
        np.testing.assert_allclose(fine[0, 0, :, k, 0], want, rtol=1e-5)
    np.testing.assert_array_equal(fine[0, 0, ::MU_S_SPLIT][:cells + 1], table[0, 0, :cells + 1])
    np.testing.assert_array_equal(fine[0, 0, MU_S_SPLIT * cells:], table[0, 0, cells:])
    # only some columns: the same values
    np.testing.assert_array_equal(lookup.refine_sun_zenith(table, cells, (4, 9)), fine[:, :, 4:9])
    np.testing.assert_array_equal(lookup.refine_sun_zenith(table, cells, (11, 17)), fine[:, :, 11:17])
    with pytest.raises(ValueError, match="outside the refined axis"):
        lookup.refine_sun_zenith(table, cells, (0, n_f + 1))


def test_refinement_at_the_earth_shadow_falls_back_within_the_cell():
    """Columns with texels in the Earth's shadow (zeros): where the four-point stencil holds a zero, the cell's
    sub-texels stay between its two values; where the cell's lower texel is zero, they are positive and at most
    the linear read (the sky falls faster towards the shadow, not slower); an all-zero column stays zero."""
    n, cells = 12, 6
    y = np.exp(0.8 * np.arange(n))
    lit_from_2 = np.where(np.arange(n) >= 2, y, 0.0)
    lit_from_1 = np.where(np.arange(n) >= 1, y, 0.0)
    table = _column_table([lit_from_2, lit_from_1, np.zeros(n)])
    fine = lookup.refine_sun_zenith(table, cells)[0, 0, :, :, 0]
    for k in range(2):
        col = table[0, 0, :, k, 0].astype(float)  # the float32 values the rule reads
        for j in range(MU_S_SPLIT * cells):
            i, m = divmod(j, MU_S_SPLIT)
            a, b, w = col[i], col[i + 1], m / MU_S_SPLIT
            v = fine[j, k]
            if m == 0:
                assert v == a  # a stored texel
            elif a == 0.0 and b > 0.0:
                assert 0.0 < v <= w * b * (1 + 1e-6)
            else:
                assert min(a, b) * (1 - 1e-6) <= v <= max(a, b) * (1 + 1e-6)
    # the geometric read across a cell whose lower neighbour is dark: exp is log-linear, so exact
    np.testing.assert_allclose(fine[MU_S_SPLIT * 2 + 1, 0], y[2] ** (2 / 3) * y[3] ** (1 / 3), rtol=1e-5)
    assert np.all(fine[:, 2] == 0.0)


@pytest.fixture(scope="module")
def coarse_and_fine():
    """Earth tables at 550 nm with the default 32 and 94 (= 3 x 31 + 1) sun-zenith texels, otherwise equal (small
    sizes along the other axes): texel ``3 k`` of 94 is texel ``k`` of 32 (the same mapping), so the 94's texels in
    between are the 32's sub-texels."""
    sizes = dict(transmittance_mu=64, transmittance_r=16, irradiance_mu_s=16, irradiance_r=8, scattering_r=8,
                 scattering_mu=32, scattering_nu=4)
    return [PrecomputedAtmosphere.compute(EARTH, orders=3, wavelengths=[550.0], progress=False,
                                          sizes=TableSizes(**sizes, scattering_mu_s=n)) for n in (32, 94)]


@pytest.mark.slow
def test_sub_texels_against_a_precomputation_with_three_times_the_texels(coarse_and_fine):
    """The 32-texel tables' sub-texels in their split cells against the 94-texel tables' own texels there (an
    independent precomputation at those suns), each of the three 4D tables, every (r, mu, nu) where the value is
    above 1e-3 of the column's largest: the refined values' median relative difference at most a third of the
    linear read's, and below 10 %."""
    coarse, fine = coarse_and_fine
    cells = twilight_cells(RB, RT, MU_S_MIN, 32)
    np.testing.assert_allclose(mu_s_texels(RB, RT, MU_S_MIN, 94)[::3], mu_s_texels(RB, RT, MU_S_MIN, 32), rtol=1e-12)
    sub = [j for j in range(MU_S_SPLIT * cells) if j % MU_S_SPLIT]
    for name in ("single_rayleigh", "single_mie", "multiple"):
        base = np.asarray(coarse.tables[name], dtype=np.float64)
        ref = np.asarray(fine.tables[name], dtype=np.float64)[:, :, sub]
        got = lookup.refine_sun_zenith(coarse.tables[name], cells)[:, :, sub]
        i = np.array(sub) // MU_S_SPLIT
        w = (np.array(sub) % MU_S_SPLIT / MU_S_SPLIT)[None, None, :, None, None]
        linear = base[:, :, i] + w * (base[:, :, i + 1] - base[:, :, i])
        keep = ref > 1e-3 * ref.max(axis=2, keepdims=True)
        e_ref = np.median(np.abs(got[keep] / ref[keep] - 1.0))
        e_lin = np.median(np.abs(linear[keep] / ref[keep] - 1.0))
        assert e_ref <= e_lin / 3.0 and e_ref < 0.10, (name, e_ref, e_lin)


def test_daytime_lookups_unchanged_and_twilight_refined(coarse_and_fine):
    """The general per-ray kernel on the refined tables against the same kernel on the stored tables with no cell
    split: a sun 20 deg up equal to the bit (every read above the split is the stored axis'), and the aerial
    perspective too; a sun 4.5 deg below the horizon different (the refined read is in use)."""
    atm = coarse_and_fine[0]
    bottom, top, mu_s_min = atm._geometry()
    rng = np.random.default_rng(5)
    d = rng.normal(size=(400, 3))
    d[:, 2] = np.abs(d[:, 2]) + 0.05
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    pos = np.broadcast_to([0.0, 0.0, RB + 500.0], d.shape)

    def read(sun, t, cells):
        rad = np.zeros((d.shape[0], 1))
        tr = np.ones((d.shape[0], 1))
        lookup.sky_kernel(np.ascontiguousarray(pos), d, np.ascontiguousarray(np.broadcast_to(sun, d.shape)),
                          np.zeros(d.shape[0]), t["transmittance"], t["single_rayleigh"], t["single_mie"],
                          t["multiple"], t["irradiance"], atm._albedo, atm._solar, bottom, top, mu_s_min, cells,
                          atm._mie_g, atm._mie_kind, atm._lobe, *atm._aerosol_phase[2:], *atm._profiles,
                          atm.parameters.sun_angular_radius, True, rad, tr, 0, d.shape[0])
        return rad

    for elev, equal in ((20.0, True), (2.0, True), (-4.5, False)):
        e = math.radians(elev)
        sun = np.array([0.0, math.cos(e), math.sin(e)])
        refined = read(sun, atm.lookup_tables, atm._mu_s_cells)
        assert np.array_equal(refined, read(sun, atm.tables, 0)) == equal
        np.testing.assert_allclose(atm.sky_radiance(pos, d, sun), refined, rtol=1e-12)  # the library reads these
    # the aerial perspective to points 20 km away, its two reads per ray (camera and point)
    pts = np.asarray(pos) + 20e3 * d

    def aerial(sun, t, cells):
        tr = np.ones((d.shape[0], 1))
        ins = np.zeros((d.shape[0], 1))
        lookup.aerial_kernel(np.ascontiguousarray(pos), pts, np.ascontiguousarray(np.broadcast_to(sun, d.shape)),
                             np.zeros(d.shape[0]), t["transmittance"], t["single_rayleigh"], t["single_mie"],
                             t["multiple"], bottom, top, mu_s_min, cells, atm._mie_g, atm._mie_kind, atm._lobe,
                             *atm._aerosol_phase[2:], *atm._profiles, tr, ins, 0, d.shape[0])
        return ins

    for elev, equal in ((20.0, True), (-4.5, False)):
        e = math.radians(elev)
        sun = np.array([0.0, math.cos(e), math.sin(e)])
        refined = aerial(sun, atm.lookup_tables, atm._mu_s_cells)
        assert np.all(refined > 0.0)
        assert np.array_equal(refined, aerial(sun, atm.tables, 0)) == equal
    assert atm.lookup_tables["multiple"].shape[2] == refined_mu_s_count(32, 8)


def test_refined_caches_are_built_once_across_threads(coarse_and_fine):
    """The refined tables and radius layers are built on first use; eight threads asking at once (per-ray sky,
    aerial perspective and the observer's sky, twilight and day) get what one thread gets, to the bit."""
    from concurrent.futures import ThreadPoolExecutor

    atm = coarse_and_fine[0]
    rng = np.random.default_rng(9)
    d = rng.normal(size=(200, 3))
    d[:, 2] = np.abs(d[:, 2]) + 0.05
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    ground = np.array([0.0, 0.0, RB + 2.0])
    per_ray = np.broadcast_to(ground, d.shape)

    def calls(per_ray_too):
        out = []
        for elev in (-5.0, -3.3, 12.0):
            e = math.radians(elev)
            sun = np.array([0.0, math.cos(e), math.sin(e)])
            out.append(atm.sky_luminance(ground, d, sun))
            if per_ray_too:
                out.append(atm.sky_radiance(per_ray, d, sun))
                out.append(atm.aerial_perspective(per_ray, per_ray + 3e3 * d, sun)[1])
        return out

    def fresh():
        for name in ("_lookup_tables_cache", "_lookup_layers", "_sub_texel_row", "_sub_texel_source"):
            atm.__dict__.pop(name, None)

    for per_ray_too in (False, True):  # the observer's layers alone, then with the whole refined tables
        fresh()
        want = calls(per_ray_too)
        fresh()
        with ThreadPoolExecutor(8) as pool:
            got = list(pool.map(lambda _, p=per_ray_too: calls(p), range(8)))
        for g in got:
            for a, b in zip(g, want, strict=True):
                assert np.array_equal(a, b)
        if not per_ray_too:
            assert 1 <= len(atm.__dict__["_lookup_layers"]) <= 6 and "_lookup_tables_cache" not in atm.__dict__


def test_observer_slices_refine_their_own_columns_as_the_kept_layers(coarse_and_fine):
    """``lookup.observer_slices`` without ``layers`` (its two radius rows refined in the two columns it reads, or the
    stored columns above the split) equals its read of whole refined radius layers, to the bit, for suns in and
    above the split cells and an observer on the ground and at 3 km."""
    atm = coarse_and_fine[0]
    bottom, top, mu_s_min = atm._geometry()
    st = atm.stored
    cells = atm._mu_s_cells
    tables = (st["single_rayleigh"], st["single_mie"], st["multiple"])

    def layer(j, i):
        return lookup.refine_sun_zenith(lookup.radius_layer(tables[j], i)[None], cells)[0]

    for r in (RB + 1.0, RB + 3000.0):
        for elev in (-10.0, -5.1, -2.0, 0.5, 20.0):
            mu_s = math.sin(math.radians(elev))
            own = lookup.observer_slices(*tables, r, mu_s, bottom, top, mu_s_min, cells, np.eye(1))
            kept = lookup.observer_slices(*tables, r, mu_s, bottom, top, mu_s_min, cells, np.eye(1), layers=layer)
            assert np.any(own) and np.array_equal(own, kept)


def test_single_scattering_sub_texels_are_computed_at_their_suns(coarse_and_fine):
    """The library's refined single-scattering tables hold, at the sub-texels, the single scattering computed at
    their suns (``compute.stored_single_scattering`` at ``lookup.sub_texel_suns``): against the independent
    precomputation with three times the texels, whose texels are those suns, within its half-precision storage
    (measured 4.8e-4 largest relative difference where the value is above 1e-3 of its radius layer's largest, the
    scale of the half-precision values; tolerance 2e-3); the suns are its texels to 1e-12; the observer's radius
    layers, built first, hold the same values; the multiple scattering's sub-texels are the rule's, and so are all
    of them for tables constructed directly (``computed`` False). Given sub-texels of the wrong shape are
    refused."""
    coarse, fine = coarse_and_fine
    cells = coarse._mu_s_cells
    assert cells == 8 and coarse.computed
    # the observer's radius layers, built before the whole refined tables (a fresh state), hold the same values
    for name in ("_lookup_tables_cache", "_lookup_layers", "_sub_texel_row", "_sub_texel_source"):
        coarse.__dict__.pop(name, None)
    layers = {name: coarse._lookup_layer(name, 3).copy() for name in ("single_rayleigh", "single_mie", "multiple")}
    assert "_lookup_tables_cache" not in coarse.__dict__
    suns = lookup.sub_texel_suns(RB, RT, MU_S_MIN, 32, cells)
    sub = [j for j in range(MU_S_SPLIT * cells) if j % MU_S_SPLIT]
    np.testing.assert_allclose(suns, mu_s_texels(RB, RT, MU_S_MIN, 94)[sub], rtol=0, atol=1e-12)
    for name in ("single_rayleigh", "single_mie"):
        got = coarse.lookup_tables[name][:, :, sub].astype(np.float64)
        ref = np.asarray(fine.tables[name], dtype=np.float64)[:, :, sub]
        keep = ref > 1e-3 * ref.max(axis=(1, 2, 3), keepdims=True)
        assert keep.sum() > 2000 and np.max(np.abs(got[keep] / ref[keep] - 1.0)) < 2e-3, name
        np.testing.assert_array_equal(layers[name], coarse.lookup_tables[name][3])
        # tables that are not the precomputation's of their parameters (constructed directly): the rule
        rule = lookup.refine_sun_zenith(coarse.tables[name], cells)
        assert not np.array_equal(coarse.lookup_tables[name], rule)
        other = PrecomputedAtmosphere(coarse.parameters, coarse.wavelengths, coarse.sizes, coarse.orders,
                                      coarse.stored)
        assert not other.computed
        np.testing.assert_array_equal(other.lookup_tables[name], rule)
    np.testing.assert_array_equal(layers["multiple"], coarse.lookup_tables["multiple"][3])
    rule = lookup.refine_sun_zenith(coarse.tables["multiple"], cells)
    np.testing.assert_array_equal(coarse.lookup_tables["multiple"], rule)  # the multiple's sub-texels: the rule
    with pytest.raises(ValueError, match="sub_texels must have shape"):
        lookup.refine_sun_zenith(coarse.tables["single_mie"], cells, sub_texels=np.zeros((1, 1, 1, 1, 1)))
