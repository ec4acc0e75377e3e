"""Clouds in the medium: 3D cloud fields (gridded extinction over a box) and their procedural generation.

A :class:`CloudField` is a grid of ``nx x ny x nz`` voxels of constant extinction coefficient [m^-1] at a
reference wavelength (550 nm) over a box anchored at the observer's foot point on the planet: horizontally
``origin[0] <= x <= origin[0] + size[0]`` (east) and ``origin[1] <= y <= origin[1] + size[1]`` (north) [m]
in the tangent plane there, vertically between the altitudes ``base`` and ``top`` [m] above the ground. The
voxel boundaries are vertical planes in x and y and spheres of constant altitude, so a field of one column
is exactly a spherical shell. The sides are periodic (the field repeats with its size) or open (no cloud
outside the box). What the droplets do at each wavelength (extinction spectrum relative to the reference
wavelength, single-scattering albedo, phase function) is a particle component (:mod:`.particles`): the
same description as the aerosols and the horizontally uniform cloud layers; the field holds only where the
cloud is and how dense.

Sources of fields:

* :meth:`CloudField.from_array` - a numpy array (extinction, or liquid water content with
  :meth:`CloudField.from_liquid_water_content`);
* :meth:`CloudField.load` / :meth:`CloudField.save` - NetCDF (``.nc``) or Zarr (``.zarr``) through xarray: a
  variable ``extinction`` [m^-1] on dimensions ``(x, y, z)`` with cell-centre coordinates [m] and the
  attributes ``periodic``, ``base``, ``top``, ``reference_wavelength``. (OpenVDB: the PyPI binding
  ``pyopenvdb`` was last released in 2020 and builds against no current Python; not supported.)
* :meth:`CloudField.procedural` - fractal Perlin-Worley noise remapped by a cloud cover fraction, in the
  manner of the real-time cloudscapes of [Schneider2015] and [Schneider2017]: a periodic 2D coverage map
  thresholded at the requested cover fraction (exactly that fraction of the columns is cloudy), a cloud top
  that rises with the coverage value, 3D Worley erosion of the edges, and a liquid water content rising
  linearly from the base (adiabatic clouds; [Brenguier2000] Sec. 2), scaled to the requested mean optical
  depth of the cloudy columns. Deterministic for a seed.
* :meth:`CloudField.i3rc_step_cloud` - the step cloud of the I3RC Phase 1 case 1 ([Cahalan2005]): 32 periodic
  columns across 0.5 km, 16 of optical depth 2 and 16 of 18, 0.25 km thick, uniform in y.

The noise (no PyPI noise library gives periodic 3D gradient and cellular noise on numpy arrays: ``noise``
evaluates one point per Python call and ``opensimplex`` is not periodic) is written here: Perlin's improved
gradient noise ([Perlin2002]: quintic fade ``6t^5 - 15t^4 + 10t^3`` and 12 edge gradients) on a periodic
lattice, and Worley's cellular noise ([Worley1996]: distance to the nearest of one random feature point per
cell, the neighbours taken with wrap-around); fractal sums of octaves doubling the frequency
and halving the amplitude stay periodic. The random tables (a gradient per lattice node, a feature point per
cell) are drawn with numpy's generator of the seed; each octave's loop over the points is compiled with numba
(:mod:`._noise_numba`, loaded on first use): 0.1 CPU-s for the 0.5 million voxels of a 128 x 128 x 32 field
against 2 s for the numpy evaluation it replaced, which gave the same fields to the last bit.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import FileFormatError, InvalidParameterError, OutputError
from ..fileio import atomic_path, check_output_path
from ..validation import whole_number
from .particles import ParticleComponent, register_particle_kind

__all__ = ["CloudField", "CloudLayer", "REFERENCE_WAVELENGTH", "MAX_VOXELS", "perlin_fbm", "worley_fbm"]

#: Wavelength [nm] at which a field's extinction is given.
REFERENCE_WAVELENGTH = 550.0
#: Largest number of voxels of a field (2^27: 1 GiB of float64).
MAX_VOXELS = 2**27
#: Largest extinction coefficient of a voxel [m^-1] (an optical depth of 1000 per 10 m).
MAX_EXTINCTION = 100.0
#: Density of liquid water [kg m^-3] (at 4 deg C; the conversion of liquid water content to extinction).
WATER_DENSITY = 1000.0


def _number(name: str, value: Any, lo: float = -math.inf, hi: float = math.inf, unit: str = "m") -> float:
    if isinstance(value, bool):
        raise InvalidParameterError(f"{name} must be a number [{unit}]; got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a number [{unit}]; got {value!r}") from None
    if not (math.isfinite(v) and lo <= v <= hi):
        raise InvalidParameterError(f"{name} must be in [{lo:g}, {hi:g}] {unit}; got {value!r}")
    return v


def _pair(name: str, value: Any, lo: float, hi: float) -> tuple[float, float]:
    v = np.atleast_1d(np.asarray(value, dtype=object))
    if v.size == 1:
        v = np.array([v[0], v[0]], dtype=object)
    if v.size != 2:
        raise InvalidParameterError(f"{name} must be one number or a pair (x, y) [m]; got {value!r}")
    return _number(f"{name}[0]", v[0], lo, hi), _number(f"{name}[1]", v[1], lo, hi)


class CloudField:
    """A gridded 3D cloud: extinction [m^-1] at :data:`REFERENCE_WAVELENGTH` per voxel (module docstring).

    Parameters
    ----------
    extinction : array_like, shape (nx, ny, nz)
        Extinction coefficient of each voxel at 550 nm [m^-1], finite, in [0, 100]; index ``[i, j, k]`` is the
        voxel ``i`` along x (east), ``j`` along y (north), ``k`` upwards from the base.
    size : float or (float, float)
        Horizontal size of the box (x, y) [m], > 0.
    base, top : float
        Altitudes of the bottom and top of the box above the ground [m], ``0 <= base < top <= 100 km``.
    particles : ParticleComponent
        The droplets' optics (:mod:`skyscatter.atmosphere.particles`): extinction spectrum (used relative to its
        value at 550 nm), single-scattering albedo and phase function; its density profile is not used.
    origin : float or (float, float), optional
        Position of the box's south-west corner relative to the observer's foot point (east, north) [m];
        default: the box centred on it.
    periodic : bool
        True (default): the field repeats with period ``size`` in x and y; False: no cloud outside the box.

    Raises
    ------
    InvalidParameterError
        Naming the parameter that is wrong and what is allowed.
    """

    __slots__ = ("_extinction", "size", "base", "top", "particles", "origin", "periodic", "_digest")

    def __init__(self, extinction: ArrayLike, size: Any, base: float, top: float, particles: Any, *,
                 origin: Any = None, periodic: bool = True) -> None:
        ext = np.asarray(extinction, dtype=float)
        if ext.ndim != 3 or min(ext.shape) < 1:
            raise InvalidParameterError(
                f"cloud field extinction must be a 3D array (nx, ny, nz); got shape {ext.shape}")
        if ext.size > MAX_VOXELS:
            raise InvalidParameterError(f"cloud field has {ext.size} voxels; at most {MAX_VOXELS} are allowed")
        if not np.all(np.isfinite(ext)) or np.any(ext < 0) or np.any(ext > MAX_EXTINCTION):
            raise InvalidParameterError(
                f"cloud field extinction must be finite and in [0, {MAX_EXTINCTION:g}] m^-1 (at 550 nm)")
        sx, sy = _pair("cloud field size", size, 1e-3, 1e8)
        b = _number("cloud field base", base, 0.0, 1e5)
        t = _number("cloud field top", top, 0.0, 1e5)
        if not t > b:
            raise InvalidParameterError(f"cloud field top ({t:g} m) must be above its base ({b:g} m)")
        if origin is None:
            ox, oy = -0.5 * sx, -0.5 * sy
        else:
            ox, oy = _pair("cloud field origin", origin, -1e8, 1e8)
        if not isinstance(periodic, (bool, np.bool_)):
            raise InvalidParameterError(f"cloud field periodic must be True or False; got {periodic!r}")
        _check_particles(particles)
        arr = np.ascontiguousarray(ext)
        arr.setflags(write=False)
        self._extinction = arr
        self.size = (sx, sy)
        self.base = b
        self.top = t
        self.particles = particles
        self.origin = (ox, oy)
        self.periodic = bool(periodic)
        self._digest: str | None = None

    # ------------------------------------------------------------------ properties

    @property
    def extinction(self) -> NDArray[np.float64]:
        """Extinction coefficient per voxel at 550 nm [m^-1], (nx, ny, nz), read-only."""
        return self._extinction

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(int(n) for n in self._extinction.shape)  # type: ignore[return-value]

    @property
    def voxel_size(self) -> tuple[float, float, float]:
        """(dx, dy, dz) [m]."""
        nx, ny, nz = self.shape
        return self.size[0] / nx, self.size[1] / ny, (self.top - self.base) / nz

    def coordinates(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Cell centres x, y (relative to the observer's foot point) and altitude z [m]."""
        nx, ny, nz = self.shape
        dx, dy, dz = self.voxel_size
        return (self.origin[0] + (np.arange(nx) + 0.5) * dx, self.origin[1] + (np.arange(ny) + 0.5) * dy,
                self.base + (np.arange(nz) + 0.5) * dz)

    def optical_depth(self) -> NDArray[np.float64]:
        """Vertical optical depth of each column at 550 nm [-], (nx, ny)."""
        return self._extinction.sum(axis=2) * self.voxel_size[2]

    def cloud_fraction(self, threshold: float = 0.0) -> float:
        """Fraction of the columns whose vertical optical depth at 550 nm exceeds ``threshold`` [-]."""
        return float(np.mean(self.optical_depth() > threshold))

    def replace(self, **changes: Any) -> CloudField:
        """A copy with some of the constructor's arguments changed (validated again)."""
        kw = dict(extinction=self._extinction, size=self.size, base=self.base, top=self.top,
                  particles=self.particles, origin=self.origin, periodic=self.periodic)
        kw.update(changes)
        ext = kw.pop("extinction")
        return CloudField(ext, kw.pop("size"), kw.pop("base"), kw.pop("top"), kw.pop("particles"), **kw)

    def digest(self) -> str:
        """SHA-256 of the extinction grid (its bytes, little-endian float64, C order) and shape."""
        if self._digest is None:
            h = hashlib.sha256(str(self.shape).encode())
            h.update(np.ascontiguousarray(self._extinction, dtype="<f8").tobytes())
            self._digest = h.hexdigest()
        return self._digest

    def description(self) -> dict[str, Any]:
        """JSON-compatible description for job identities and cache keys (the grid by its SHA-256)."""
        return {"kind": "cloud_field", "shape": list(self.shape), "extinction_sha256": self.digest(),
                "size_m": list(self.size), "base_m": self.base, "top_m": self.top, "origin_m": list(self.origin),
                "periodic": self.periodic, "reference_wavelength_nm": REFERENCE_WAVELENGTH,
                "particles": self.particles.to_dict()}

    def to_dict(self) -> dict[str, Any]:
        """Complete JSON-compatible description (the grid as nested lists; :meth:`from_dict` reads it back)."""
        return {**self.description(), "extinction": self._extinction.tolist()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> CloudField:
        from .particles import particle_component_from_dict

        try:
            field = cls(np.asarray(data["extinction"], dtype=float), tuple(data["size_m"]), data["base_m"],
                        data["top_m"], particle_component_from_dict(data["particles"]), origin=tuple(data["origin_m"]),
                        periodic=bool(data["periodic"]))
        except (KeyError, TypeError) as exc:
            raise FileFormatError(f"cloud field description is incomplete or malformed: {exc}") from None
        if "extinction_sha256" in data and data["extinction_sha256"] != field.digest():
            raise FileFormatError("cloud field description: the grid does not match its SHA-256")
        return field

    def __repr__(self) -> str:
        return (f"CloudField(shape={self.shape}, size={self.size}, base={self.base:g}, top={self.top:g}, "
                f"origin={self.origin}, periodic={self.periodic}, particles={getattr(self.particles, 'name', '?')!r})")

    # ------------------------------------------------------------------ constructors

    @classmethod
    def from_array(cls, extinction: ArrayLike, size: Any, base: float, top: float, particles: Any,
                   **kw: Any) -> CloudField:
        """The field of an extinction array [m^-1 at 550 nm] (the constructor's arguments)."""
        return cls(extinction, size, base, top, particles, **kw)

    @classmethod
    def from_liquid_water_content(cls, lwc: ArrayLike, size: Any, base: float, top: float, particles: Any,
                                  effective_radius: float, **kw: Any) -> CloudField:
        """A field from liquid water content [kg m^-3] per voxel and the droplets' effective radius [m].

        ``beta_e = 3 Q_e LWC / (4 rho_w r_e)`` ([HansenTravis1974] Eq. 2.53, with the extinction efficiency
        ``Q_e`` = 2 of large droplets; [Stephens1978] Eq. 8): for ``r_e`` in [1, 100] um, ``rho_w`` = 1000 kg m^-3.
        """
        w = np.asarray(lwc, dtype=float)
        if w.ndim != 3 or not np.all(np.isfinite(w)) or np.any(w < 0) or np.any(w > 0.1):
            raise InvalidParameterError("liquid water content must be a finite 3D array in [0, 0.1] kg m^-3")
        r = _number("effective radius", effective_radius, 1e-6, 1e-4)
        return cls(3.0 * 2.0 * w / (4.0 * WATER_DENSITY * r), size, base, top, particles, **kw)

    @classmethod
    def i3rc_step_cloud(cls, particles: Any) -> CloudField:
        """The I3RC Phase 1 step cloud ([Cahalan2005], case 1; module docstring): 32 columns 15.625 m wide across
        a periodic 0.5 km domain, the first 16 of optical depth 2 and the last 16 of 18, from the ground to 0.25 km,
        uniform in y; ``origin`` (0, 0), so that column ``i`` spans ``x`` in ``[15.625 i, 15.625 (i + 1)]`` m."""
        tau = np.concatenate([np.full(16, 2.0), np.full(16, 18.0)])
        ext = (tau / 250.0)[:, None, None]
        return cls(ext, (500.0, 500.0), 0.0, 250.0, particles, origin=(0.0, 0.0), periodic=True)

    @classmethod
    def procedural(cls, *, cover: float, base: float, top: float, particles: Any, optical_depth: float = 10.0,
                   size: Any = 20_000.0, resolution: Any = (128, 128, 32), feature_size: float = 2_000.0,
                   seed: int = 0, origin: Any = None, periodic: bool = True) -> CloudField:
        """Broken cumuliform clouds from fractal Perlin-Worley noise (module docstring).

        Parameters
        ----------
        cover : float
            Cloud cover fraction in [0, 1]: the fraction of the columns that hold cloud.
        base, top : float
            Cloud base and the highest cloud top [m] above the ground.
        particles : ParticleComponent
            The droplets' optics.
        optical_depth : float
            Mean vertical optical depth at 550 nm of the cloudy columns, in (0, 500] (default 10).
        size : float or (float, float)
            Horizontal size [m] (default 20 km).
        resolution : int or (int, int, int)
            Voxels (nx, ny, nz) (default 128 x 128 x 32).
        feature_size : float
            Size of the largest cloud features [m] (the coverage map's base period; default 2 km).
        seed : int
            Seed (>= 0); equal seeds give the same field.
        origin, periodic
            As the constructor.
        """
        c = _number("cloud cover", cover, 0.0, 1.0, "")
        b = _number("cloud base", base, 0.0, 1e5)
        t = _number("cloud top", top, 0.0, 1e5)
        if not t > b:
            raise InvalidParameterError(f"cloud top ({t:g} m) must be above the cloud base ({b:g} m)")
        tau = _number("optical depth", optical_depth, 0.0, 500.0, "")
        if tau <= 0:
            raise InvalidParameterError("optical depth must be > 0")
        sx, sy = _pair("size", size, 1.0, 1e7)
        res = np.atleast_1d(np.asarray(resolution))
        if res.size == 1:
            res = np.repeat(res, 3)
        if res.size != 3 or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v >= 1
                                    for v in res.tolist()):
            raise InvalidParameterError(f"resolution must be whole numbers >= 1 (nx, ny, nz); got {resolution!r}")
        nx, ny, nz = (int(v) for v in res)
        if nx * ny * nz > MAX_VOXELS:
            raise InvalidParameterError(f"resolution gives {nx * ny * nz} voxels; at most {MAX_VOXELS}")
        fs = _number("feature size", feature_size, 1.0, 1e7)
        seed = whole_number("seed", seed, 0)
        ext = _procedural_extinction(c, nx, ny, nz, sx, sy, t - b, fs, tau, int(seed))
        return cls(ext, (sx, sy), b, t, particles, origin=origin, periodic=periodic)

    # ------------------------------------------------------------------ files

    def to_dataset(self):
        """The field as an xarray Dataset (variable ``extinction`` (x, y, z) [m^-1], cell-centre coordinates)."""
        import xarray as xr

        x, y, z = self.coordinates()
        return xr.Dataset(
            {"extinction": (("x", "y", "z"), np.asarray(self._extinction),
                            {"units": "m-1", "long_name": f"extinction coefficient at {REFERENCE_WAVELENGTH:g} nm"})},
            coords={"x": ("x", x, {"units": "m", "long_name": "east of the observer's foot point"}),
                    "y": ("y", y, {"units": "m", "long_name": "north of the observer's foot point"}),
                    "z": ("z", z, {"units": "m", "long_name": "altitude above the ground"})},
            attrs={"title": "skyscatter cloud field", "periodic": int(self.periodic), "base": self.base,
                   "top": self.top, "size_x": self.size[0], "size_y": self.size[1],
                   "reference_wavelength": REFERENCE_WAVELENGTH,
                   "particles": json.dumps(self.particles.to_dict(), sort_keys=True)},
        )

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the field to ``path``: NetCDF 4 (``.nc``, h5netcdf) or a Zarr store (``.zarr``), atomically."""
        target = Path(path)
        ds = self.to_dataset()
        if target.suffix == ".nc":
            check_output_path(target)
            with atomic_path(target) as tmp:
                ds.to_netcdf(tmp, engine="h5netcdf")
        elif target.suffix == ".zarr":
            if target.exists():
                raise OutputError(f"{target} exists; a cloud field store is not overwritten")
            tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
            ds.to_zarr(tmp, mode="w-", consolidated=False)
            os.replace(tmp, target)
        else:
            raise OutputError(f"{target}: a cloud field is saved as .nc (NetCDF) or .zarr; got {target.suffix!r}")
        return target

    @classmethod
    def load(cls, path: str | os.PathLike[str], particles: Any = None) -> CloudField:
        """Read a field written by :meth:`save` (or any NetCDF/Zarr with a variable ``extinction`` on ``(x, y,
        z)`` cell-centre coordinates [m], uniformly spaced, and attributes ``base`` and ``top`` [m]; ``periodic``
        defaults to 1). ``particles`` replaces the stored optics (required when the file has none)."""
        import xarray as xr

        p = Path(path)
        if not p.exists():
            raise FileFormatError(f"{p}: no such cloud field file")
        try:
            ds = xr.open_zarr(p, consolidated=False) if p.suffix == ".zarr" or p.is_dir() else \
                xr.open_dataset(p, engine="h5netcdf")
        except Exception as exc:  # noqa: BLE001 - any unreadable file is refused the same way
            raise FileFormatError(f"{p}: not a readable NetCDF/Zarr cloud field ({exc})") from None
        with ds:
            if "extinction" not in ds or ds["extinction"].dims != ("x", "y", "z"):
                raise FileFormatError(f"{p}: needs a variable 'extinction' on dimensions (x, y, z)")
            coords = []
            for name in ("x", "y", "z"):
                v = np.asarray(ds[name].values, dtype=float)
                if v.size > 1 and not np.allclose(np.diff(v), v[1] - v[0], rtol=1e-6, atol=1e-9):
                    raise FileFormatError(f"{p}: coordinate {name} must be uniformly spaced")
                coords.append(v)
            try:
                base = float(ds.attrs["base"])
                top = float(ds.attrs["top"])
            except (KeyError, TypeError, ValueError):
                raise FileFormatError(f"{p}: attributes 'base' and 'top' [m] are required") from None
            ext = np.asarray(ds["extinction"].values, dtype=float)
            periodic = bool(int(ds.attrs.get("periodic", 1)))
            stored = ds.attrs.get("particles")
        dims = []
        for name, v, key in (("x", coords[0], "size_x"), ("y", coords[1], "size_y")):
            step = (v[1] - v[0]) if v.size > 1 else None
            size = float(ds.attrs.get(key, step * v.size if step else math.nan))
            if not math.isfinite(size):
                raise FileFormatError(f"{p}: one cell along {name} needs the attribute {key} [m]")
            dims.append((size, float(v[0] - 0.5 * size / v.size)))
        if particles is None:
            if stored is None:
                raise FileFormatError(f"{p}: holds no particle optics; pass particles=")
            from .particles import particle_component_from_dict

            particles = particle_component_from_dict(json.loads(stored))
        return cls(ext, (dims[0][0], dims[1][0]), base, top, particles, origin=(dims[0][1], dims[1][1]),
                   periodic=periodic)


def _check_particles(particles: Any) -> None:
    needed = ("extinction_at", "single_scattering_albedo_at", "phase_table", "to_dict")
    if not all(hasattr(particles, a) for a in needed):
        raise InvalidParameterError(
            f"particles must be a particle component (skyscatter.atmosphere.particles); got {type(particles).__name__}")


# --------------------------------------------------------------------------------------------- noise

# the 12 edge gradients of [Perlin2002]
_GRADIENTS = np.array([[1, 1, 0], [-1, 1, 0], [1, -1, 0], [-1, -1, 0], [1, 0, 1], [-1, 0, 1], [1, 0, -1],
                       [-1, 0, -1], [0, 1, 1], [0, -1, 1], [0, 1, -1], [0, -1, -1]], dtype=float)


def _noise_arguments(points: ArrayLike, period: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Points (..., d) of the noise as a C-ordered (n, d) float64 array, and the period (d,) as int64; d must be
    2 or 3 and the period whole numbers >= 1 (the compiled octaves index their tables without bounds checks)."""
    pts = np.ascontiguousarray(points, dtype=np.float64)
    if pts.ndim < 1 or pts.shape[-1] not in (2, 3):
        raise InvalidParameterError(f"noise points must have 2 or 3 coordinates (..., d); got shape {pts.shape}")
    per = np.asarray(period)
    if per.shape != (pts.shape[-1],) or not np.issubdtype(per.dtype, np.integer) or np.any(per < 1):
        raise InvalidParameterError(f"noise period must be {pts.shape[-1]} whole numbers >= 1; got {period!r}")
    return pts.reshape(-1, pts.shape[-1]), per.astype(np.int64)


