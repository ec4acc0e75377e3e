"""Spectral Monte Carlo reference for the spherical atmosphere: a brute-force path tracer run on Dask.

``sky_radiance(atmosphere, directions, wavelengths, sun_zenith=...)`` traces backward paths from the observer
through the shells of an :class:`~skyscatter.atmosphere.AtmosphereParameters` medium (all orders of scattering, or
one order or a window of them with ``orders=``; Lambertian ground, the sun as a disc), with next-event estimation
to the sun, a forced first collision, Russian roulette and hero-wavelength spectral MIS ([Wilkie2014]). Results
depend only on the seed. See ``docs/montecarlo.md`` for the method and its validation.

numba kernels are in :mod:`.kernels`, random numbers in :mod:`.rng`, the Dask driver in :mod:`.driver` and the
Zarr batch front end in :mod:`.dataset`. Dask, xarray and zarr are imported only when used.

``sphere_ground_fluxes(atmosphere, wavelengths, elevation_edges=..., photons=...)`` (:mod:`.sphere`) is the forward
counterpart for horizontally uniform media: photons from the sun through the whole spherical atmosphere, the
ground's direct and diffuse irradiance and sky radiance tallied by local sun elevation (the low sun's reference
under cloud layers).
"""

from .driver import MonteCarloResult, sky_radiance, solar_disc_radiance
from .sphere import SphereGroundFluxes, sphere_direct_irradiance, sphere_ground_fluxes

__all__ = ["MonteCarloResult", "SphereGroundFluxes", "sky_radiance", "solar_disc_radiance", "sphere_direct_irradiance",
           "sphere_ground_fluxes"]
