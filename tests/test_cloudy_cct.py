"""The cloudy sky's correlated colour temperature (CCT) of the diffuse light on the ground against the Monte Carlo
(issue 22 item 5: within 200 K; docs/clouds.md, "Accuracy against the Monte Carlo").

Reference (not the model's code): the Monte Carlo's diffuse irradiance at 450 / 550 / 650 nm under the water
cloud 1000-1500 m (r_e 10 um), Earth air, ground albedo 0.2, pooled over its independent stored runs
(``tests/cloudy_cct_reference.py``: tests/data/cloudy_montecarlo.json, cloudy_sun30_forward.json and
cloudy_low_sun.json, written by benchmarks/cloudy_montecarlo_reference.py and cloudy_low_sun_reference.py with
their seeds and photon or path counts). Its CCT is that of the model's diffuse spectrum times the Monte Carlo /
model ratio interpolated between the three wavelengths (Hernandez 1999): the Monte Carlo fixes the spectrum's
colour at three wavelengths, the model only its shape between them. Its standard error ``sigma``: the three
ratios drawn within the Monte Carlo's standard errors. Printed by benchmarks/cloudy_cct.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from cloudy_cct_reference import FINE, MONTECARLO, WAVELENGTHS, monte_carlo_cct, reference
from skyscatter.sky.cloudy import CloudySky

pytest.importorskip("disortpp")

#: the target of docs/clouds.md [K]
TARGET_K = 200.0
#: cases with a Monte Carlo reference (sun 2 deg: optical depths 30 and 60 have 20000 backward paths only)
CASES = ([(tau, sun) for sun in (60.0, 30.0, 10.0) for tau in (1.0, 5.0, 15.0, 30.0, 60.0)]
         + [(1.0, 2.0), (5.0, 2.0), (15.0, 2.0)])


def _model(tau: float, sun: float) -> tuple[np.ndarray, np.ndarray]:
    sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau, cloud_base=MONTECARLO["cloud_base_m"],
                    cloud_top=MONTECARLO["cloud_top_m"], ground_albedo=MONTECARLO["ground_albedo"])
    return sky.diffuse_fluxes(FINE)[0], sky.diffuse_fluxes(WAVELENGTHS)[0]


@pytest.mark.parametrize("tau, sun", CASES)
def test_cct_of_the_diffuse_light_against_the_monte_carlo(tau, sun):
    """Within 200 K of the pooled Monte Carlo (docs/clouds.md; measured -150..+96 K, sigma 7-223 K). Against the
    stored single runs alone three cases missed (optical depth 60 at sun 30 and 10 deg by 295 and 235 K, 5 at
    sun 2 deg by 528 K): those runs' noise, as the runs added on 2026-12-04 show."""
    ref = reference(tau, sun)
    assert ref is not None
    mc, err, _, _ = ref
    spectrum, model = _model(tau, sun)
    t_model, t_mc, sigma = monte_carlo_cct(spectrum, model, mc, err)
    assert abs(t_model - t_mc) <= TARGET_K, (t_model, t_mc, sigma)


def test_cct_uncertainty_is_the_linear_propagation():
    """The sampled standard error of the CCT equals the first-order propagation of the three ratios' standard
    errors (finite differences of the same CCT), and a Monte Carlo equal to the model gives the model's CCT."""
    spectrum = np.interp(FINE, [380.0, 780.0], [1.2, 0.8])          # a bluish flat-ish spectrum [W m^-2 nm^-1]
    model = np.interp(WAVELENGTHS, FINE, spectrum)
    err = np.array([0.01, 0.02, 0.03]) * model
    t_model, t_same, sigma = monte_carlo_cct(spectrum, model, model, err, draws=20000)
    assert abs(t_same - t_model) < 1e-6 * t_model
    grads = []
    for k in range(3):
        bumped = model.copy()
        bumped[k] *= 1.0 + 1e-4
        grads.append((monte_carlo_cct(spectrum, model, bumped, err, draws=1)[1] - t_same) / (1e-4 * model[k]))
    linear = math.sqrt(sum((g * e) ** 2 for g, e in zip(grads, err, strict=True)))
    assert abs(sigma / linear - 1.0) < 0.05, (sigma, linear)
