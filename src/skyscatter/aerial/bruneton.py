"""Aerial perspective and light shafts from the precomputed tables (Bruneton & Neyret 2008, Sec. 5, Eqs. 16-18).

Reference: [Bruneton2008].

An object at ``x_o`` seen from ``x`` has radiance ``L = T(x, x_o) L_o + S|x - T(x, x_o) S|x_o`` (Eq. 16), the
inscattered light ``S`` coming from the 4D tables. With terrain shadows, the total length ``l`` of the view ray
that lies in shadow is moved to one end of the ray: to the object's end for rays that meet the terrain
(Eq. 17, ``x_s = x_o - l v``) and to the camera's end for rays that see the sky (Eq. 18, ``x_s = x + l v``).
The paper finds ``l`` with a shadow-volume pass on the GPU; here any :class:`~skyscatter.aerial.base.ShadowCaster`
gives it (the heightfield tracer of :mod:`skyscatter.render.heightfield` estimates it by ray marching).

* :func:`aerial_perspective`, :func:`aerial_perspective_shafts`, :func:`sky_radiance_shafts` - Eqs. 16-18 for
  planet-centred positions [m] (add ``(0, 0, bottom_radius)`` to local East-North-Up coordinates whose origin
  is on the surface), spectral at the atmosphere's table wavelengths (``atmosphere.to_xyz`` converts).
* :class:`BrunetonAerialPerspective` - the same as an aerial-perspective model
  (:class:`~skyscatter.aerial.base.AerialPerspective`) for :class:`skyscatter.render.Scene`. The renderer
  works in a flat East-North-Up world whose heights are above sea level; the camera is put on the
  planet-centred frame's +z axis at radius ``bottom_radius + height`` and scene points at ``camera + s v``
  (directions are the same vectors in both frames), as :meth:`skyscatter.BrunetonSky.aerial_perspective` does,
  so points far away lie above the curved sea level by about ``s^2 / (2 R)`` (200 m at 50 km): the planet's
  curvature is ignored by the flat terrain, and rays longer than the distance to the sphere are cut there.

Wavelengths: the tables hold a few wavelengths (3 by default); the renderer asks for its own grid.
Inscattered radiance is resampled with the atmosphere's reconstruction (:mod:`skyscatter.precomputed.conversion`,
``atmosphere.resample``). Transmittance is reconstructed physically: the tables' optical depths
``-ln T(lambda_k) = beta_R(lambda_k) L_R + beta_M^e(lambda_k) L_M + beta_O(lambda_k) L_O`` (Eq. 5 with the
ozone term of the 2017 rewrite) are solved for the three optical lengths ``L_i`` [m] of each path (least
squares for more than 3 table wavelengths), and ``T(lambda) = exp(-sum_i beta_i(lambda) L_i)`` is evaluated at
the renderer's wavelengths with the atmosphere's own coefficients. When the renderer's wavelengths are the
table's, values pass through unchanged.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..conventions import as_directions
from ..deprecation import warn_renamed
from ..errors import InvalidParameterError
from ..precomputed import AtmosphereParameters, PrecomputedAtmosphere
from ..precomputed.cache import resolve_atmosphere
from ..sky.base import SkyModel
from ..sky.bruneton import BrunetonSky
from ..spectral import as_wavelengths
from ..validation import whole_number
from .base import DEFAULT_REFINE, DEFAULT_SHADOW_SAMPLES, AerialPerspective, ShadowCaster, check_path, check_rays

__all__ = ["BrunetonAerialPerspective", "aerial_perspective", "aerial_perspective_shafts", "sky_radiance_shafts",
           "transmittance_matrix"]


# --------------------------------------------------------------------------------------------- functions

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
    return resolve_atmosphere(atmosphere).aerial_perspective(positions, points, sun_dir)


def aerial_perspective_shafts(positions: ArrayLike, points: ArrayLike, sun_dir: ArrayLike,
                              shadow_length: ArrayLike, *,
                              atmosphere: PrecomputedAtmosphere | AtmosphereParameters | None = None
                              ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`aerial_perspective` with light shafts: ``shadow_length`` [m] of each ray is in shadow (Eq. 17)."""
    return resolve_atmosphere(atmosphere).aerial_perspective(positions, points, sun_dir, shadow_length=shadow_length)


