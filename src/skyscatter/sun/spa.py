"""The NREL Solar Position Algorithm (SPA) in numpy: topocentric sun zenith and azimuth for many times at once.

[RedaAndreas2004] (report NREL/TP-560-34302, revised 2008, whose step numbers and equation numbers are
cited below); about 0.0003 deg uncertainty over the years -2000..6000. It follows [Meeus1998]: the Earth's
heliocentric position from the abridged VSOP87 periodic terms (Table A4.2), nutation from Table A4.3, then the sun's
geocentric and topocentric coordinates.

The periodic terms ship as ``skyscatter/data/nrel_spa_terms.csv`` (generated from pvlib's copy of the tables by
``tools/generate_spa_tables.py``, checked equal in the tests). The algorithm is written here from the report's
equations so that the sun position needs neither pvlib nor pandas (importing pvlib costs about 0.7 s, more than
a whole sky matrix: docs/architecture.md, "Start-up"); tests/test_sun_position.py checks it against the report's
worked example and against pvlib's implementation (``pvlib.spa.solar_position``) to 1e-8 deg.

Delta T (TT - UT1) defaults to the polynomial expressions of [EspenakMeeus2006] Sec. 2.6 (published on the NASA eclipse
web site, "Polynomial Expressions for Delta T"), the same rule pvlib's ``calculate_deltat`` uses.
"""

from __future__ import annotations

from functools import cache
from importlib import resources

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["EARTH_RADIUS_SPA", "delta_t_espenak_meeus", "spa_solar_position"]

#: Earth's equatorial radius [m] of the SPA's parallax terms (step 3.12.4-3.12.5).
EARTH_RADIUS_SPA = 6378140.0
_EARTH_TABLES = ("L0", "L1", "L2", "L3", "L4", "L5", "B0", "B1", "R0", "R1", "R2", "R3", "R4")
#: Apparent angular radius of the sun [deg] (NREL's spa.c): refraction is applied while e0 >= -(this + refraction).
_SUN_RADIUS_DEG = 0.26667


@cache
def _terms() -> tuple[dict[str, tuple[NDArray[np.float64], ...]], NDArray[np.float64], NDArray[np.float64]]:
    """The tables from package data: Earth terms ``name -> (2 A, B / 2, C / 2, sum A)`` (the form
    :func:`_series` evaluates), nutation multiples Y (63, 5) and coefficients a, b, c, d (63, 4)."""
    text = resources.files("skyscatter").joinpath("data/nrel_spa_terms.csv").read_text(encoding="utf-8")
    rows: dict[str, list[list[float]]] = {}
    for line in text.splitlines():
        if not line or line.startswith("#") or line.startswith("table,"):
            continue
        name, *values = line.split(",")
        rows.setdefault(name, []).append([float(v) for v in values])
    earth = {}
    for name in _EARTH_TABLES:
        t = np.array(rows[name])
        earth[name] = (2.0 * t[:, 0:1], 0.5 * t[:, 1:2], 0.5 * t[:, 2:3], float(t[:, 0].sum()))
    nutation = np.array(rows["Y"])
    return earth, nutation[:, :5], nutation[:, 5:]


