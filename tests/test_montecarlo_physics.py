"""Physics of the Monte Carlo reference (skyscatter.montecarlo) against things we did not write.

* Column densities along rays against scipy's adaptive quadrature (QUADPACK).
* Free paths from inside a cloud layer by decomposition against the march's collision density (Kolmogorov-Smirnov
  on the sampled optical depths, scipy).
* An optically thin atmosphere against the single-scattering integral (closed form in the path length for a
  uniform medium, integrated by scipy).
* The plane-parallel limit against DISORT (disortpp; Stamnes et al. 1988, Appl. Opt. 27, 2502,
  doi:10.1364/AO.27.002502): pure Rayleigh and Rayleigh + aerosol (Henyey-Greenstein moments g^l), ground albedo
  0.1 and 0.8, sun zenith 30 and 70 deg, view zenith 0-80 deg in the principal plane.
* Energy: a conservative atmosphere over a white ground reflects all of the incident flux; with absorption the
  budget closes (reflected + absorbed = incident).

Tolerances come from the Monte Carlo standard error (3 sigma) plus stated deterministic allowances.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from disort_reference import cornette_shanks_moments, solve_ground_radiance, solve_upward_flux
from skyscatter.atmosphere import AtmosphereParameters, DensityProfile
from skyscatter.errors import InvalidParameterError
from skyscatter.montecarlo import kernels, sky_radiance, solar_disc_radiance
from skyscatter.montecarlo.driver import prepare_medium

EARTH = AtmosphereParameters()


def _ray_density_integral(p: AtmosphereParameters, r0: float, mu: float, t_end: float) -> np.ndarray:
    from scipy.integrate import quad

    out = []
    for prof in (p.rayleigh_density, p.mie_density, p.ozone_density):
        def f(t, prof=prof):
            return float(prof(math.sqrt(r0 * r0 + 2 * r0 * mu * t + t * t) - p.bottom_radius))

        # break points where the ray passes its lowest point and the layer kinks, so QUADPACK converges
        pts = [t for t in (-r0 * mu,) if 0 < t < t_end]
        out.append(quad(f, 0.0, t_end, points=pts or None, limit=500, epsabs=0.0, epsrel=1e-10)[0])
    return np.array(out)


@pytest.mark.parametrize("alt, zen_deg", [(0.0, 0.0), (0.0, 60.0), (0.0, 89.5), (0.0, 95.0), (5000.0, 93.0),
                                          (30000.0, 96.0), (59000.0, 120.0)])
def test_columns_match_adaptive_quadrature(alt, zen_deg):
    """Gauss-Legendre columns over the quadrature shells agree with QUADPACK to 3e-7 for steep rays and 2e-6 for
    grazing ones (relative; the bounds stated in montecarlo/kernels.py), for rays upwards, grazing, and down to the
    ground."""
    p = EARTH
    m = prepare_medium(p, np.array([550.0]))
    r0 = p.bottom_radius + alt
    mu = math.cos(math.radians(zen_deg))
    d = (math.sqrt(1 - mu * mu), 0.0, mu)
    t_end, _ = kernels._exit_distance(0.0, 0.0, r0, *d, p.bottom_radius, p.top_radius)
    cols, tmp = np.empty(3), np.empty(3)
    kernels.column_along(0.0, 0.0, r0, *d, t_end, np.inf, np.zeros(3), p.bottom_radius, m.edges, m.layers,
                         m.nlay, cols, tmp)
    ref = _ray_density_integral(p, r0, mu, t_end)
    np.testing.assert_allclose(cols, ref, rtol=3e-7 if abs(mu) > 0.2 else 2e-6, atol=1e-6)


@pytest.mark.parametrize("alt, zen_deg", [(1200.0, 0.0), (1499.0, 60.0), (1000.0, 85.0), (0.0, 89.0),
                                          (500.0, 60.0), (1300.0, 89.9)])
def test_shadow_rays_columns_above_a_cloud_layer_match_adaptive_quadrature(alt, zen_deg):
    """Shadow rays of a cloudy medium from below its cloud top take the columns above it from a table over the
    cosine there (kernels._shadow_march, driver.columns_above): every component's column to the top of the
    atmosphere agrees with QUADPACK within the bounds of the marched columns (3e-7 steep, 2e-6 grazing, relative;
    montecarlo/kernels.py)."""
    from scipy.integrate import quad

    from skyscatter.atmosphere.clouds import CloudLayer

    p = EARTH.replace(particles=(CloudLayer(1000.0, 1500.0, 15.0, effective_radius=10e-6),))
    m = prepare_medium(p, np.array([550.0]))
    assert m.sgeo[0] == p.bottom_radius + 1500.0  # the table starts at the cloud top
    r0 = p.bottom_radius + alt
    mu = math.cos(math.radians(zen_deg))
    d = (math.sqrt(1 - mu * mu), 0.0, mu)
    t_end, ground = kernels._exit_distance(0.0, 0.0, r0, *d, p.bottom_radius, p.top_radius)
    assert not ground
    nc = m.layers.shape[0]
    cols, tmp, rec = np.empty(nc), np.empty(nc), np.empty((2 * m.edges.size + 2, 2 + nc))
    deep = kernels._shadow_march(0.0, 0.0, r0, *d, t_end, np.inf, np.zeros(nc), p.bottom_radius, m.edges, m.layers,
                                 m.nlay, m.sgeo, m.stab, cols, tmp, rec)
    assert not deep
    ref = []
    for prof in (p.rayleigh_density, p.mie_density, p.ozone_density, p.particle_components[1].density):
        def f(t, prof=prof):
            return float(prof(math.sqrt(r0 * r0 + 2 * r0 * mu * t + t * t) - p.bottom_radius))

        # break points where the ray crosses the cloud's base and top, so QUADPACK converges
        pts = [-r0 * mu + math.sqrt(max((r0 * mu) ** 2 - (r0 * r0 - rr * rr), 0.0))
               for rr in (p.bottom_radius + 1000.0, p.bottom_radius + 1500.0) if rr > r0]
        ref.append(quad(f, 0.0, t_end, points=pts or None, limit=500, epsabs=0.0, epsrel=1e-10)[0])
    np.testing.assert_allclose(cols, ref, rtol=3e-7 if abs(mu) > 0.2 else 2e-6, atol=1e-6)


@pytest.mark.parametrize("alt, zen_deg, length", [(1200.0, 30.0, 30.0), (1499.0, 60.0, 1.5), (1001.0, 120.0, 1.0),
                                                   (1300.0, 90.0, 1900.0), (1250.0, 89.9, 800.0),
                                                   (1100.0, 45.0, 560.0), (1480.0, 175.0, 450.0)])
def test_short_pieces_inside_a_cloud_layer_match_adaptive_quadrature(alt, zen_deg, length):
    """Pieces of a ray inside a cloud layer up to 2 km long (free paths and shadow rays there) take their columns
    in closed form about the piece's midpoint (kernels._short_piece_columns, used by kernels._uniform_free_path and
    kernels._shadow_march): every component's column agrees with QUADPACK to 1e-9 relative (the bound its
    docstring derives), horizontal and downward rays included; the layer's own column is its length. Too long a
    piece, or one across the layer's base, is left to Gauss-Legendre."""
    from scipy.integrate import quad

    from skyscatter.atmosphere.clouds import CloudLayer

    p = EARTH.replace(particles=(CloudLayer(1000.0, 1500.0, 15.0, effective_radius=10e-6),))
    m = prepare_medium(p, np.array([550.0]))
    r0 = p.bottom_radius + alt
    mu = math.cos(math.radians(zen_deg))
    nc = m.layers.shape[0]
    cols = np.full(nc, np.nan)
    assert kernels._short_piece_columns(r0 * r0, r0 * mu, 0.0, length, p.bottom_radius, m.layers, m.nlay, cols)
    ref = []
    for prof in (p.rayleigh_density, p.mie_density, p.ozone_density, p.particle_components[1].density):
        def f(t, prof=prof):
            return float(prof(math.sqrt(r0 * r0 + 2 * r0 * mu * t + t * t) - p.bottom_radius))

        pts = [t for t in (-r0 * mu,) if 0 < t < length]
        ref.append(quad(f, 0.0, length, points=pts or None, limit=500, epsabs=0.0, epsrel=1e-13)[0])
    assert ref[3] == pytest.approx(length, rel=1e-12)  # the ray stays in the layer
    np.testing.assert_allclose(cols, ref, rtol=1e-9, atol=1e-12)
    assert not kernels._short_piece_columns(r0 * r0, r0 * mu, 0.0, 2100.0, p.bottom_radius, m.layers, m.nlay, cols)
    r1 = p.bottom_radius + 999.0  # straight up from 1 m below the base, 2 m: across it
    assert not kernels._short_piece_columns(r1 * r1, r1, 0.0, 2.0, p.bottom_radius, m.layers, m.nlay, cols)