def perlin_fbm(points: ArrayLike, period: ArrayLike, octaves: int, seed: int) -> NDArray[np.float64]:
    """Fractal sum of [Perlin2002] gradient-noise octaves (frequency x2, amplitude /2), normalised to amplitude 1.

    Parameters
    ----------
    points : array (..., d)
        Where [lattice units of the first octave], d = 2 or 3 (2D uses the gradients' first two components).
    period : int array (d,)
        Lattice period of the first octave [cells]; octave ``o`` has period ``period * 2**o``.
    octaves : int
        Number of octaves.
    seed : int
        Seed of the gradient tables (one index into the 12 edge gradients per lattice node and octave, drawn
        with numpy's generator in octave order).

    Returns
    -------
    array (...)
        The noise [-], about [-1, 1].
    """
    from ._noise_numba import add_perlin_octave

    pts, per = _noise_arguments(points, period)
    rng = np.random.default_rng(seed)
    total = np.zeros(pts.shape[0])
    amp = 1.0
    norm = 0.0
    for o in range(octaves):
        per_o = per * 2**o
        grads = rng.integers(0, 12, size=tuple(int(p) for p in per_o))
        add_perlin_octave(total, pts, float(2**o), per_o, grads.ravel(), _GRADIENTS, amp)
        norm += amp
        amp *= 0.5
    return (total / norm).reshape(np.shape(points)[:-1])


