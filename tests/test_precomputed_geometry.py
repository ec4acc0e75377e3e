"""Ray geometry and table parameterisations (Bruneton & Neyret 2008, Sec. 4): the analytic cases and the
mapping round trips at the horizon and the bounds."""

import math

import numpy as np
import pytest

from skyscatter.precomputed import geometry as g

BOTTOM, TOP = 6_360_000.0, 6_420_000.0
H = math.sqrt(TOP**2 - BOTTOM**2)
MU_S_MIN = math.cos(math.radians(102.0))


def test_distances_analytic():
    """Vertical up from the ground = thickness; horizontal from the ground = sqrt(Rt^2 - Rg^2); straight down
    from altitude h = h; a ray grazing the ground touches it at the horizon distance rho."""
    assert math.isclose(g.distance_to_top(BOTTOM, 1.0, TOP), TOP - BOTTOM, rel_tol=1e-12)
    assert math.isclose(g.distance_to_top(BOTTOM, 0.0, TOP), H, rel_tol=1e-12)
    assert math.isclose(g.distance_to_top(BOTTOM, -1.0, TOP), 2 * BOTTOM + (TOP - BOTTOM), rel_tol=1e-12)
    for h in (1.0, 1000.0, 30_000.0):
        assert math.isclose(g.distance_to_bottom(BOTTOM + h, -1.0, BOTTOM), h, rel_tol=1e-9)
        assert g.ray_hits_ground(BOTTOM + h, -1.0, BOTTOM)
    r = BOTTOM + 10_000.0
    rho = math.sqrt(r * r - BOTTOM * BOTTOM)
    mu_h = -rho / r
    assert g.ray_hits_ground(r, mu_h - 1e-9, BOTTOM)
    assert not g.ray_hits_ground(r, mu_h + 1e-6, BOTTOM)
    assert math.isclose(g.distance_to_bottom(r, mu_h - 1e-12, BOTTOM), rho, rel_tol=1e-4)
    # from the top looking up: zero length, without cancellation
    assert g.distance_to_top(TOP, 1.0, TOP) == 0.0


def test_distance_matches_quadratic(rng):
    """Both roots written without cancellation agree with the textbook formula."""
    for _ in range(200):
        r = BOTTOM + rng.uniform(0, TOP - BOTTOM)
        mu = rng.uniform(-1, 1)
        d = g.distance_to_top(r, mu, TOP)
        assert math.isclose(d * d + 2 * r * mu * d + r * r, TOP * TOP, rel_tol=1e-12)
        if g.ray_hits_ground(r, mu, BOTTOM):
            d = g.distance_to_bottom(r, mu, BOTTOM)
            assert math.isclose(d * d + 2 * r * mu * d + r * r, BOTTOM * BOTTOM, rel_tol=1e-10)


@pytest.mark.parametrize("n", [(16, 64)])
def test_transmittance_mapping_round_trip(n):
    n_r, n_mu = n
    for i_r in range(n_r):
        for i_mu in range(n_mu):
            r, mu = g.transmittance_params(i_r, i_mu, BOTTOM, TOP, n_r, n_mu)
            p_r, p_mu = g.transmittance_coord(r, mu, BOTTOM, TOP, n_r, n_mu)
            assert abs(p_r - i_r) < 1e-6 and abs(p_mu - i_mu) < 1e-5
    # bounds: ground and top; straight up and the horizon
    assert g.transmittance_params(0, 0, BOTTOM, TOP, n_r, n_mu) == (BOTTOM, 1.0)
    r, mu = g.transmittance_params(0, n_mu - 1, BOTTOM, TOP, n_r, n_mu)
    assert r == BOTTOM and abs(mu) < 1e-9
    r, mu = g.transmittance_params(n_r - 1, n_mu - 1, BOTTOM, TOP, n_r, n_mu)
    assert math.isclose(r, TOP, rel_tol=1e-12) and math.isclose(mu, -H / TOP, rel_tol=1e-9)


