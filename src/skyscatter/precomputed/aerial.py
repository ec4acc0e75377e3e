"""Entry points for landscape renderers: aerial perspective and light shafts from the precomputed tables.

Bruneton & Neyret (2008), Sec. 5: an object at ``x_o`` seen from ``x`` has radiance
``L = T(x, x_o) L_o + S|x - T(x, x_s) S|x_s`` (Eq. 16), where the inscattered light ``S`` comes from the 4D
tables. With terrain shadows, the total shadowed length ``l`` along the view ray (from a shadow map, shadow
volumes or ray marching) is moved to the far end of the ray, ``x_s = x_o - l v`` (Eq. 17); for rays that see the
sky, to the near end, ``x_s = x + l v`` (Eq. 18). These functions wrap the methods of
:class:`~skyscatter.precomputed.PrecomputedAtmosphere` so a renderer needs no other import; positions are
planet-centred [m] (add ``(0, 0, bottom_radius)`` to local East-North-Up coordinates whose origin is on the
surface), results are spectral at the atmosphere's table wavelengths (``atmosphere.to_xyz`` converts).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .parameters import AtmosphereParameters
from .tables import PrecomputedAtmosphere

__all__ = ["aerial_perspective", "aerial_perspective_shafts", "sky_radiance_shafts"]


def _atmosphere(atmosphere: PrecomputedAtmosphere | AtmosphereParameters | None) -> PrecomputedAtmosphere:
    from .sky import _resolve_atmosphere

    return _resolve_atmosphere(atmosphere)


def aerial_perspective(positions: ArrayLike, points: ArrayLike, sun_dir: ArrayLike, *,
                       atmosphere: PrecomputedAtmosphere | AtmosphereParameters | None = None
                       ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Transmittance and inscattered radiance between cameras and scene points (Eq. 16).

    Parameters
    ----------
    positions, points : array_like, shape (..., 3)
        Camera and object positions [m] from the planet centre (broadcast together).
    sun_dir : array_like, shape (3,) or (..., 3)
        Unit direction towards the sun.
    atmosphere : PrecomputedAtmosphere or AtmosphereParameters, optional
        Tables (default: the cached Earth tables).

    Returns
    -------
    transmittance, inscatter : ndarray, shape (..., n_wavelengths)
        ``L = transmittance * L_object + inscatter`` [W m^-2 sr^-1 nm^-1].
    """
    return _atmosphere(atmosphere).aerial_perspective(positions, points, sun_dir)


def aerial_perspective_shafts(positions: ArrayLike, points: ArrayLike, sun_dir: ArrayLike,
                              shadow_length: ArrayLike, *,
                              atmosphere: PrecomputedAtmosphere | AtmosphereParameters | None = None
                              ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`aerial_perspective` with light shafts: ``shadow_length`` [m] of each ray is in shadow (Eq. 17)."""
    return _atmosphere(atmosphere).aerial_perspective(positions, points, sun_dir, shadow_length=shadow_length)


def sky_radiance_shafts(positions: ArrayLike, directions: ArrayLike, sun_dir: ArrayLike, shadow_length: ArrayLike,
                        *, atmosphere: PrecomputedAtmosphere | AtmosphereParameters | None = None
                        ) -> NDArray[np.float64]:
    """Sky (and spherical ground) radiance along view rays whose first ``shadow_length`` [m] lie in the shadow
    of terrain (Eq. 18), shape (..., n_wavelengths) [W m^-2 sr^-1 nm^-1]."""
    return _atmosphere(atmosphere).sky_radiance(positions, directions, sun_dir, shadow_length=shadow_length)
