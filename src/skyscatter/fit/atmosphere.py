"""Retrieval of the air from measurements: the aerosol and the ground albedo by least squares over the
precomputed sky.

Measurements (any combination):

* :class:`SkyScan` - sky radiance [W m^-2 sr^-1 nm^-1] at wavelengths, or luminance [cd m^-2], in known directions
  (zenith, azimuth [rad]) for one sun position (an 81-direction scan of a sky scanner);
* :class:`Irradiance` - direct normal and diffuse horizontal spectral irradiance [W m^-2 nm^-1] at wavelengths;
* :class:`AerosolOpticalDepth` - a sun photometer's aerosol optical depth spectrum.

The model is the precomputed atmosphere of [Bruneton2008], built
for each trial air at the measurement wavelengths with the reduced :data:`FIT_SIZES` and 4 orders (about 1-1.5 s
per build on 2 busy cores at 3 wavelengths); sky radiance from :meth:`~.PrecomputedAtmosphere.sky_radiance`,
luminance from :meth:`~.PrecomputedAtmosphere.sky_luminance` (this needs 16 table wavelengths), the direct
beam from :meth:`~.PrecomputedAtmosphere.sun_transmittance` times the extraterrestrial spectrum and the diffuse
from the sky part of :meth:`~.PrecomputedAtmosphere.ground_irradiance`. The aerosol optical depth needs no table.

The free parameters are chosen from :data:`FREE_PARAMETERS`: with the default analytic aerosol (Angstrom's law,
Cornette-Shanks phase) its optical depth at 550 nm, Angstrom exponent, asymmetry g and single-scattering albedo;
with an OPAC aerosol type (``aerosol_type``, :mod:`skyscatter.atmosphere.aerosol_types`) its optical depth and
relative humidity; with a mixture of OPAC components or types (``mixture``, e.g. a fine and a coarse mode:
:meth:`~skyscatter.atmosphere.aerosol_types.OpacAerosol.mixture`, the external mixture of [Hess1998] Eqs. 1-2)
each member's optical depth at 550 nm and the relative humidity, and from them the total optical depth and each
member's fraction with uncertainties propagated from the covariance; and the ground albedo.

Residuals are relative: ``ln(model / measured) / sigma`` for radiance, luminance and irradiance (``sigma`` the
stated relative noise) and ``(model - measured) / sigma`` for optical depths. :func:`scipy.optimize.least_squares`
(trust-region reflective, within the parameters' bounds) with a forward-difference Jacobian (relative step 1e-2: the
tables are float32) costs ``1 + n_free`` table builds per iteration; :attr:`AtmosphereFit.builds` reports the total.

Uncertainties are the square roots of the diagonal of the covariance ``s^2 (J^T J)^-1`` at the solution, with
``J`` the Jacobian of the weighted residuals and ``s^2 = max(1, chi^2 / (m - n))``: the stated noise, inflated by
the misfit when the model cannot reach the measurements ([Press2007] Sec.
15.4-15.5). The residual of the sky scan is reported by region: within 20 deg of the sun, below 15 deg elevation
(the horizon) and the rest (relative RMS, %).

With a sky scan the covariance also carries the tables' systematic error in sky radiance against the Monte Carlo
reference (:data:`SCAN_MODEL_ERROR`: 4.5 % below 15 deg elevation, 2 % at 15-30 deg, 1.5 % above, each common to
its band's directions and wavelengths) propagated through the solution (``model_error=True``, the default): without
it the ground albedo from a Monte Carlo scan came back 11 % high at 5 stated standard deviations, the horizon
band's -4.3 % taken up by the parameter the scan is least sensitive to. With a diffuse horizontal irradiance
it carries the tables' systematic error in DHI against DISORT the same way (:data:`IRRADIANCE_MODEL_ERROR`: an
offset common to the wavelengths and a slope in ``ln(lambda / 550 nm)``, sized by the phase kind, analytic or
tabulated): the tables' diffuse irradiance is a hemisphere quadrature of the sky (8 x 16 directions at the fit
sizes), so DHI comes out 0.2-10 % low with the analytic aerosol and 0.1-6 % low with Mie airs (the higher
orders at the fit sizes; most at 400 nm), by amounts that change with the table sizes and the sun; without it a
fine + coarse mixture from DNI and DHI came back 2.3 stated standard deviations off (table format 8).
``AtmosphereFit.extra`` keeps the statistical part alone (``statistical_uncertainties``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere import AtmosphereParameters
from ..conventions import direction_from_angles
from ..errors import InvalidParameterError

__all__ = ["FIT_SIZES", "FREE_PARAMETERS", "IRRADIANCE_MODEL_ERROR", "MEMBER", "SCAN_MODEL_ERROR",
           "AerosolOpticalDepth", "AtmosphereFit", "Irradiance", "SkyScan", "fit_atmosphere"]

#: Table sizes of the fits: a third of the default 4D table's radii, mu and mu_s (build about 1 s).
FIT_SIZES = dict(scattering_r=12, scattering_mu=48, scattering_mu_s=16, scattering_nu=8, transmittance_r=16,
                 transmittance_mu=64, irradiance_r=8, irradiance_mu_s=16, density_sphere_samples=8,
                 irradiance_sphere_samples=8, ray_samples=24)
#: Free parameters, their bounds and meaning.
FREE_PARAMETERS = {
    "aerosol_optical_depth": (0.0, 3.0, "vertical aerosol optical depth at 550 nm"),
    "angstrom_alpha": (-0.5, 3.0, "Angstrom exponent (analytic aerosol)"),
    "mie_phase_g": (0.0, 0.95, "asymmetry parameter of the Cornette-Shanks phase (analytic aerosol)"),
    "mie_single_scattering_albedo": (0.5, 1.0, "aerosol single-scattering albedo (analytic aerosol)"),
    "relative_humidity": (0.0, 99.0, "relative humidity [%] (OPAC aerosol type or mixture)"),
    "ground_albedo": (0.0, 1.0, "Lambertian ground albedo, the same at every wavelength"),
}
_ANALYTIC_ONLY = ("angstrom_alpha", "mie_phase_g", "mie_single_scattering_albedo")
#: Prefix of a mixture member's free optical depth at 550 nm: ``"optical_depth:waso"``.
MEMBER = "optical_depth:"
#: Systematic error of the fit's tables (:data:`FIT_SIZES`, 4 orders) in sky radiance against the Monte Carlo
#: reference, by view elevation band: (lowest [deg], highest [deg], relative error). Measured (docs/aerosols.md:
#: air optical depth 0.25, g 0.7, albedo 0.2, sun 40 deg, 440 and 670 nm, ring means of an 81-direction scan):
#: -4.3 / -4.4 % at 10 deg elevation (-4.6 / -4.2 % with 6 orders and 16 x 64 radii x mu: not the table size),
#: -1.7 / -2.0 % at 19 deg, within 1.6 % above 28 deg.
SCAN_MODEL_ERROR = ((0.0, 15.0, 0.045), (15.0, 30.0, 0.02), (30.0, 90.0, 0.015))
#: Systematic error of the fit's tables (:data:`FIT_SIZES`, 4 orders) in diffuse horizontal irradiance against
#: DISORT ([Stamnes1988]), by aerosol phase kind: (RMS offset common to all wavelengths, RMS slope per unit
#: ln(lambda / 550 nm)), relative. Measured by ``benchmarks/irradiance_model_error.py`` (docs/aerosols.md): each
#: case's error ``DHI_tables / DHI_DISORT - 1`` at 400-830 nm fitted by ``a + b ln(lambda / 550 nm)``, RMS over
#: sun zenith 20, 40, 60 deg and, for ``"analytic"``, Cornette-Shanks aerosols (optical depth 0.1-0.5, g 0.7-0.8;
#: 9 cases: a -1.0 to -7.2 %, b +2.7 to +8.3 %; table format 10, whose first-order irradiance keeps the
#: analytic phase's forward peak: format 9 gave 0.045, 0.047 with a -1.5 to -9.4 %), for ``"table"``, Mie
#: phases (OPAC waso, sscm, two waso + sscm mixtures, continental-average, maritime-clean, desert, urban at
#: optical depth 0.1-0.25; 24 cases: a -3.0 to -0.8 %, b +1.5 to +7.4 %; table format 11, whose orders run in
#: the delta-M scaled medium: format 10 gave 0.076, 0.062 with sscm alone at sun 40 / 60 deg a +32 / +16 %).
IRRADIANCE_MODEL_ERROR = {"analytic": (0.035, 0.055), "table": (0.018, 0.039)}
NEAR_SUN = math.radians(20.0)
HORIZON = math.radians(15.0)


def _array(name: str, value: ArrayLike, ndim: int | None = None) -> NDArray[np.float64]:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be numbers") from None
    if ndim is not None and a.ndim != ndim:
        raise InvalidParameterError(f"{name} must be {ndim}-dimensional; got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InvalidParameterError(f"{name} contains NaN or infinite values")
    return a


def _sun(zenith: float, azimuth: float) -> tuple[float, float]:
    z, a = float(zenith), float(azimuth)
    if not (math.isfinite(z) and math.isfinite(a) and 0.0 <= z < math.radians(89.0)):
        raise InvalidParameterError(f"sun zenith must be in [0, 89) deg for a fit; got {math.degrees(z):.4g} deg")
    return z, a


@dataclass(frozen=True, eq=False)
class SkyScan:
    """Sky radiance or luminance in known directions for one sun position.

    Parameters
    ----------
    zenith, azimuth : array_like (n,)
        View directions [rad]: zenith in [0, 90 deg), azimuth from north towards east.
    values : array_like (n, n_wl) or (n,)
        Radiance [W m^-2 sr^-1 nm^-1] at ``wavelengths``, or luminance [cd m^-2] when ``wavelengths`` is None;
        > 0.
    sun_zenith, sun_azimuth : float
        [rad].
    wavelengths : array_like (n_wl,) or None
        [nm] in 360-830 (the ozone data), or None for luminance.
    relative_noise : float
        Standard deviation of the measurement noise relative to the value (default 0.03).
    """

    zenith: NDArray[np.float64]
    azimuth: NDArray[np.float64]
    values: NDArray[np.float64]
    sun_zenith: float
    sun_azimuth: float
    wavelengths: NDArray[np.float64] | None = None
    relative_noise: float = 0.03

    def __post_init__(self) -> None:
        z = _array("scan zenith", self.zenith, 1)
        a = _array("scan azimuth", self.azimuth, 1)
        v = _array("scan values", self.values)
        if z.shape != a.shape or z.size < 3:
            raise InvalidParameterError("a sky scan needs at least 3 directions, zenith and azimuth of equal length")
        if np.any(z < 0) or np.any(z >= math.pi / 2):
            raise InvalidParameterError("scan directions must be above the horizon (zenith in [0, 90) deg)")
        if self.wavelengths is None:
            if v.shape != z.shape:
                raise InvalidParameterError(f"luminance values must have shape {z.shape}; got {v.shape}")
            wl = None
        else:
            wl = _array("scan wavelengths", self.wavelengths, 1)
            if v.ndim == 1 and wl.size == 1:
                v = v[:, None]
            if v.shape != (z.size, wl.size):
                raise InvalidParameterError(f"radiance values must have shape {(z.size, wl.size)}; got {v.shape}")
        if np.any(v <= 0):
            raise InvalidParameterError("scan values must be > 0 (radiance or luminance)")
        _sun(self.sun_zenith, self.sun_azimuth)
        if not (math.isfinite(self.relative_noise) and self.relative_noise > 0):
            raise InvalidParameterError("relative_noise must be > 0")
        for name, arr in (("zenith", z), ("azimuth", a), ("values", v), ("wavelengths", wl)):
            object.__setattr__(self, name, arr)


@dataclass(frozen=True, eq=False)
class Irradiance:
    """Direct normal and diffuse horizontal spectral irradiance [W m^-2 nm^-1] at ``wavelengths`` [nm] for one sun
    position [rad]; either may be None. ``relative_noise`` default 0.02."""

    wavelengths: NDArray[np.float64]
    sun_zenith: float
    sun_azimuth: float
    direct_normal: NDArray[np.float64] | None = None
    diffuse_horizontal: NDArray[np.float64] | None = None
    relative_noise: float = 0.02

    def __post_init__(self) -> None:
        wl = _array("irradiance wavelengths", self.wavelengths, 1)
        object.__setattr__(self, "wavelengths", wl)
        _sun(self.sun_zenith, self.sun_azimuth)
        if self.direct_normal is None and self.diffuse_horizontal is None:
            raise InvalidParameterError("give a direct normal or a diffuse horizontal irradiance (or both)")
        for name in ("direct_normal", "diffuse_horizontal"):
            v = getattr(self, name)
            if v is not None:
                v = _array(name.replace("_", " "), v, 1)
                if v.shape != wl.shape or np.any(v <= 0):
                    raise InvalidParameterError(f"{name.replace('_', ' ')} must be > 0, one value per wavelength")
                object.__setattr__(self, name, v)


@dataclass(frozen=True, eq=False)
class AerosolOpticalDepth:
    """A vertical aerosol optical depth spectrum (a sun photometer): ``values`` [-] >= 0 at ``wavelengths`` [nm],
    absolute noise ``noise`` (default 0.01)."""

    wavelengths: NDArray[np.float64]
    values: NDArray[np.float64]
    noise: float = 0.01

    def __post_init__(self) -> None:
        wl = _array("optical depth wavelengths", self.wavelengths, 1)
        v = _array("aerosol optical depths", self.values, 1)
        if v.shape != wl.shape or np.any(v < 0):
            raise InvalidParameterError("aerosol optical depths must be >= 0, one per wavelength")
        object.__setattr__(self, "wavelengths", wl)
        object.__setattr__(self, "values", v)


@dataclass
class AtmosphereFit:
    """The result of :func:`fit_atmosphere`.

    ``parameters`` the fitted air; ``values``, ``uncertainties`` (one standard deviation) by free parameter;
    ``covariance`` (n_free, n_free) in the order of ``free``; ``derived`` (value, standard deviation) of a
    mixture's total optical depth at 550 nm (``"aerosol_optical_depth"``) and its members' fractions
    (``"fraction:<member>"``), first-order propagation of ``covariance``; ``residuals`` relative RMS [%] by group and
    region (``"sky: near sun"``, ``"sky: horizon"``, ``"sky: rest"``, ``"direct"``, ``"diffuse"``) and the optical
    depth's absolute RMS (``"aod"``); ``chi2_reduced``; ``builds`` table builds and ``seconds`` wall time.
    """

    parameters: AtmosphereParameters
    free: tuple[str, ...]
    values: dict[str, float]
    uncertainties: dict[str, float]
    covariance: NDArray[np.float64]
    residuals: dict[str, float]
    chi2_reduced: float
    builds: int
    seconds: float
    aerosol_type: str | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    mixture: tuple[str, ...] | None = None
    derived: dict[str, tuple[float, float]] = field(default_factory=dict)

    def report(self) -> dict[str, Any]:
        """JSON-compatible summary (what ``skyscatter fit-atmosphere`` stores beside the air)."""
        return {"free": list(self.free), "values": self.values, "uncertainties": self.uncertainties,
                "covariance": self.covariance.tolist(), "residual_rms": self.residuals,
                "chi2_reduced": self.chi2_reduced, "builds": self.builds, "seconds": self.seconds,
                "aerosol_type": self.aerosol_type, "mixture": None if self.mixture is None else list(self.mixture),
                "derived": {k: list(v) for k, v in self.derived.items()}, **self.extra}


def _air(base: AtmosphereParameters, names: tuple[str, ...], x: NDArray[np.float64],
         aerosol_type: str | None, start: dict[str, float],
         mixture: tuple[str, ...] | None = None) -> AtmosphereParameters:
    v = dict(start)
    v.update(zip(names, (float(t) for t in x), strict=True))
    if mixture is not None:
        from ..atmosphere.aerosol_types import OpacAerosol

        return base.replace(ground_albedo=v["ground_albedo"], aerosol=OpacAerosol.mixture(
            [(m, v[MEMBER + m]) for m in mixture], v["relative_humidity"], column_height=base.thickness))
    if aerosol_type is not None:  # the relative humidity is the fit's own (not a user option of the air)
        from ..atmosphere.aerosol_types import OpacAerosol

        return base.replace(ground_albedo=v["ground_albedo"], aerosol=OpacAerosol.preset(
            aerosol_type, v["aerosol_optical_depth"], v["relative_humidity"], base.thickness))
    air = AtmosphereParameters.from_options(base, aerosol_optical_depth=v["aerosol_optical_depth"],
                                            angstrom_alpha=v["angstrom_alpha"], ground_albedo=v["ground_albedo"],
                                            mie_phase_g=v["mie_phase_g"])
    return air.replace(mie_single_scattering_albedo=v["mie_single_scattering_albedo"])


def _start_values(base: AtmosphereParameters, aerosol_type: str | None, relative_humidity: float,
                  mixture: tuple[str, ...] | None = None) -> dict[str, float]:
    from ..atmosphere.turbidity import angstrom_beta_from_optical_depth

    tau = float(base.aerosol_component.optical_depth([550.0], base.thickness)[0])
    if base.aerosol is None:
        tau = base.mie_angstrom_beta / angstrom_beta_from_optical_depth(1.0, base.mie_angstrom_alpha)
    out = {"aerosol_optical_depth": max(tau, 0.02), "angstrom_alpha": base.mie_angstrom_alpha,
           "mie_phase_g": base.mie_phase_g, "mie_single_scattering_albedo": base.mie_single_scattering_albedo,
           "relative_humidity": relative_humidity,
           "ground_albedo": float(np.mean(base.ground_albedo_at([550.0])))}
    members = tuple(mixture or ())
    for m in members:  # equal shares of the base's optical depth
        out[MEMBER + m] = out["aerosol_optical_depth"] / len(members)
    return out


def _mixture_derived(mixture: tuple[str, ...], free: tuple[str, ...], x: NDArray[np.float64],
                     cov: NDArray[np.float64], start: dict[str, float]) -> dict[str, tuple[float, float]]:
    """The mixture's total optical depth at 550 nm and each member's fraction of it, with standard deviations
    propagated from the covariance to first order (``g^T C g``, ``g`` the gradient of each quantity)."""
    names = [MEMBER + m for m in mixture]
    tau = np.array([float(x[free.index(n)]) if n in free else start[n] for n in names])
    grad_rows = np.zeros((len(mixture), len(free)))
    for i, n in enumerate(names):
        if n in free:
            grad_rows[i, free.index(n)] = 1.0
    total = float(tau.sum())
    g_total = grad_rows.sum(axis=0)
    out = {"aerosol_optical_depth": (total, float(np.sqrt(max(g_total @ cov @ g_total, 0.0))))}
    if total > 0:
        for i, m in enumerate(mixture):
            g = (grad_rows[i] * total - tau[i] * g_total) / total**2
            out["fraction:" + m] = (float(tau[i] / total), float(np.sqrt(max(g @ cov @ g, 0.0))))
    return out


def fit_atmosphere(scan: SkyScan | None = None, irradiance: Irradiance | None = None,
                   aod: AerosolOpticalDepth | None = None, *,
                   free: tuple[str, ...] = ("aerosol_optical_depth", "mie_phase_g", "ground_albedo"),
                   base: AtmosphereParameters | None = None, aerosol_type: str | None = None,
                   mixture: tuple[str, ...] | None = None,
                   relative_humidity: float = 50.0, orders: int = 4, sizes: dict[str, int] | None = None,
                   max_builds: int = 60, model_error: bool = True) -> AtmosphereFit:
    """Fit the air to the measurements (module docstring).

    Parameters
    ----------
    scan, irradiance, aod : measurements (at least one; a fit of more than the optical depth needs a scan or
        irradiance).
    free : tuple of str
        Names from :data:`FREE_PARAMETERS` (default optical depth, g, ground albedo).
    base : AtmosphereParameters
        The air the fit starts from and keeps otherwise (default the Earth defaults with optical depth 0.1,
        Angstrom exponent 1.3).
    aerosol_type : str, optional
        Fit an OPAC aerosol type (its optical depth and humidity) instead of the analytic aerosol.
    mixture : tuple of str, optional
        Fit an external mixture of two or more OPAC components or types
        (:meth:`~skyscatter.atmosphere.aerosol_types.OpacAerosol.mixture`, e.g. ``("waso", "sscm")``: a fine
        and a coarse mode): ``"aerosol_optical_depth"`` in ``free`` stands for the optical depth at 550 nm of
        every member (free parameters ``"optical_depth:<member>"``, each >= 0; start: equal shares of the
        base's). :attr:`AtmosphereFit.derived` gives the total optical depth and each member's fraction of it
        with their propagated uncertainties.
    relative_humidity : float
        [%], start (or fixed) humidity of an aerosol type or mixture.
    orders, sizes : the table builds' scattering orders and sizes (default 4 and :data:`FIT_SIZES`).
    max_builds : int
        Limit of table builds (function evaluations).
    model_error : bool
        Add the tables' systematic errors in sky radiance (:data:`SCAN_MODEL_ERROR`) and in diffuse horizontal
        irradiance (:data:`IRRADIANCE_MODEL_ERROR`) to the covariance (default True; module docstring). Without a
        scan or a DHI nothing is added.
    """
    from scipy.optimize import least_squares

    from ..precomputed import PrecomputedAtmosphere

    if scan is None and irradiance is None and aod is None:
        raise InvalidParameterError("give at least one measurement: a sky scan, irradiance or optical depths")
    free = tuple(free)
    if mixture is not None:
        mixture = tuple(str(m) for m in mixture)
        if aerosol_type is not None:
            raise InvalidParameterError("give an aerosol type or a mixture, not both")
        if len(mixture) < 2 or len(set(mixture)) != len(mixture):
            raise InvalidParameterError("a mixture needs two or more distinct members")
        from ..atmosphere.aerosol_types import AEROSOL_TYPES, OPAC_COMPONENTS

        for m in mixture:
            if m not in OPAC_COMPONENTS and m not in AEROSOL_TYPES:
                raise InvalidParameterError(f"unknown mixture member {m!r}; OPAC components: "
                                            f"{', '.join(OPAC_COMPONENTS)}; types: {', '.join(AEROSOL_TYPES)}")
    for name in free:
        if name not in FREE_PARAMETERS:
            raise InvalidParameterError(f"unknown free parameter {name!r}; known: {', '.join(FREE_PARAMETERS)}")
        if (aerosol_type is not None or mixture is not None) and name in _ANALYTIC_ONLY:
            raise InvalidParameterError(f"{name} belongs to the analytic aerosol; an aerosol type or mixture fits "
                                        "aerosol_optical_depth and relative_humidity")
        if aerosol_type is None and mixture is None and name == "relative_humidity":
            raise InvalidParameterError("relative_humidity is fitted with an aerosol type or mixture")
    if len(set(free)) != len(free) or not free:
        raise InvalidParameterError("free parameters must be distinct, at least one")
    if scan is None and irradiance is None and set(free) - {"aerosol_optical_depth", "angstrom_alpha"}:
        raise InvalidParameterError("optical depths alone determine only aerosol_optical_depth and angstrom_alpha")
    base = AtmosphereParameters.from_aerosol_optical_depth(0.1, 1.3) if base is None else base
    start = _start_values(base, aerosol_type, relative_humidity, mixture)
    if mixture is not None and "aerosol_optical_depth" in free:
        i = free.index("aerosol_optical_depth")
        free = free[:i] + tuple(MEMBER + m for m in mixture) + free[i + 1:]
    bounds = {**FREE_PARAMETERS, **{MEMBER + m: (0.0, 3.0, "") for m in mixture or ()}}
    lo = np.array([bounds[n][0] for n in free])
    hi = np.array([bounds[n][1] for n in free])
    x0 = np.clip(np.array([start[n] for n in free]), lo + 1e-6 * (hi - lo), hi - 1e-6 * (hi - lo))
    sz = FIT_SIZES if sizes is None else sizes
    wl_set: set[float] = set()
    if scan is not None:
        wl_set |= set(np.linspace(400.0, 700.0, 16)) if scan.wavelengths is None else set(scan.wavelengths)
    if irradiance is not None:
        wl_set |= set(irradiance.wavelengths)
    table_wl = np.array(sorted(wl_set)) if wl_set else None
    builds = 0
    t0 = time.perf_counter()

    def model(x: NDArray[np.float64]):
        nonlocal builds
        air = _air(base, free, x, aerosol_type, start, mixture)
        out: dict[str, NDArray[np.float64]] = {}
        if table_wl is not None:
            atm = PrecomputedAtmosphere.compute(air, orders=orders, wavelengths=table_wl, sizes=sz, progress=False)
            builds += 1
            pos = np.array([0.0, 0.0, air.bottom_radius])
            if scan is not None:
                sun = direction_from_angles(scan.sun_zenith, scan.sun_azimuth)
                dirs = direction_from_angles(scan.zenith, scan.azimuth)
                if scan.wavelengths is None:
                    out["sky"] = atm.sky_luminance(pos, dirs, sun)
                else:
                    idx = np.searchsorted(table_wl, scan.wavelengths)
                    out["sky"] = atm.sky_radiance(pos, dirs, sun)[:, idx]
            if irradiance is not None:
                sun = direction_from_angles(irradiance.sun_zenith, irradiance.sun_azimuth)
                idx = np.searchsorted(table_wl, irradiance.wavelengths)
                if irradiance.direct_normal is not None:
                    out["direct"] = (atm.sun_transmittance(pos, sun) * air.solar_irradiance_at(table_wl))[idx]
                if irradiance.diffuse_horizontal is not None:
                    out["diffuse"] = atm.ground_irradiance(pos, np.array([0.0, 0.0, 1.0]), sun)[1][idx]
        if aod is not None:
            out["aod"] = air.aerosol_component.optical_depth(aod.wavelengths, air.thickness)
        return out

    def residuals(x: NDArray[np.float64]) -> NDArray[np.float64]:
        m = model(x)
        parts = []
        if scan is not None:
            parts.append((np.log(np.maximum(m["sky"], 1e-30)) - np.log(scan.values)).ravel() / scan.relative_noise)
        if irradiance is not None:
            for key, meas in (("direct", irradiance.direct_normal), ("diffuse", irradiance.diffuse_horizontal)):
                if meas is not None:
                    parts.append((np.log(np.maximum(m[key], 1e-30)) - np.log(meas)) / irradiance.relative_noise)
        if aod is not None:
            parts.append((m["aod"] - aod.values) / aod.noise)
        return np.concatenate(parts)

    res = least_squares(residuals, x0, bounds=(lo, hi), method="trf", jac="2-point", diff_step=1e-2,
                        x_scale=np.maximum(hi - lo, 1e-3) * 0.1, max_nfev=max_builds, xtol=1e-4, ftol=1e-6)
    r = res.fun
    m, n = r.size, len(free)
    chi2 = float(r @ r) / max(m - n, 1)
    jac = res.jac
    try:
        cov = np.linalg.pinv(jac.T @ jac) * max(1.0, chi2)
    except np.linalg.LinAlgError:  # pragma: no cover
        cov = np.full((n, n), np.nan)
    statistical = np.sqrt(np.maximum(np.diag(cov), 0.0))
    fitted = _air(base, free, res.x, aerosol_type, start, mixture)
    phase_kind = "analytic" if fitted.aerosol_component.analytic_phase is not None else "table"
    patterns = _model_error_patterns(scan, irradiance, phase_kind) if model_error else []
    if patterns:
        cov = cov + _model_error_covariance(jac, patterns)
    final = model(res.x)
    rms: dict[str, float] = {}
    if scan is not None:
        rel = final["sky"] / scan.values - 1.0
        rel = rel if rel.ndim == 1 else np.sqrt(np.mean(rel ** 2, axis=-1))
        sun = direction_from_angles(scan.sun_zenith, scan.sun_azimuth)
        gamma = np.arccos(np.clip(direction_from_angles(scan.zenith, scan.azimuth) @ sun, -1.0, 1.0))
        near = gamma < NEAR_SUN
        horizon = ~near & (scan.zenith > math.pi / 2 - HORIZON)
        for name, sel in (("sky: near sun", near), ("sky: horizon", horizon), ("sky: rest", ~near & ~horizon)):
            if sel.any():
                rms[name] = float(100.0 * np.sqrt(np.mean(rel[sel] ** 2)))
    if irradiance is not None:
        for key, meas in (("direct", irradiance.direct_normal), ("diffuse", irradiance.diffuse_horizontal)):
            if meas is not None:
                rms[key] = float(100.0 * np.sqrt(np.mean((final[key] / meas - 1.0) ** 2)))
    if aod is not None:
        rms["aod"] = float(np.sqrt(np.mean((final["aod"] - aod.values) ** 2)))
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    derived = {} if mixture is None else _mixture_derived(mixture, free, res.x, cov, start)
    extra: dict[str, Any] = {"statistical_uncertainties": {k: float(v)
                                                           for k, v in zip(free, statistical, strict=True)}}
    if scan is not None and model_error:
        extra["scan_model_error"] = [list(b) for b in SCAN_MODEL_ERROR]
    if irradiance is not None and irradiance.diffuse_horizontal is not None and model_error:
        extra["diffuse_model_error"] = {"phase": phase_kind, "offset": IRRADIANCE_MODEL_ERROR[phase_kind][0],
                                        "slope_per_ln_wavelength": IRRADIANCE_MODEL_ERROR[phase_kind][1]}
    return AtmosphereFit(fitted, free, {k: float(v) for k, v in zip(free, res.x, strict=True)},
                         {k: float(v) for k, v in zip(free, sd, strict=True)}, cov, rms, chi2, builds,
                         time.perf_counter() - t0, aerosol_type, extra=extra, mixture=mixture, derived=derived)


def _model_error_patterns(scan: SkyScan | None, irradiance: Irradiance | None,
                          phase_kind: str) -> list[NDArray[np.float64]]:
    """The tables' systematic errors as patterns ``u`` in the space of the weighted residuals (in their order:
    the scan's, then DNI's, DHI's, the optical depths'), each a relative error ``delta`` common to its
    measurements divided by their noise, independent between patterns: one per elevation band of the scan
    (:data:`SCAN_MODEL_ERROR`), and for DHI an offset and a slope in ``ln(lambda / 550 nm)``
    (:data:`IRRADIANCE_MODEL_ERROR`). The direct beam's own error (0.26 % at 400 nm against the Monte Carlo
    reference's exact transmittance, docs/aerosols.md) is left out: below any stated noise."""
    n_scan = 0 if scan is None else scan.values.size
    n_irr = 0
    if irradiance is not None:
        n_irr = irradiance.wavelengths.size * ((irradiance.direct_normal is not None)
                                               + (irradiance.diffuse_horizontal is not None))
    n = n_scan + n_irr  # the optical depths' residuals follow, without a model error
    out = []
    if scan is not None:
        n_wl = 1 if scan.values.ndim == 1 else scan.values.shape[1]
        elevation = np.degrees(math.pi / 2 - scan.zenith)
        for lo, hi, delta in SCAN_MODEL_ERROR:
            sel = (elevation >= lo) & ((elevation < hi) | (hi >= 90.0))
            if sel.any():
                u = np.zeros(n)
                u[:n_scan] = np.repeat(sel, n_wl) * (delta / scan.relative_noise)
                out.append(u)
    if irradiance is not None and irradiance.diffuse_horizontal is not None:
        offset, slope = IRRADIANCE_MODEL_ERROR[phase_kind]
        k = irradiance.wavelengths.size
        first = n_scan + (k if irradiance.direct_normal is not None else 0)
        for shape in (np.full(k, offset), slope * np.log(irradiance.wavelengths / 550.0)):
            u = np.zeros(n)
            u[first:first + k] = shape / irradiance.relative_noise
            out.append(u)
    return out


def _model_error_covariance(jac: NDArray[np.float64], patterns: list[NDArray[np.float64]]) -> NDArray[np.float64]:
    """Covariance of the fitted parameters from the tables' systematic errors (:func:`_model_error_patterns`):
    each pattern ``u_b`` carried by the least-squares solution's linear map ``G = (J^T J)^+ J^T`` (``J`` the
    Jacobian of the weighted residuals), ``sum_b (G u_b)(G u_b)^T`` (linear propagation through the least-squares
    solution, [Press2007] Sec. 15.4)."""
    gmap = np.linalg.pinv(jac.T @ jac) @ jac.T
    out = np.zeros((jac.shape[1], jac.shape[1]))
    for u in patterns:
        d = gmap[:, :u.size] @ u
        out += np.outer(d, d)
    return out