def worley_fbm(points: ArrayLike, period: ArrayLike, octaves: int, seed: int) -> NDArray[np.float64]:
    """Fractal sum of inverted [Worley1996] cellular-noise octaves (``1 - F1``, F1 the distance to the nearest
    feature point, one uniform in each cell; frequency x2, amplitude /2), normalised to amplitude 1.

    Parameters
    ----------
    points : array (..., d)
        Where [lattice units of the first octave], d = 2 or 3.
    period : int array (d,)
        Lattice period of the first octave [cells]; octave ``o`` has period ``period * 2**o``.
    octaves : int
        Number of octaves.
    seed : int
        Seed of the feature points (drawn with numpy's generator in octave order).

    Returns
    -------
    array (...)
        The noise [-], about [0, 1].
    """
    from ._noise_numba import add_worley_octave

    pts, per = _noise_arguments(points, period)
    d = pts.shape[1]
    rng = np.random.default_rng(seed)
    total = np.zeros(pts.shape[0])
    amp = 1.0
    norm = 0.0
    for o in range(octaves):
        per_o = per * 2**o
        feats = rng.random(tuple(int(p) for p in per_o) + (d,))
        add_worley_octave(total, pts, float(2**o), per_o, feats.reshape(-1, d), amp)
        norm += amp
        amp *= 0.5
    return (total / norm).reshape(np.shape(points)[:-1])