def test_scattering_mapping_round_trip_and_bounds():
    n_r, n_mu, n_s, n_n = 8, 32, 8, 4
    half = n_mu // 2
    for i_r in range(n_r):
        r_ref = math.sqrt((H * i_r / (n_r - 1)) ** 2 + BOTTOM**2)
        for i_mu in range(n_mu):
            r, mu, hits = g.scattering_r_mu_params(i_r, i_mu, BOTTOM, TOP, n_r, n_mu)
            assert math.isclose(r, r_ref, rel_tol=1e-12)
            assert hits == (i_mu < half)
            if i_r == 0 and hits:
                continue  # from the ground every downward ray has zero length: mu = -1 by convention
            p_r, p_mu = g.scattering_r_mu_coord(r, mu, hits, BOTTOM, TOP, n_r, n_mu)
            assert abs(p_r - i_r) < 1e-6
            assert abs(p_mu - i_mu) < 1e-4, (i_r, i_mu, p_mu)
        if i_r > 0:
            # the horizon is at both ends of the mu axis, seen from its two sides
            mu_h = -math.sqrt(1 - (BOTTOM / r_ref) ** 2)
            assert math.isclose(g.scattering_r_mu_params(i_r, 0, BOTTOM, TOP, n_r, n_mu)[1], mu_h, rel_tol=1e-6)
            assert math.isclose(g.scattering_r_mu_params(i_r, n_mu - 1, BOTTOM, TOP, n_r, n_mu)[1], mu_h,
                                rel_tol=1e-6)
            assert math.isclose(g.scattering_r_mu_params(i_r, half - 1, BOTTOM, TOP, n_r, n_mu)[1], -1.0, abs_tol=1e-12)
    assert g.scattering_r_mu_params(0, half, BOTTOM, TOP, n_r, n_mu)[1] == 1.0
    for i_s in range(n_s):
        mu_s = g.scattering_mu_s_param(i_s, BOTTOM, TOP, MU_S_MIN, n_s)
        assert abs(g.scattering_mu_s_coord(mu_s, BOTTOM, TOP, MU_S_MIN, n_s) - i_s) < 1e-6
    assert math.isclose(g.scattering_mu_s_param(0, BOTTOM, TOP, MU_S_MIN, n_s), MU_S_MIN, rel_tol=1e-9)
    assert g.scattering_mu_s_param(n_s - 1, BOTTOM, TOP, MU_S_MIN, n_s) == 1.0
    # below the limit the coordinate clamps to the first texel
    assert g.scattering_mu_s_coord(-0.5, BOTTOM, TOP, MU_S_MIN, n_s) == 0.0
    # nu: linear, clamped to what mu and mu_s allow
    _, _, _, nu, _ = g.scattering_params(3, 20, 4, 0, BOTTOM, TOP, MU_S_MIN, n_r, n_mu, n_s, n_n)
    lo, hi = g.nu_range(g.scattering_r_mu_params(3, 20, BOTTOM, TOP, n_r, n_mu)[1],
                        g.scattering_mu_s_param(4, BOTTOM, TOP, MU_S_MIN, n_s))
    # equal to rounding (the two formulas may contract to a fused multiply-add differently)
    assert math.isclose(nu, lo, rel_tol=1e-14) and lo > -1.0


def test_mu_s_mapping_is_denser_near_the_horizon():
    """Like the paper's u_mu_s, the texels crowd near mu_s = 0 (steps in the sun's zenith angle 3x finer there
    than at the zenith), but no cell spans more than 7 deg of sun zenith angle: the 2017 mapping alone left 0-42
    deg in one cell of 32, too coarse for the forward-peaked aerosol multiple scattering (docs/bruneton.md)."""
    n = 32
    mus = np.array([g.scattering_mu_s_param(i, BOTTOM, TOP, MU_S_MIN, n) for i in range(n)])
    assert np.all(np.diff(mus) > 0)
    steps = -np.diff(np.degrees(np.arccos(mus)))
    near_horizon = steps[np.argmin(np.abs(mus[:-1]))]
    assert near_horizon < steps[-1] / 3
    assert steps.max() < 7.0


def test_sky_mu_mapping_has_no_wide_cell_at_the_zenith():
    """The sky half of the mu axis: dense at the horizon (< 0.3 deg steps at the ground with 64 texels per
    half) and no step wider than 3.2 deg anywhere (2 x 98 deg / 63 at 60 km); the distance mapping alone gave
    0-36 deg in one cell."""
    n_r, n_mu = 32, 128
    for i_r in (0, 5, 31):
        mus = np.array([g.scattering_r_mu_params(i_r, i, BOTTOM, TOP, n_r, n_mu)[1] for i in range(64, 128)])
        ang = np.degrees(np.arccos(mus))
        assert np.all(np.diff(ang) > 0)
        assert np.diff(ang).max() < 3.2
        if i_r == 0:
            assert np.diff(ang)[-1] < 0.3


