"""The precomputed atmosphere of Bruneton & Neyret (2008) as a skyscatter sky model: :class:`BrunetonSky`.

Reference: [Bruneton2008]. The tables come from :mod:`skyscatter.precomputed`.

The observer stands at ``altitude`` above the planet's surface; the local East-North-Up frame is the
planet-centred frame with the observer on its +z axis. Directions that meet the planet return the ground
(Lambertian, the atmosphere's albedo, lit by the sun and the sky) seen through the atmosphere, so the model
renders the whole sphere of directions from the ground to orbit (``renders_ground = True``). The solar disc is
separate (:meth:`BrunetonSky.sun_spectral_radiance`).
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..deprecation import renamed_keywords, warn_renamed
from ..errors import InvalidParameterError, SunBelowHorizonError
from ..precomputed import AtmosphereParameters, PrecomputedAtmosphere
from ..precomputed.cache import resolve_atmosphere
from ..spectral import DEFAULT_WAVELENGTHS, as_wavelengths
from . import registry
from .base import SkyModel, SunSkyMixin, check_sun_angles

__all__ = ["BrunetonSky"]

#: Highest observer altitude accepted [m] (10^5 km; the registry's range of ``altitude``).
MAX_ALTITUDE = 1.0e8


class BrunetonSky(SunSkyMixin, SkyModel):
    """Physically based sky from precomputed multiple scattering (Bruneton & Neyret 2008).

    Parameters
    ----------
    sun_zenith : float
        Sun zenith angle [rad] at the observer. Inside the atmosphere, up to the atmosphere's
        ``max_sun_zenith`` (102 deg by default): the sun may be below the horizon (twilight). Above the top of
        the atmosphere any value in [0, pi]: the limit then applies where each view ray enters the atmosphere,
        and parts whose sun is beyond it are dark.
    sun_azimuth : float
        Sun azimuth [rad] from north towards east.
    altitude : float
        Observer altitude above the surface [m], >= 0; above the top of the atmosphere (60 km for the Earth)
        the view is from space.
    atmosphere : AtmosphereParameters, optional
        The atmosphere, whose tables are taken from the disk cache (computed the first time, about 10-30 s on
        2 cores, with a warning saying so); default: the Earth defaults.
    precomputed : PrecomputedAtmosphere, optional
        Precomputed tables instead (they hold their atmosphere; not with ``atmosphere``, the medium options or
        ``tables``).
    turbidity : float, optional
        Aerosols from turbidity, 1 to 20 (Preetham 1999 A.1: Angstrom alpha 1.3, beta 0.04608 T - 0.04586).
    aerosol_optical_depth : float, optional
        Vertical aerosol optical depth at 550 nm, 0 to 10, with ``angstrom_alpha`` (default 1.3); instead of
        ``turbidity``.
    ground_albedo : float, optional
        Albedo of the atmosphere's ground, 0 to 1 (the Earth defaults: 0.1).
    ozone_column : float, optional
        Total ozone [Dobson units], 0 to 1000 (the Earth defaults: 300).
    aerosol_type : str, optional
        An OPAC aerosol type with Mie optics (:data:`skyscatter.atmosphere.aerosol_types.AEROSOL_TYPES`, Hess et
        al. 1998), its optical depth at 550 nm ``aerosol_optical_depth`` (default: the type's own).
    atmosphere_file : str, optional
        A JSON file with the air (:meth:`AtmosphereParameters.load_json`, written by ``skyscatter
        fit-atmosphere``); the other medium options change it.
    mie_phase_g : float, optional
        Asymmetry g of the aerosol phase function, -0.99 to 0.99 (the Earth defaults: 0.8).
    tables : {"spectral", "rgb"}, optional
        Which tables to build from the atmosphere: "spectral" (the default, 16 wavelengths from 400 to 700 nm,
        colour within delta-xy 0.003 of a 41-wavelength computation) or "rgb" (3, about 30 % quicker to build,
        colour wrong at low sun: ``docs/bruneton.md``). Not with ``precomputed`` tables, which have their own.

    The medium options (:data:`skyscatter.atmosphere.options.ATMOSPHERE_OPTIONS`, applied by
    :meth:`AtmosphereParameters.from_options`) change the Earth defaults (or ``atmosphere``); each atmosphere's
    tables are computed once and cached. Deprecated spellings (until the next release): ``albedo`` for
    ``ground_albedo``, ``wavelengths`` for ``tables``, and tables passed as ``atmosphere`` (now ``precomputed``).

    Notes
    -----
    Tables from parameters have the default wavelengths (16, 400-700 nm: the spectral mode); for the faster
    3-wavelength mode pass ``tables="rgb"``. In the spectral mode
    ``spectral_radiance`` is the tables' own spectrum: the table radiance at the table wavelengths,
    ``E_sun(lambda)`` times ``L / E_sun`` interpolated linearly in wavelength between them, and zero outside
    the table range; ``xyz`` is the CIE 1931 observer integral of that spectrum. With 3 wavelengths both are
    reconstructed from the three samples by a model of the spectrum's shape (less accurate in twilight). See
    :mod:`skyscatter.precomputed.conversion` and ``docs/bruneton.md``.
    """

    model_name = "bruneton"
    renders_ground = True

    @renamed_keywords(albedo="ground_albedo", wavelengths="tables")
    def __init__(self, sun_zenith: float, sun_azimuth: float, *, altitude: float = 0.0,
                 atmosphere: AtmosphereParameters | None = None, precomputed: PrecomputedAtmosphere | None = None,
                 turbidity: float | None = None, aerosol_optical_depth: float | None = None,
                 angstrom_alpha: float | None = None, ground_albedo: float | None = None,
                 ozone_column: float | None = None, mie_phase_g: float | None = None, aerosol_type: str | None = None,
                 atmosphere_file: str | None = None, tables: str | None = None) -> None:
        zen, azi = check_sun_angles(sun_zenith, sun_azimuth, allow_below_horizon=True)
        if isinstance(atmosphere, PrecomputedAtmosphere):  # the spelling before the glossary
            if precomputed is not None:
                raise InvalidParameterError("give the tables as precomputed= only")
            warn_renamed("atmosphere=<tables>", "precomputed=<tables>", "BrunetonSky")
            atmosphere, precomputed = None, atmosphere
        medium = {k: v for k, v in (("turbidity", turbidity), ("aerosol_optical_depth", aerosol_optical_depth),
                                    ("angstrom_alpha", angstrom_alpha), ("ground_albedo", ground_albedo),
                                    ("ozone_column", ozone_column), ("mie_phase_g", mie_phase_g),
                                    ("aerosol_type", aerosol_type), ("atmosphere_file", atmosphere_file))
                  if v is not None}
        alt = registry.get(self.model_name).parameter("altitude").check(altitude, self.model_name)
        if precomputed is not None:
            if not isinstance(precomputed, PrecomputedAtmosphere):
                raise InvalidParameterError(f"precomputed must be a PrecomputedAtmosphere; got "
                                            f"{type(precomputed).__name__}")
            if atmosphere is not None or medium or tables is not None:
                raise InvalidParameterError("the atmosphere, its options and tables= are not with precomputed tables "
                                            "(they hold their atmosphere and wavelengths)")
            atm = precomputed
        else:
            params = AtmosphereParameters.from_options(atmosphere, **medium)
            atm = resolve_atmosphere(params, tables=tables)
        limit = atm.parameters.max_sun_zenith
        top_altitude = atm.parameters.top_radius - atm.parameters.bottom_radius
        # Inside the atmosphere every lookup starts at the observer, with the observer's sun zenith: beyond
        # the table's limit there is no data. From above the top, lookups start where each ray enters the
        # atmosphere, with that point's own sun zenith (the kernels return 0 where it is beyond the limit),
        # so any sun zenith is valid there (terminator and night-side views from orbit).
        if zen > limit + 1e-12 and alt < top_altitude:
            raise SunBelowHorizonError(
                f"sun zenith {math.degrees(zen):.4g} deg is beyond the precomputed limit "
                f"{math.degrees(limit):.4g} deg, which applies to observers inside the atmosphere (below "
                f"{top_altitude / 1e3:g} km; above it any sun zenith is accepted). Raise the limit (up to 180 deg) "
                f"from Python with AtmosphereParameters(max_sun_zenith=math.radians(...)); 'skyscatter sky' uses "
                f"the default tables"
            )
        self.sun_zenith = zen
        self.sun_azimuth = azi
        self.altitude = alt
        #: The tables (:class:`~skyscatter.precomputed.PrecomputedAtmosphere`); their atmosphere is
        #: ``precomputed.parameters``.
        self.precomputed = atm
        self.sun_angular_radius = atm.parameters.sun_angular_radius
        self._remember(altitude=alt, atmosphere=atmosphere, precomputed=precomputed, **medium,
                       **({} if tables is None else {"tables": tables}))

    @property
    def atmosphere(self) -> PrecomputedAtmosphere:
        """Deprecated: the tables, now :attr:`precomputed` (their atmosphere is ``precomputed.parameters``)."""
        warn_renamed("BrunetonSky.atmosphere (the tables)", "BrunetonSky.precomputed", "BrunetonSky", stacklevel=3)
        return self.precomputed

    def __repr__(self) -> str:
        return (f"BrunetonSky(sun_zenith={self.sun_zenith:.6g}, sun_azimuth={self.sun_azimuth:.6g}, "
                f"altitude={self.altitude:g})")

    @cached_property
    def position(self) -> NDArray[np.float64]:
        """Observer position [m] in the planet-centred frame (on the +z axis)."""
        return np.array([0.0, 0.0, self.precomputed.parameters.bottom_radius + self.altitude])

    def table_radiance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] at the table wavelengths, shape (..., n_table_wavelengths)."""
        return self.precomputed.sky_radiance(self.position, directions, self.sun_direction)

    def spectral_radiance(self, directions: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] of sky and ground (no solar disc), (..., n_wavelengths).

        ``wavelengths`` [nm] default to 380-780 nm every 10 nm. In the spectral mode (the default tables) values
        between table wavelengths are interpolated (``L / E_sun`` linear in wavelength) and values outside the
        table range are zero (see the class notes).
        """
        wl = DEFAULT_WAVELENGTHS if wavelengths is None else as_wavelengths(wavelengths)
        return self.precomputed.sky_spectrum(self.position, directions, self.sun_direction, wl)

    def xyz(self, directions: ArrayLike) -> NDArray[np.float64]:
        """CIE 1931 XYZ [cd m^-2] of sky and ground in ``directions`` (..., 3)."""
        return self.precomputed.sky_xyz(self.position, directions, self.sun_direction)

    def luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Luminance [cd m^-2] of sky and ground in ``directions`` (...)."""
        return self.precomputed.sky_luminance(self.position, directions, self.sun_direction)

    def aerial_perspective(self, points: ArrayLike, *, shadow_length: ArrayLike | None = None
                           ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Transmittance and inscattered radiance between the observer and ``points`` (Eqs. 16-17).

        Parameters
        ----------
        points : array_like, shape (..., 3)
            Positions [m] in the local frame of the surface point below the observer (x east, y north, z up
            from the surface); the observer is at ``(0, 0, altitude)``. The planet's curvature is the caller's:
            a point 100 km away at z = 0 lies about 800 m above the curved surface.
        shadow_length : array_like, optional
            Shadowed length [m] of each view ray (light shafts, Eq. 17).

        Returns
        -------
        transmittance, inscatter : ndarray, shape (..., n_table_wavelengths)
            ``L = transmittance * L_object + inscatter`` [W m^-2 sr^-1 nm^-1] at the table wavelengths; use
            ``self.precomputed.to_xyz`` for colour.
        """
        pts = np.asarray(points, dtype=float) + np.array([0.0, 0.0, self.precomputed.parameters.bottom_radius])
        return self.precomputed.aerial_perspective(self.position, pts, self.sun_direction, shadow_length=shadow_length)

    def sun_table_radiance(self) -> NDArray[np.float64]:
        """Mean radiance of the solar disc at the table wavelengths [W m^-2 sr^-1 nm^-1] (after transmission)."""
        return self.precomputed.sun_radiance(self.position, self.sun_direction)

    def sun_spectral_radiance(self, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Mean spectral radiance of the solar disc [W m^-2 sr^-1 nm^-1] seen by the observer (Eq. 9)."""
        wl = DEFAULT_WAVELENGTHS if wavelengths is None else as_wavelengths(wavelengths)
        return self.precomputed.resample(self.sun_table_radiance(), wl)

    def sun_xyz(self) -> NDArray[np.float64]:
        """CIE XYZ [cd m^-2] of the solar disc after transmission."""
        return self.precomputed.to_xyz(self.sun_table_radiance())