def _procedural_extinction(cover: float, nx: int, ny: int, nz: int, sx: float, sy: float, depth: float,
                           feature: float, tau: float, seed: int) -> NDArray[np.float64]:
    """Extinction [m^-1] of a procedural field (:meth:`CloudField.procedural`)."""
    if cover == 0.0:
        return np.zeros((nx, ny, nz))
    ss = np.random.SeedSequence(seed).spawn(3)
    seeds = [int(s.generate_state(1)[0]) for s in ss]
    # periods of the first octave in whole cells, so that the noise tiles the domain
    px = max(1, round(sx / feature))
    py = max(1, round(sy / feature))
    gx = (np.arange(nx) + 0.5) / nx
    gy = (np.arange(ny) + 0.5) / ny
    xy = np.stack(np.meshgrid(gx * px, gy * py, indexing="ij"), axis=-1)
    # coverage map: Perlin-Worley ([Schneider2017]): Perlin fBm remapped into the Worley fBm's range
    perlin = 0.5 * (1.0 + perlin_fbm(xy, (px, py), 4, seeds[0]))
    worley = worley_fbm(xy, (px, py), 3, seeds[1])
    shape = np.clip(perlin - (1.0 - worley) * 0.5, 0.0, None) + 1e-9 * perlin
    if cover >= 1.0:
        thresh = -np.inf
        rel = (shape - shape.min()) / max(float(np.ptp(shape)), 1e-12)
    else:
        thresh = float(np.quantile(shape, 1.0 - cover))
        hi = float(shape.max())
        rel = np.clip((shape - thresh) / max(hi - thresh, 1e-12), 0.0, 1.0)
    cloudy = shape > thresh
    # local cloud top rises with the coverage value: thickness from 30 % to 100 % of base..top
    thick = np.where(cloudy, 0.3 + 0.7 * np.sqrt(rel), 0.0)
    hz = (np.arange(nz) + 0.5) / nz  # height in the box [0, 1]
    # 3D erosion of the edges by Worley fBm (4 cells of the domain's feature size vertically)
    pz = max(1, round(depth / feature * 4))
    xyz = np.stack(np.meshgrid(gx * px * 2, gy * py * 2, hz * pz, indexing="ij"), axis=-1)
    erosion = worley_fbm(xyz, (2 * px, 2 * py, pz), 2, seeds[2])
    frac = hz[None, None, :] / np.maximum(thick[:, :, None], 1e-12)
    inside = (frac < 1.0) & cloudy[:, :, None]
    # adiabatic: liquid water rising linearly from the base; edges eroded where the cloud is thin
    lwc = np.where(inside, frac, 0.0)
    edge = np.clip((1.0 - frac) * 4.0, 0.0, 1.0) * np.clip(rel[:, :, None] * 4.0, 0.0, 1.0)
    lwc = lwc * np.clip(1.0 - 0.6 * (1.0 - edge) * erosion, 0.0, 1.0)
    lwc = np.where(lwc > 0.02, lwc, 0.0)
    col = lwc.sum(axis=2)
    cloudy_cols = col > 0
    if not np.any(cloudy_cols):
        return np.zeros((nx, ny, nz))
    dz = depth / nz
    mean_col = float(col[cloudy_cols].mean()) * dz
    return lwc * (tau / mean_col)