def test_irradiance_mapping_round_trip():
    for i_r in range(8):
        for i_s in range(16):
            r, mu_s = g.irradiance_params(i_r, i_s, BOTTOM, TOP, 8, 16)
            p = g.irradiance_coord(r, mu_s, BOTTOM, TOP, 8, 16)
            assert abs(p[0] - i_r) < 1e-9 and abs(p[1] - i_s) < 1e-9



def test_acos_table_within_its_published_bound():
    """Abramowitz & Stegun 4.4.46 state |error| <= 2e-8 rad on [0, 1]; with the coefficients as printed (10
    decimals) the largest error is 2.18e-8, at x = 0 (a0 = 1.5707963050 against pi / 2), and the odd extension
    keeps it on [-1, 1]. Checked against libm on a dense grid and at the ends."""
    x = np.concatenate([np.linspace(-1.0, 1.0, 200_001), [-1.0, -0.0, 0.0, 1.0, 1 - 1e-12, -1 + 1e-12]])
    approx = np.array([g.acos_table(v) for v in x])
    err = np.abs(approx - np.arccos(x))
    assert err.max() <= 2.2e-8
    assert err.max() > 1e-10  # it is an approximation: the test would notice libm's acos in its place
    assert g.acos_table(1.0) == 0.0 and abs(g.acos_table(-1.0) - math.pi) < 2e-8
    # out of range (rounding in a caller) clamps instead of returning NaN
    assert g.acos_table(1.0 + 1e-15) == 0.0 and math.isfinite(g.acos_table(-1.0 - 1e-15))


def test_last_sky_texel_is_the_horizon_itself():
    """The sky half's last view-zenith texel is the horizon, cos = -rho / r, to rounding (not through the
    polynomial arc cosine, 2e-8 rad off, which put it below the horizon at some radii while flagged as missing
    the ground; review of the vectorised kernels)."""
    n_r, n_mu = 32, 128
    for i_r in range(1, n_r):
        r, mu, hits = g.scattering_r_mu_params(i_r, n_mu - 1, BOTTOM, TOP, n_r, n_mu)
        assert not hits
        rho = H * i_r / (n_r - 1)  # as the mapping defines it (sqrt(r^2 - R_g^2) loses digits to cancellation)
        assert math.isclose(mu, -rho / r, rel_tol=1e-15)


def test_log_lerp_weight_follows_the_geometric_interpolation(rng):
    """With the weight of :func:`log_lerp_weight` the linear interpolation ``a + w' (b - a)`` equals the geometric
    one ``a^(1 - w) b^w`` (computed here with numpy's power) at both ends and the centre of the cell, stays within
    0.15 % of it in between for end values a factor 2 apart and within a factor 1.4 for 100 (the linear
    interpolation is up to 8.3 times too high there); the weight runs from 0 to 1 and increases with ``w``; below
    the floor the weight is that of the floor (a texel in the Earth's shadow), applied to the values themselves (the
    ends are kept); equal or zero end values give ``w``."""
    a = 10.0 ** rng.uniform(-8.0, 8.0, 3000)
    b = a * 10.0 ** rng.uniform(-2.99, 2.99, a.size)
    for w in (0.0, 0.5, 1.0):
        got = np.array([g.log_lerp_weight(x, y, w) for x, y in zip(a, b, strict=True)])
        np.testing.assert_allclose(a + got * (b - a), a ** (1.0 - w) * b ** w, rtol=1e-12)
    w = np.linspace(0.0, 1.0, 201)
    for ratio, bound in ((2.0, 1.0015), (0.5, 1.0015), (100.0, 1.4), (0.01, 1.4)):
        wp = np.array([g.log_lerp_weight(3.0, 3.0 * ratio, t) for t in w])
        q = (1.0 + wp * (ratio - 1.0)) / ratio ** w
        assert q.max() < bound and q.min() > 1.0 / bound, (ratio, q.min(), q.max())
        assert wp[0] == 0.0 and math.isclose(wp[-1], 1.0, rel_tol=1e-12) and np.all(np.diff(wp) > 0)
    floor = g.LOG_LERP_FLOOR
    for t in (0.1, 0.5, 0.9):
        assert math.isclose(g.log_lerp_weight(0.0, 2.0, t), t / (t + (1.0 - t) / math.sqrt(floor)), rel_tol=1e-12)
        assert math.isclose(g.log_lerp_weight(5.0, 1e-9, t), t / (t + (1.0 - t) * math.sqrt(floor)), rel_tol=1e-12)
        assert g.log_lerp_weight(0.0, 0.0, t) == t
        assert math.isclose(g.log_lerp_weight(7.0, 7.0, t), t, rel_tol=1e-15)


