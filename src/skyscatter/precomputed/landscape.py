"""The precomputed atmosphere in the landscape renderer: aerial perspective and light shafts (Eqs. 16-18).

Bruneton & Neyret (2008), Sec. 5, render terrain seen through the atmosphere with Eq. 16,
``L = T(x, x_o) L_o + S|x - T(x, x_o) S|x_o``, and light shafts by moving the total length ``l`` of the view
ray that lies in terrain shadow to one end of the ray: to the object's end for rays that meet the terrain
(Eq. 17, ``x_s = x_o - l v``) and to the camera's end for rays that see the sky (Eq. 18, ``x_s = x + l v``).
The paper finds ``l`` with a shadow-volume pass on the GPU; here it is estimated on the CPU
(:func:`shadow_lengths`) by marching each view ray and casting a shadow ray towards the sun with the exact
heightfield tracer of :mod:`skyscatter.render.heightfield` at every sample: ``samples`` equal steps up to the
ray's end, and each step whose two ends disagree (one lit, one shadowed) is bisected ``refine`` times to place
the light/shadow boundary. A ray crossing one shadow boundary per step is measured to within
``step / 2**(refine + 1)``; shadows thinner than a step between two samples of the same state are missed.

:class:`BrunetonAerialPerspective` is the aerial-perspective provider of :class:`skyscatter.render.Scene`
(the protocol of :mod:`skyscatter.aerial.base`). The renderer works in a flat East-North-Up world whose
heights are above sea level; the camera is put on the planet-centred frame's +z axis at radius
``bottom_radius + height`` and scene points at ``camera + s v`` (directions are the same vectors in both
frames), as :meth:`skyscatter.BrunetonSky.aerial_perspective` does, so points far away lie above the curved
sea level by about ``s^2 / (2 R)`` (200 m at 50 km): the planet's curvature is ignored by the flat terrain,
and rays longer than the distance to the sphere are cut there.

Wavelengths: the tables hold a few wavelengths (3 by default); the renderer asks for its own grid.
Inscattered radiance is resampled with the atmosphere's reconstruction (:mod:`.conversion`,
``atmosphere.resample``). Transmittance is reconstructed physically: the tables' optical depths
``-ln T(lambda_k) = beta_R(lambda_k) L_R + beta_M^e(lambda_k) L_M + beta_O(lambda_k) L_O`` (Eq. 5 with the
ozone term of the 2017 rewrite) are solved for the three optical lengths ``L_i`` [m] of each path (least
squares for more than 3 table wavelengths), and ``T(lambda) = exp(-sum_i beta_i(lambda) L_i)`` is evaluated at
the renderer's wavelengths with the atmosphere's own coefficients. When the renderer's wavelengths are the
table's, values pass through unchanged.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..aerial.base import check_path
from ..conventions import as_directions
from ..errors import InvalidParameterError
from ..render.heightfield import HeightfieldTracer, _trace
from ..render.terrain import Terrain
from ..spectral import as_wavelengths
from .parameters import AtmosphereParameters

__all__ = ["DEFAULT_REFINE", "DEFAULT_SHADOW_SAMPLES", "BrunetonAerialPerspective", "shadow_lengths",
           "transmittance_matrix"]

#: Equal steps along each view ray of the shadow-length estimate.
DEFAULT_SHADOW_SAMPLES = 32
#: Bisections of each step whose ends disagree (the boundary is then placed within step / 2**(refine + 1)).
DEFAULT_REFINE = 8


# --------------------------------------------------------------------------------------------- shadow length

@numba.njit(cache=True, inline="always")
def _in_shadow(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, px, py, pz, sx, sy, sz, t_min, t_max):
    """True if the point sees the terrain towards the sun (the tracer's shadow test)."""
    return _trace(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, px, py, pz, sx, sy, sz,
                  t_min, t_max) != np.inf


@numba.njit(cache=True, parallel=True)
def _shadow_lengths(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, origins, dirs, dist, sun,
                    samples, refine, t_min, t_max, end_offset, out):
    n = dirs.shape[0]
    stride = 0 if origins.shape[0] == 1 else 1
    sx, sy, sz = sun[0], sun[1], sun[2]
    for i in numba.prange(n):
        k = i * stride
        ox, oy, oz = origins[k, 0], origins[k, 1], origins[k, 2]
        dx, dy, dz = dirs[i, 0], dirs[i, 1], dirs[i, 2]
        s = dist[i]
        out[i] = 0.0
        if not s > 0.0:
            continue
        # With the sun above the horizon nothing above the highest terrain is shadowed: march only the
        # part of the ray below it.
        ta = 0.0
        tb = s
        if oz > hmax:
            if dz >= 0.0:
                continue
            ta = (hmax - oz) / dz
        if dz > 0.0:
            tb = min(tb, (hmax - oz) / dz)
        if tb <= ta:
            continue
        # The ray's end is on the surface when it meets the terrain: test just before it.
        last = tb - end_offset if tb == s else tb
        if last <= ta:
            last = 0.5 * (ta + tb)
        step = (tb - ta) / samples
        t_prev = ta
        prev = _in_shadow(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, ox + ta * dx, oy + ta * dy,
                          oz + ta * dz, sx, sy, sz, t_min, t_max)
        total = 0.0
        for j in range(1, samples + 1):
            t_cur = ta + j * step
            t_test = min(t_cur, last)
            cur = _in_shadow(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, ox + t_test * dx,
                             oy + t_test * dy, oz + t_test * dz, sx, sy, sz, t_min, t_max)
            if cur == prev:
                if cur:
                    total += t_cur - t_prev
            else:
                lo = t_prev
                hi = t_test
                for _ in range(refine):
                    mid = 0.5 * (lo + hi)
                    st = _in_shadow(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, ox + mid * dx,
                                    oy + mid * dy, oz + mid * dz, sx, sy, sz, t_min, t_max)
                    if st == prev:
                        lo = mid
                    else:
                        hi = mid
                edge = 0.5 * (lo + hi)
                if prev:
                    total += edge - t_prev
                else:
                    total += t_cur - edge
            prev = cur
            t_prev = t_cur
        out[i] = min(total, s)


def shadow_lengths(tracer: HeightfieldTracer | Terrain, origins: ArrayLike, directions: ArrayLike,
                   distances: ArrayLike, sun_direction: ArrayLike, *, samples: int = DEFAULT_SHADOW_SAMPLES,
                   refine: int = DEFAULT_REFINE) -> NDArray[np.float64]:
    """Length [m] of each view ray that lies in the terrain's shadow (ray marching with exact shadow rays).

    Parameters
    ----------
    tracer : HeightfieldTracer or Terrain
        The terrain (a tracer is built for a Terrain).
    origins : array_like, shape (3,) or (..., 3)
        Ray origins [m, ENU, heights above sea level]; one origin may be shared by all rays.
    directions : array_like, shape (..., 3)
        View directions (normalised here).
    distances : array_like, shape (...)
        Length [m] of each ray: the distance to the terrain for rays that hit it; for rays that miss, any
        finite length (the part above the highest terrain point is never shadowed and is not marched).
    sun_direction : array_like, shape (3,)
        Unit vector towards the sun; with the sun on or below the horizon every length is 0 (the Earth's own
        shadow is in the tables).
    samples : int
        Equal steps per ray (>= 1).
    refine : int
        Bisections of each step whose ends disagree (>= 0).

    Returns
    -------
    ndarray, shape (...)
        Shadowed length [m], in [0, distance].
    """
    if isinstance(tracer, Terrain):
        tracer = HeightfieldTracer(tracer)
    if not isinstance(tracer, HeightfieldTracer):
        raise InvalidParameterError(f"tracer must be a HeightfieldTracer or Terrain; got {type(tracer).__name__}")
    for name, value, low in (("samples", samples, 1), ("refine", refine, 0)):
        if isinstance(value, bool) or int(value) != value or value < low:
            raise InvalidParameterError(f"{name} must be a whole number >= {low}; got {value!r}")
    d = as_directions(directions)
    shape = d.shape[:-1]
    s = np.asarray(distances, dtype=float)
    try:
        s = np.broadcast_to(s, shape)
    except ValueError:
        raise InvalidParameterError(f"distances {s.shape} do not match the directions {d.shape}") from None
    if not np.all(np.isfinite(s)) or np.any(s < 0):
        raise InvalidParameterError("distances must be finite and >= 0 [m] (give a finite length for misses)")
    o = np.asarray(origins, dtype=float)
    if o.shape[-1:] != (3,) or not np.all(np.isfinite(o)):
        raise InvalidParameterError(f"ray origins must be finite ENU positions [m], shape (..., 3); got {o.shape}")
    o2 = o.reshape(1, 3) if o.ndim == 1 else np.ascontiguousarray(np.broadcast_to(o, d.shape).reshape(-1, 3))
    sun = as_directions(sun_direction).reshape(-1)
    if sun.size != 3:
        raise InvalidParameterError("sun_direction must be a single direction (3,)")
    out = np.zeros(int(np.prod(shape, dtype=np.int64)))
    if sun[2] <= 0.0 or out.size == 0:
        return out.reshape(shape)
    t = tracer.terrain
    eps = 1e-3 * t.spacing
    _shadow_lengths(t.heights, tracer._bmax, t.wrap, tracer.block, t.spacing, t.origin[0], t.origin[1],
                    float(t.base_height), tracer._hmin, tracer._hmax, o2,
                    np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float64),
                    np.ascontiguousarray(s.reshape(-1), dtype=np.float64), np.ascontiguousarray(sun),
                    int(samples), int(refine), eps, tracer.max_distance, eps, out)
    return out.reshape(shape)


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


