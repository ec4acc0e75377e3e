"""Self-checks of the brute-force reference (tests/precomputed_reference.py) against closed forms."""

import numpy as np

from precomputed_reference import optical_depth, ray_end
from skyscatter.precomputed import AtmosphereParameters

# ------------------------------------------------------------------------------------------ self-checks


def test_reference_vertical_optical_depth_of_exponential_layer():
    """Closed form H (1 - exp(-(R_t - R_g) / H)) for the Rayleigh layer alone, to 1e-9 relative."""
    p = AtmosphereParameters(mie_angstrom_beta=0.0, ozone_column=0.0)
    wl = np.array([550.0])
    tau = optical_depth(np.array(p.bottom_radius), np.array(1.0), np.array(p.thickness), p, wl)
    expected = p.rayleigh_scattering_at(wl) * 8000.0 * (1 - np.exp(-p.thickness / 8000.0))
    np.testing.assert_allclose(tau, expected, rtol=1e-9)


def test_reference_ray_end():
    p = AtmosphereParameters()
    d, hits = ray_end(p.bottom_radius + 1000.0, -1.0, p)
    assert hits and abs(d - 1000.0) < 1e-6
    d, hits = ray_end(p.bottom_radius, 0.0, p)
    assert not hits and abs(d - np.sqrt(p.top_radius**2 - p.bottom_radius**2)) < 1e-6