def test_free_path_inversion_hits_the_target_optical_depth():
    """Sampling a distance by optical depth returns the point where k . col equals the target."""
    p = EARTH
    m = prepare_medium(p, np.array([400.0]))
    k = m.coef[0]
    r0 = p.bottom_radius + 1000.0
    mu = math.cos(math.radians(85.0))
    d = (math.sqrt(1 - mu * mu), 0.0, mu)
    t_end, _ = kernels._exit_distance(0.0, 0.0, r0, *d, p.bottom_radius, p.top_radius)
    cols, tmp = np.empty(3), np.empty(3)
    for target in (1e-4, 0.05, 0.3, 1.0):
        t, reached = kernels.column_along(0.0, 0.0, r0, *d, t_end, target, k, p.bottom_radius, m.edges,
                                          m.layers, m.nlay, cols, tmp)
        assert reached
        ref = _ray_density_integral(p, r0, mu, t)
        assert abs(float(k @ ref) / target - 1) < 1e-6


def _thin_single_scattering(p, beta, sun_zen, view_zen, view_side):
    """Single-scattering radiance of a uniform Rayleigh medium by scipy quadrature of
    ``E beta p(theta) exp(-beta (t + s_sun(t))) dt`` (s_sun: straight path to the top towards the sun)."""
    from scipy.integrate import quad

    rb, rt = p.bottom_radius, p.top_radius
    sun = np.array([0.0, math.sin(sun_zen), math.cos(sun_zen)])
    d = np.array([0.0, view_side * math.sin(view_zen), math.cos(view_zen)])
    o = np.array([0.0, 0.0, rb])
    b = o @ d
    t_end = -b + math.sqrt(b * b - (rb * rb - rt * rt))
    mu = float(d @ sun)
    phase = 3 / (16 * math.pi) * (1 + mu * mu)

    def f(t):
        x = o + t * d
        bs = x @ sun
        s = -bs + math.sqrt(bs * bs - (x @ x - rt * rt))
        return math.exp(-beta * (t + s))

    return beta * phase * quad(f, 0.0, t_end, epsrel=1e-10, limit=200)[0]


