"""Spectral Monte Carlo reference for the spherical atmosphere: a brute-force path tracer run on Dask.

``sky_radiance(atmosphere, directions, wavelengths, sun_zenith=...)`` traces backward paths from the observer
through the shells of an :class:`~skyscatter.atmosphere.AtmosphereParameters` medium (all orders of scattering,
Lambertian ground, the sun as a disc), with next-event estimation to the sun, a forced first collision,
Russian roulette and hero-wavelength spectral MIS ([Wilkie2014]). Results depend
only on the seed. See ``docs/montecarlo.md`` for the method and its validation.

numba kernels are in :mod:`.kernels`, random numbers in :mod:`.rng`, the Dask driver in :mod:`.driver` and the
Zarr batch front end in :mod:`.dataset`. Dask, xarray and zarr are imported only when used.
"""

from .driver import MonteCarloResult, sky_radiance, solar_disc_radiance

__all__ = ["MonteCarloResult", "sky_radiance", "solar_disc_radiance"]
