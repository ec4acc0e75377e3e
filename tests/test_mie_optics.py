"""Mie optics over size distributions (atmosphere.mie_optics), OPAC aerosol types (atmosphere.aerosol_types).

References not written by us:
* Wiscombe (1979), NCAR/TN-140+STR, doi:10.5065/D6ZP4414, MIEV0 test cases 7, 9, 10, 14, 16, 17, 18 (Q_sca, g to
  six decimals: compared to 1e-6), and Bohren & Huffman (1983), Appendix A (m = 1.55, x = 5.213: Q_ext = Q_sca =
  3.10543, Q_back = 2.92534, g = 0.63314; compared to 1e-5, the digits given);
* a second Mie code: OPAC's own optics of its components (Hess, Koepke & Schult 1998; tests/data/opac_*.csv,
  extracted by tools/extract_opac_tables.py) and its continental-polluted type at 80 % humidity (OPAC 3.1
  output: extinction 0.1746 km^-1, albedo 0.8925, g 0.6977 at 550 nm for the type's number densities);
* miepython's own single-sphere amplitudes S_1, S_2 (for the products over sizes).
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.atmosphere.aerosol_types import AEROSOL_TYPES, OPAC_COMPONENTS, OpacAerosol, opac_component
from skyscatter.atmosphere.mie_optics import _miepython, mie_optics, sphere_efficiencies, water_droplets
from skyscatter.atmosphere.particles import particle_component_from_dict
from skyscatter.atmosphere.refractive_index import RefractiveIndex, water_refractive_index
from skyscatter.atmosphere.size_distributions import LogNormalMode, ModifiedGammaMode
from skyscatter.errors import InvalidParameterError

DATA = Path(__file__).parent / "data"


def _rows(name):
    with open(DATA / name) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


# m = n + i k (k >= 0 absorbs), x, published Q_sca, g (Wiscombe 1979, MIEV0 test cases)
WISCOMBE = [(complex(0.75, 0.0), 10.0, 2.232265, 0.896473), (complex(1.33, 1e-5), 1.0, 0.093923, 0.184517),
            (complex(1.33, 1e-5), 100.0, 2.096594, 0.868959), (complex(1.5, 1.0), 1.0, 0.6634538, 0.192136),
            (complex(1.5, 1.0), 10000.0, 1.236575, 0.846309), (complex(10.0, 10.0), 1.0, 2.049405, -0.110664),
            (complex(10.0, 10.0), 100.0, 1.836785, 0.556215)]


@pytest.mark.parametrize(("m", "x", "qsca", "g"), WISCOMBE)
def test_single_spheres_match_wiscombe_1979(m, x, qsca, g):
    _, qs, _, gg = sphere_efficiencies(m, x)
    assert abs(qs - qsca) <= 1e-6 and abs(gg - g) <= 1e-6


def test_single_sphere_matches_bohren_huffman_appendix():
    qe, qs, qb, g = sphere_efficiencies(1.55, 2 * math.pi * 0.525 / 0.6328)
    assert max(abs(qe - 3.10543), abs(qs - 3.10543), abs(qb - 2.92534), abs(g - 0.63314)) < 1e-5


def test_a_narrow_mode_gives_the_single_sphere_amplitudes():
    # our products of miepython's a_n, b_n with pi_n, tau_n over a block of sizes == miepython's S_1, S_2
    mp = _miepython()
    r, lam, m = 2.0e-6, 550.0, complex(1.45, 0.002)
    mode = LogNormalMode(r, 1.0 + 1e-7)
    out = mie_optics(mode, RefractiveIndex.constant(m), [lam], nodes_per_e=4)
    x = 2 * math.pi * r / (lam * 1e-9)
    mu = np.cos(out.phase.angles)
    s1, s2 = mp.S1_S2(m.conjugate(), x, mu, norm="wiscombe")
    qe, qs, _, g = mp.efficiencies_mx(m.conjugate(), x)
    ref = (np.abs(s1) ** 2 + np.abs(s2) ** 2) / (2 * math.pi * x * x * qs)
    np.testing.assert_allclose(out.phase.values[0], ref / out.angular_closure[0], rtol=1e-7)
    assert abs(out.extinction_cross_section[0] / (math.pi * r * r) - qe) < 1e-6 * qe
    assert abs(out.asymmetry_mie[0] - g) < 1e-9 and abs(out.phase.asymmetry[0] - g) < 2e-4


@pytest.fixture(scope="module")
def opac_rows():
    return _rows("opac_optics.csv")


@pytest.mark.parametrize("code", OPAC_COMPONENTS)
def test_component_optics_match_opac(code, opac_rows):
    # the second Mie code: OPAC's extinction per particle and albedo at 400, 550 and 800 nm, dry and at 80 % RH
    cid = OPAC_COMPONENTS.index(code) + 1
    for rh in (0, 80):
        sel = [r for r in opac_rows if int(r["component_id"]) == cid and int(r["rh_percent"]) == rh
               and float(r["wavelength_nm"]) in (400.0, 550.0, 800.0)]
        if not sel:
            continue
        mode, index = opac_component(code, rh)
        out = mie_optics(mode, index, [float(r["wavelength_nm"]) for r in sel])
        ext = np.array([float(r["ext_per_km"]) for r in sel]) * 1e-9  # 1/km per particle/cm^3 -> m^2
        np.testing.assert_allclose(out.extinction_cross_section, ext, rtol=7e-3)
        np.testing.assert_allclose(out.single_scattering_albedo, [float(r["ssa"]) for r in sel], atol=1e-3)
        assert np.all(np.abs(out.angular_closure - 1) < 1e-3)  # the grid resolves the forward peak
        np.testing.assert_allclose(out.phase.asymmetry, out.asymmetry_mie, atol=1e-4)


def test_phase_functions_match_opac_tables_where_converged():
    # OPAC's tabulated phase functions at 550 nm: fine-mode components to 2.5 %, the forward peak of every
    # component to 2 %, g to 0.002 of the g of OPAC's own table (OPAC's listed g of its coarse components is
    # 0.004-0.007 above the g of its table; see docs/aerosols.md)
    rows = _rows("opac_phase_550nm.csv")
    theta = np.radians([float(r["angle_deg"]) for r in rows])
    optics = {(int(r["component_id"]), int(r["rh_percent"])): float(r["sca_per_km"])
              for r in _rows("opac_optics.csv") if float(r["wavelength_nm"]) == 550.0}
    for name in ("waso00", "waso80", "soot00", "suso00", "minm00", "inso00", "micm00", "sscm80"):
        code, rh = name[:4], int(name[4:])
        p_opac = np.array([float(r[name]) for r in rows]) / optics[(OPAC_COMPONENTS.index(code) + 1, rh)]
        mode, index = opac_component(code, rh)
        p = mie_optics(mode, index, [550.0]).phase.evaluate(np.cos(theta), 0)
        assert abs(p[0] / p_opac[0] - 1) < 0.02
        if code in ("waso", "soot", "suso", "minm"):
            assert np.max(np.abs(p / p_opac - 1)) < 0.025
        g_opac = np.trapezoid(p_opac * np.cos(theta) * np.sin(theta), theta) / np.trapezoid(p_opac * np.sin(theta),
                                                                                              theta)
        g_ours = np.trapezoid(p * np.cos(theta) * np.sin(theta), theta) / np.trapezoid(p * np.sin(theta), theta)
        assert abs(g_ours - g_opac) < 2e-3


def test_continental_polluted_type_matches_opac():
    a = OpacAerosol.preset("continental-polluted", relative_humidity=80.0)
    assert abs(a.extinction_at([550.0])[0] * 1e3 / 0.1746 - 1) < 5e-3
    assert abs(a.single_scattering_albedo_at([550.0])[0] - 0.8925) < 1e-3
    assert abs(a.phase_table([550.0]).asymmetry[0] - 0.6977) < 2e-3


def test_size_quadrature_converges():
    mode, index = opac_component("inso", 0.0)
    a = mie_optics(mode, index, [450.0, 650.0], nodes_per_e=24)
    b = mie_optics(mode, index, [450.0, 650.0], nodes_per_e=48)
    np.testing.assert_allclose(a.extinction_cross_section, b.extinction_cross_section, rtol=2e-3)
    np.testing.assert_allclose(a.phase.asymmetry, b.phase.asymmetry, atol=1e-3)  # measured 8e-4


def test_water_droplets():
    wl = [450.0, 650.0]
    mode = ModifiedGammaMode.from_effective(10e-6, 0.1)
    assert abs(mode.effective_radius / 10e-6 - 1) < 1e-4  # Hansen & Travis (1974), Eq. 2.53
    out = water_droplets(10e-6, 0.1, wl)
    assert np.all(np.abs(out.angular_closure - 1) < 1e-3)
    assert np.all(out.single_scattering_albedo > 0.9999)  # water barely absorbs in the visible
    # extinction efficiency of large spheres approaches 2 from above (van de Hulst 1957, Sec. 8.22)
    q = out.extinction_cross_section / (math.pi * mode.moment(2.0))
    assert np.all((q > 2.0) & (q < 2.15))
    # the diffraction peak is resolved: p falls by 10x within about 2 deg of the forward direction
    p = out.phase.evaluate(np.cos(np.radians([0.0, 2.0])), 0)
    assert p[0] > 10 * p[1] and 0.85 < out.phase.asymmetry[0] < 0.88
    n = water_refractive_index()(np.array([300.0, 550.0, 1000.0]))
    np.testing.assert_allclose(n, [1.349 + 1.6e-8j, 1.333 + 1.96e-9j, 1.327 + 2.89e-6j])  # Hale & Querry (1973)


def test_water_droplets_size_quadrature_resolves_the_phase_ripple():
    """The droplets' phase function at 20-60 deg from a quadrature fine enough in size parameter: the default
    (a step of 0.5 in x at r_e) within 2 % of one four times finer (measured 0.9 % at 650 nm, r_e 10 um, v_eff 0.1),
    where the former 24 nodes per e (a step of 4 in x) were 13 % off: the aliased ripple that put a 7 % error
    into the cloudy sky's radiance at 650 nm (docs/clouds.md, "Radiance under clouds")."""
    cos = np.cos(np.radians(np.arange(20.0, 60.1, 1.0)))
    fine = water_droplets(10e-6, 0.1, [650.0], nodes_per_e=4 * 2 * 97)
    rel = np.ravel(water_droplets(10e-6, 0.1, [650.0]).phase.evaluate(cos)) / np.ravel(fine.phase.evaluate(cos)) - 1
    assert np.max(np.abs(rel)) < 0.02, np.max(np.abs(rel))