def test_irradiance_read_is_log_quadratic_below_the_horizon_and_linear_above():
    """The irradiance table's read along mu_s (:func:`sampling.irradiance_read`) on a synthetic table of 8 mu_s
    texels (mu_s = -1 .. 1, cells 2/7 wide) and 2 radii, 3 wavelengths whose logarithm is quadratic in mu_s (a fall
    that steepens towards the lowest sun, as the twilight sky irradiance's): in a cell that starts below the horizon
    (first texel at mu_s < 0) each wavelength's read is the table's function itself, exactly (the three-point
    Lagrange formula in ``ln E`` is exact for a quadratic, [Abramowitz1964] Eq. 25.2.11); in a cell above, the linear
    interpolation; linear in r (the second radius holds twice the first)."""
    from skyscatter.precomputed.sampling import irradiance_read

    mu = np.linspace(-1.0, 1.0, 8)
    rates = np.array([4.0, 10.0, 20.0])  # e-folds per unit mu_s at the horizon: 3.1, 17 and 300 times across a cell
    curv = np.array([2.0, 5.0, 8.0])  # the fall steepens below the horizon
    table = np.empty((2, 8, 3), dtype=np.float64)
    table[0] = np.exp(rates * mu[:, None] - curv * mu[:, None] ** 2)
    table[1] = 2.0 * table[0]
    out = np.empty(3)
    for j, below in ((0, True), (2, True), (3, True), (4, False), (5, False)):  # texel 3 at -1/7, texel 4 at +1/7
        assert g.irradiance_log_cell(j, 8) == below
        a, b = table[0, j], table[0, j + 1]
        for w in (0.2, 0.5, 0.7):
            p = j + w
            m = -1.0 + 2.0 * p / 7.0
            irradiance_read(table, 0.0, p, out)
            want = np.exp(rates * m - curv * m * m) if below else a + w * (b - a)
            np.testing.assert_allclose(out, want, rtol=1e-9)
            irradiance_read(table, 0.5, p, out)  # linear in r: 1.5 times the first radius
            np.testing.assert_allclose(out, 1.5 * want, rtol=1e-9)
        for p in (float(j), j + 1.0):  # the texels themselves
            irradiance_read(table, 0.0, p, out)
            np.testing.assert_allclose(out, table[0, int(p)], rtol=1e-9)


def test_scattering_radius_index_is_linear_in_the_altitude_within_a_cell():
    """Between two rows of the 4D tables (rows at rho_i = H i / (n_r - 1), Bruneton & Neyret 2008, Sec. 4) the
    index position of a ray that misses the ground is linear in the altitude, i + (h - h_i) / (h_(i+1) - h_i), in the
    cells that start below 200 m (the rows' altitudes computed here from their rho; since table format 16 the cell
    touching the ground too), rho / H (n_r - 1) elsewhere; a ray that meets the ground keeps rho / H (n_r - 1).
    1e-9."""
    n_r, n_mu = 32, 128
    heights = [math.sqrt((H * i / (n_r - 1)) ** 2 + BOTTOM**2) - BOTTOM for i in range(n_r)]
    assert 62.0 < heights[1] < 63.0  # the first row above the ground (default 32 rows, 60 km thick)
    for h in (0.0, 1.0, 10.0, 30.0, 62.0, 63.0, 150.0, 250.0, 400.0, 2000.0, 35_000.0, 59_999.0, 60_000.0):
        r = BOTTOM + h
        i = min(int(np.searchsorted(heights, h, side="right")) - 1, n_r - 2)
        expected = i + (h - heights[i]) / (heights[i + 1] - heights[i])
        if heights[i] >= g.ALTITUDE_LINEAR_BELOW:  # the cells from 200 m up: in rho
            expected = math.sqrt(r * r - BOTTOM**2) / H * (n_r - 1)
        p_r, _ = g.scattering_r_mu_coord(r, 0.5, False, BOTTOM, TOP, n_r, n_mu)
        assert abs(p_r - expected) < 1e-9, (h, p_r, expected)
        if h > 0.0:
            p_g, _ = g.scattering_r_mu_coord(r, -1.0, True, BOTTOM, TOP, n_r, n_mu)
            assert abs(p_g - math.sqrt(r * r - BOTTOM**2) / H * (n_r - 1)) < 1e-9
    # 150 m: 0.464 of the way from the 62.7 m row to the 251 m one (0.546 in rho)
    assert abs(g.scattering_r_mu_coord(BOTTOM + 150.0, 0.5, False, BOTTOM, TOP, n_r, n_mu)[0] - 1.4638) < 1e-3