# --------------------------------------------------------------------------------------------- cloud layers

#: Largest optical depth of a cloud layer at 550 nm (a thick cumulonimbus reaches a few hundred).
MAX_LAYER_OPTICAL_DEPTH = 1000.0
#: Range of effective radii of the droplet optics [m] (water's refractive index covers 250-1200 nm).
EFFECTIVE_RADIUS_RANGE = (1e-6, 50e-6)


@lru_cache(maxsize=16)
def _droplet_optics(effective_radius: float, effective_variance: float, wavelengths: tuple[float, ...]):
    """The droplets' Mie optics at ``wavelengths`` [nm] (:func:`.mie_optics.water_droplets`), kept per process:
    the per-wavelength optics are cached there already, but joining them into one table took 2 ms a call, and a
    cloudy sky's solve asks for the same layer's optics seven times. Their arrays are read-only."""
    from .mie_optics import water_droplets

    return water_droplets(effective_radius, effective_variance, np.array(wavelengths))


def _with_reference(wavelengths: ArrayLike) -> tuple[tuple[float, ...], NDArray[np.int64], int]:
    wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
    grid = np.unique(np.concatenate([wl, [REFERENCE_WAVELENGTH]]))
    return tuple(float(v) for v in grid), np.searchsorted(grid, wl), int(np.searchsorted(grid, REFERENCE_WAVELENGTH))


