"""The Monte Carlo reference as a sky model (:class:`MonteCarloSky`), answering the sky protocol.

Radiances come from :func:`skyscatter.montecarlo.sky_radiance` with a fixed number of paths per direction and a
fixed seed, so a ``MonteCarloSky`` is a deterministic function of its parameters (equal inputs give bit-identical
outputs on any scheduler). Cost: one call traces ``samples`` paths per direction, shared by up to 16
wavelengths; ``xyz``/``luminance`` use the protocol's default, the spectrum at the 95 reference wavelengths
(360-830 nm, 5 nm), i.e. six wavelength groups, about 6x the cost of one ``spectral_radiance`` call at 16 or
fewer wavelengths. Method: docs/montecarlo.md.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere import AtmosphereParameters
from ..conventions import as_directions
from ..errors import InvalidParameterError
from ..spectral import DEFAULT_WAVELENGTHS, REFERENCE_WAVELENGTHS, as_wavelengths
from ..validation import whole_number
from . import registry
from .base import SkyModel, SunSkyMixin, check_sun_angles

__all__ = ["MonteCarloSky"]


class MonteCarloSky(SunSkyMixin, SkyModel):
    """Spectral Monte Carlo sky (all orders of scattering, spherical atmosphere, Lambertian ground).

    Parameters
    ----------
    sun_zenith, sun_azimuth : float
        Sun position at the observer [rad]; any zenith in [0, pi] (twilight and night included).
    atmosphere : AtmosphereParameters, optional
        The medium (default: the Earth defaults of :class:`~skyscatter.atmosphere.AtmosphereParameters`); its
        ``mie_phase_function`` ("cornette-shanks" or "henyey-greenstein") and ``mie_phase_g`` give the aerosol
        phase function.
    altitude : float
        Observer altitude [m], >= 0.
    samples : int
        Paths per direction (default 1024: about 2-3 % standard error in the visible for a clear sky).
    seed : int
        Seed of the random streams (default 0).
    scheduler : optional
        Dask scheduler for :func:`~skyscatter.montecarlo.sky_radiance` (None = local threads).
    cloud_optical_depth : float
        Optical depth at 550 nm of a horizontally uniform water cloud layer added to the atmosphere (0 = none,
        the default; :class:`~skyscatter.atmosphere.clouds.CloudLayer`), in [0, 1000].
    cloud_base, cloud_top : float
        Its base and top altitudes [m] (default 1000 and 1500 m).
    cloud_effective_radius : float
        Its droplets' effective radius [m] (default 10 um; effective variance 0.1), in [1, 50] um.
    clouds : CloudField, optional
        A 3D cloud field (:class:`~skyscatter.atmosphere.clouds.CloudField`) around the observer.

    Directions that meet the ground return the radiance of the ground (``renders_ground`` is True), as in
    :class:`~skyscatter.precomputed.sky.BrunetonSky`; the solar disc is never included (see
    :meth:`sun_spectral_radiance`).
    """

    model_name = "montecarlo"

    renders_ground = True

    def __init__(self, sun_zenith: float, sun_azimuth: float = 0.0, *, atmosphere: AtmosphereParameters | None = None,
                 altitude: float = 0.0, samples: int = 1024, seed: int = 0, scheduler: Any = None,
                 cloud_optical_depth: float = 0.0, cloud_base: float = 1000.0, cloud_top: float = 1500.0,
                 cloud_effective_radius: float = 10e-6, clouds: Any = None) -> None:
        zen, azi = check_sun_angles(sun_zenith, sun_azimuth, allow_below_horizon=True)
        base_atm = AtmosphereParameters() if atmosphere is None else atmosphere
        if not isinstance(base_atm, AtmosphereParameters):
            raise InvalidParameterError(f"atmosphere must be AtmosphereParameters; got {type(base_atm).__name__}")
        from ..atmosphere.clouds import CloudField, CloudLayer

        layer = None
        tau = float(cloud_optical_depth)
        if not (math.isfinite(tau) and tau >= 0):
            raise InvalidParameterError(f"cloud_optical_depth must be >= 0; got {cloud_optical_depth!r}")
        # validated even without a cloud (the registry's ranges hold for every value given)
        checked = CloudLayer(cloud_base, cloud_top, tau, effective_radius=cloud_effective_radius)
        if tau > 0:
            layer = checked
        if clouds is not None and not isinstance(clouds, CloudField):
            raise InvalidParameterError(f"clouds must be a CloudField or None; got {type(clouds).__name__}")
        atm = base_atm if layer is None else base_atm.replace(particles=(*base_atm.particles, layer))
        spec = registry.get(self.model_name)  # the ranges, stated once
        alt = spec.parameter("altitude").check(altitude, spec.name)
        samples = whole_number("samples", samples, 1, spec.parameter("samples").high)
        seed = whole_number("seed", seed, 0, spec.parameter("seed").high)
        self.sun_zenith = zen
        self.sun_azimuth = azi
        self.atmosphere = atm
        self.altitude = alt
        self.samples = int(samples)
        self.seed = int(seed)
        self.scheduler = scheduler
        #: ``progress(done, total)`` called as the tasks of each evaluation finish (not a model parameter).
        self.progress: Callable[[int, int], None] | None = None
        self.clouds = clouds
        self.cloud_layer = layer
        self.sun_angular_radius = atm.sun_angular_radius
        self._remember(altitude=alt, samples=self.samples, seed=self.seed, atmosphere=atmosphere,
                       cloud_optical_depth=tau, cloud_base=float(cloud_base), cloud_top=float(cloud_top),
                       cloud_effective_radius=float(cloud_effective_radius), clouds=clouds)

    def __repr__(self) -> str:
        return (f"MonteCarloSky(sun_zenith={self.sun_zenith:.6g}, sun_azimuth={self.sun_azimuth:.6g}, "
                f"altitude={self.altitude:g}, samples={self.samples}, seed={self.seed})")

    def radiance_and_error(self, directions: ArrayLike, wavelengths: ArrayLike | None = None
                           ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Spectral radiance and its standard error [W m^-2 sr^-1 nm^-1], each (..., n_wavelengths)."""
        from ..montecarlo import sky_radiance

        wl = DEFAULT_WAVELENGTHS if wavelengths is None else as_wavelengths(wavelengths)
        d = as_directions(directions, normalise=False)  # validated here, normalised by the driver
        shape = d.shape[:-1]
        res = sky_radiance(self.atmosphere, d.reshape(-1, 3), wl, sun_zenith=self.sun_zenith,
                           sun_azimuth=self.sun_azimuth, altitude=self.altitude, samples=self.samples,
                           seed=self.seed, scheduler=self.scheduler, progress=self.progress, clouds=self.clouds)
        return res.radiance.reshape(*shape, wl.size), res.stderr.reshape(*shape, wl.size)

    def estimate_seconds(self, n_directions: int, n_wavelengths: int = REFERENCE_WAVELENGTHS.size) -> float:
        """Estimated wall-clock time [s] of one evaluation over ``n_directions`` at ``n_wavelengths``
        (``xyz`` and ``luminance`` use the 95 reference wavelengths).

        Measured, not guessed: a pilot run of one task (32 directions spread over the sphere, 512 paths each, one
        wavelength group of 16, this thread) scaled by the directions, the wavelength groups and the paths, and
        divided by the threads (:func:`skyscatter.runtime.num_threads`). The pilot takes about 0.2-0.5 s.
        """
        from ..montecarlo import sky_radiance
        from ..montecarlo.driver import DEFAULT_GROUP_SIZE, batch_layout
        from ..runtime import num_threads

        n, pilot_samples = 32, 512
        z = 1.0 - (np.arange(n) + 0.5) / n * 2.0  # 32 directions equal in solid angle over the sphere
        phi = np.arange(n) * math.pi * (3.0 - math.sqrt(5.0))
        r = np.sqrt(1.0 - z * z)
        pilot_dirs = np.stack([r * np.sin(phi), r * np.cos(phi), z], axis=-1)
        wl = REFERENCE_WAVELENGTHS[np.linspace(0, REFERENCE_WAVELENGTHS.size - 1, DEFAULT_GROUP_SIZE).astype(int)]
        kw = dict(sun_zenith=self.sun_zenith, sun_azimuth=self.sun_azimuth, altitude=self.altitude, seed=self.seed,
                  scheduler="synchronous", clouds=self.clouds)
        sky_radiance(self.atmosphere, pilot_dirs[:1], wl, samples=1, **kw)  # loads the compiled kernels
        t0 = time.perf_counter()
        sky_radiance(self.atmosphere, pilot_dirs, wl, samples=pilot_samples, **kw)
        pilot = time.perf_counter() - t0
        bs, nb = batch_layout(self.samples)
        groups = -(-int(n_wavelengths) // DEFAULT_GROUP_SIZE)
        return pilot * (n_directions / n) * groups * (bs * nb / pilot_samples) / num_threads()

    def spectral_radiance(self, directions: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] of sky and ground (no solar disc), (..., n_wavelengths)."""
        return self.radiance_and_error(directions, wavelengths)[0]

    def sun_spectral_radiance(self, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Transmitted solar-disc radiance averaged over the disc [W m^-2 sr^-1 nm^-1] (deterministic)."""
        from ..montecarlo import solar_disc_radiance

        wl = DEFAULT_WAVELENGTHS if wavelengths is None else as_wavelengths(wavelengths)
        return solar_disc_radiance(self.atmosphere, wl, sun_zenith=self.sun_zenith, sun_azimuth=self.sun_azimuth,
                                   altitude=self.altitude, clouds=self.clouds)