@pytest.mark.parametrize(("n_r", "apart"), [(32, True), (16, True), (8, False), (1, False)])
def test_ground_cell_rows_apart_only_in_thin_cells(n_r, apart):
    """The ground cell's rows are read apart (own mu coordinate, altitude weight) only if the first row above the
    ground lies below 300 m: 62.7 m (32 rows), 268 m (16 rows); not 1230 m (8 rows: the coarse tables, whose
    diffuse horizontal irradiance against DISORT went from +0.85 % to +4.6 % under the rule, docs/aerosols.md).
    The row altitudes here from the rows' definition, rho_i = H i / (n - 1) (Bruneton & Neyret 2008, Sec. 4)."""
    from skyscatter.precomputed.geometry import ALTITUDE_LINEAR_CELL_TOP, ground_cell_rows_apart

    bottom, top = 6_360_000.0, 6_420_000.0
    if n_r > 1:
        rho1 = math.sqrt(top**2 - bottom**2) / (n_r - 1)
        assert (math.hypot(rho1, bottom) - bottom < ALTITUDE_LINEAR_CELL_TOP) == apart
    assert ground_cell_rows_apart(bottom, top, n_r) == apart
    # and the radius index follows: linear in the altitude at mid-height of the cell only where the rows are apart
    from skyscatter.precomputed.geometry import scattering_r_index

    if n_r > 1:
        big_h = math.sqrt(top**2 - bottom**2)
        rho1 = big_h / (n_r - 1)
        h1 = math.hypot(rho1, bottom) - bottom
        r = bottom + 0.5 * h1
        rho = math.sqrt(r * r - bottom * bottom)
        expected = 0.5 if apart else rho / rho1
        assert scattering_r_index(r, rho, bottom, big_h, n_r) == pytest.approx(expected, rel=1e-9)


def test_multiple_lobe_is_normalised_and_weighted_by_the_aerosol_share():
    """The lobe the multiple-scattering tables are divided by (:func:`sampling.multiple_lobe`): ``1 - a + a 4 pi
    HG(nu; g)`` with the Henyey-Greenstein phase of :func:`skyscatter.atmosphere.phase.henyey_greenstein` (another
    implementation; [HenyeyGreenstein1941]), so its mean over the sphere is 1 (the integral of a phase function over
    the sphere, here by the trapezoidal rule on 200001 cosines, to 1e-6), the same in numba and numpy; its weight
    ``a`` (:func:`sampling.lobe_weight`) is 0 without aerosol (no lobe: the tables as before) and below
    ``MULTIPLE_LOBE_WEIGHT`` with it, larger for the hazier sky."""
    from skyscatter.atmosphere.phase import henyey_greenstein
    from skyscatter.precomputed import AtmosphereParameters
    from skyscatter.precomputed import sampling as s

    nu = np.linspace(-1.0, 1.0, 200001)
    for a in (0.0, 0.3, 0.9):
        f = s.multiple_lobe_array(nu, a)
        want = 1.0 - a + a * 4.0 * math.pi * henyey_greenstein(nu, s.MULTIPLE_LOBE_G)
        np.testing.assert_allclose(f, want, rtol=1e-12)
        assert abs(0.5 * np.trapezoid(f, nu) - 1.0) < 1e-6
        for x in (-1.0, 0.0, 0.7, 1.0):
            assert math.isclose(s.multiple_lobe(x, a), float(s.multiple_lobe_array(np.array([x]), a)[0]),
                                rel_tol=1e-12)
    assert s.lobe_weight(AtmosphereParameters(mie_angstrom_beta=0.0)) == 0.0
    earth = s.lobe_weight(AtmosphereParameters())
    hazy = s.lobe_weight(AtmosphereParameters.from_aerosol_optical_depth(0.5))
    assert 0.0 < earth < hazy < s.MULTIPLE_LOBE_WEIGHT
