"""Heightfield terrains: the built-in procedural mountains and user elevation models (.npy, GeoTIFF).

A :class:`Terrain` is a regular grid of heights [m above sea level] in the ENU frame. Sample ``heights[iy, ix]``
sits at ``x = x0 + ix * spacing`` (east) and ``y = y0 + iy * spacing`` (north), so row index grows
**northwards** inside the class; the loaders flip north-up rasters (row 0 = northern edge, the image and
GeoTIFF convention) on the way in. Between samples the surface is the bilinear interpolant of the four
corners of each cell.

Outside the grid a terrain is either periodic (``wrap=True``; the procedural landscape is seamless, so it
repeats to the horizon) or a flat plain at ``base_height`` (user elevation models).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import FileFormatError, InvalidParameterError

__all__ = ["DEFAULT_SEED", "MAX_TERRAIN_HEIGHT", "Terrain", "default_terrain", "procedural_heights"]

#: Largest |height| [m] of a terrain sample: the flat, exponential atmosphere of the aerial-perspective models
#: (Preetham et al. 1999, Eq. 5) is meant for the lower atmosphere, and observers are limited to 100 km too.
MAX_TERRAIN_HEIGHT = 100_000.0

#: Seed of the built-in landscape; changing it changes every demo image and the render regression reference.
DEFAULT_SEED = 1999


@dataclass(frozen=True, eq=False)
class Terrain:
    """A heightfield terrain.

    Parameters
    ----------
    heights : array_like, shape (ny, nx)
        Heights [m above sea level]; ``heights[iy, ix]`` is at ``(x0 + ix * spacing, y0 + iy * spacing)``,
        row index growing northwards. At least 2 x 2 samples, all finite.
    spacing : float
        Distance between neighbouring samples [m], the same east-west and north-south.
    origin : tuple of float
        ENU position ``(x0, y0)`` [m] of sample ``heights[0, 0]`` (the south-west corner).
    wrap : bool
        If True the terrain is periodic with period ``(nx * spacing, ny * spacing)`` (sample ``nx`` equals
        sample 0); otherwise the world outside the grid is a flat plain at ``base_height``.
    base_height : float, optional
        Height [m] of the plain outside a non-periodic grid; default the lowest sample.
    name : str
        A label used in messages and image metadata.

    Raises
    ------
    InvalidParameterError
        If the heights are not a finite 2-D array of at least 2 x 2 samples or the spacing is not a finite
        positive number.
    """

    heights: NDArray[np.float64]
    spacing: float
    origin: tuple[float, float] = (0.0, 0.0)
    wrap: bool = False
    base_height: float | None = None
    name: str = "terrain"

    def __post_init__(self) -> None:
        raw = np.asarray(self.heights)
        if np.issubdtype(raw.dtype, np.complexfloating) or raw.dtype == bool or raw.dtype.kind in "OUSV":
            raise InvalidParameterError(f"terrain heights must be real numbers [m]; got dtype {raw.dtype}")
        h = np.asarray(raw, dtype=np.float64)
        if h.ndim != 2 or min(h.shape) < 2:
            raise InvalidParameterError(
                f"terrain heights must be a 2-D array of at least 2 x 2 samples [m]; got shape {h.shape}"
            )
        bad = ~np.isfinite(h)
        if bad.any():
            iy, ix = np.argwhere(bad)[0]
            raise InvalidParameterError(
                f"terrain heights contain {int(bad.sum())} NaN or infinite values (first at row {iy}, "
                f"column {ix}); fill the holes before rendering"
            )
        if np.abs(h).max() > MAX_TERRAIN_HEIGHT:
            raise InvalidParameterError(
                f"terrain heights must lie within +-{MAX_TERRAIN_HEIGHT:g} m of sea level (the flat-atmosphere "
                f"model's domain); got {h.min():.6g} to {h.max():.6g} m"
            )
        try:
            spacing = float(self.spacing)
        except (TypeError, ValueError):
            raise InvalidParameterError(
                f"terrain spacing must be a finite positive length [m]; got {self.spacing!r}") from None
        if not (np.isfinite(spacing) and spacing > 0):
            raise InvalidParameterError(f"terrain spacing must be a finite positive length [m]; got {self.spacing!r}")
        x0, y0 = (float(v) for v in self.origin)
        if not (np.isfinite(x0) and np.isfinite(y0)):
            raise InvalidParameterError(f"terrain origin must be finite [m]; got {self.origin!r}")
        base = float(h.min()) if self.base_height is None else float(self.base_height)
        if not np.isfinite(base):
            raise InvalidParameterError(f"base_height must be finite [m]; got {self.base_height!r}")
        h = np.ascontiguousarray(h)
        h.setflags(write=False)
        object.__setattr__(self, "heights", h)
        object.__setattr__(self, "spacing", spacing)
        object.__setattr__(self, "origin", (x0, y0))
        object.__setattr__(self, "wrap", bool(self.wrap))
        object.__setattr__(self, "base_height", base)

    # -- geometry ---------------------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int]:
        """(ny, nx) samples."""
        return self.heights.shape  # type: ignore[return-value]

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max) [m] of the sampled grid (one period for a periodic terrain)."""
        ny, nx = self.shape
        x0, y0 = self.origin
        if self.wrap:
            return x0, x0 + nx * self.spacing, y0, y0 + ny * self.spacing
        return x0, x0 + (nx - 1) * self.spacing, y0, y0 + (ny - 1) * self.spacing

    @cached_property
    def height_range(self) -> tuple[float, float]:
        """Lowest and highest height [m] anywhere (including the plain of a non-periodic terrain)."""
        lo, hi = float(self.heights.min()), float(self.heights.max())
        if not self.wrap:
            lo, hi = min(lo, self.base_height), max(hi, self.base_height)  # type: ignore[type-var]
        return lo, hi

    def _cell_coords(self, x: ArrayLike, y: ArrayLike):
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        ny, nx = self.shape
        gx = (x - self.origin[0]) / self.spacing
        gy = (y - self.origin[1]) / self.spacing
        if self.wrap:
            gx = np.mod(gx, nx)
            gy = np.mod(gy, ny)
            ix = np.minimum(np.floor(gx).astype(np.int64), nx - 1)
            iy = np.minimum(np.floor(gy).astype(np.int64), ny - 1)
            ix1, iy1 = (ix + 1) % nx, (iy + 1) % ny
            inside = np.ones(np.broadcast(gx, gy).shape, dtype=bool)
        else:
            inside = (gx >= 0) & (gx <= nx - 1) & (gy >= 0) & (gy <= ny - 1)
            ix = np.clip(np.floor(gx).astype(np.int64), 0, nx - 2)
            iy = np.clip(np.floor(gy).astype(np.int64), 0, ny - 2)
            ix1, iy1 = ix + 1, iy + 1
        return gx - ix, gy - iy, ix, iy, ix1, iy1, inside

    def height_at(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Surface height [m] at ENU positions ``x``, ``y`` [m] (bilinear; ``base_height`` off a finite grid)."""
        u, v, ix, iy, ix1, iy1, inside = self._cell_coords(x, y)
        h = self.heights
        z = (h[iy, ix] * (1 - u) * (1 - v) + h[iy, ix1] * u * (1 - v) + h[iy1, ix] * (1 - u) * v
             + h[iy1, ix1] * u * v)
        return np.where(inside, z, self.base_height)

    @cached_property
    def _vertex_gradients(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        h = self.heights
        if self.wrap:
            gx = (np.roll(h, -1, axis=1) - np.roll(h, 1, axis=1)) / (2 * self.spacing)
            gy = (np.roll(h, -1, axis=0) - np.roll(h, 1, axis=0)) / (2 * self.spacing)
        else:
            gy, gx = np.gradient(h, self.spacing)
        return np.ascontiguousarray(gx), np.ascontiguousarray(gy)

    def normal_at(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Unit surface normal(s) (..., 3) at ENU positions [m].

        The normal is built from the bilinearly interpolated central-difference gradient of the samples
        (smooth shading), not from the facet of the bilinear patch, so shading has no visible cell edges.
        Off a finite grid the plain's normal is straight up.
        """
        u, v, ix, iy, ix1, iy1, inside = self._cell_coords(x, y)
        n = []
        for g in self._vertex_gradients:
            n.append(g[iy, ix] * (1 - u) * (1 - v) + g[iy, ix1] * u * (1 - v) + g[iy1, ix] * (1 - u) * v
                     + g[iy1, ix1] * u * v)
        gx = np.where(inside, n[0], 0.0)
        gy = np.where(inside, n[1], 0.0)
        normal = np.stack([-gx, -gy, np.ones_like(gx)], axis=-1)
        return normal / np.linalg.norm(normal, axis=-1, keepdims=True)

    # -- constructors -----------------------------------------------------------------------------------
    @classmethod
    def from_north_up(cls, raster: ArrayLike, spacing: float, *, origin: tuple[float, float] | None = None,
                      name: str = "terrain", base_height: float | None = None) -> Terrain:
        """A terrain from a north-up raster (row 0 = northern edge, column 0 = western edge).

        ``origin`` is the ENU position [m] of the south-west sample; by default the grid is centred on the
        ENU origin.
        """
        r = np.asarray(raster)  # converted (and its dtype checked) by the constructor
        if r.ndim != 2:
            raise InvalidParameterError(f"an elevation raster must be 2-D (rows, columns); got shape {r.shape}")
        h = r[::-1]
        if origin is None:
            ny, nx = h.shape
            origin = (-(nx - 1) * float(spacing) / 2, -(ny - 1) * float(spacing) / 2)
        return cls(h, spacing, origin=origin, name=name, base_height=base_height)

    @classmethod
    def load(cls, path: str | os.PathLike[str], *, spacing: float | None = None) -> Terrain:
        """Read a digital elevation model from ``.npy`` or GeoTIFF (``.tif``/``.tiff``, needs ``tifffile``).

        Parameters
        ----------
        path : path-like
            ``.npy`` with a 2-D float array of heights [m], north-up (row 0 = north edge); or a single-band
            GeoTIFF with heights [m] in a projected (metric) coordinate system.
        spacing : float, optional
            Sample spacing [m]. Required for ``.npy`` and for GeoTIFFs in a geographic (degree) or geocentric
            coordinate system; for other GeoTIFFs it defaults to the ModelPixelScale tag. Samples equal to the
            GDAL_NODATA value become NaN and are refused.

        Raises
        ------
        FileFormatError
            Unknown extension, unreadable file, wrong shape or dtype (complex, boolean), NaN/inf or no-data
            heights, heights beyond +-100 km, or no usable spacing.
        """
        p = Path(path)
        suffix = p.suffix.lower()
        if not p.is_file():
            raise FileFormatError(f"elevation model {p} does not exist")
        if suffix == ".npy":
            raster = _read_npy_heights(p)
            if spacing is None:
                raise FileFormatError(f"{p}: a .npy elevation model carries no sample spacing; pass spacing [m]")
        elif suffix in (".tif", ".tiff"):
            raster, tag_spacing, crs_kind = _read_geotiff(p)
            if spacing is None and tag_spacing is None:
                why = (f"its coordinate system is {crs_kind}, so the pixel scale is not a length in metres"
                       if crs_kind else "it has no ModelPixelScale tag")
                raise FileFormatError(f"{p}: {why}; pass the ground spacing of the samples [m] explicitly "
                                      "(--dem-spacing on the command line)")
            spacing = tag_spacing if spacing is None else spacing
        else:
            raise FileFormatError(f"{p}: unknown elevation model format {suffix!r}; use .npy, .tif or .tiff")
        if (raster.ndim != 2 or min(raster.shape) < 2 or not np.issubdtype(raster.dtype, np.number)
                or np.issubdtype(raster.dtype, np.complexfloating)):
            raise FileFormatError(
                f"{p}: an elevation model must be a 2-D real-valued array of at least 2 x 2 heights [m]; "
                f"got shape {raster.shape} and dtype {raster.dtype}"
            )
        try:
            return cls.from_north_up(raster, spacing, name=p.name)
        except InvalidParameterError as exc:
            raise FileFormatError(f"{p}: {exc}") from exc

    @classmethod
    def procedural(cls, *, seed: int = DEFAULT_SEED, size: int = 1024, spacing: float = 60.0,
                   relief: float = 2400.0) -> Terrain:
        """The built-in mountain landscape: seamless (periodic) fractal ridges from a fixed seed.

        Parameters
        ----------
        seed : int
            Random seed; the default gives the embedded demo landscape.
        size : int
            Samples per side (a power of two is fastest); the landscape repeats every ``size * spacing``.
        spacing : float
            Sample spacing [m].
        relief : float
            Height difference [m] between the lowest valley and the highest peak.
        """
        h = procedural_heights(seed=seed, size=size, relief=relief, spacing=spacing)
        return cls(h, spacing, origin=(-size * spacing / 2, -size * spacing / 2), wrap=True,
                   name=f"procedural(seed={seed}, size={size}, spacing={spacing:g} m)")


def procedural_heights(*, seed: int, size: int, relief: float, spacing: float = 60.0) -> NDArray[np.float64]:
    """Periodic fractal mountain heights [m], shape (size, size), from 0 m up to ``relief``.

    A ridged multifractal (Musgrave's construction) built by spectral synthesis: eight octaves of band-pass
    noise with wavelengths 16 km, 8 km, ... 125 m, each folded into crests with ``(1 - |n|)^2``, weighted by
    the previous octave (so detail gathers on ridges and valleys stay smooth) and damped by ``2^(-0.8 i)``,
    on top of a Brownian (``k^-2``) large-scale relief. The noise is uniform white noise from
    ``numpy.random.default_rng(seed)`` filtered with FFTs, so the field is periodic and tiles seamlessly.
    """
    if int(size) != size or size < 8:
        raise InvalidParameterError(f"procedural terrain size must be a whole number >= 8; got {size!r}")
    if not (np.isfinite(relief) and relief > 0):
        raise InvalidParameterError(f"relief must be a positive height [m]; got {relief!r}")
    if not (np.isfinite(spacing) and spacing > 0):
        raise InvalidParameterError(f"spacing must be a positive length [m]; got {spacing!r}")
    size = int(size)
    rng = np.random.default_rng(seed)
    ky = np.fft.fftfreq(size, d=spacing)  # [1/m]
    kx = np.fft.rfftfreq(size, d=spacing)
    kk = np.hypot(ky[:, None], kx[None, :])
    kk[0, 0] = 1e-12

    def filtered_noise(strength: NDArray[np.float64]) -> NDArray[np.float64]:
        strength = strength.copy()
        strength[0, 0] = 0.0
        f = np.fft.irfft2(np.fft.rfft2(rng.random((size, size)) - 0.5) * strength, s=(size, size))
        std = f.std()
        return f / std if std > 0 else f

    base = filtered_noise(1.0 / np.maximum(kk, 1.0 / 30_000.0) ** 2)
    ridged = np.zeros((size, size))
    weight = np.ones((size, size))
    wavelength = 16_000.0
    for octave in range(8):
        band = filtered_noise(np.exp(-0.5 * (np.log(kk * wavelength) / 0.45) ** 2))
        signal = (1.0 - np.abs(band)) ** 2 * weight
        weight = np.clip(2.0 * signal, 0.0, 1.0)
        ridged += signal * 2.0 ** (-0.8 * octave)
        wavelength /= 2.0
    h = ridged / ridged.std() + 0.8 * base
    lo, hi = np.percentile(h, [1.0, 99.9])
    h = np.clip((h - lo) / (hi - lo), 0.0, None)
    return relief * h / h.max()


def default_terrain() -> Terrain:
    """The embedded demo landscape: ``Terrain.procedural()`` with the fixed :data:`DEFAULT_SEED` (cached)."""
    return _default_terrain_cached()


_DEFAULT: list[Terrain] = []


def _default_terrain_cached() -> Terrain:
    if not _DEFAULT:
        _DEFAULT.append(Terrain.procedural())
    return _DEFAULT[0]


#: GeoTIFF GTModelTypeGeoKey codes (GeoTIFF 1.1, Sec. 7.1.1) whose pixel scale is not a length in metres.
_NON_METRIC_MODEL_TYPES = {2: "geographic (latitude/longitude)", 3: "geocentric"}


def _read_geotiff(path: Path) -> tuple[NDArray[np.float64], float | None, str | None]:
    try:
        import tifffile
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise FileFormatError(
            f"{path}: reading GeoTIFF needs the optional 'tifffile' package (pip install skyscatter[geotiff])"
        ) from exc
    try:
        with tifffile.TiffFile(path) as tif:
            page = tif.pages[0]
            raster = page.asarray()
            scale_tag = page.tags.get("ModelPixelScaleTag")
            scale = None if scale_tag is None else tuple(float(v) for v in scale_tag.value[:2])
            nodata_tag = page.tags.get("GDAL_NODATA")
            nodata = None if nodata_tag is None else str(nodata_tag.value).strip("\x00 ")
            geokeys = tif.geotiff_metadata or {}
    except Exception as exc:  # tifffile raises many exception types for broken files
        raise FileFormatError(f"cannot read {path} as a TIFF: {exc}") from exc
    raster = np.asarray(raster)
    if raster.ndim == 3 and 1 in raster.shape:
        raster = raster.squeeze()
    raster = raster.astype(np.float64)
    if nodata is not None:
        try:
            raster[raster == float(nodata)] = np.nan
        except ValueError:
            pass
    spacing = None
    if scale is not None:
        sx, sy = scale
        if not np.isclose(sx, sy, rtol=1e-6):
            raise FileFormatError(f"{path}: pixels are not square ({sx} x {sy}); resample the DEM first")
        spacing = sx
    model_type = geokeys.get("GTModelTypeGeoKey", 0)
    try:
        # tifffile gives an IntEnum whose str() is the number on Python >= 3.11: compare the code itself.
        model_type = int(model_type)
    except (TypeError, ValueError):
        model_type = 0
    if model_type in _NON_METRIC_MODEL_TYPES:
        # Pixel scale in degrees (geographic) or an earth-centred frame: not a ground spacing in metres.
        spacing = None
    return raster, spacing, _NON_METRIC_MODEL_TYPES.get(model_type)


#: Largest elevation model read [samples] (8192 x 8192: 0.5 GB as float64; the renderer needs a few copies).
MAX_DEM_SAMPLES = 8192 * 8192


def _read_npy_heights(p: Path) -> NDArray:
    """Read a .npy height grid, checking its header (format, dtype, size) before loading any data."""
    try:
        with open(p, "rb") as fh:
            version = np.lib.format.read_magic(fh)
            read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
            shape, _, dtype = read(fh)
    except (ValueError, OSError, EOFError) as exc:
        raise FileFormatError(f"{p}: not a NumPy .npy file ({exc})") from None
    if dtype.hasobject or dtype.kind not in "biuf":
        raise FileFormatError(
            f"{p}: an elevation model holds real-valued heights [m]; this .npy holds {dtype} values"
        )
    n = int(np.prod(shape, dtype=object)) if shape else 1
    if n > MAX_DEM_SAMPLES:
        raise FileFormatError(
            f"{p}: elevation model of {' x '.join(map(str, shape))} samples is larger than the "
            f"{MAX_DEM_SAMPLES:,} samples (8192 x 8192) supported; crop or resample it"
        )
    try:
        return np.load(p, allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise FileFormatError(f"{p}: cannot read the .npy data ({exc})") from None
