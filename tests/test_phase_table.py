"""Tabulated phase functions (skyscatter.atmosphere.phase_table) and particle components (atmosphere.particles).

References not written by us: Henyey & Greenstein (1941) (Legendre moments g^l), Cornette & Shanks (1992) (mean
cosine 3 g (4 + g^2) / (5 (2 + g^2))), Wiscombe (1977) (delta-M moments of Henyey-Greenstein), scipy's adaptive
quadrature and Kolmogorov-Smirnov test (normalisation, moments, samples).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, stats

from skyscatter.atmosphere import AtmosphereParameters, DensityProfile, PowerLawSpectrum, TabulatedSpectrum
from skyscatter.atmosphere import phase as phase_module
from skyscatter.atmosphere import phase_table as pt
from skyscatter.atmosphere.particles import (
    AnalyticParticles,
    TabulatedParticles,
    particle_component_from_dict,
)
from skyscatter.atmosphere.phase_table import PhaseTable, phase_angle_grid
from skyscatter.errors import FileFormatError, InvalidParameterError

WL = np.array([450.0, 550.0, 650.0])


@pytest.fixture(scope="module")
def hg():
    return PhaseTable.henyey_greenstein([0.5, 0.8, 0.95], WL)


# ------------------------------------------------------------------ grid


def test_angle_grid_is_dense_forward_and_spans_the_sphere():
    th = phase_angle_grid()
    d = np.degrees(np.diff(th))
    assert th[0] == 0.0 and th[-1] == math.pi and np.all(d > 0)
    assert 0.0099 < d[0] < 0.0102  # the forward step, 0.01 deg
    assert d.max() <= 0.25 + 1e-9 and abs(d[-1] - 0.25) < 1e-6
    assert np.all(np.diff(d[: np.searchsorted(th, math.radians(15.0))]) > 0)  # growing over the ramp
    for bad in ((0.0, 0.01, 0.2), (0.02, 0.01, 0.2), (0.001, 0.01, 4.0), (0.001, float("nan"), 0.1)):
        with pytest.raises(InvalidParameterError):
            phase_angle_grid(*bad)


# ------------------------------------------------------------------ the interpolant


def test_tables_integrate_to_one_over_the_sphere_by_adaptive_quadrature(hg):
    nodes = hg.numba_arrays().mu
    chunks = np.array_split(np.arange(nodes.size), 24)
    for k in range(3):
        total = 0.0
        for c in chunks:  # adaptive quadrature over pieces of ~36 segments, their nodes as break points
            lo, hi = nodes[c[0]], nodes[min(c[-1] + 1, nodes.size - 1)]
            part, _ = integrate.quad(lambda m, k=k: float(hg.evaluate(m, k)), lo, hi, points=nodes[c[1:]],
                                     limit=200, epsabs=1e-13)
            total += part
        assert abs(2 * math.pi * total - 1.0) < 1e-9


@pytest.mark.parametrize(("kind", "g", "tol"), [("henyey-greenstein", 0.8, 2e-4), ("henyey-greenstein", 0.99, 5e-4),
                                                ("cornette-shanks", 0.8, 2e-4), ("cornette-shanks", -0.3, 1e-5)])
def test_tabulated_analytic_functions_match_the_formulas(kind, g, tol):
    table = PhaseTable.from_analytic(kind, g, [550.0])
    mu = np.cos(np.linspace(0.0, math.pi, 20001))
    ref = phase_module.aerosol_phase(mu, g, kind)
    assert np.max(np.abs(table.evaluate(mu, 0) / ref - 1.0)) < tol


def test_legendre_moments_of_henyey_greenstein_are_powers_of_g(hg):
    # Henyey & Greenstein (1941): chi_l = g^l exactly; the table differs by its interpolation error
    chi = hg.legendre_moments(200)
    ell = np.arange(200)
    for k, (g, tol) in enumerate(((0.5, 2e-6), (0.8, 2e-5), (0.95, 5e-5))):
        assert np.max(np.abs(chi[k] - g ** ell)) < tol
    np.testing.assert_allclose(hg.asymmetry, [0.5, 0.8, 0.95], atol=3e-5)


def test_cornette_shanks_mean_cosine_is_the_published_one():
    g = 0.8
    table = PhaseTable.cornette_shanks(g, [550.0])
    assert abs(table.asymmetry[0] - 3 * g * (4 + g * g) / (5 * (2 + g * g))) < 2e-5  # Cornette & Shanks 1992


def test_legendre_moments_are_exact_for_the_interpolant_by_independent_quadrature(hg):
    # composite Gauss-Legendre (16 points per segment) of the interpolant times P_l: an independent integral
    arr = hg.numba_arrays()
    x, w = np.polynomial.legendre.leggauss(16)
    a, b = arr.mu[:-1, None], arr.mu[1:, None]
    m = 0.5 * (b - a) * x + 0.5 * (a + b)
    ww = 0.5 * (b - a) * w
    p = hg.evaluate(m.ravel(), 2).reshape(m.shape)
    chi = hg.legendre_moments(65)[2]
    for ell in (1, 2, 7, 32, 64):
        ref = 2 * math.pi * np.sum(ww * p * np.polynomial.legendre.legval(m, [0] * ell + [1]))
        assert abs(chi[ell] - ref) < 1e-10


def test_series_from_legendre_moments_round_trips():
    chi = np.array([1.0, 0.6, 0.3, 0.1, 0.02])
    table = PhaseTable.from_legendre_moments(chi, [500.0])
    np.testing.assert_allclose(table.legendre_moments(8)[0], np.r_[chi, 0, 0, 0], atol=2e-6)
    with pytest.raises(InvalidParameterError, match="negative"):
        PhaseTable.from_legendre_moments([1.0, 0.0, 0.0, 0.9], [500.0])


# ------------------------------------------------------------------ numba and sampling


def test_numba_lookups_equal_the_numpy_interpolant(hg):
    arr = hg.numba_arrays()
    assert all(a.flags.c_contiguous and a.dtype == np.float64 for a in arr)
    assert arr.mu[0] == -1.0 and arr.mu[-1] == 1.0 and np.all(np.diff(arr.mu) > 0)
    mu = np.r_[-1.0, 1.0, arr.mu[[5, 400, 860]], np.random.default_rng(1).uniform(-1, 1, 200), 0.99999999]
    out = np.empty(3)
    for m in mu:
        ref = hg.evaluate(m)
        pt.phase_table_values(arr.mu, arr.values, m, out)
        np.testing.assert_allclose(out, ref, rtol=1e-14, atol=0)
        assert abs(pt.phase_table_value(arr.mu, arr.values, 1, m) - ref[1]) <= 1e-14 * ref[1]


def test_inverse_cdf_is_exact_for_the_interpolant_and_numba_agrees(hg):
    arr = hg.numba_arrays()
    u = np.r_[0.0, 1e-9, np.linspace(0.0, 1.0, 1001), 1.0 - 1e-12, 1.0]
    for k in range(3):
        mu = hg.inverse_cdf(u, k)
        assert np.all(np.diff(mu[2:-2]) >= 0) and mu[0] == -1.0 and mu[-1] == 1.0
        np.testing.assert_allclose(hg.cdf(mu, k), u, atol=1e-12)
        nb = np.array([pt.phase_table_inverse_cdf(arr.mu, arr.values, arr.cdf, k, x) for x in u])
        np.testing.assert_allclose(nb, mu, atol=1e-13)



def test_segment_hints_give_the_bisection_to_the_bit(hg):
    """The look-ups the Monte Carlo shares (``phase_table_inverse_cdf_segment``'s segment as the hint of
    ``phase_table_segment_near``, ``phase_table_values_at``): the same ``(i, w)`` and values as the bisection, for
    the right hint, wrong hints, no hint and the ends; a hint is only a shortcut."""
    arr = hg.numba_arrays()
    n = arr.mu.size
    u = np.r_[0.0, 1e-300, 1e-9, np.random.default_rng(3).random(400), 1.0 - 1e-16, 1.0]
    out_a = np.empty(3)
    out_b = np.empty(3)
    used = 0
    for k in range(3):
        for x in u:
            mu, seg = pt.phase_table_inverse_cdf_segment(arr.mu, arr.values, arr.cdf, k, x)
            assert mu == pt.phase_table_inverse_cdf(arr.mu, arr.values, arr.cdf, k, x)
            ref = pt.phase_table_segment(arr.mu, mu)
            for hint in (seg, -1, 0, n - 2, n - 1, n + 5, (seg + 1) % (n - 1), max(seg - 1, 0)):
                got = pt.phase_table_segment_near(arr.mu, mu, hint)
                assert got[0] == ref[0] and got[1] == ref[1], (k, x, mu, hint, got, ref)
            used += seg == ref[0]
            pt.phase_table_values(arr.mu, arr.values, mu, out_a)
            pt.phase_table_values_at(arr.values, ref[0], ref[1], out_b)
            assert np.array_equal(out_a, out_b)
    assert used >= 0.95 * 3 * u.size  # the drawn segment is almost always the cosine's: the bisection is skipped

def test_samples_follow_the_analytic_function_ks():
    g = 0.8
    table = PhaseTable.henyey_greenstein(g, [550.0])
    s = table.sample(20000, 0, np.random.default_rng(7))

    def hg_cdf(mu):  # 2 pi int_{-1}^{mu} p_HG, closed form
        return (1 - g * g) / (2 * g) * (1 / np.sqrt(1 + g * g - 2 * g * mu) - 1 / (1 + g))

    assert stats.kstest(s, hg_cdf).pvalue > 1e-3


# ------------------------------------------------------------------ delta-M, wavelengths, mixtures


def test_delta_m_of_henyey_greenstein_follows_wiscombe_1977():
    g, m = 0.85, 16
    table = PhaseTable.henyey_greenstein(g, [550.0])
    trunc, f = table.delta_m(m)
    assert abs(f[0] - g ** m) < 2e-5  # f = chi_M = g^M
    ell = np.arange(m)
    expected = (g ** ell - g ** m) / (1 - g ** m)  # Wiscombe (1977), Eq. 7 for HG
    np.testing.assert_allclose(trunc.legendre_moments(m)[0], expected, atol=2e-4)
    forward = np.sum((2 * ell + 1) * expected) / (4 * math.pi)  # the series at mu = 1, far below p_HG(1)
    assert abs(trunc.evaluate(1.0, 0) / forward - 1) < 1e-3 and forward < 0.6 * table.evaluate(1.0, 0)
    with pytest.raises(InvalidParameterError):
        table.delta_m(1)


def test_wavelength_interpolation_and_mixtures(hg):
    mid = hg.at_wavelengths([500.0])
    np.testing.assert_allclose(mid.values[0], 0.5 * (hg.values[0] + hg.values[1]), rtol=1e-12)
    assert hg.at_wavelengths(WL) is hg
    with pytest.raises(InvalidParameterError, match="covers"):
        hg.at_wavelengths([700.0])
    a = PhaseTable.henyey_greenstein(0.5, [550.0])
    b = PhaseTable.henyey_greenstein(0.9, [550.0])
    mix = PhaseTable.mixture([a, b], [1.0, 3.0])
    ell = np.arange(6)
    np.testing.assert_allclose(mix.legendre_moments(6)[0], (0.5 ** ell + 3 * 0.9 ** ell) / 4, atol=2e-5)


def test_bad_tables_are_refused():
    th = phase_angle_grid()
    good = np.ones(th.size)
    for kwargs in (dict(angles=th[1:], values=good[1:]), dict(angles=th, values=-good),
                   dict(angles=th, values=np.r_[np.nan, good[1:]]), dict(angles=th, values=0 * good),
                   dict(angles=th, values=np.ones((2, th.size))), dict(angles=th[::-1], values=good)):
        with pytest.raises(InvalidParameterError):
            PhaseTable([550.0], **kwargs)
    with pytest.raises(InvalidParameterError, match="integrate"):
        PhaseTable([550.0], th, good, normalise=False)
    with pytest.raises(InvalidParameterError):
        PhaseTable([550.0, 500.0], th, good)
    table = PhaseTable([550.0], th, good)
    assert abs(table.values[0, 0] - 1 / (4 * math.pi)) < 1e-15
    with pytest.raises(InvalidParameterError):
        table.evaluate(1.5)
    with pytest.raises(InvalidParameterError):
        table.inverse_cdf(0.5, 1)
    with pytest.raises(FileFormatError):
        PhaseTable.from_dict({"kind": "phase_table", "angles": [0, 1]})
    assert PhaseTable.from_dict(table.to_dict()) == table and hash(PhaseTable.from_dict(table.to_dict())) == hash(table)


# ------------------------------------------------------------------ particle components in the medium


def test_default_aerosol_component_gives_the_same_coefficients_bit_for_bit():
    p = AtmosphereParameters.from_aerosol_optical_depth(0.2, 1.3)
    comp = p.aerosol_component
    assert isinstance(comp, AnalyticParticles) and comp.analytic_phase == ("cornette-shanks", 0.8)
    assert p.particle_components == (comp,)
    wl = np.linspace(380.0, 780.0, 41)
    column = p.mie_density.column(p.thickness)
    legacy = p.mie_angstrom_beta * (wl / 1000.0) ** (-p.mie_angstrom_alpha) / column  # the formula before
    assert np.array_equal(comp.extinction_at(wl), legacy) and np.array_equal(p.mie_extinction_at(wl), legacy)
    assert np.array_equal(comp.scattering_at(wl), legacy * 0.9)
    assert abs(comp.optical_depth([550.0], p.thickness)[0] - 0.2) < 1e-12
    assert "aerosol" not in p.to_dict() and "particles" not in p.to_dict()
    table = p.aerosol_phase_table([550.0])
    assert abs(table.asymmetry[0] - 3 * 0.8 * 4.64 / (5 * 2.64)) < 2e-5
    np.testing.assert_allclose(p.aerosol_phase(0.3), phase_module.cornette_shanks(0.3, 0.8))


def _tabulated(name="mie", bottom=0.0, top=2000.0):
    wl = (400.0, 700.0)
    return TabulatedParticles(name, DensityProfile.box(bottom, top), TabulatedSpectrum(wl, (1e-4, 5e-5), "ext"),
                              TabulatedSpectrum(wl, (0.95, 0.9), "ssa"),
                              PhaseTable.henyey_greenstein([0.7, 0.6], wl))


def test_a_tabulated_aerosol_replaces_the_default_everywhere():
    comp = _tabulated()
    p = AtmosphereParameters(aerosol=comp)
    assert p.aerosol_component is comp and comp.analytic_phase is None
    np.testing.assert_allclose(p.mie_extinction_at([400.0, 550.0]), [1e-4, 7.5e-5])
    np.testing.assert_allclose(comp.optical_depth([400.0], p.thickness), [0.2], rtol=1e-12)  # box column exact
    _, aer = p.scattering_coefficients([1000.0, 3000.0], [400.0])
    np.testing.assert_allclose(aer[:, 0], [0.95e-4, 0.0])
    np.testing.assert_allclose(p.absorption_coefficient([1000.0], [400.0])[0, 0], 0.05e-4 + p.ozone_absorption_at(
        [400.0])[0] * p.ozone_density(np.array([1000.0])), rtol=1e-12)
    assert abs(p.aerosol_phase_table([550.0]).asymmetry[0] - 0.65) < 3e-5
    assert p.aerosol_phase([0.2, 0.5], [400.0, 700.0]).shape == (2, 2)
    with pytest.raises(InvalidParameterError, match="wavelength"):
        p.aerosol_phase(0.5)
    assert p.sample_aerosol_phase(10, 1, 550.0).shape == (10,)
    back = AtmosphereParameters.from_dict(p.to_dict())
    assert back == p and back.canonical_json() == p.canonical_json()
    assert hash(back) == hash(p)


def test_further_particle_components_add_to_the_medium():
    cloud = _tabulated("cloud", 3000.0, 4000.0)
    p = AtmosphereParameters(particles=(cloud,))
    assert p.particle_components[1] is cloud
    _, with_cloud = p.scattering_coefficients([3500.0], [400.0])
    _, without = AtmosphereParameters().scattering_coefficients([3500.0], [400.0])
    np.testing.assert_allclose(with_cloud - without, [[0.95e-4]])
    assert AtmosphereParameters.from_dict(p.to_dict()) == p


def test_bad_components_are_refused():
    with pytest.raises(InvalidParameterError, match="ParticleComponent"):
        AtmosphereParameters(aerosol="maritime")
    with pytest.raises(InvalidParameterError):
        AtmosphereParameters(particles=(1,))
    for kwargs in (dict(single_scattering_albedo=1.2), dict(g=1.0), dict(phase_function="mie")):
        with pytest.raises(InvalidParameterError):
            AnalyticParticles("a", DensityProfile.exponential(1000.0), 1e-5, **kwargs)
    with pytest.raises(FileFormatError, match="kind"):
        particle_component_from_dict({"kind": "nonsense"})
    with pytest.raises(InvalidParameterError, match="particle components"):
        from skyscatter.precomputed import PrecomputedAtmosphere

        PrecomputedAtmosphere.compute(AtmosphereParameters(particles=(_tabulated(),)), wavelengths=[550.0])
    comp = AnalyticParticles("a", DensityProfile.boundary_layer(1500.0, 1000.0), PowerLawSpectrum(1e-5, 550.0, -1.0))
    assert particle_component_from_dict(comp.to_dict()) == comp
    assert abs(comp.density.column(60000.0) - 2500.0) < 1e-3


def test_from_cosines_is_the_table_of_its_numba_arrays():
    """:meth:`PhaseTable.from_cosines` of a table's :meth:`~PhaseTable.numba_arrays` (what a precomputed-table file
    stores) has the same arrays bit for bit, so the same moments and delta-M fraction (the lookups' sub-texels of a
    Mie aerosol's single scattering are computed from it); cosines that do not run from -1 to 1 are refused."""
    wl = [450.0, 650.0]
    table = PhaseTable.from_function(lambda m: 1.0 + 0.9 * m + 3.0 * np.exp(40.0 * (m - 1.0)), wl)
    arr = table.numba_arrays()
    back = PhaseTable.from_cosines(wl, arr.mu, arr.values)
    for a, b in zip(back.numba_arrays(), arr, strict=True):
        np.testing.assert_array_equal(a, b)
    t1, f1 = table.delta_m(32)
    t2, f2 = back.delta_m(32)
    np.testing.assert_array_equal(f1, f2)
    np.testing.assert_array_equal(t1.numba_arrays().values, t2.numba_arrays().values)
    with pytest.raises(InvalidParameterError, match="from exactly -1 to 1"):
        PhaseTable.from_cosines(wl, arr.mu[1:], arr.values[:, 1:])