def test_optically_thin_against_single_scattering():
    """Uniform Rayleigh medium with vertical optical depth 1e-3, black ground: the Monte Carlo radiance equals the
    single-scattering integral within 0.5 % (multiple scattering adds O(tau) ~ 0.1-0.3 % at these angles; the
    Monte Carlo standard error is kept below 0.1 %)."""
    thick = 60_000.0
    beta = 1e-3 / thick
    p = AtmosphereParameters(rayleigh_density=DensityProfile.uniform(), rayleigh_scattering=beta,
                             mie_angstrom_beta=0.0, ozone_column=0.0, ground_albedo=0.0, solar_irradiance=1.0)
    sun_zen = math.radians(40.0)
    views = [(0.0, 1.0), (math.radians(50.0), 1.0), (math.radians(50.0), -1.0), (math.radians(80.0), -1.0)]
    dirs = np.array([[0.0, s * math.sin(z), math.cos(z)] for z, s in views])
    res = sky_radiance(p, dirs, [550.0], sun_zenith=sun_zen, samples=16384, scheduler="synchronous", seed=3)
    ref = np.array([_thin_single_scattering(p, beta, sun_zen, z, s) for z, s in views])
    rel = res.radiance[:, 0] / ref - 1
    assert np.all(res.relative_stderr[:, 0] < 1e-3), res.relative_stderr
    assert np.all(np.abs(rel) < 5e-3), rel