def test_presets_in_the_atmosphere():
    p = AtmosphereParameters.with_aerosol_type("maritime-clean", 0.12, relative_humidity=80.0)
    assert abs(p.aerosol_component.optical_depth([550.0], p.thickness)[0] - 0.12) < 1e-9
    back = AtmosphereParameters.from_dict(p.to_dict())
    assert back == p and back.to_dict()["aerosol"]["name"] == "maritime-clean"
    assert isinstance(particle_component_from_dict(p.to_dict()["aerosol"]), OpacAerosol)
    assert set(AEROSOL_TYPES) >= {"continental-clean", "continental-average", "continental-polluted", "urban",
                                  "maritime-clean", "desert"}


def test_bad_particle_inputs_are_refused():
    """One specific error each, saying what was wrong and what is allowed."""
    for m, message in ((complex(1.5, -0.01), "imaginary part k must be >= 0"), (complex(-1.0, 0.0), "n must be > 0")):
        with pytest.raises(InvalidParameterError, match=message):
            RefractiveIndex.constant(m)
    for args, message in (((0.0, 2.0), "median radius must be > 0"), ((-1e-6, 2.0), "median radius must be > 0"),
                          ((1e-6, 1.0), "sigma .* must be > 1"), ((1e-6, 0.5), "sigma .* must be > 1"),
                          ((1e-6, float("nan")), "sigma .* must be > 1")):
        with pytest.raises(InvalidParameterError, match=message):
            LogNormalMode(*args)
    with pytest.raises(InvalidParameterError, match="radius limits need 0 <= r_min < r_max"):
        LogNormalMode(1e-6, 2.0, r_min=1e-5, r_max=1e-6)
    variance = r"effective variance .*\(0, 1/3\)"
    for args, message in (((0.0, 0.1), "effective radius must be > 0"), ((10e-6, 0.0), variance),
                          ((10e-6, 0.5), variance)):
        with pytest.raises(InvalidParameterError, match=message):
            ModifiedGammaMode.from_effective(*args)
    with pytest.raises(InvalidParameterError, match="aerosol_optical_depth -0.1 is outside 0 to 10"):
        AtmosphereParameters.from_aerosol_optical_depth(-0.1, 1.3)
    with pytest.raises(InvalidParameterError, match="humidity"):
        OpacAerosol.preset("urban", relative_humidity=100.0)
    with pytest.raises(InvalidParameterError, match="optical depth"):
        OpacAerosol.preset("urban", -0.1)
    with pytest.raises(InvalidParameterError, match="aerosol type"):
        OpacAerosol.preset("volcanic")
    with pytest.raises(InvalidParameterError, match="tabulated"):
        mie_optics(LogNormalMode(1e-7, 2.0), water_refractive_index(), [1500.0])
    with pytest.raises(InvalidParameterError):
        sphere_efficiencies(1.5, 0.0)