def sky_radiance_shafts(positions: ArrayLike, directions: ArrayLike, sun_dir: ArrayLike, shadow_length: ArrayLike,
                        *, atmosphere: PrecomputedAtmosphere | AtmosphereParameters | None = None
                        ) -> NDArray[np.float64]:
    """Sky (and spherical ground) radiance along view rays whose first ``shadow_length`` [m] lie in the shadow
    of terrain (Eq. 18), shape (..., n_wavelengths) [W m^-2 sr^-1 nm^-1]."""
    return resolve_atmosphere(atmosphere).sky_radiance(positions, directions, sun_dir, shadow_length=shadow_length)


# --------------------------------------------------------------------------------------------- wavelengths

def transmittance_matrix(table_wavelengths: ArrayLike, wavelengths: ArrayLike,
                         params: AtmosphereParameters) -> NDArray[np.float64]:
    """Matrix M (n_out, n_table) with ``-ln T(wavelengths) = M @ (-ln T(table_wavelengths))``.

    The optical depth of any path is ``sum_i beta_i(lambda) L_i`` over Rayleigh scattering, aerosol
    extinction and ozone absorption (Bruneton & Neyret 2008, Eq. 5; ozone as in the 2017 rewrite), so the
    optical lengths ``L_i`` [m] follow from the table wavelengths (exactly for 3, least squares for more) and
    give the depth at any wavelength. Absorbers absent from the atmosphere (zero coefficients) are left out.
    """
    tw = np.asarray(table_wavelengths, dtype=float)
    wl = np.asarray(wavelengths, dtype=float)
    cols = (params.rayleigh_scattering_at, params.mie_extinction_at, params.ozone_absorption_at)
    b_tab = np.stack([np.asarray(f(tw), dtype=float) for f in cols], axis=-1)
    keep = np.any(b_tab != 0.0, axis=0)
    b_tab = b_tab[:, keep]
    b_out = np.stack([np.asarray(f(wl), dtype=float) for f, k in zip(cols, keep, strict=True) if k], axis=-1)
    if b_tab.shape[1] > tw.size:
        raise InvalidParameterError(
            f"{tw.size} table wavelength(s) cannot separate {b_tab.shape[1]} extinction components; "
            "compute the tables at 3 or more wavelengths"
        )
    # Scale columns to unit norm so the pseudo-inverse is not dominated by the largest coefficient.
    norm = np.linalg.norm(b_tab, axis=0)
    return (b_out / norm) @ np.linalg.pinv(b_tab / norm)


# --------------------------------------------------------------------------------------------- model