# ----------------------------------------------------------------------------------------------- DISORT


#: Planet radius of the plane-parallel limit [m]: 1000 x the Earth's.
FLAT_RADIUS = 6.36e9


def _flat(**changes) -> AtmosphereParameters:
    base = dict(bottom_radius=FLAT_RADIUS, top_radius=FLAT_RADIUS + 60_000.0, ozone_column=0.0, solar_irradiance=1.0)
    base.update(changes)
    return AtmosphereParameters(**base)


def _disort_principal_plane(p: AtmosphereParameters, wl: float, sun_zen_deg: float, albedo: float,
                            view_zen_deg: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """DISORT downwelling radiance at the ground for unit beam flux, (n_view, 2): towards the sun, away; the
    aerosol phase moments are those of ``p.mie_phase_function`` (Henyey-Greenstein: g^l; Cornette-Shanks: by
    400-point Gauss-Legendre quadrature). ``scale`` multiplies every layer's single-scattering albedo and the
    ground's albedo (:func:`_disort_orders`)."""
    pytest.importorskip("disortpp")
    edges = np.concatenate([np.linspace(0.0, 6000.0, 31), np.linspace(7000.0, 60000.0, 54)])[::-1]
    n = edges.size - 1
    br = float(p.rayleigh_scattering_at([wl])[0])
    be = float(p.mie_extinction_at([wl])[0])
    g = p.mie_phase_g
    streams = 32
    nmom = streams

    def col(prof, lo, hi):
        hs = np.linspace(lo, hi, 201)
        return np.trapezoid(prof(hs), hs)

    tau_r = np.array([br * col(p.rayleigh_density, edges[i + 1], edges[i]) for i in range(n)])
    tau_me = np.array([be * col(p.mie_density, edges[i + 1], edges[i]) for i in range(n)])
    tau_ms = tau_me * p.mie_single_scattering_albedo if be > 0 else tau_me
    dtau = tau_r + tau_me
    ray = np.zeros(nmom + 1)
    ray[0], ray[2] = 1.0, 0.1
    if p.mie_phase_function == "henyey-greenstein":
        hg = g ** np.arange(nmom + 1)
    else:
        hg = cornette_shanks_moments(g, nmom, n_nodes=400)
    mom = [(tau_r[i] * ray + tau_ms[i] * hg) / (tau_r[i] + tau_ms[i]) for i in range(n)]
    return solve_ground_radiance(dtau, scale * (tau_r + tau_ms) / dtau, mom, sun_zenith=math.radians(sun_zen_deg),
                                 view_zenith=np.radians(view_zen_deg), relative_azimuth=[0.0, math.pi],
                                 ground_albedo=scale * albedo, n_streams=streams)


#: Sphericity allowance of the plane-parallel comparison (relative). With a planet 1000 x the Earth's radius the
#: air mass of the most oblique ray used (80 deg) differs from sec(80 deg) by (H / R) tan^2(80 deg) / 2 = 2e-5
#: (first order of the Chapman function in H / R); we allow 1e-4, plus 2e-3 for DISORT's discretisation
#: (84 homogeneous layers, 32 streams: doubling the layers and going to 48 streams changes the radiances of the
#: hazy case by < 1.8e-3).
PLANE_PARALLEL_ALLOWANCE = 1e-4 + 2e-3


@pytest.mark.parametrize("aerosol", [False, True], ids=["rayleigh", "rayleigh+aerosol"])
@pytest.mark.parametrize("albedo", [0.1, 0.8])
@pytest.mark.parametrize("sun_zen_deg", [30.0, 70.0])
def test_plane_parallel_limit_against_disort(aerosol, albedo, sun_zen_deg):
    """Principal-plane sky radiance at the ground, 500 nm: Monte Carlo (planet radius 6.36e9 m) vs DISORT
    (32 streams, Nakajima-Tanaka intensity correction), within 3 standard errors plus PLANE_PARALLEL_ALLOWANCE.
    Aerosol: Angstrom beta 0.1, alpha 0, H = 1.2 km, single-scattering albedo 0.9, Henyey-Greenstein g = 0.8."""
    p = _flat(ground_albedo=albedo, mie_angstrom_beta=0.1 if aerosol else 0.0, mie_phase_function="henyey-greenstein")
    view = np.array([0.0, 20.0, 40.0, 60.0, 80.0])
    ref = _disort_principal_plane(p, 500.0, sun_zen_deg, albedo, view)
    dirs, refs = [], []
    for i, z in enumerate(np.radians(view)):
        for j, side in enumerate((1.0, -1.0)):
            if z == 0.0 and side < 0:
                continue
            dirs.append([0.0, side * math.sin(z), math.cos(z)])
            refs.append(ref[i, j])
    res = sky_radiance(p, np.array(dirs), [500.0], sun_zenith=math.radians(sun_zen_deg), samples=3072, seed=11)
    mc, se, refs = res.radiance[:, 0], res.stderr[:, 0], np.array(refs)
    tol = 3 * se + PLANE_PARALLEL_ALLOWANCE * refs
    assert np.all(np.abs(mc - refs) <= tol), np.c_[mc, refs, (mc - refs) / se]


@pytest.mark.parametrize("sun_zen_deg", [30.0, 70.0])
def test_plane_parallel_limit_against_disort_cornette_shanks(sun_zen_deg):
    """As above with the Cornette-Shanks aerosol phase (the tables' phase, sampled as HG and reweighted): DISORT
    gets its Legendre moments by quadrature; aerosol tau 0.1, g 0.8, ground albedo 0.1."""
    p = _flat(ground_albedo=0.1, mie_angstrom_beta=0.1)
    assert p.mie_phase_function == "cornette-shanks"
    view = np.array([0.0, 20.0, 40.0, 60.0, 80.0])
    ref = _disort_principal_plane(p, 500.0, sun_zen_deg, 0.1, view)
    dirs = np.array([[0.0, s * math.sin(z), math.cos(z)] for z in np.radians(view) for s in (1.0, -1.0)])
    refs = np.array([ref[i, j] for i in range(view.size) for j in range(2)])
    res = sky_radiance(p, dirs, [500.0], sun_zenith=math.radians(sun_zen_deg), samples=3072, seed=13)
    mc, se = res.radiance[:, 0], res.stderr[:, 0]
    assert np.all(np.abs(mc - refs) <= 3 * se + PLANE_PARALLEL_ALLOWANCE * refs), np.c_[mc, refs, (mc - refs) / se]


def _disort_orders(p: AtmosphereParameters, wl: float, sun_zen_deg: float, albedo: float, view_zen_deg: np.ndarray,
                   n_terms: int = 8, s_max: float = 0.3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """DISORT's radiance split by order of scattering: (order 1, order 2, orders >= 3), each (n_view, 2).

    Every scattering and every ground reflection multiplies a light path's contribution by one single-scattering
    albedo (or the ground's albedo), so with all of them scaled by ``s`` the radiance is the power series
    ``L(s) = sum_k s^k L_k`` whose coefficient ``L_k`` is the order ``k`` (the Neumann series of the radiative
    transfer equation; Chandrasekhar 1960, Sec. 11; Preetham's course notes, "successive orders of scattering").
    ``L_1`` and ``L_2`` are fitted from ``n_terms`` solutions at Chebyshev nodes ``s`` in (0, ``s_max``) (the terms
    after ``s^n_terms`` below 1e-6 of the radiance there: doubling ``n_terms`` or ``s_max`` moves ``L_1, L_2`` by
    less than 1e-7 relative), the rest is ``L(1) - L_1 - L_2``. Exact for DISORT's own problem as long as its
    delta-M truncation does not depend on ``s`` (Henyey-Greenstein g 0.7 at 32 streams: ``g^32`` = 1e-5)."""
    k = np.arange(n_terms)
    s = s_max * (1 + np.cos(np.pi * (k + 0.5) / n_terms)) / 2
    values = np.array([_disort_principal_plane(p, wl, sun_zen_deg, albedo, view_zen_deg, x) for x in s])
    powers = np.vander(s, n_terms + 1, increasing=True)[:, 1:]
    coef = np.linalg.lstsq(powers, values.reshape(n_terms, -1), rcond=None)[0].reshape(n_terms, *values.shape[1:])
    whole = _disort_principal_plane(p, wl, sun_zen_deg, albedo, view_zen_deg)
    return coef[0], coef[1], whole - coef[0] - coef[1]


@pytest.mark.parametrize("sun_zen_deg", [40.0, 80.0])
def test_orders_of_scattering_against_disort(sun_zen_deg):
    """The windows of orders (``orders=1``, ``2``, ``(3, None)``) against DISORT's radiance split into its power
    series in the single-scattering albedo (:func:`_disort_orders`): Rayleigh + aerosol (Angstrom beta 0.1, HG g 0.7,
    single-scattering albedo 0.9), ground albedo 0.3 (its reflections are orders too), 550 nm, plane-parallel
    limit; within 3 standard errors plus PLANE_PARALLEL_ALLOWANCE of the whole radiance (DISORT's discretisation is
    shared out among the orders). The three windows of one seed add up to the whole estimate exactly."""
    p = _flat(ground_albedo=0.3, mie_angstrom_beta=0.1, mie_phase_function="henyey-greenstein", mie_phase_g=0.7)
    view = np.array([0.0, 45.0, 75.0])
    parts = _disort_orders(p, 550.0, sun_zen_deg, 0.3, view)
    whole_ref = sum(parts)
    dirs = np.array([[0.0, s * math.sin(z), math.cos(z)] for z in np.radians(view) for s in (1.0, -1.0)])
    pick = [(i, j) for i in range(view.size) for j in range(2)]
    kw = dict(sun_zenith=math.radians(sun_zen_deg), samples=8192, seed=17)
    whole = sky_radiance(p, dirs, [550.0], **kw).radiance[:, 0]
    total = np.zeros(len(pick))
    for window, ref in zip((1, 2, (3, None)), parts, strict=True):
        res = sky_radiance(p, dirs, [550.0], orders=window, **kw)
        mc, se = res.radiance[:, 0], res.stderr[:, 0]
        r = np.array([ref[i, j] for i, j in pick])
        allowance = PLANE_PARALLEL_ALLOWANCE * np.array([whole_ref[i, j] for i, j in pick])
        assert np.all(np.abs(mc - r) <= 3 * se + allowance), (window, np.c_[mc, r, (mc - r) / se])
        total += mc
    np.testing.assert_allclose(total, whole, rtol=1e-12)


def test_orders_window_is_validated():
    p = _flat()
    d = [[0.0, 0.0, 1.0]]
    for bad in (0, (2, 1), (0, 3), (1, 2, 3), 1.5, True, (1, kernels.MAX_ORDER + 1)):
        with pytest.raises(InvalidParameterError, match="orders"):
            sky_radiance(p, d, [550.0], sun_zenith=0.5, samples=8, orders=bad)


# ----------------------------------------------------------------------------------------------- energy


def _upward_flux_at_top(p, sun_zen, samples, seed=5):
    """Reflected flux through the top of the atmosphere per unit incident flux, for a flat (huge) planet:
    integral of L cos over the upward hemisphere, by a Gauss-Legendre x uniform-azimuth quadrature of MC radiances
    seen from just above the atmosphere."""
    mu, w = np.polynomial.legendre.leggauss(8)
    mu = 0.5 * (mu + 1)
    w = 0.5 * w
    n_phi = 8
    phi = (np.arange(n_phi) + 0.5) * 2 * math.pi / n_phi
    dirs = []
    weights = []
    for m, wm in zip(mu, w, strict=True):
        for ph in phi:
            s = math.sqrt(1 - m * m)
            dirs.append([s * math.sin(ph), s * math.cos(ph), -m])  # looking down from the top
            weights.append(wm * m * 2 * math.pi / n_phi)
    res = sky_radiance(p, np.array(dirs), [500.0], sun_zenith=sun_zen, altitude=p.thickness + 1.0,
                       samples=samples, seed=seed)
    weights = np.array(weights)
    flux = weights @ res.radiance[:, 0]
    err = math.sqrt(np.sum((weights * res.stderr[:, 0]) ** 2))
    return flux / math.cos(sun_zen), err / math.cos(sun_zen)


def test_energy_conservative_atmosphere_reflects_everything():
    """No absorption (Rayleigh + non-absorbing aerosol, no ozone) over a white ground: the flux leaving the top
    equals the incident flux cos(theta_s) E. Tolerance: 3 standard errors plus 0.5 % for the 8 x 8 angular
    quadrature of the exitance (the same rule reproduces DISORT's flux in the absorbing case below)."""
    p = _flat(ground_albedo=1.0, mie_angstrom_beta=0.05, mie_single_scattering_albedo=1.0)
    ratio, err = _upward_flux_at_top(p, math.radians(30.0), samples=512)
    # the directly transmitted beam reflected by the ground and transmitted out is part of the sky seen from above
    assert abs(ratio - 1.0) < 3 * err + 5e-3, (ratio, err)


def test_energy_budget_closes_with_absorption():
    """With absorbing aerosol (single-scattering albedo 0.8, tau 0.2) over a black ground the atmosphere reflects
    less than it receives; the reflected flux equals DISORT's upward flux at the top (so absorbed + transmitted
    close the budget as in DISORT) within 3 standard errors + 0.5 % (angular quadrature)."""
    pytest.importorskip("disortpp")
    p = _flat(ground_albedo=0.0, mie_angstrom_beta=0.2, mie_single_scattering_albedo=0.8)
    sun_zen = math.radians(30.0)
    ratio, err = _upward_flux_at_top(p.replace(mie_phase_function="henyey-greenstein"), sun_zen, samples=512)
    # DISORT (Henyey-Greenstein moments g^l, as the Monte Carlo phase here) upward flux at the top for unit beam flux
    br = float(p.rayleigh_scattering_at([500.0])[0])
    be = float(p.mie_extinction_at([500.0])[0])
    n = 120
    edges = np.linspace(60000.0, 0.0, n + 1)
    tr = br * 8000.0 * (np.exp(-edges[1:] / 8000.0) - np.exp(-edges[:-1] / 8000.0))
    tm = be * 1200.0 * (np.exp(-edges[1:] / 1200.0) - np.exp(-edges[:-1] / 1200.0))
    tms = tm * 0.8
    ray = np.zeros(33)
    ray[0], ray[2] = 1.0, 0.1
    hg = p.mie_phase_g ** np.arange(33)
    mom = [(tr[i] * ray + tms[i] * hg) / (tr[i] + tms[i]) for i in range(n)]
    up = solve_upward_flux(tr + tm, (tr + tms) / (tr + tm), mom, sun_zenith=sun_zen, ground_albedo=0.0,
                           n_streams=32) / math.cos(sun_zen)
    assert abs(ratio - up) < 3 * err + 5e-3 * up, (ratio, up, err)


def test_solar_disc_radiance_is_beer_lambert():
    """Transmitted disc radiance = E / Omega_sun * exp(-tau_vertical / cos z) for a flat planet (uniform disc)."""
    p = _flat(solar_irradiance=1.0)
    zen = math.radians(30.0)
    wl = np.array([450.0, 550.0])
    got = solar_disc_radiance(p, wl, sun_zenith=zen)
    tau = (p.rayleigh_scattering_at(wl) * p.rayleigh_density.column(p.thickness)
           + p.mie_extinction_at(wl) * p.mie_density.column(p.thickness))
    omega = 2 * math.pi * (1 - math.cos(p.sun_angular_radius))
    np.testing.assert_allclose(got, np.exp(-tau / math.cos(zen)) / omega, rtol=1e-4)


@pytest.mark.parametrize("alt, zen_deg, wl", [(1200.0, 60.0, 550.0), (1499.0, 30.0, 360.0), (1010.0, 170.0, 550.0),
                                              (1300.0, 89.9, 360.0), (1001.0, 95.0, 760.0)])
def test_uniform_shell_free_paths_follow_the_collision_density(alt, zen_deg, wl):
    """Free paths from inside a cloud layer by decomposition (kernels._uniform_free_path: the layer's exponential
    free path, the air marched up to it, a fresh free path from the layer's boundary when it is left) have the
    collision density ``sigma_t T`` of the march: the hero's optical depth at the sampled distances, ``1 -
    exp(-tau)``, is uniform below ``1 - T_end`` (Kolmogorov-Smirnov, 20000 draws, p > 1e-3), the paths that reach
    the end number ``T_end`` of them (within 4 binomial standard deviations), and the columns returned are the
    march's to the sampled distance (within 1e-9 relative)."""
    from scipy.stats import kstest

    from skyscatter.atmosphere.clouds import CloudLayer

    p = EARTH.replace(particles=(CloudLayer(1000.0, 1500.0, 15.0, effective_radius=10e-6),))
    m = prepare_medium(p, np.array([wl]))
    assert m.ushell.shape == (1, 6) and m.ushell[0, 5] == 1.0  # the layer's shell, its density 1
    r0 = p.bottom_radius + alt
    mu = math.cos(math.radians(zen_deg))
    d = (math.sqrt(1 - mu * mu), 0.0, mu)
    t_end, _ = kernels._exit_distance(0.0, 0.0, r0, *d, p.bottom_radius, p.top_radius)
    nc = m.layers.shape[0]
    kh = m.coef[0].copy()
    s = kernels._uniform_shell(r0 * r0, m.ushell)
    assert s == 0
    cols, tmp, rec = np.empty(nc), np.empty(nc), np.empty((2 * m.edges.size + 2, 2 + nc))
    kha, cseg, ref, tmp2 = np.empty(nc), np.empty(nc), np.empty(nc), np.empty(nc)
    st = np.array([0x9E3779B97F4A7C15], dtype=np.uint64)
    kernels.column_along(0.0, 0.0, r0, *d, t_end, np.inf, kh, p.bottom_radius, m.edges, m.layers, m.nlay, ref, tmp2)
    big_f = -math.expm1(-float(kh @ ref))  # probability of a collision before t_end
    u_reached, n_end, n = [], 0, 20000
    rng = np.random.default_rng(5)
    for _ in range(n):
        target = -math.log1p(-rng.random())
        t, reached = kernels._uniform_free_path(0.0, 0.0, r0, *d, t_end, target, kh, s, m.ushell, p.bottom_radius,
                                                m.edges, m.layers, m.nlay, cols, tmp, rec, kha, cseg, st)
        kernels.column_along(0.0, 0.0, r0, *d, t, np.inf, kh, p.bottom_radius, m.edges, m.layers, m.nlay, ref, tmp2)
        np.testing.assert_allclose(cols, ref, rtol=1e-9, atol=1e-9)
        if reached:
            u_reached.append(-math.expm1(-float(kh @ ref)) / big_f)
        else:
            assert t == t_end
            n_end += 1
    assert abs(n_end - n * (1 - big_f)) <= 4 * math.sqrt(n * big_f * (1 - big_f)) + 1e-9, (n_end, n * (1 - big_f))
    assert kstest(u_reached, "uniform").pvalue > 1e-3