def _cos_sin(x: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """cos x and sin x from ``t = tan(x / 2)``: ``((1 - t^2) / (1 + t^2), 2 t / (1 + t^2))``.

    numpy's float64 tan is vectorised (about 2 ns a value here) while its cos and sin call the C library one value
    at a time (13-25 ns); the SPA needs about 250 of them per instant. Within 2.3e-16 of the C library's cos
    and sin for arguments up to 5e4 rad (checked in the tests); at x = pi, t is about 1.6e16 and the formulas
    give -1 and 1.2e-16.
    """
    t = np.tan(0.5 * x)
    t2 = t * t
    d = 1.0 / (1.0 + t2)
    return (1.0 - t2) * d, 2.0 * t * d


def _series(prefix: str, count: int, jme: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(X0 + X1 JME + ... + X_{n-1} JME^{n-1}) / 1e8`` with ``X_i = sum A cos(B + C JME)`` (Eqs. 9-11).

    Each cosine as in :func:`_cos_sin`: ``A cos x = 2 A / (1 + tan^2(x / 2)) - A``, summed over the table.
    """
    earth = _terms()[0]
    total = np.zeros_like(jme)
    work = np.empty((64, jme.size))
    for i in reversed(range(count)):
        two_a, half_b, half_c, sum_a = earth[f"{prefix}{i}"]
        w = work[: two_a.shape[0]]
        np.multiply(half_c, jme, out=w)
        w += half_b
        np.tan(w, out=w)
        np.multiply(w, w, out=w)
        w += 1.0
        np.divide(two_a, w, out=w)
        total = total * jme + (w.sum(axis=0) - sum_a)
    return total / 1e8


def delta_t_espenak_meeus(year: ArrayLike, month: ArrayLike) -> NDArray[np.float64]:
    """Delta T = TT - UT1 [s] from Espenak & Meeus (2006)'s polynomials, for a calendar year and month (1-12).

    ``y = year + (month - 0.5) / 12``; the segment is chosen by the whole year. Before -500 and from 2150 on, the
    long-term parabola ``-20 + 32 ((y - 1820) / 100)^2``; 2050-2150 that parabola minus ``0.5628 (2150 - y)``.
    Outside -1999..3000 the values are extrapolations.
    """
    yr = np.asarray(year, dtype=float)
    y = yr + (np.asarray(month, dtype=float) - 0.5) / 12.0
    u = (y - 1820.0) / 100.0
    out = -20.0 + 32.0 * u * u  # before -500 and from 2150
    out = np.where((yr >= 2050) & (yr < 2150), out - 0.5628 * (2150.0 - y), out)
    for low, high, origin, scale, coefficients in _DELTA_T_SEGMENTS:
        t = (y - origin) / scale
        value = np.zeros_like(t)
        for c in reversed(coefficients):
            value = value * t + c
        out = np.where((yr >= low) & (yr < high), value, out)
    return out


# (first year, year after the last, origin, scale, coefficients of t^0, t^1, ...) with t = (y - origin) / scale
_DELTA_T_SEGMENTS = (
    (-500, 500, 0.0, 100.0,
     (10583.6, -1014.41, 33.78311, -5.952053, -0.1798452, 0.022174192, 0.0090316521)),
    (500, 1600, 1000.0, 100.0,
     (1574.2, -556.01, 71.23472, 0.319781, -0.8503463, -0.005050998, 0.0083572073)),
    (1600, 1700, 1600.0, 1.0, (120.0, -0.9808, -0.01532, 1.0 / 7129.0)),
    (1700, 1800, 1700.0, 1.0, (8.83, 0.1603, -0.0059285, 0.00013336, -1.0 / 1174000.0)),
    (1800, 1860, 1800.0, 1.0,
     (13.72, -0.332447, 0.0068612, 0.0041116, -0.00037436, 0.0000121272, -0.0000001699, 0.000000000875)),
    (1860, 1900, 1860.0, 1.0, (7.62, 0.5737, -0.251754, 0.01680668, -0.0004473624, 1.0 / 233174.0)),
    (1900, 1920, 1900.0, 1.0, (-2.79, 1.494119, -0.0598939, 0.0061966, -0.000197)),
    (1920, 1941, 1920.0, 1.0, (21.20, 0.84493, -0.076100, 0.0020936)),
    (1941, 1961, 1950.0, 1.0, (29.07, 0.407, -1.0 / 233.0, 1.0 / 2547.0)),
    (1961, 1986, 1975.0, 1.0, (45.45, 1.067, -1.0 / 260.0, -1.0 / 718.0)),
    (1986, 2005, 2000.0, 1.0, (63.86, 0.3345, -0.060374, 0.0017275, 0.000651814, 0.00002373599)),
    (2005, 2050, 2000.0, 1.0, (62.92, 0.32217, 0.005589)),
)


def spa_solar_position(
    unix_seconds: ArrayLike,
    latitude: float,
    longitude: float,
    *,
    elevation: float = 0.0,
    pressure: float = 1013.25,
    temperature: float = 12.0,
    delta_t: ArrayLike = 67.0,
    refraction: float = 0.5667,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Topocentric sun position by the NREL SPA (steps 3.1-3.15 of the report).

    Parameters
    ----------
    unix_seconds : array_like
        UTC instants as seconds since 1970-01-01T00:00Z (UT1 taken equal to UTC, as the report allows to 0.9 s).
    latitude, longitude : float
        Site latitude (north positive) and longitude (east positive) [deg].
    elevation : float
        Site height above sea level [m].
    pressure : float
        Mean annual local pressure [hPa = mbar], for the refraction correction.
    temperature : float
        Mean annual local temperature [deg C], for the refraction correction.
    delta_t : array_like
        TT - UT1 [s] (broadcast against the times); see :func:`delta_t_espenak_meeus`.
    refraction : float
        Atmospheric refraction at sunrise and sunset [deg] (0.5667, the report's value).

    Returns
    -------
    apparent_zenith, zenith, azimuth : ndarray
        Topocentric zenith angle with and without the refraction correction, and the topocentric azimuth from
        north towards east, [deg], shaped like ``unix_seconds``.
    """
    unix = np.asarray(unix_seconds, dtype=float)
    shape = unix.shape
    flat = unix.reshape(-1)
    dt_flat = np.broadcast_to(np.asarray(delta_t, dtype=float), shape).reshape(-1)
    out = np.empty((3, flat.size))
    for start in range(0, flat.size, _CHUNK):
        sl = slice(start, start + _CHUNK)
        out[:, sl] = _spa(flat[sl], dt_flat[sl], float(latitude), float(longitude), float(elevation),
                          float(pressure), float(temperature), float(refraction))
    return out[0].reshape(shape), out[1].reshape(shape), out[2].reshape(shape)


#: Instants per vectorised step (the (terms x instants) temporaries stay in the CPU caches).
_CHUNK = 1024


def _spa(unix, delta_t, latitude, longitude, elevation, pressure, temperature, refraction):
    """Steps 3.1-3.15 for a 1-D block of instants; returns (apparent zenith, zenith, azimuth) [deg]."""
    _, nut_y, nut_abcd = _terms()
    jd = unix / 86400.0 + 2440587.5  # 3.1.1, Eq. 4 for Unix time
    jde = jd + delta_t / 86400.0  # Eq. 5
    jc = (jd - 2451545.0) / 36525.0  # Eq. 6
    jce = (jde - 2451545.0) / 36525.0  # Eq. 7
    jme = jce / 10.0  # Eq. 8
    # 3.2 Earth heliocentric longitude, latitude [deg] and radius vector [AU] (Eqs. 9-14)
    big_l = np.mod(np.degrees(_series("L", 6, jme)), 360.0)
    big_b = np.degrees(_series("B", 2, jme))
    big_r = _series("R", 5, jme)
    # 3.3 geocentric longitude and latitude (Eqs. 13-14)
    theta = np.mod(big_l + 180.0, 360.0)
    beta = -big_b
    # 3.4 nutation in longitude and obliquity (Eqs. 15-23) [deg]
    x = np.stack([
        297.85036 + 445267.111480 * jce - 0.0019142 * jce**2 + jce**3 / 189474.0,  # Eq. 15, moon elongation
        357.52772 + 35999.050340 * jce - 0.0001603 * jce**2 - jce**3 / 300000.0,  # Eq. 16, sun mean anomaly
        134.96298 + 477198.867398 * jce + 0.0086972 * jce**2 + jce**3 / 56250.0,  # Eq. 17, moon mean anomaly
        93.27191 + 483202.017538 * jce - 0.0036825 * jce**2 + jce**3 / 327270.0,  # Eq. 18, moon latitude arg.
        125.04452 - 1934.136261 * jce + 0.0020708 * jce**2 + jce**3 / 450000.0,  # Eq. 19, moon ascending node
    ], axis=-1)
    arg = np.radians(x @ nut_y.T)  # (n, 63)
    a, b, c, d = (nut_abcd[:, k] for k in range(4))
    jce_col = jce[:, None]
    cos_arg, sin_arg = _cos_sin(arg)
    delta_psi = ((a + b * jce_col) * sin_arg).sum(axis=-1) / 36000000.0  # Eqs. 20, 22
    delta_eps = ((c + d * jce_col) * cos_arg).sum(axis=-1) / 36000000.0  # Eqs. 21, 23
    # 3.5 true obliquity of the ecliptic (Eqs. 24-25)
    u = jme / 10.0
    eps0 = 84381.448 + u * (-4680.93 + u * (-1.55 + u * (1999.25 + u * (-51.38 + u * (-249.67 + u * (
        -39.05 + u * (7.12 + u * (27.87 + u * (5.79 + u * 2.45)))))))))
    eps = np.radians(eps0 / 3600.0 + delta_eps)
    # 3.6-3.7 aberration and apparent sun longitude (Eqs. 26-27)
    lam = np.radians(theta + delta_psi - 20.4898 / (3600.0 * big_r))
    # 3.8 apparent sidereal time at Greenwich (Eqs. 28-30) [deg]
    nu0 = np.mod(280.46061837 + 360.98564736629 * (jd - 2451545.0) + 0.000387933 * jc**2 - jc**3 / 38710000.0,
                 360.0)
    nu = nu0 + delta_psi * np.cos(eps)
    # 3.9-3.10 geocentric right ascension and declination (Eqs. 31-32)
    beta_r = np.radians(beta)
    alpha = np.mod(np.degrees(np.arctan2(np.sin(lam) * np.cos(eps) - np.tan(beta_r) * np.sin(eps), np.cos(lam))),
                   360.0)
    delta = np.arcsin(np.sin(beta_r) * np.cos(eps) + np.cos(beta_r) * np.sin(eps) * np.sin(lam))
    # 3.11 observer local hour angle (Eq. 33)
    h = np.radians(np.mod(nu + longitude - alpha, 360.0))
    # 3.12 topocentric right ascension and declination (Eqs. 34-41)
    phi = np.radians(latitude)
    xi = np.radians(8.794 / (3600.0 * big_r))
    uu = np.arctan(0.99664719 * np.tan(phi))
    xx = np.cos(uu) + elevation / EARTH_RADIUS_SPA * np.cos(phi)
    yy = 0.99664719 * np.sin(uu) + elevation / EARTH_RADIUS_SPA * np.sin(phi)
    denominator = np.cos(delta) - xx * np.sin(xi) * np.cos(h)
    delta_alpha = np.arctan2(-xx * np.sin(xi) * np.sin(h), denominator)
    delta_prime = np.arctan2((np.sin(delta) - yy * np.sin(xi)) * np.cos(delta_alpha), denominator)
    # 3.13 topocentric local hour angle (Eq. 42)
    h_prime = h - delta_alpha
    # 3.14 topocentric zenith angle (Eqs. 43-47)
    e0 = np.degrees(np.arcsin(np.sin(phi) * np.sin(delta_prime) + np.cos(phi) * np.cos(delta_prime) * np.cos(h_prime)))
    with np.errstate(divide="ignore", invalid="ignore"):
        delta_e = (pressure / 1010.0) * (283.0 / (273.0 + temperature)) * 1.02 / (
            60.0 * np.tan(np.radians(e0 + 10.3 / (e0 + 5.11))))
    delta_e = np.where(e0 >= -(_SUN_RADIUS_DEG + refraction), delta_e, 0.0)  # NREL spa.c: only near/above horizon
    # 3.15 topocentric azimuth (Eqs. 48-49), from north towards east
    gamma = np.degrees(np.arctan2(np.sin(h_prime), np.cos(h_prime) * np.sin(phi) - np.tan(delta_prime) * np.cos(phi)))
    azimuth = np.mod(gamma + 180.0, 360.0)
    return 90.0 - (e0 + delta_e), 90.0 - e0, azimuth