class BrunetonAerialPerspective(AerialPerspective):
    """Aerial perspective and light shafts from the precomputed tables, for :class:`skyscatter.render.Scene`.

    Parameters
    ----------
    sky : BrunetonSky, PrecomputedAtmosphere, AtmosphereParameters or None
        A :class:`~skyscatter.sky.bruneton.BrunetonSky` gives the tables and the sun; otherwise the tables
        (None: the cached Earth tables) and ``sun_direction`` is required.
    sun_direction : array_like, shape (3,), optional
        Unit vector towards the sun (ENU); default the sky's.
    terrain : ShadowCaster, optional
        What shadows the air (a :class:`skyscatter.render.heightfield.HeightfieldTracer`): light shafts
        (Eqs. 17-18); None: no shafts (Eq. 16).
    camera_xy : tuple of float, optional
        Camera (x, y) [m, ENU], needed for shafts when the renderer calls :meth:`evaluate`, which gives only
        the camera's height (:meth:`evaluate_rays` and :meth:`sky_radiance` take whole positions).
    samples, refine : int
        Ray-marching steps and bisections of the shadow-length estimate
        (:meth:`~skyscatter.aerial.base.ShadowCaster.shadow_lengths`).

    Raises
    ------
    InvalidParameterError
        Missing sun direction, a terrain that is not a ShadowCaster, or bad ``samples`` / ``refine``.
    """

    def __init__(self, sky: BrunetonSky | PrecomputedAtmosphere | AtmosphereParameters | None = None,
                 sun_direction: ArrayLike | None = None, *, terrain: ShadowCaster | None = None,
                 camera_xy: tuple[float, float] | None = None, samples: int = DEFAULT_SHADOW_SAMPLES,
                 refine: int = DEFAULT_REFINE) -> None:
        if isinstance(sky, BrunetonSky):
            self.sky = sky
            self.precomputed = sky.precomputed
            default_sun = sky.sun_direction
        else:
            self.precomputed = resolve_atmosphere(sky)
            default_sun = None
        if sun_direction is None:
            if default_sun is None:
                raise InvalidParameterError("sun_direction is required unless a BrunetonSky is given")
            sun_direction = default_sun
        self.sun_direction = as_directions(sun_direction).reshape(3)
        if terrain is not None and not isinstance(terrain, ShadowCaster):
            raise InvalidParameterError(
                f"terrain must be a ShadowCaster such as skyscatter.render.heightfield.HeightfieldTracer; got "
                f"{type(terrain).__name__}"
            )
        self.terrain = terrain
        if camera_xy is not None:
            cx, cy = (float(v) for v in camera_xy)
            if not (math.isfinite(cx) and math.isfinite(cy)):
                raise InvalidParameterError(f"camera_xy must be finite [m]; got {camera_xy!r}")
            camera_xy = (cx, cy)
        self.camera_xy = camera_xy
        self.samples = whole_number("samples", samples, 1, integral_floats=True)
        self.refine = whole_number("refine", refine, 0, integral_floats=True)
        self._matrices: dict[bytes, NDArray[np.float64] | None] = {}

    @property
    def atmosphere(self) -> PrecomputedAtmosphere:
        """Deprecated: the tables, now :attr:`precomputed`."""
        warn_renamed("BrunetonAerialPerspective.atmosphere (the tables)", "BrunetonAerialPerspective.precomputed",
                     "BrunetonAerialPerspective", stacklevel=3)
        return self.precomputed

    @property
    def shafts(self) -> bool:
        """True when terrain shadows (light shafts) are applied."""
        return self.terrain is not None and self.sun_direction[2] > 0.0

    # -- wavelengths ------------------------------------------------------------------------------------
    def _spectral(self, wl: NDArray[np.float64]) -> NDArray[np.float64] | None:
        """Optical-depth matrix (:func:`transmittance_matrix`) for ``wl``, or None to pass table values through."""
        key = wl.tobytes()
        if key not in self._matrices:
            atm = self.precomputed
            if wl.shape == atm.wavelengths.shape and np.allclose(wl, atm.wavelengths, rtol=0, atol=1e-9):
                self._matrices[key] = None
            else:
                self._matrices[key] = transmittance_matrix(atm.wavelengths, wl, atm.parameters)
        return self._matrices[key]

    def _to_wavelengths(self, tau, inscatter, wl):
        m = self._spectral(wl)
        if m is None:
            return tau, inscatter
        depth = -np.log(np.clip(tau, 1e-300, 1.0))
        return np.exp(-np.maximum(depth @ m.T, 0.0)), self.precomputed.resample(inscatter, wl)

    # -- geometry ---------------------------------------------------------------------------------------
    def _planet(self, height: NDArray[np.float64]) -> NDArray[np.float64]:
        cam = np.zeros(height.shape + (3,))
        cam[..., 2] = self.precomputed.parameters.bottom_radius + height
        return cam

    def _clip_to_sphere(self, d, s, height):
        """Distances cut where the straight ray from the camera meets the planet's sphere."""
        bottom = self.precomputed.parameters.bottom_radius
        r = bottom + height
        mu = d[..., 2]
        disc = r * r * (mu * mu - 1.0) + bottom * bottom
        with np.errstate(invalid="ignore"):
            ground = np.where((mu < 0) & (disc >= 0), -r * mu - np.sqrt(np.maximum(disc, 0.0)), np.inf)
        return np.minimum(s, np.maximum(ground, 0.0))

    def shadow_length(self, origins: ArrayLike, directions: ArrayLike, distances: ArrayLike) -> NDArray[np.float64]:
        """Shadowed length [m] of each view ray from ``origins`` (ENU [m]); zeros without terrain shafts."""
        d = as_directions(directions)
        s = np.broadcast_to(np.asarray(distances, dtype=float), d.shape[:-1])
        if not self.shafts:
            return np.zeros(s.shape)
        return self.terrain.shadow_lengths(origins, d, s, self.sun_direction, samples=self.samples,
                                           refine=self.refine)

    # -- protocol ---------------------------------------------------------------------------------------
    def evaluate_rays(self, origins: ArrayLike, directions: ArrayLike, distances: ArrayLike,
                      wavelengths: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Transmittance and inscattered radiance of rays from ``origins`` (Eq. 16, Eq. 17 with shafts).

        Parameters
        ----------
        origins : array_like, shape (3,) or (..., 3)
            Camera positions [m, ENU, height above sea level].
        directions : array_like, shape (..., 3)
            Unit view directions.
        distances : array_like, shape (...)
            Distance [m] to the object along each ray.
        wavelengths : array_like, optional
            [nm]; default 380-780 nm every 10 nm.

        Returns
        -------
        tau, inscatter : ndarray, shape (..., n_wavelengths)
            ``L = tau L_0 + inscatter`` [W m^-2 sr^-1 nm^-1].
        """
        o, d, s, wl = check_rays(origins, directions, distances, wavelengths)
        shadow = self.shadow_length(o, d, s) if self.shafts else None
        return self._evaluate(d, s, o[..., 2], wl, shadow)

    def _evaluate(self, d, s, h, wl, shadow):
        s = self._clip_to_sphere(d, s, h)
        cam = self._planet(h)
        points = cam + s[..., None] * d
        if shadow is not None:
            shadow = np.minimum(shadow, s)
        tau, inscatter = self.precomputed.aerial_perspective(cam, points, self.sun_direction, shadow_length=shadow)
        return self._to_wavelengths(tau, inscatter, wl)

    def evaluate(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                 wavelengths: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(transmittance, inscattered) for an observer at height ``observer_height`` [m].

        With terrain shafts the camera is at ``(camera_xy, observer_height)``; the height must then be one
        value for all rays.
        """
        d, s, h, wl = check_path(directions, distances, observer_height, wavelengths)
        if not self.shafts:
            return self._evaluate(d, s, h, wl, None)
        if self.camera_xy is None:
            raise InvalidParameterError("light shafts need the camera position: give camera_xy, or call "
                                        "evaluate_rays(origins, ...)")
        if h.size and not np.all(h == h.flat[0]):
            raise InvalidParameterError("with light shafts all rays must start from one camera (one observer_height)")
        z = float(h.flat[0]) if h.size else 0.0
        origin = np.array([self.camera_xy[0], self.camera_xy[1], z])
        return self._evaluate(d, s, h, wl, self.shadow_length(origin, d, s))

    def sky_radiance(self, origins: ArrayLike, directions: ArrayLike, wavelengths: ArrayLike | None = None, *,
                     sky: SkyModel | None = None) -> NDArray[np.float64]:
        """Sky radiance [W m^-2 sr^-1 nm^-1] along rays from ``origins`` that miss the terrain (Eq. 18).

        The shadowed length of each ray (marched up to where it rises above the highest terrain, or to the
        caster's range) is moved to the camera's end: ``L = T(x, x_s) S|x_s``, ``x_s = x + l v``. Without
        terrain this is the sky of :meth:`PrecomputedAtmosphere.sky_radiance` (the spherical ground included
        for rays that meet it). ``sky`` is not used: the tables are this model's sky. Shape (..., n_wavelengths).
        """
        d = as_directions(directions)
        o = np.asarray(origins, dtype=float)
        if o.shape[-1:] != (3,) or not np.all(np.isfinite(o)):
            raise InvalidParameterError(f"ray origins must be finite ENU positions [m], shape (..., 3); got {o.shape}")
        try:
            o = np.broadcast_to(o, d.shape)
        except ValueError:
            raise InvalidParameterError(f"origins {o.shape} do not broadcast with directions {d.shape}") from None
        wl = as_wavelengths(wavelengths)
        cam = self._planet(o[..., 2])
        shadow = None
        if self.shafts:
            reach = np.full(d.shape[:-1], self.terrain.max_distance)
            shadow = self.shadow_length(o, d, reach)
        rad = self.precomputed.sky_radiance(cam, d, self.sun_direction, shadow_length=shadow)
        return rad if self._spectral(wl) is None else self.precomputed.resample(rad, wl)