def test_mixture_of_members_adds_their_optical_depths():
    """OpacAerosol.mixture: one type alone is that type's preset (optical depth, albedo at 3 wavelengths); two
    members' optical depths add at every wavelength (external mixture, Hess et al. 1998 Eq. 1) and each keeps
    its own spectral shape; the 550 nm optical depths are the ones asked for."""
    wl = [440.0, 550.0, 870.0]
    one = OpacAerosol.mixture([("continental-average", 0.2)])
    ref = OpacAerosol.preset("continental-average", 0.2)
    np.testing.assert_allclose(one.optical_depth(wl, 60e3), ref.optical_depth(wl, 60e3), rtol=1e-12)
    np.testing.assert_allclose(one.single_scattering_albedo_at(wl), ref.single_scattering_albedo_at(wl), rtol=1e-12)
    fine = OpacAerosol.mixture([("waso", 0.15)], density=one.density)
    coarse = OpacAerosol.mixture([("sscm", 0.1)], density=one.density)
    both = OpacAerosol.mixture([("waso", 0.15), ("sscm", 0.1)], density=one.density)
    np.testing.assert_allclose(both.optical_depth(wl, 60e3), fine.optical_depth(wl, 60e3) +
                               coarse.optical_depth(wl, 60e3), rtol=1e-12)
    np.testing.assert_allclose(both.optical_depth([550.0], 60e3), [0.25], rtol=1e-12)
    assert both.name == "waso+sscm" and dict(both.components).keys() == {"waso", "sscm"}
    with pytest.raises(InvalidParameterError, match="unknown mixture member"):
        OpacAerosol.mixture([("waso", 0.1), ("dust", 0.1)])
    with pytest.raises(InvalidParameterError, match="optical depth of waso"):
        OpacAerosol.mixture([("waso", -0.1)])