class CloudLayer(ParticleComponent):
    """A horizontally uniform water cloud between two altitudes: a particle component of the medium.

    Its droplets follow a modified-gamma size distribution of effective radius and variance ([HansenTravis1974]
    Eqs. 2.53-2.56), with the optics of liquid water from Mie theory (:func:`.mie_optics.water_droplets`:
    extinction spectrum, single-scattering albedo and the tabulated phase function with its diffraction peak,
    rainbow and glory). The layer has constant density from ``base`` to ``top`` (a box profile), and its amount is
    given by the vertical optical depth at 550 nm or by the liquid water path ``LWP``, related by ``tau = LWP C_e /
    (rho_w <V>)`` (the droplets' mean extinction cross-section over their mean volume, ``rho_w`` = 1000 kg m^-3;
    [Stephens1978] Eq. 8 in the limit ``Q_e = 2``: ``tau = 3 LWP / (2 rho_w r_e)``). Several layers stack in
    ``AtmosphereParameters(particles=(layer1, layer2))``; every solver that reads the medium's particle
    components sees them (the Monte Carlo traces them exactly; the precomputed tables refuse or handle them as
    their documentation says).

    Parameters
    ----------
    base, top : float
        Altitudes of the cloud base and top above the ground [m], ``0 <= base < top <= 100 km``.
    optical_depth : float, optional
        Vertical optical depth at 550 nm, in [0, 1000].
    liquid_water_path : float, optional
        [kg m^-2] in [0, 10] (instead of ``optical_depth``; exactly one of the two).
    effective_radius : float
        [m] in [1, 50] um (default 10 um).
    effective_variance : float
        [-] in (0, 0.5] (default 0.1).
    name : str
        Label (default "cloud").
    """

    kind = "cloud_layer"
    __slots__ = ("base", "top", "optical_depth_550", "effective_radius", "effective_variance", "name")
    # the slots' types, for type checkers (set once in __init__ through object.__setattr__: the layer is frozen)
    base: float
    top: float
    optical_depth_550: float
    effective_radius: float
    effective_variance: float
    name: str

    def __init__(self, base: float, top: float, optical_depth: float | None = None, *,
                 liquid_water_path: float | None = None, effective_radius: float = 10e-6,
                 effective_variance: float = 0.1, name: str = "cloud") -> None:
        b = _number("cloud base", base, 0.0, 1e5)
        t = _number("cloud top", top, 0.0, 1e5)
        if not t > b:
            raise InvalidParameterError(f"cloud top ({t:g} m) must be above the cloud base ({b:g} m)")
        lo, hi = EFFECTIVE_RADIUS_RANGE
        r = _number("effective radius", effective_radius, lo, hi)
        v = _number("effective variance", effective_variance, 0.0, 0.5, "")
        if v <= 0:
            raise InvalidParameterError("effective variance must be > 0")
        if (optical_depth is None) == (liquid_water_path is None):
            raise InvalidParameterError("give exactly one of optical_depth (at 550 nm) and liquid_water_path [kg m^-2]")
        if not isinstance(name, str) or not name:
            raise InvalidParameterError("cloud layer name must be a non-empty string")
        object.__setattr__(self, "base", b)
        object.__setattr__(self, "top", t)
        object.__setattr__(self, "effective_radius", r)
        object.__setattr__(self, "effective_variance", v)
        object.__setattr__(self, "name", name)
        if optical_depth is not None:
            tau = _number("cloud optical depth", optical_depth, 0.0, MAX_LAYER_OPTICAL_DEPTH, "")
        else:
            lwp = _number("liquid water path", liquid_water_path, 0.0, 10.0, "kg m^-2")
            tau = lwp * self._extinction_per_mass()
            if tau > MAX_LAYER_OPTICAL_DEPTH:
                raise InvalidParameterError(
                    f"liquid water path {lwp:g} kg m^-2 gives optical depth {tau:.4g} > {MAX_LAYER_OPTICAL_DEPTH:g}")
        object.__setattr__(self, "optical_depth_550", tau)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("CloudLayer is immutable; use replace()")

    def __reduce__(self) -> tuple[Any, tuple[dict[str, Any]]]:
        # pickle (Dask's distributed scheduler, process pools) would restore the slots by assignment, which the
        # frozen layer refuses: rebuild it from its exact description instead
        from .particles import particle_component_from_dict

        return particle_component_from_dict, (self.to_dict(),)

    def _extinction_per_mass(self) -> float:
        """Mass extinction coefficient at 550 nm [m^2 kg^-1]: ``C_e / (rho_w 4/3 pi <r^3>)``."""
        from .size_distributions import ModifiedGammaMode

        mode = ModifiedGammaMode.from_effective(self.effective_radius, self.effective_variance)
        optics = _droplet_optics(self.effective_radius, self.effective_variance, (REFERENCE_WAVELENGTH,))
        volume = 4.0 / 3.0 * math.pi * mode.moment(3) / mode.moment(0)
        return float(optics.extinction_cross_section[0]) / (WATER_DENSITY * volume)

    @property
    def liquid_water_path(self) -> float:
        """[kg m^-2] of the layer's optical depth."""
        return self.optical_depth_550 / self._extinction_per_mass()

    @property
    def density(self):
        from .profiles import DensityProfile

        return DensityProfile.box(self.base, self.top)

    @property
    def analytic_phase(self) -> None:
        return None

    def _optics(self, wavelengths: ArrayLike):
        grid, idx, ref = _with_reference(wavelengths)
        return _droplet_optics(self.effective_radius, self.effective_variance, grid), idx, ref

    def extinction_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Extinction coefficient inside the layer [m^-1]: the optical depth spread over its thickness, with the
        droplets' extinction spectrum relative to 550 nm."""
        optics, idx, ref = self._optics(wavelengths)
        ce = optics.extinction_cross_section
        return self.optical_depth_550 / (self.top - self.base) * ce[idx] / ce[ref]

    def single_scattering_albedo_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        optics, idx, _ = self._optics(wavelengths)
        return np.asarray(optics.single_scattering_albedo[idx], dtype=float)

    def scattering_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        return self.extinction_at(wavelengths) * self.single_scattering_albedo_at(wavelengths)

    def absorption_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        return self.extinction_at(wavelengths) - self.scattering_at(wavelengths)

    def optical_depth(self, wavelengths: ArrayLike, height: float) -> NDArray[np.float64]:
        """Vertical optical depth [-] from the ground to ``height`` [m]."""
        return self.extinction_at(wavelengths) * self.density.column(float(height))

    def phase_table(self, wavelengths: ArrayLike, angles: ArrayLike | None = None):
        optics, _, _ = self._optics(wavelengths)
        table = optics.phase.at_wavelengths(np.atleast_1d(np.asarray(wavelengths, dtype=float)))
        return table if angles is None else table.on_angles(angles)

    def replace(self, **changes: Any) -> CloudLayer:
        kw: dict[str, Any] = dict(base=self.base, top=self.top, optical_depth=self.optical_depth_550,
                                  effective_radius=self.effective_radius,
                                  effective_variance=self.effective_variance, name=self.name)
        if "liquid_water_path" in changes:
            kw.pop("optical_depth")
        kw.update(changes)
        base, top = kw.pop("base"), kw.pop("top")
        return CloudLayer(base, top, kw.pop("optical_depth", None), **kw)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "name": self.name, "base": self.base, "top": self.top,
                "optical_depth_550": self.optical_depth_550, "effective_radius": self.effective_radius,
                "effective_variance": self.effective_variance}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> CloudLayer:
        return cls(float(data["base"]), float(data["top"]), float(data["optical_depth_550"]),
                   effective_radius=float(data["effective_radius"]),
                   effective_variance=float(data["effective_variance"]), name=str(data["name"]))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, CloudLayer) and self.to_dict() == other.to_dict()

    def __hash__(self) -> int:
        return hash(tuple(sorted(self.to_dict().items())))

    def __repr__(self) -> str:
        return (f"CloudLayer(base={self.base:g}, top={self.top:g}, optical_depth={self.optical_depth_550:g}, "
                f"effective_radius={self.effective_radius:g}, effective_variance={self.effective_variance:g})")


register_particle_kind(CloudLayer)
