"""Perez, Seals & Michalsky (1993) all-weather sky luminance model, with the Perez et al. (1990) sky parameters.

Relative luminance (Perez et al. 1993, Eq. 1; Preetham 2003 course notes, seed ``002``)::

    F(theta, gamma) = (1 + a exp(b / cos theta)) (1 + c exp(d gamma) + e cos^2 gamma)

with theta the zenith angle of the sky element and gamma its angle from the sun. Each coefficient
X in (a, b, c, d, e) is ``X1 + X2 Z + delta (X3 + X4 Z)`` (Eq. 6), Z the solar zenith angle [rad], with
X1-X4 from Table 1 for the sky-clearness bin of epsilon (``skyscatter/data/perez1993_coefficients.csv``);
in bin 1 (overcast, 1 <= epsilon < 1.065) c and d take the special forms (Eqs. 7-8)
``c = exp[(delta (c1 + c2 Z))^c3] - c4`` and ``d = -exp[delta (d1 + d2 Z)] + d3 + delta d4``.
The absolute luminance is ``L = D_v F / integral(F cos theta dOmega)`` (Eq. 3: the sky integrates to the
horizontal diffuse illuminance D_v).

Sky parameters from irradiance (Perez et al. 1990): clearness (Eq. 1)
``epsilon = ((D_h + I_n) / D_h + kappa Z^3) / (1 + kappa Z^3)``, kappa = 1.041, and brightness (Eq. 2)
``delta = D_h m / I_0``, with D_h the diffuse horizontal and I_n the direct normal irradiance [W m^-2], m the
relative optical air mass (Kasten 1966, :func:`skyscatter.atmosphere.airmass.relative_optical_mass`) and
I_0 the extraterrestrial normal irradiance (1367 W m^-2 times Spencer's 1971 eccentricity factor,
:func:`extraterrestrial_irradiance`). Illuminance from irradiance uses the luminous efficacy models of
Perez et al. 1990, Table 4 (``skyscatter/data/perez1990_luminous_efficacy.csv``), with the precipitable water
``W = exp(0.07 T_d - 0.075)`` [cm] from the surface dew point T_d [deg C] (Eq. 3).

Guards (on by default, ``guards=False`` turns them off; each is what Radiance's gendaylit/gendaymtx apply):

* epsilon cap: epsilon is clamped to [1, 11.9] (the fitted range; the last bin is open-ended in the paper);
* delta range: delta is clamped to [0.01, 0.6], the range of the data the model was fitted to;
* delta floor: for 1.065 < epsilon < 2.8 (bins 2-5) the coefficients use max(delta, 0.2); with a smaller
  delta those bins can give b > 0, and exp(b / cos theta) then diverges towards the horizon;
* sun altitude clamp: the model's solar zenith angle is kept >= 3 deg (altitude <= 87 deg) so the
  circumsolar peak does not sit on the zenith; the sun direction used for gamma moves with it;
* horizon: cos(theta) in exp(b / cos theta) is floored at 0.01 (Radiance's perezlum.cal), so the gradation
  stays finite for the few (epsilon, delta, Z) where b > 0;
* negative luminance: F < 0 (some coefficient sets, e.g. bin 4 with a large delta near the sun, or bins 6-8
  with b > 0 near the horizon) is set to 0; if that leaves no positive luminance at all, the sky is made
  uniform (gendaymtx's last resort), noted in ``guards_applied``.

Spectra: CIE D65 scaled to the luminance (``cct`` = 6504 K). Directions below the horizon are 0.

References: [Perez1993], [Perez1990].
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere.airmass import relative_optical_mass
from ..atmosphere.tables import load_table
from ..conventions import as_directions, check_daylight_limit, direction_from_angles
from ..errors import InvalidParameterError
from ..quadrature import plane_integral
from .base import LuminanceOnlySky, SunSkyMixin, check_sun_angles
from .cie import LuminanceSunMixin
from .perez_family import perez_f

__all__ = [
    "DEFAULT_DEW_POINT",
    "DELTA_FLOOR_BINS_2_5",
    "DELTA_RANGE",
    "EPSILON_BIN_EDGES",
    "EPSILON_CAP",
    "KAPPA",
    "MIN_SUN_ZENITH",
    "SOLAR_CONSTANT",
    "PerezSky",
    "PerezParameters",
    "PerezSkyCondition",
    "epsilon_bin",
    "extraterrestrial_irradiance",
    "luminous_efficacy",
    "perez_coefficients",
    "perez_parameters",
    "perez_relative_luminance",
    "perez_sky_condition",
    "precipitable_water",
    "sky_brightness",
    "sky_clearness",
]

#: kappa in the sky clearness formula (Perez et al. 1990, Eq. 1), for the solar zenith angle in radians.
KAPPA = 1.041
#: Solar constant [W m^-2] used for the extraterrestrial irradiance in delta (as in Radiance's gendaylit).
SOLAR_CONSTANT = 1367.0
#: Lower edges of the 8 sky clearness bins (Perez et al. 1990, Table 1; Perez et al. 1993, Table 1).
EPSILON_BIN_EDGES = (1.0, 1.065, 1.230, 1.500, 1.950, 2.800, 4.500, 6.200)
#: Largest sky clearness the guards let through (Radiance's gendaymtx).
EPSILON_CAP = 11.9
#: Sky brightness range the guards clamp to (Radiance's gendaymtx).
DELTA_RANGE = (0.01, 0.6)
#: Smallest delta used for the coefficients in bins 2-5 (1.065 < epsilon < 2.8) with guards on.
DELTA_FLOOR_BINS_2_5 = 0.2
#: Smallest solar zenith angle [rad] the model uses with guards on (sun altitude <= 87 deg).
MIN_SUN_ZENITH = float(np.radians(3.0))
#: Dew point [deg C] used when none is given: W = exp(0.07 * 11 - 0.075) = 2.0 cm (gendaylit's default W).
DEFAULT_DEW_POINT = 11.0
#: Sky condition when none is given: a clear sky of the clearest bin (epsilon > 6.2), typical brightness.
DEFAULT_EPSILON = 6.5
DEFAULT_DELTA = 0.15
_COEFFS = "abcde"


def _table(name: str) -> dict[str, NDArray[np.float64]]:
    return load_table(name)


def epsilon_bin(epsilon: ArrayLike) -> NDArray[np.int64]:
    """Sky clearness bin index 0-7 (bin 1-8 of the papers) for epsilon >= 1; values below 1 go to bin 0."""
    eps = np.asarray(epsilon, dtype=float)
    return np.clip(np.searchsorted(EPSILON_BIN_EDGES, eps, side="right") - 1, 0, 7)


def sky_clearness(
    direct_normal_irradiance: ArrayLike, diffuse_horizontal_irradiance: ArrayLike, sun_zenith: ArrayLike
) -> NDArray[np.float64]:
    """Perez sky clearness epsilon (Perez et al. 1990, Eq. 1).

    ``epsilon = ((D_h + I_n) / D_h + kappa Z^3) / (1 + kappa Z^3)``, kappa = 1.041.

    Parameters
    ----------
    direct_normal_irradiance : array_like
        I_n [W m^-2], >= 0.
    diffuse_horizontal_irradiance : array_like
        D_h [W m^-2], > 0.
    sun_zenith : array_like
        Solar zenith angle Z [rad].
    """
    i_n = np.asarray(direct_normal_irradiance, dtype=float)
    d_h = np.asarray(diffuse_horizontal_irradiance, dtype=float)
    z3 = KAPPA * np.asarray(sun_zenith, dtype=float) ** 3
    return ((d_h + i_n) / d_h + z3) / (1.0 + z3)


def extraterrestrial_irradiance(day_of_year: ArrayLike | None) -> NDArray[np.float64] | float:
    """Extraterrestrial normal irradiance I_0 [W m^-2]: 1367 W m^-2 times Spencer's (1971) eccentricity factor.

    ``E_0 = 1.000110 + 0.034221 cos G + 0.001280 sin G + 0.000719 cos 2G + 0.000077 sin 2G`` with the day angle
    ``G = 2 pi (day_of_year - 1) / 365`` ([Spencer1971]; [Iqbal1983] Eq. 1.2.1); equal to
    ``pvlib.irradiance.get_extra_radiation(method="spencer")`` in the tests. ``day_of_year`` is 1-366; None gives the
    mean Sun-Earth distance (I_0 = 1367 W m^-2).
    """
    if day_of_year is None:
        return SOLAR_CONSTANT
    doy = np.asarray(day_of_year, dtype=float)
    if np.any(~np.isfinite(doy)) or np.any(doy < 1) or np.any(doy > 366):
        raise InvalidParameterError(f"day_of_year must be within 1-366; got {day_of_year!r}")
    g = (2.0 * np.pi / 365.0) * (doy - 1.0)
    out = SOLAR_CONSTANT * (1.00011 + 0.034221 * np.cos(g) + 0.00128 * np.sin(g) + 0.000719 * np.cos(2.0 * g)
                            + 7.7e-05 * np.sin(2.0 * g))
    return float(out) if out.ndim == 0 else out


def sky_brightness(
    diffuse_horizontal_irradiance: ArrayLike, sun_zenith: ArrayLike, day_of_year: ArrayLike | None = None
) -> NDArray[np.float64]:
    """Perez sky brightness ``delta = D_h m / I_0`` (Perez et al. 1990, Eq. 2).

    Parameters
    ----------
    diffuse_horizontal_irradiance : array_like
        D_h [W m^-2].
    sun_zenith : array_like
        Solar zenith angle [rad], at most pi/2 (air mass: Kasten 1966).
    day_of_year : array_like, optional
        1-366 for the Sun-Earth distance; None for the mean distance.
    """
    m = relative_optical_mass(np.minimum(np.asarray(sun_zenith, dtype=float), np.pi / 2))
    return np.asarray(diffuse_horizontal_irradiance, dtype=float) * m / extraterrestrial_irradiance(day_of_year)


def precipitable_water(dew_point: ArrayLike) -> NDArray[np.float64]:
    """Atmospheric precipitable water ``W = exp(0.07 T_d - 0.075)`` [cm] (Perez et al. 1990, Eq. 3).

    Parameters
    ----------
    dew_point : array_like
        Surface dew point temperature T_d [deg C].
    """
    return np.exp(0.07 * np.asarray(dew_point, dtype=float) - 0.075)


def luminous_efficacy(
    kind: str, epsilon: ArrayLike, delta: ArrayLike, sun_zenith: ArrayLike, water: ArrayLike
) -> NDArray[np.float64]:
    """Perez et al. (1990) luminous efficacy [lm W^-1] (Table 4).

    * ``"global"`` and ``"diffuse"``: ``K = a + b W + c cos Z + d ln(delta)``;
    * ``"direct"``: ``K = max(0, a + b W + c exp(5.73 Z - 5) + d delta)``;

    a-d per sky-clearness bin of epsilon.

    Parameters
    ----------
    kind : {"global", "direct", "diffuse"}
    epsilon, delta : array_like
        Sky clearness (>= 1) and brightness (> 0).
    sun_zenith : array_like
        Solar zenith angle Z [rad].
    water : array_like
        Precipitable water W [cm] (:func:`precipitable_water`).
    """
    if kind not in ("global", "direct", "diffuse"):
        raise InvalidParameterError(f"kind must be 'global', 'direct' or 'diffuse'; got {kind!r}")
    table = _table("perez1990_luminous_efficacy")
    i = epsilon_bin(epsilon)
    a, b, c, d = (table[f"{kind}_{k}"][i] for k in "abcd")
    z = np.asarray(sun_zenith, dtype=float)
    w = np.asarray(water, dtype=float)
    dl = np.asarray(delta, dtype=float)
    if kind == "direct":
        return np.maximum(0.0, a + b * w + c * np.exp(5.73 * z - 5.0) + d * dl)
    return a + b * w + c * np.cos(z) + d * np.log(dl)


def perez_coefficients(
    epsilon: ArrayLike, delta: ArrayLike, sun_zenith: ArrayLike, *, delta_floor: bool = True
) -> NDArray[np.float64]:
    """Coefficients (a, b, c, d, e) of the all-weather model, shape (..., 5) (Perez et al. 1993, Table 1).

    ``X = X1 + X2 Z + delta (X3 + X4 Z)`` (Eq. 6), except c and d in bin 1 (Eqs. 7-8). With ``delta_floor``
    the bins 2-5 use ``max(delta, 0.2)`` (see the module notes).

    Parameters
    ----------
    epsilon, delta : array_like
        Sky clearness (>= 1) and brightness (> 0), broadcast together with ``sun_zenith``.
    sun_zenith : array_like
        Solar zenith angle Z [rad].
    """
    eps, dl, z = np.broadcast_arrays(
        np.asarray(epsilon, dtype=float), np.asarray(delta, dtype=float), np.asarray(sun_zenith, dtype=float)
    )
    if delta_floor:
        dl = np.where((eps > 1.065) & (eps < 2.8), np.maximum(dl, DELTA_FLOOR_BINS_2_5), dl)
    table = _table("perez1993_coefficients")
    i = epsilon_bin(eps)
    out = np.empty(eps.shape + (5,))
    for k, name in enumerate(_COEFFS):
        x1, x2, x3, x4 = (table[f"{name}{j}"][i] for j in range(1, 5))
        out[..., k] = x1 + x2 * z + dl * (x3 + x4 * z)
    bin1 = i == 0
    if np.any(bin1):
        c1, c2, c3, c4 = (table[f"c{j}"][0] for j in range(1, 5))
        d1, d2, d3, d4 = (table[f"d{j}"][0] for j in range(1, 5))
        base = np.maximum(dl * (c1 + c2 * z), 0.0)
        out[..., 2] = np.where(bin1, np.exp(base**c3) - c4, out[..., 2])
        out[..., 3] = np.where(bin1, -np.exp(dl * (d1 + d2 * z)) + d3 + dl * d4, out[..., 3])
    return out


def perez_relative_luminance(
    cos_theta: ArrayLike, cos_gamma: ArrayLike, coefficients: ArrayLike, *, guards: bool = True
) -> NDArray[np.float64]:
    """Relative luminance F(theta, gamma) of the all-weather model (Perez et al. 1993, Eq. 1).

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the sky element's zenith angle (>= 0).
    cos_gamma : array_like
        Cosine of the element's angle from the sun.
    coefficients : array_like, shape (..., 5)
        (a, b, c, d, e) from :func:`perez_coefficients`, broadcast against the angles' shape.
    guards : bool
        Clip negative F to 0 (default). The gradation's cos(theta) is floored at 0.01 either way (the one horizon
        rule of :mod:`skyscatter.sky.perez_family`, as Radiance's perezlum.cal).
    """
    gamma = np.arccos(np.clip(np.asarray(cos_gamma, dtype=float), -1.0, 1.0))
    f = perez_f(cos_theta, gamma, coefficients)
    return np.maximum(f, 0.0) if guards else f


class PerezParameters:
    """Sky parameters of the Perez model for one or many hours (arrays broadcast together).

    Attributes
    ----------
    epsilon, delta : ndarray
        Clearness and brightness the model uses (after the guards).
    sun_zenith : ndarray
        Solar zenith angle the model uses [rad] (after the altitude clamp).
    coefficients : ndarray, shape (..., 5)
        (a, b, c, d, e).
    diffuse_illuminance : ndarray
        Horizontal diffuse illuminance D_v [lx].
    sun_illuminance_normal : ndarray
        Direct normal illuminance of the sun [lx].
    diffuse_horizontal_irradiance, direct_normal_irradiance : ndarray
        D_h and I_n [W m^-2] (given, or derived from epsilon and delta).
    water : ndarray
        Precipitable water [cm].
    """

    def __init__(self, **arrays: NDArray[np.float64]) -> None:
        self.__dict__.update(arrays)


def _model_zenith(sun_zenith: NDArray[np.float64], guards: bool) -> NDArray[np.float64]:
    z = np.minimum(sun_zenith, np.pi / 2)
    return np.maximum(z, MIN_SUN_ZENITH) if guards else z


def perez_parameters(
    sun_zenith: ArrayLike,
    *,
    epsilon: ArrayLike | None = None,
    delta: ArrayLike | None = None,
    direct_normal_irradiance: ArrayLike | None = None,
    diffuse_horizontal_irradiance: ArrayLike | None = None,
    diffuse_illuminance: ArrayLike | None = None,
    day_of_year: ArrayLike | None = None,
    dew_point: ArrayLike = DEFAULT_DEW_POINT,
    guards: bool = True,
) -> PerezParameters:
    """Vectorised sky parameters: from (epsilon, delta) or from (direct normal, diffuse horizontal) irradiance.

    The inputs are validated by :class:`PerezSky` (scalars) or :func:`skyscatter.skymatrix` (hours); this
    function only computes. The solar zenith angle is limited to pi/2 (twilight hours get the sun on the
    horizon) and, with ``guards``, to at least 3 deg. With irradiances, ``D_v = D_h K_diffuse`` and
    ``E_sun = I_n K_direct``; with (epsilon, delta), ``D_h = delta I_0 / m`` and
    ``I_n = D_h (epsilon - 1)(1 + kappa Z^3)`` (Eqs. 1-2 inverted, as gendaylit -P does), unless
    ``diffuse_illuminance`` [lx] is given, which then sets D_v and scales the sun with it.
    """
    z = _model_zenith(np.asarray(sun_zenith, dtype=float), guards)
    water = precipitable_water(dew_point)
    if direct_normal_irradiance is not None:
        i_n = np.asarray(direct_normal_irradiance, dtype=float)
        d_h = np.asarray(diffuse_horizontal_irradiance, dtype=float)
        eps = sky_clearness(i_n, d_h, z)
        dl = sky_brightness(d_h, z, day_of_year)
    else:
        eps = np.asarray(epsilon, dtype=float)
        dl = np.asarray(delta, dtype=float)
        d_h = i_n = None
    if guards:
        eps = np.clip(eps, 1.0, EPSILON_CAP)
        dl = np.clip(dl, *DELTA_RANGE)
    k_dif = luminous_efficacy("diffuse", eps, dl, z, water)
    k_dir = luminous_efficacy("direct", eps, dl, z, water)
    ratio = (eps - 1.0) * (1.0 + KAPPA * z**3)  # I_n / D_h, Eq. 1 inverted
    if d_h is None:
        d_h = dl * extraterrestrial_irradiance(day_of_year) / relative_optical_mass(z)
        i_n = d_h * ratio
    if diffuse_illuminance is not None:
        d_v = np.asarray(diffuse_illuminance, dtype=float) * np.ones_like(eps)
        e_sun = i_n * k_dir if direct_normal_irradiance is not None else d_v * ratio * k_dir / k_dif
    else:
        d_v = d_h * k_dif
        e_sun = i_n * k_dir
    coeffs = perez_coefficients(eps, dl, z, delta_floor=guards)
    return PerezParameters(
        epsilon=eps,
        delta=dl,
        sun_zenith=z,
        coefficients=coeffs,
        diffuse_illuminance=d_v,
        sun_illuminance_normal=e_sun,
        diffuse_horizontal_irradiance=np.asarray(d_h, dtype=float),
        direct_normal_irradiance=np.asarray(i_n, dtype=float),
        water=np.asarray(water, dtype=float),
    )


def _finite(name: str, value, unit: str, *, low: float | None = None, strict_low: bool = False,
            high: float | None = None, why: str = "") -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a number [{unit}]; got {value!r}") from None
    if not np.isfinite(v):
        raise InvalidParameterError(f"{name} must be finite [{unit}]; got {v}")
    if low is not None and (v <= low if strict_low else v < low):
        rel = ">" if strict_low else ">="
        raise InvalidParameterError(f"{name} must be {rel} {low:g} [{unit}]; got {v:g}")
    if high is not None and v > high:
        raise InvalidParameterError(f"{name} must be at most {high:g} [{unit}]{why}; got {v:g}")

    check_daylight_limit(name, v, unit)
    return v


class PerezSkyCondition:
    """The validated sky condition of one hour: what :func:`perez_sky_condition` returns.

    Attributes
    ----------
    sun_zenith, sun_azimuth : float
        The sun [rad] as given (validated; azimuth wrapped into [0, 2 pi)).
    parameters : PerezParameters
        Epsilon, delta, the illuminances and the rest (:func:`perez_parameters`, scalars).
    day_of_year : int or None
    dew_point : float
        [deg C].
    guards : bool
    notes : list of str
        The guards that changed the sky condition (epsilon cap, delta range, sun altitude clamp).
    model_parameters : dict
        The keyword arguments that rebuild the condition (what a sky ``_remember``s).
    """

    def __init__(self, **values) -> None:
        self.__dict__.update(values)


def perez_sky_condition(
    sun_zenith: float,
    sun_azimuth: float,
    *,
    epsilon: float | None = None,
    delta: float | None = None,
    diffuse_illuminance: float | None = None,
    direct_normal_irradiance: float | None = None,
    diffuse_horizontal_irradiance: float | None = None,
    day_of_year: int | None = None,
    dew_point: float = DEFAULT_DEW_POINT,
    guards: bool = True,
) -> PerezSkyCondition:
    """Validate one hour's inputs and compute its Perez et al. (1990) sky condition (the skies' shared front end).

    Takes the arguments of :class:`PerezSky` (units and ranges there); raises
    :class:`~skyscatter.errors.InvalidParameterError` (or ``SunBelowHorizonError``) naming the bad input, and
    computes :func:`perez_parameters` with the guards. :class:`PerezSky` and
    :class:`~skyscatter.sky.asrc_cie.ASRCCIESky` both start here, so the same hour gives both the same epsilon,
    delta, diffuse illuminance and sun.
    """
    sun_zenith, sun_azimuth = check_sun_angles(sun_zenith, sun_azimuth, allow_below_horizon=False)
    by_irradiance = direct_normal_irradiance is not None or diffuse_horizontal_irradiance is not None
    by_parameters = epsilon is not None or delta is not None
    if by_irradiance and by_parameters:
        raise InvalidParameterError(
            "give either epsilon and delta or direct_normal_irradiance and diffuse_horizontal_irradiance, "
            "not both"
        )
    kwargs: dict = {}
    notes: list[str] = []
    if by_irradiance:
        if direct_normal_irradiance is None or diffuse_horizontal_irradiance is None:
            raise InvalidParameterError(
                "direct_normal_irradiance and diffuse_horizontal_irradiance [W m^-2] must be given together"
            )
        kwargs["direct_normal_irradiance"] = _finite(
            "direct_normal_irradiance", direct_normal_irradiance, "W m^-2", low=0.0)
        kwargs["diffuse_horizontal_irradiance"] = _finite(
            "diffuse_horizontal_irradiance", diffuse_horizontal_irradiance, "W m^-2", low=0.0, strict_low=True)
    elif by_parameters:
        if epsilon is None or delta is None:
            raise InvalidParameterError("epsilon and delta must be given together")
        kwargs["epsilon"] = _finite("epsilon (sky clearness)", epsilon, "-", low=1.0)
        kwargs["delta"] = _finite("delta (sky brightness)", delta, "-", low=0.0, strict_low=not guards)
    else:
        kwargs["epsilon"], kwargs["delta"] = DEFAULT_EPSILON, DEFAULT_DELTA
    if diffuse_illuminance is not None:
        kwargs["diffuse_illuminance"] = _finite("diffuse_illuminance", diffuse_illuminance, "lx", low=0.0)
    if day_of_year is not None:
        doy = _finite("day_of_year", day_of_year, "day", low=1.0)
        if doy > 366 or not doy.is_integer():
            raise InvalidParameterError(f"day_of_year must be a whole number 1-366; got {day_of_year!r}")
        day_of_year = int(doy)
    dew_point = _finite("dew_point", dew_point, "deg C", low=-90.0, high=60.0,
                        why=" (the range of surface dew points on Earth)")
    guards = bool(guards)
    p = perez_parameters(sun_zenith, day_of_year=day_of_year, dew_point=dew_point, guards=guards, **kwargs)
    if guards:
        raw_z = min(sun_zenith, np.pi / 2)
        if raw_z < MIN_SUN_ZENITH:
            notes.append(f"sun zenith {np.degrees(raw_z):.3g} deg raised to 3 deg (altitude clamp)")
        with np.errstate(all="ignore"):  # the unguarded model is evaluated only to describe the guards
            raw = perez_parameters(sun_zenith, day_of_year=day_of_year, dew_point=dew_point, guards=False, **kwargs)
        if float(raw.epsilon) > EPSILON_CAP:
            notes.append(f"epsilon {float(raw.epsilon):.4g} capped at {EPSILON_CAP}")
        if not DELTA_RANGE[0] <= float(raw.delta) <= DELTA_RANGE[1]:
            notes.append(f"delta {float(raw.delta):.4g} clamped to [{DELTA_RANGE[0]}, {DELTA_RANGE[1]}]")
    return PerezSkyCondition(
        sun_zenith=sun_zenith,
        sun_azimuth=sun_azimuth,
        parameters=p,
        day_of_year=day_of_year,
        dew_point=dew_point,
        guards=guards,
        notes=notes,
        model_parameters={**kwargs, "day_of_year": day_of_year, "dew_point": dew_point, "guards": guards},
    )


class PerezSky(LuminanceSunMixin, SunSkyMixin, LuminanceOnlySky):
    """Perez et al. (1993) all-weather sky, from (epsilon, delta) or from direct and diffuse irradiance.

    Parameters
    ----------
    sun_zenith : float
        Solar zenith angle [rad], at most pi/2.
    sun_azimuth : float
        Solar azimuth [rad, from north towards east].
    epsilon : float, optional
        Sky clearness, >= 1 (1: overcast; above about 6: clear).
    delta : float, optional
        Sky brightness, >= 0 (typically 0.05-0.5). With neither (epsilon, delta) nor the irradiances, the sky
        is a clear one of the clearest bin: ``DEFAULT_EPSILON`` = 6.5 and ``DEFAULT_DELTA`` = 0.15.
    diffuse_illuminance : float, optional
        Horizontal diffuse illuminance D_v [lx]; default: from the irradiance (or from delta) with the Perez
        1990 diffuse luminous efficacy.
    direct_normal_irradiance, diffuse_horizontal_irradiance : float, optional
        I_n >= 0 and D_h > 0 [W m^-2]; give both instead of epsilon and delta.
    day_of_year : int, optional
        1-366, for the Sun-Earth distance in delta; default None: mean distance (I_0 = 1367 W m^-2).
    dew_point : float
        Surface dew point [deg C] for the luminous efficacies; default 11 (precipitable water 2 cm).
    guards : bool
        Apply the practitioners' guards listed in the module notes (default True).

    Attributes
    ----------
    epsilon, delta : float
        The values the model uses (after the guards).
    epsilon_bin : int
        Sky clearness bin 1-8.
    coefficients : dict
        a, b, c, d, e.
    diffuse_illuminance : float
        D_v [lx]; the sky integrates to it.
    sun_illuminance_normal : float
        Direct normal illuminance of the sun [lx] (Perez 1990 direct efficacy); the solar disc carries it.
    guards_applied : list of str
        Which guards changed an input.
    """

    model_name = "perez"

    def __init__(
        self,
        sun_zenith: float,
        sun_azimuth: float,
        *,
        epsilon: float | None = None,
        delta: float | None = None,
        diffuse_illuminance: float | None = None,
        direct_normal_irradiance: float | None = None,
        diffuse_horizontal_irradiance: float | None = None,
        day_of_year: int | None = None,
        dew_point: float = DEFAULT_DEW_POINT,
        guards: bool = True,
    ) -> None:
        c = perez_sky_condition(
            sun_zenith, sun_azimuth, epsilon=epsilon, delta=delta, diffuse_illuminance=diffuse_illuminance,
            direct_normal_irradiance=direct_normal_irradiance,
            diffuse_horizontal_irradiance=diffuse_horizontal_irradiance, day_of_year=day_of_year,
            dew_point=dew_point, guards=guards,
        )
        self.sun_zenith, self.sun_azimuth = c.sun_zenith, c.sun_azimuth
        self.dew_point, self.guards, day_of_year, p = c.dew_point, c.guards, c.day_of_year, c.parameters
        notes = list(c.notes)
        if self.guards and 1.065 < float(p.epsilon) < 2.8 and float(p.delta) < DELTA_FLOOR_BINS_2_5:
            notes.append(f"delta {float(p.delta):.4g} raised to 0.2 for the coefficients (bins 2-5)")
        self.guards_applied = notes
        self._remember(**c.model_parameters)
        self.day_of_year = day_of_year
        self.epsilon = float(p.epsilon)
        self.delta = float(p.delta)
        self.epsilon_bin = int(epsilon_bin(self.epsilon)) + 1
        self.model_sun_zenith = float(p.sun_zenith)
        self.coefficients = {k: float(v) for k, v in zip(_COEFFS, p.coefficients, strict=True)}
        self._coeffs = np.asarray(p.coefficients, dtype=float)
        self.diffuse_illuminance = float(p.diffuse_illuminance)
        self.sun_illuminance_normal = float(p.sun_illuminance_normal)
        self.diffuse_horizontal_irradiance = float(p.diffuse_horizontal_irradiance)
        self.direct_normal_irradiance = float(p.direct_normal_irradiance)
        self.precipitable_water = float(p.water)
        self._model_sun = direction_from_angles(self.model_sun_zenith, self.sun_azimuth)
        self.uniform = False
        integral = plane_integral(self.relative_luminance)
        if not integral > 0:
            if not self.guards:
                raise InvalidParameterError(
                    f"the Perez sky for epsilon={self.epsilon:.4g}, delta={self.delta:.4g} has no positive "
                    "luminance (guards=False)"
                )
            # gendaymtx's last resort: an all-negative distribution becomes a uniform sky
            notes.append("no positive luminance anywhere: uniform sky used")
            self.uniform = True
            integral = np.pi
        self.normalisation = self.diffuse_illuminance / integral

    def __repr__(self) -> str:
        return (
            f"PerezSky(sun_zenith={self.sun_zenith:.6g}, sun_azimuth={self.sun_azimuth:.6g}, "
            f"epsilon={self.epsilon:.4g}, delta={self.delta:.4g}, diffuse_illuminance={self.diffuse_illuminance:.6g})"
        )

    def relative_luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Relative luminance F(theta, gamma) (Eq. 1), 0 below the horizon; the sky is ``normalisation * F``."""
        d = as_directions(directions)
        if getattr(self, "uniform", False):
            return np.where(d[..., 2] >= 0.0, 1.0, 0.0)
        f = perez_relative_luminance(d[..., 2], d @ self._model_sun, self._coeffs, guards=self.guards)
        return np.where(d[..., 2] >= 0.0, f, 0.0)

    def luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Sky luminance [cd m^-2] for view directions (..., 3)."""
        return self.normalisation * self.relative_luminance(directions)

    @property
    def zenith_luminance(self) -> float:
        """Zenith luminance [cd m^-2]."""
        return float(self.luminance(np.array([0.0, 0.0, 1.0])))
