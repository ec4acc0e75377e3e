"""Cross-check of skyscatter's Hosek-Wilkie sky against Mitsuba 3's ``sunsky`` emitter (an independent code).

What Mitsuba's ``sunsky`` (3.9) returns from ``Emitter.eval`` with ``si.wi = -d`` (emitter frame = world frame,
z up; ``sun_direction`` a world vector, so skyscatter's ENU vectors can be passed as they are):

* ``scalar_spectral``: the Hosek-Wilkie spectral sky in W m^-2 sr^-1 nm^-1, linear between the 11 bands,
  zero outside 320-720 nm, evaluated in float32 (``Float`` is ``float`` in the scalar variants). Unlike
  skyscatter it does not clip the reference's small negative values on the horizon at low sun.
* ``scalar_rgb``: the authors' RGB dataset times ``MI_CIE_Y_NORMALIZATION`` = 1 / 106.75026 (Mitsuba's
  integral of ybar), i.e. ``skyscatter rgb * MI_CIE_Y_NORMALIZATION``.
* the sun: ``sun_aperture`` defaults to 0.5358 deg (the real sun), not the reference's 0.51 deg. With
  ``complex_sun=True`` it is the 2013 solar function with the limb darkening stretched over that larger disc
  (equal to skyscatter's ``solar_radiance`` at the disc centre); with the default ``complex_sun=False`` it is a
  uniform disc of a tabulated irradiance divided by the 0.5358 deg disc's solid angle.

Tolerance: 1e-4 relative for the sky; the float32 rounding of Mitsuba gives at most ~1e-5 (measured), plus an
absolute 1e-8 W m^-2 sr^-1 nm^-1 for values that cancel to near zero on the horizon (float32 resolution of the
O(0.01-1) terms of the sum), and Mitsuba's negative values compared after clipping at 0.
"""

from __future__ import annotations

import numpy as np
import pytest

from skyscatter.conventions import direction_from_angles
from skyscatter.sky.hosek_wilkie import SOLAR_RADIUS, HosekWilkieSky

mi = pytest.importorskip("mitsuba")

CASES = [  # sun zenith [deg], turbidity, albedo
    (89.9, 1.0, 0.0),
    (88.0, 3.0, 0.5),
    (75.0, 10.0, 0.2),
    (60.0, 3.0, 0.1),
    (33.3, 6.5, 1.0),
    (2.0, 2.0, 0.0),
]
# Not exactly 720 nm: there Mitsuba 3.9 also evaluates band index 11, one past its table, with weight 0
# (``query_idx_high = query_idx_low + 1``); whatever it reads is usually finite, but once in a few runs it was not
# and 0 * inf gave NaN at 720 nm (seen in this test at the horizon; not reproducible on demand, so it depends on
# the memory after the table). 719.99 nm exercises the top band; 720 nm itself is checked against the C code.
WAVELENGTHS = np.array([320.0, 400.0, 555.0, 700.0, 360.0, 431.7, 640.0, 719.99])


def _directions(rng: np.random.Generator, sun_azimuth: float) -> np.ndarray:
    z = np.concatenate([[0.0, 1e-4, 1e-3, 1e-2, 1.0], rng.uniform(0, 1, 40)])
    azi = np.concatenate([np.full(5, sun_azimuth + 2.0), rng.uniform(0, 2 * np.pi, 40)])
    return direction_from_angles(np.arccos(z), azi)


def _eval(emitter, d: np.ndarray, wavelengths=None) -> np.ndarray:
    si = mi.SurfaceInteraction3f()
    si.wi = -mi.Vector3f(*d)
    if wavelengths is not None:
        si.wavelengths = mi.Spectrum(wavelengths)
    return np.array(emitter.eval(si), dtype=np.float64)


def _emitter(s: np.ndarray, t: float, a: float, **extra):
    return mi.load_dict({"type": "sunsky", "sun_direction": s.tolist(), "turbidity": t, "albedo": a, **extra})


@pytest.mark.parametrize("zen_deg,t,a", CASES)
def test_spectral_sky_matches_mitsuba(zen_deg, t, a):
    mi.set_variant("scalar_spectral")
    rng = np.random.default_rng(int(zen_deg * 10))
    zen, azi = np.radians(zen_deg), rng.uniform(0, 2 * np.pi)
    sky = HosekWilkieSky(zen, azi, turbidity=t, ground_albedo=a)
    em = _emitter(sky.sun_direction, t, a, sun_scale=0.0)
    dirs = _directions(rng, azi)
    ours = sky.spectral_radiance(dirs, WAVELENGTHS)
    theirs = np.array([np.concatenate([_eval(em, d, WAVELENGTHS[:4]), _eval(em, d, WAVELENGTHS[4:])]) for d in dirs])
    np.testing.assert_allclose(np.maximum(theirs, 0.0), ours, rtol=1e-4, atol=1e-8)


@pytest.mark.parametrize("zen_deg,t,a", CASES[::2])
def test_rgb_sky_matches_mitsuba(zen_deg, t, a):
    mi.set_variant("scalar_rgb")
    rng = np.random.default_rng(int(zen_deg * 10) + 1)
    zen, azi = np.radians(zen_deg), rng.uniform(0, 2 * np.pi)
    sky = HosekWilkieSky(zen, azi, turbidity=t, ground_albedo=a)
    em = _emitter(sky.sun_direction, t, a, sun_scale=0.0)
    dirs = _directions(rng, azi)
    theirs = np.array([_eval(em, d) for d in dirs]) / mi.MI_CIE_Y_NORMALIZATION
    np.testing.assert_allclose(theirs, sky.rgb(dirs), rtol=1e-4, atol=1e-6)


@pytest.mark.parametrize("zen_deg,t,a", CASES[1:5])
def test_solar_disc_centre_matches_mitsuba_complex_sun(zen_deg, t, a):
    """Disc centre agrees; off centre Mitsuba's limb darkening is our profile stretched to its 0.5358 deg disc."""
    mi.set_variant("scalar_spectral")
    zen, azi = np.radians(zen_deg), 0.4
    sky = HosekWilkieSky(zen, azi, turbidity=t, ground_albedo=a)
    em = _emitter(sky.sun_direction, t, a, sky_scale=0.0, complex_sun=True)
    wl = WAVELENGTHS[:4]
    np.testing.assert_allclose(_eval(em, sky.sun_direction, wl), sky.solar_radiance(sky.sun_direction, wl),
                               rtol=1e-4)
    r_mi = np.radians(0.5358) / 2
    s = sky.sun_direction
    side = np.cross([0.0, 0.0, 1.0], s)
    side /= np.linalg.norm(side)  # horizontal: moving along it keeps the view elevation (to second order)

    def off(angle: float) -> np.ndarray:
        return np.cos(angle) * s + np.sin(angle) * side

    # Off centre Mitsuba gets gamma (~4e-3 rad) in float32, a relative error ~3e-5 that the limb darkening
    # amplifies by 2 sin^2 / (1 - sin^2 / sin^2 r): ~5e-4 at 0.95 of the radius. Hence 1e-3 here.
    for frac in (0.5, 0.8, 0.95):
        ours = sky.solar_radiance(off(frac * SOLAR_RADIUS), wl)
        theirs = _eval(em, off(frac * r_mi), wl)
        np.testing.assert_allclose(theirs, ours, rtol=1e-3)