# --------------------------------------------------------------------------------------------- provider

class BrunetonAerialPerspective:
    """Aerial perspective and light shafts from the precomputed tables, for :class:`skyscatter.render.Scene`.

    Parameters
    ----------
    sky : BrunetonSky, PrecomputedAtmosphere, AtmosphereParameters or None
        A :class:`~skyscatter.BrunetonSky` gives the tables and the sun; otherwise the tables (None: the
        cached Earth tables) and ``sun_direction`` is required.
    sun_direction : array_like, shape (3,), optional
        Unit vector towards the sun (ENU); default the sky's.
    terrain : Terrain or HeightfieldTracer, optional
        The terrain whose shadow makes light shafts (Eqs. 17-18); None: no shafts (Eq. 16).
    camera_xy : tuple of float, optional
        Camera (x, y) [m, ENU], needed for shafts when the renderer calls the protocol methods, which give
        only the camera's height (:meth:`evaluate_rays` and :meth:`sky_radiance` take the whole position).
    samples, refine : int
        Ray-marching steps and bisections of the shadow-length estimate (:func:`shadow_lengths`).

    Raises
    ------
    InvalidParameterError
        Missing sun direction, or bad ``samples`` / ``refine``.
    """

    def __init__(self, sky=None, sun_direction: ArrayLike | None = None, *,
                 terrain: Terrain | HeightfieldTracer | None = None,
                 camera_xy: tuple[float, float] | None = None, samples: int = DEFAULT_SHADOW_SAMPLES,
                 refine: int = DEFAULT_REFINE) -> None:
        from .sky import BrunetonSky, _resolve_atmosphere

        if isinstance(sky, BrunetonSky):
            self.atmosphere = sky.atmosphere
            default_sun = sky.sun_direction
        else:
            self.atmosphere = _resolve_atmosphere(sky)
            default_sun = None
        if sun_direction is None:
            if default_sun is None:
                raise InvalidParameterError("sun_direction is required unless a BrunetonSky is given")
            sun_direction = default_sun
        self.sun_direction = as_directions(sun_direction).reshape(3)
        if isinstance(terrain, Terrain):
            terrain = HeightfieldTracer(terrain)
        if terrain is not None and not isinstance(terrain, HeightfieldTracer):
            raise InvalidParameterError(f"terrain must be a Terrain or HeightfieldTracer; got {type(terrain).__name__}")
        self.tracer = terrain
        if camera_xy is not None:
            cx, cy = (float(v) for v in camera_xy)
            if not (math.isfinite(cx) and math.isfinite(cy)):
                raise InvalidParameterError(f"camera_xy must be finite [m]; got {camera_xy!r}")
            camera_xy = (cx, cy)
        self.camera_xy = camera_xy
        for name, value, low in (("samples", samples, 1), ("refine", refine, 0)):
            if isinstance(value, bool) or int(value) != value or value < low:
                raise InvalidParameterError(f"{name} must be a whole number >= {low}; got {value!r}")
        self.samples = int(samples)
        self.refine = int(refine)
        self._matrices: dict[bytes, tuple[NDArray[np.float64], NDArray[np.float64]] | None] = {}

    @property
    def shafts(self) -> bool:
        """True when terrain shadows (light shafts) are applied."""
        return self.tracer is not None and self.sun_direction[2] > 0.0

    # -- wavelengths ------------------------------------------------------------------------------------
    def _spectral(self, wl: NDArray[np.float64]):
        """(transmittance depth matrix, inscatter reconstruction matrix) for ``wl``, or None to pass through."""
        key = wl.tobytes()
        if key not in self._matrices:
            atm = self.atmosphere
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
        return np.exp(-np.maximum(depth @ m.T, 0.0)), self.atmosphere.resample(inscatter, wl)

    # -- geometry ---------------------------------------------------------------------------------------
    def _planet(self, height: NDArray[np.float64]) -> NDArray[np.float64]:
        cam = np.zeros(height.shape + (3,))
        cam[..., 2] = self.atmosphere.parameters.bottom_radius + height
        return cam

    def _clip_to_sphere(self, d, s, height):
        """Distances cut where the straight ray from the camera meets the planet's sphere."""
        bottom = self.atmosphere.parameters.bottom_radius
        r = bottom + height
        mu = d[..., 2]
        disc = r * r * (mu * mu - 1.0) + bottom * bottom
        with np.errstate(invalid="ignore"):
            ground = np.where((mu < 0) & (disc >= 0), -r * mu - np.sqrt(np.maximum(disc, 0.0)), np.inf)
        return np.minimum(s, np.maximum(ground, 0.0))

    def _origin(self, origin: ArrayLike) -> NDArray[np.float64]:
        o = np.asarray(origin, dtype=float).reshape(-1)
        if o.shape != (3,) or not np.all(np.isfinite(o)):
            raise InvalidParameterError(f"origin must be one finite ENU position [m], shape (3,); got {o.shape}")
        return o

    def shadow_length(self, origin: ArrayLike, directions: ArrayLike, distances: ArrayLike) -> NDArray[np.float64]:
        """Shadowed length [m] of each view ray from ``origin`` (ENU [m]); zeros without terrain shafts."""
        d = as_directions(directions)
        s = np.broadcast_to(np.asarray(distances, dtype=float), d.shape[:-1])
        if not self.shafts:
            return np.zeros(s.shape)
        return shadow_lengths(self.tracer, self._origin(origin), d, s, self.sun_direction,
                              samples=self.samples, refine=self.refine)

    # -- protocol ---------------------------------------------------------------------------------------
    def evaluate_rays(self, origin: ArrayLike, directions: ArrayLike, distances: ArrayLike,
                      wavelengths: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Transmittance and inscattered radiance of rays from ``origin`` (Eq. 16, Eq. 17 with shafts).

        Parameters
        ----------
        origin : array_like, shape (3,)
            Camera position [m, ENU, height above sea level].
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
        o = self._origin(origin)
        d, s, h, wl = check_path(directions, distances, o[2], wavelengths)
        shadow = self.shadow_length(o, d, s) if self.shafts else None
        return self._evaluate(d, s, h, wl, shadow)

    def _evaluate(self, d, s, h, wl, shadow):
        s = self._clip_to_sphere(d, s, h)
        cam = self._planet(h)
        points = cam + s[..., None] * d
        if shadow is not None:
            shadow = np.minimum(shadow, s)
        tau, inscatter = self.atmosphere.aerial_perspective(cam, points, self.sun_direction, shadow_length=shadow)
        return self._to_wavelengths(tau, inscatter, wl)

    def evaluate(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                 wavelengths: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(transmittance, inscattered) of the aerial-perspective protocol (:mod:`skyscatter.aerial.base`).

        With terrain shafts the camera is at ``(camera_xy, observer_height)``; the height must then be one
        value for all rays.
        """
        d, s, h, wl = check_path(directions, distances, observer_height, wavelengths)
        if not self.shafts:
            return self._evaluate(d, s, h, wl, None)
        if self.camera_xy is None:
            raise InvalidParameterError("light shafts need the camera position: give camera_xy, or call "
                                        "evaluate_rays(origin, ...)")
        if h.size and not np.all(h == h.flat[0]):
            raise InvalidParameterError("with light shafts all rays must start from one camera (one observer_height)")
        z = float(h.flat[0]) if h.size else 0.0
        origin = np.array([self.camera_xy[0], self.camera_xy[1], z])
        return self._evaluate(d, s, h, wl, self.shadow_length(origin, d, s))

    def transmittance(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                      wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Transmittance [-] of the paths, shape (..., n_wavelengths)."""
        return self.evaluate(directions, distances, observer_height, wavelengths)[0]

    def inscattered(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                    wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """In-scattered radiance [W m^-2 sr^-1 nm^-1] of the paths (light shafts included), (..., n)."""
        return self.evaluate(directions, distances, observer_height, wavelengths)[1]

    def sky_radiance(self, origin: ArrayLike, directions: ArrayLike,
                     wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Sky radiance [W m^-2 sr^-1 nm^-1] along rays from ``origin`` that miss the terrain (Eq. 18).

        The shadowed length of each ray (marched up to where it rises above the highest terrain, or to the
        tracer's range) is moved to the camera's end: ``L = T(x, x_s) S|x_s``, ``x_s = x + l v``. Without
        terrain this is the sky of :meth:`PrecomputedAtmosphere.sky_radiance` (the spherical ground included
        for rays that meet it). Shape (..., n_wavelengths).
        """
        o = self._origin(origin)
        d = as_directions(directions)
        wl = as_wavelengths(wavelengths)
        cam = self._planet(np.full(d.shape[:-1], o[2]))
        shadow = None
        if self.shafts:
            reach = np.full(d.shape[:-1], self.tracer.max_distance)
            shadow = self.shadow_length(o, d, reach)
        rad = self.atmosphere.sky_radiance(cam, d, self.sun_direction, shadow_length=shadow)
        return rad if self._spectral(wl) is None else self.atmosphere.resample(rad, wl)
