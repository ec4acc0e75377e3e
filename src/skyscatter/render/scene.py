"""Landscape rendering: heightfield terrain under a sky, with aerial perspective (Preetham et al. 1999, Sec. 5).

For each pixel of a pinhole camera the view ray is cast against the terrain
(:class:`~skyscatter.render.heightfield.HeightfieldTracer`). Where it hits at distance s, the terrain's
radiance is

    L_0 = rho / pi * (E_sun max(0, n . omega_sun) V + E_sky(n) + rho E_h (1 - n_z) / 2)

(Lambertian albedo rho; direct sunlight ``E_sun = L_sun Omega_sun`` [W m^-2 nm^-1] with the terrain shadow
V from a shadow ray towards the sun's centre and the sky's cloud shadows (``sky.sun_shadow``, a 3D cloud
field); sky irradiance on the tilted surface ``E_sky(n)``; light
reflected by the surrounding ground, taken as a horizontal plane of the same albedo lit by the global
horizontal irradiance E_h, seen over the view factor ``(1 - n_z) / 2``), and the camera sees
``L = L_0 tau + L_in`` from the aerial-perspective model. Rays that miss see the sky model, plus the solar
disc if wanted; a miss below the horizon (a periodic terrain followed to its maximum distance) sees the
in-scattered light of that whole path.

Sky irradiance: ``E_sky(n) = integral L_sky(omega) max(0, n . omega) d omega`` over the sky hemisphere is
computed once per image by quadrature (Gauss-Legendre in cos theta x uniform azimuth, 1152 directions) for a
table of normals (tilt every 10 deg, azimuth every 15 deg) and interpolated bilinearly per pixel. The terrain
does not occlude the sky (no sky-view factor): valleys receive the full sky, a documented simplification.

Output follows the sky-image conventions: linear sRGB (D65), Y = luminance [cd m^-2] / 683, float32.
Spectra are carried at ``wavelengths`` (default 380-780 nm every 10 nm) and converted with the CIE 1931
observer at the end.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..aerial.base import AerialPerspective, PathFunctions, as_aerial_perspective
from ..aerial.scattering import hemisphere_quadrature
from ..conventions import direction_from_angles
from ..deprecation import renamed_keywords
from ..errors import InvalidParameterError
from ..sky.base import SkyModel
from ..spectral import HDR_SCALE, as_wavelengths, spectrum_to_xyz, xyz_to_linear_srgb
from .camera import PinholeCamera
from .heightfield import HeightfieldTracer
from .sun_disc import PinholeProjection, disc_deposit, disc_profile_spectral, profile_nodes_for
from .terrain import Terrain, default_terrain

__all__ = ["RenderResult", "Scene", "camera_above_ground", "default_camera"]

#: Default camera of the built-in landscape: 12 km east of its centre, 300 m above the ground, looking west.
DEFAULT_CAMERA_XY = (12_000.0, 0.0)
DEFAULT_CAMERA_HEIGHT = 300.0

_TILTS = np.radians(np.arange(0.0, 91.0, 10.0))
_NORMAL_AZIMUTHS = np.radians(np.arange(0.0, 361.0, 15.0))


def camera_above_ground(terrain: Terrain, x: float, y: float, height_above_ground: float, *, heading: float,
                        pitch: float = 0.0, fov: float = math.radians(60.0)) -> PinholeCamera:
    """A camera at ENU (x, y) [m], ``height_above_ground`` [m] over the terrain surface there.

    Angles in radians (heading from north towards east, pitch above the horizon, horizontal fov).
    """
    if not (np.isfinite(height_above_ground) and height_above_ground > 0):
        raise InvalidParameterError(
            f"camera height above the ground must be a positive length [m]; got {height_above_ground!r}"
        )
    z = float(terrain.height_at(x, y)) + float(height_above_ground)
    return PinholeCamera((float(x), float(y), z), heading, pitch, fov)


def default_camera(terrain: Terrain | None = None, *, heading: float = math.radians(270.0),
                   pitch: float = math.radians(-3.0), fov: float = math.radians(60.0)) -> PinholeCamera:
    """The demo viewpoint: (12 km, 0) ENU, 300 m above the built-in landscape, looking west by default."""
    terrain = default_terrain() if terrain is None else terrain
    x, y = DEFAULT_CAMERA_XY
    if not terrain.wrap:
        x0, x1, y0, y1 = terrain.extent
        x, y = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    return camera_above_ground(terrain, x, y, DEFAULT_CAMERA_HEIGHT, heading=heading, pitch=pitch, fov=fov)


@dataclass
class RenderResult:
    """A rendered landscape.

    Attributes
    ----------
    rgb : ndarray, float32, shape (H, W, 3)
        Linear sRGB, Y = luminance [cd m^-2] / 683 (glare applied if requested).
    distance : ndarray, float32, shape (H, W)
        Distance [m] from the camera to the terrain along each pixel's ray; inf for sky pixels.
    timings : dict
        Seconds spent per stage: ``intersection`` (view and shadow rays), ``shading``,
        ``aerial_perspective``, ``sky``, ``colour`` (spectra to RGB), ``glare``, ``setup`` and ``total``.
    """

    rgb: NDArray[np.float32]
    distance: NDArray[np.float32]
    timings: dict[str, float] = field(default_factory=dict)


class Scene:
    """A heightfield landscape under a sky, seen by a pinhole camera through the air.

    Parameters
    ----------
    sky : SkyModel
        Sky for rays that miss the terrain and for the sky irradiance; its sun (if any) lights the terrain.
    terrain : Terrain, optional
        Default: the built-in procedural mountains (:func:`~skyscatter.render.terrain.default_terrain`).
    camera : PinholeCamera, optional
        Default: :func:`default_camera` for the terrain.
    aerial : AerialPerspective, "preetham" or None
        An aerial-perspective model (:class:`skyscatter.aerial.base.AerialPerspective`; objects with the
        original ``transmittance``/``inscattered`` pair are wrapped by
        :func:`~skyscatter.aerial.base.as_aerial_perspective`); ``"preetham"`` (default) builds
        :class:`~skyscatter.aerial.PreethamAerialPerspective` for the sky with ``turbidity``; None renders
        without air between camera and terrain. Rays that miss the terrain see ``aerial.sky_radiance`` (the sky
        itself unless the model changes it, e.g. light shafts).
    turbidity : float, optional
        Haze turbidity for the default aerial perspective (default ``sky.turbidity``).
    terrain_albedo : float or array_like
        Lambertian albedo of the terrain [-], a number or one value per wavelength; default 0.2 (``albedo`` is its
        deprecated spelling).
    sun_disc : bool
        Draw the solar disc where rays miss the terrain (default True).
    wavelengths : array_like, optional
        Wavelengths [nm] of the spectral computation; default 380-780 nm every 10 nm.

    Raises
    ------
    InvalidParameterError
        A sky that is not a SkyModel, an aerial argument that is not a model, albedo outside [0, 1], or a
        camera at or below the terrain surface.
    """

    @renamed_keywords(albedo="terrain_albedo")
    def __init__(self, sky: SkyModel, *, terrain: Terrain | None = None, camera: PinholeCamera | None = None,
                 aerial: AerialPerspective | PathFunctions | str | None = "preetham",
                 turbidity: float | None = None, terrain_albedo: float | ArrayLike = 0.2,
                 sun_disc: bool = True, wavelengths: ArrayLike | None = None) -> None:
        if not isinstance(sky, SkyModel):
            raise InvalidParameterError(f"Scene needs a sky model (skyscatter.sky.SkyModel); got {type(sky).__name__}")
        self.sky = sky
        self.terrain = default_terrain() if terrain is None else terrain
        self.camera = default_camera(self.terrain) if camera is None else camera
        self.wavelengths = as_wavelengths(wavelengths)
        albedo = terrain_albedo
        a = np.asarray(albedo, dtype=float)
        if a.ndim not in (0, 1) or (a.ndim == 1 and a.shape != self.wavelengths.shape):
            raise InvalidParameterError("terrain_albedo must be a number or one value per wavelength")
        if not np.all(np.isfinite(a)) or np.any(a < 0) or np.any(a > 1):
            raise InvalidParameterError(f"terrain_albedo must be within [0, 1]; got {albedo!r}")
        self.albedo = np.broadcast_to(a, self.wavelengths.shape).astype(float)
        if isinstance(aerial, str):
            if aerial != "preetham":
                raise InvalidParameterError(f"aerial must be an aerial-perspective model, 'preetham' or None; "
                                            f"got {aerial!r}")
            from ..aerial.preetham import PreethamAerialPerspective

            aerial = PreethamAerialPerspective(sky, turbidity=turbidity)
        self.aerial: AerialPerspective | None = None if aerial is None else as_aerial_perspective(aerial)
        self.sun_disc = bool(sun_disc)
        self._check_camera()
        self._tracer: HeightfieldTracer | None = None

    def _check_camera(self) -> None:
        x, y, z = self.camera.position
        ground = float(self.terrain.height_at(x, y))
        if not z > ground:
            raise InvalidParameterError(
                f"the camera at ({x:.6g}, {y:.6g}) m is {ground - z:.4g} m below the terrain surface "
                f"(ground height {ground:.6g} m, camera height {z:.6g} m); place it above the ground"
            )

    @property
    def tracer(self) -> HeightfieldTracer:
        """The ray caster for this scene's terrain (built on first use)."""
        if self._tracer is None:
            self._tracer = HeightfieldTracer(self.terrain)
        return self._tracer

    # -- lighting -----------------------------------------------------------------------------------------
    def _sun(self) -> tuple[NDArray[np.float64] | None, NDArray[np.float64]]:
        """Sun direction (or None) and the sun's spectral irradiance at normal incidence [W m^-2 nm^-1]."""
        wl = self.wavelengths
        sun = self.sky.sun
        if sun is None:
            return None, np.zeros_like(wl)
        d = np.asarray(sun.direction, dtype=float)
        e = np.asarray(sun.spectral_irradiance_normal(wl), dtype=float)
        if d[2] <= 0 or not np.any(e > 0):
            return None, np.zeros_like(wl)
        return d, e

    def sky_irradiance_table(self) -> NDArray[np.float64]:
        """Sky spectral irradiance [W m^-2 nm^-1] on surfaces with normals on the (tilt, azimuth) grid.

        Shape (n_tilt, n_azimuth, n_wavelengths): tilts 0-90 deg every 10 deg, azimuths 0-360 deg every 15 deg.
        """
        dirs, w = hemisphere_quadrature(24, 48)
        radiance = np.asarray(self.sky.spectral_radiance(dirs, self.wavelengths), dtype=float)
        normals = direction_from_angles(_TILTS[:, None], _NORMAL_AZIMUTHS[None, :])
        cos = np.clip(normals @ dirs.T, 0.0, None)  # (nt, na, nd)
        return (cos * w) @ radiance

    # -- rendering ------------------------------------------------------------------------------------------
    def render(self, width: int, height: int, *, glare: bool = False,
               progress: Callable[[int], None] | None = None, dtype: type = np.float32) -> RenderResult:
        """Render the scene.

        Parameters
        ----------
        width, height : int
            Image size [px] (positive).
        glare : bool
            Convolve the HDR image with the eye's point-spread function (:mod:`skyscatter.render.glare`).
        progress : callable, optional
            Called with the number of image rows finished after each band of rows.
        dtype : numpy dtype
            float32 (default) or float64 for the image.

        Returns
        -------
        RenderResult
        """
        width, height = (_pixel_count(name, value) for name, value in (("width", width), ("height", height)))
        try:
            out_dtype = None if dtype is None else np.dtype(dtype)
        except TypeError:
            out_dtype = None
        if out_dtype is None or out_dtype.name not in ("float32", "float64"):
            raise InvalidParameterError(f"dtype must be numpy.float32 or numpy.float64; got {dtype!r}")
        self._check_camera()  # the camera attribute may have been replaced since __init__
        timings = dict.fromkeys(("setup", "intersection", "shading", "aerial_perspective", "sky", "colour",
                                 "glare"), 0.0)
        t_start = time.perf_counter()
        wl = self.wavelengths
        cam = self.camera
        origin = np.array(cam.position)
        tracer = self.tracer
        sun_dir, e_sun = self._sun()
        e_sky = self.sky_irradiance_table()
        e_sky_h = e_sky[0, 0]
        e_h = e_sky_h + (e_sun * sun_dir[2] if sun_dir is not None else 0.0)
        rho = self.albedo
        disc_pixels = disc_values = None  # the solar disc: sorted flat pixel indices and their spectra
        if self.sun_disc and sun_dir is not None:
            disc = self.sky.sun  # not None: _sun() found a sun above the horizon
            proj = PinholeProjection(width, height, cam.heading, cam.pitch, cam.fov)
            deposit = disc_deposit(disc.direction, disc.angular_radius, proj, nodes=profile_nodes_for(disc))
            if deposit is not None:
                flat = deposit.rows * width + deposit.cols
                order = np.argsort(flat)
                disc_pixels = flat[order]
                disc_values = deposit.values(disc_profile_spectral(disc, deposit, wl))[order]
        cmf_xyz = _xyz_matrix(wl)
        pixel = cam.pixel_angle(width)
        rgb = np.empty((height, width, 3), dtype=np.float64)
        dist = np.empty((height, width), dtype=np.float32)
        rows_per_band = max(1, 32768 // width)
        timings["setup"] = time.perf_counter() - t_start
        for r0 in range(0, height, rows_per_band):
            r1 = min(height, r0 + rows_per_band)
            t0 = time.perf_counter()
            rr, cc = np.meshgrid(np.arange(r0, r1) + 0.5, np.arange(width) + 0.5, indexing="ij")
            d = cam.directions_at(rr, cc, width, height).reshape(-1, 3)
            t = tracer.intersect(origin, d)
            hit = np.isfinite(t)
            pos = origin + t[hit, None] * d[hit]
            normals = self.terrain.normal_at(pos[:, 0], pos[:, 1])
            lit = np.zeros(pos.shape[0])
            if sun_dir is not None:
                cos_i = np.clip(normals @ sun_dir, 0.0, None)
                cand = cos_i > 0
                if np.any(cand):
                    start = pos[cand] + normals[cand] * (1e-3 * self.terrain.spacing)
                    shadowed = tracer.occluded(start, np.broadcast_to(sun_dir, start.shape), t_min=0.0)
                    lit[cand] = cos_i[cand] * ~shadowed
            t1 = time.perf_counter()
            timings["intersection"] += t1 - t0
            spec = np.empty((d.shape[0], wl.size))
            l0 = _irradiance_lookup(e_sky, normals) + (e_h * rho) * (0.5 * (1.0 - normals[:, 2]))[:, None]
            sunlit = lit[:, None] * e_sun
            if np.any(lit > 0):
                # the sky's own clouds (a 3D field) shadow the sunlight (None: the sky has none)
                cloud = self.sky.sun_shadow(pos[lit > 0], wl)
                if cloud is not None:
                    sunlit[lit > 0] *= cloud
            l0 += sunlit
            l0 *= rho / np.pi
            t2 = time.perf_counter()
            timings["shading"] += t2 - t1
            if self.aerial is not None and pos.shape[0]:
                tau, l_in = self.aerial.evaluate_rays(origin, d[hit], t[hit], wl)
                l0 *= tau  # in place: l0 is this band's own array
                l0 += l_in
            spec[hit] = l0
            t3 = time.perf_counter()
            timings["aerial_perspective"] += t3 - t2
            miss = ~hit
            if np.any(miss):
                dm = d[miss]
                if self.aerial is not None:
                    # The sky as the model sees it from the camera (e.g. light shafts, Bruneton & Neyret 2008,
                    # Eq. 18); by default the sky's own radiance.
                    sky_l = np.asarray(self.aerial.sky_radiance(origin, dm, wl, sky=self.sky), dtype=float)
                else:
                    sky_l = np.asarray(self.sky.spectral_radiance(dm, wl), dtype=float)
                below = dm[:, 2] < 0
                if self.aerial is not None and np.any(below):
                    # A periodic terrain followed to the tracer's range without a hit: the whole path's haze.
                    _, haze = self.aerial.evaluate_rays(origin, dm[below], np.full(int(below.sum()),
                                                                                    tracer.max_distance), wl)
                    sky_l[below] = haze
                if disc_pixels is not None:
                    # the disc on the sky pixels it touches (terrain in front of a pixel hides its share)
                    flat = (rr.reshape(-1)[miss] - 0.5).astype(np.int64) * width + (cc.reshape(-1)[miss] - 0.5
                                                                                     ).astype(np.int64)
                    at = np.minimum(np.searchsorted(disc_pixels, flat), disc_pixels.size - 1)
                    hit_disc = disc_pixels[at] == flat
                    if np.any(hit_disc):
                        sky_l[hit_disc] += disc_values[at[hit_disc]]
                spec[miss] = sky_l
            t4 = time.perf_counter()
            timings["sky"] += t4 - t3
            rgb[r0:r1] = (spec @ cmf_xyz).reshape(r1 - r0, width, 3)
            dist[r0:r1] = t.reshape(r1 - r0, width)
            timings["colour"] += time.perf_counter() - t4
            if progress is not None:
                progress(r1 - r0)
        t5 = time.perf_counter()
        rgb = xyz_to_linear_srgb(rgb) * HDR_SCALE
        if glare:
            from .glare import apply_glare

            tg = time.perf_counter()
            rgb = apply_glare(rgb, pixel)
            timings["glare"] = time.perf_counter() - tg
        timings["colour"] += time.perf_counter() - t5 - timings["glare"]
        timings["total"] = time.perf_counter() - t_start
        return RenderResult(rgb.astype(dtype), dist, timings)


def _pixel_count(name: str, value) -> int:
    """A positive whole number of pixels, or InvalidParameterError."""
    try:
        ok = not isinstance(value, bool) and int(value) == value and value >= 1
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise InvalidParameterError(f"image {name} must be a positive whole number of pixels; got {value!r}")
    return int(value)


def _xyz_matrix(wl: NDArray[np.float64]) -> NDArray[np.float64]:
    """(n, 3) matrix M with XYZ = spectrum @ M (CIE 1931, 683 lm/W)."""
    return spectrum_to_xyz(np.eye(wl.size), wl)


def _irradiance_lookup(table: NDArray[np.float64], normals: NDArray[np.float64]) -> NDArray[np.float64]:
    """Bilinear interpolation of the (tilt, azimuth) irradiance table at unit normals (n, 3)."""
    tilt = np.arccos(np.clip(normals[:, 2], -1.0, 1.0))
    az = np.mod(np.arctan2(normals[:, 0], normals[:, 1]), 2 * np.pi)
    gt = np.clip(tilt / _TILTS[1], 0.0, _TILTS.size - 1.0)
    ga = az / _NORMAL_AZIMUTHS[1]
    it = np.minimum(gt.astype(np.int64), _TILTS.size - 2)
    ia = np.minimum(ga.astype(np.int64), _NORMAL_AZIMUTHS.size - 2)
    ft = (gt - it)[:, None]
    fa = (ga - ia)[:, None]
    return ((table[it, ia] * (1 - fa) + table[it, ia + 1] * fa) * (1 - ft)
            + (table[it + 1, ia] * (1 - fa) + table[it + 1, ia + 1] * fa) * ft)
