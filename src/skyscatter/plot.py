"""Pictures of skies: polar sky maps, relative error maps and spectra (matplotlib: the ``plot`` extra).

Every function takes a sky through the protocol only (``luminance(directions)``, ``xyz(directions)``,
``spectral_radiance(directions, wavelengths)``: any model of the registry, or any object with those methods) or
the values themselves as arrays on the map's grid (:func:`sky_grid`). Maps show the upper hemisphere as an
all-sky camera looking up sees it, like skyscatter's fisheye images (docs/conventions.md): zenith at the
centre, zenith angle along the radius (equidistant, degrees), north up and east on the left.

matplotlib is imported on first use, so ``import skyscatter.plot`` works without it; drawing without it raises
:class:`~skyscatter.errors.MissingDependencyError` naming the extra. Nothing here picks a matplotlib backend:
scripts that draw without a display call ``matplotlib.use("Agg")`` first.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .conventions import direction_from_angles
from .errors import InvalidParameterError, MissingDependencyError
from .spectral import DEFAULT_WAVELENGTHS, xyz_to_chromaticity

__all__ = ["SkyGrid", "SkyMap", "SpectraPlot", "chromaticity_map", "error_map", "luminance_map", "sky_grid",
           "spectra"]

#: Axis and colour-bar labels (units in brackets, as everywhere in skyscatter).
LUMINANCE_LABEL = "luminance [cd m$^{-2}$]"
SPECTRAL_RADIANCE_LABEL = "spectral radiance [W m$^{-2}$ sr$^{-1}$ nm$^{-1}$]"
WAVELENGTH_LABEL = "wavelength [nm]"
POLAR_LABEL = "zenith angle [deg] (radius); north up, east left"


def _pyplot() -> Any:
    try:
        import matplotlib.pyplot as plt
    except ImportError:
        raise MissingDependencyError(
            "skyscatter.plot needs matplotlib, which is not installed: pip install 'skyscatter[plot]'") from None
    return plt


def _colors() -> Any:
    _pyplot()
    import matplotlib.colors

    return matplotlib.colors


@dataclass(frozen=True)
class SkyGrid:
    """Cells of a polar sky map: ``n_zenith`` rings from the zenith to the horizon times ``n_azimuth`` sectors.

    ``zenith`` and ``azimuth`` are the cell centres [rad] (azimuth from north towards east);
    :attr:`directions` are their unit ENU vectors, shape (n_zenith, n_azimuth, 3).
    """

    n_zenith: int
    n_azimuth: int

    @property
    def shape(self) -> tuple[int, int]:
        return self.n_zenith, self.n_azimuth

    @property
    def zenith_edges(self) -> NDArray[np.float64]:
        """Ring edges [rad], 0 (zenith) .. pi/2 (horizon)."""
        return np.linspace(0.0, 0.5 * math.pi, self.n_zenith + 1)

    @property
    def azimuth_edges(self) -> NDArray[np.float64]:
        """Sector edges [rad], 0 .. 2 pi."""
        return np.linspace(0.0, 2.0 * math.pi, self.n_azimuth + 1)

    @property
    def zenith(self) -> NDArray[np.float64]:
        e = self.zenith_edges
        return 0.5 * (e[:-1] + e[1:])

    @property
    def azimuth(self) -> NDArray[np.float64]:
        e = self.azimuth_edges
        return 0.5 * (e[:-1] + e[1:])

    @property
    def directions(self) -> NDArray[np.float64]:
        return direction_from_angles(self.zenith[:, None], self.azimuth[None, :])


def sky_grid(n_zenith: int = 90, n_azimuth: int = 360) -> SkyGrid:
    """The grid of a polar sky map.

    Parameters
    ----------
    n_zenith : int
        Rings between the zenith and the horizon (>= 2); 90 gives 1 deg rings.
    n_azimuth : int
        Sectors around the horizon (>= 4); 360 gives 1 deg sectors.
    """
    for name, value, low in (("n_zenith", n_zenith, 2), ("n_azimuth", n_azimuth, 4)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or not low <= value <= 100_000:
            raise InvalidParameterError(f"{name} {value!r} must be an integer from {low} to 100000")
    return SkyGrid(int(n_zenith), int(n_azimuth))


@dataclass
class SkyMap:
    """One polar map: the matplotlib figure, axes, mesh and colour bar, and the values drawn on ``grid``."""

    figure: Any
    axes: Any
    mesh: Any
    colorbar: Any
    values: NDArray[np.float64]
    grid: SkyGrid


@dataclass
class SpectraPlot:
    """A spectra plot: figure, axes, one line per (source, direction), and the values, (n_sources, n_dir, n_wl)."""

    figure: Any
    axes: Any
    lines: list[Any]
    values: NDArray[np.float64]
    wavelengths: NDArray[np.float64]


def _evaluate(source: Any, method: str, grid: SkyGrid, trailing: tuple[int, ...], what: str) -> NDArray[np.float64]:
    """``source.method`` on the grid's directions, or ``source`` itself as an array of shape grid.shape + trailing."""
    if hasattr(source, method):
        out = np.asarray(getattr(source, method)(grid.directions.reshape(-1, 3)), dtype=float)
        return out.reshape(grid.shape + trailing)
    values = np.asarray(source, dtype=float)
    if values.shape != grid.shape + trailing:
        raise InvalidParameterError(
            f"{what} must be a sky (an object with a {method}(directions) method) or an array of shape "
            f"{grid.shape + trailing} on the map's grid, got shape {values.shape}")
    return values


def _polar_axes(ax: Any, figure: Any | None = None) -> tuple[Any, Any]:
    plt = _pyplot()
    if ax is None:
        figure = plt.figure(figsize=(5.4, 4.6)) if figure is None else figure
        ax = figure.add_subplot(projection="polar")
    if getattr(ax, "name", None) != "polar":
        raise InvalidParameterError("ax must be a polar matplotlib axes (projection='polar') or None")
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(1)  # counter-clockwise from north: east on the left, as seen looking up
    return ax.figure, ax


def _draw(values: NDArray[np.float64], grid: SkyGrid, ax: Any, *, cmap: str, norm: Any, label: str,
          title: str | None, sun: tuple[float, float] | None) -> SkyMap:
    figure, ax = _polar_axes(ax)
    mesh = ax.pcolormesh(grid.azimuth_edges, np.degrees(grid.zenith_edges), np.ma.masked_invalid(values),
                         cmap=cmap, norm=norm, shading="flat")
    ax.set_ylim(0.0, 90.0)
    ax.set_yticks([30.0, 60.0, 90.0], ["30°", "60°", "90°"])
    ax.set_rlabel_position(22.5)
    from matplotlib import patheffects  # matplotlib is there: _polar_axes imported it

    for tick in ax.get_yticklabels():  # readable on dark and light cells alike
        tick.set_path_effects([patheffects.withStroke(linewidth=2.5, foreground="white")])
    ax.set_xticks(np.radians([0.0, 90.0, 180.0, 270.0]), ["N", "E", "S", "W"])
    ax.set_xlabel(POLAR_LABEL, fontsize="small")
    ax.grid(True, alpha=0.35)
    if sun is not None:
        zen, azi = sun
        if zen <= 0.5 * math.pi:
            ax.plot([azi], [math.degrees(zen)], marker="o", mfc="none", mec="cyan", ms=9, mew=1.5)
    if title:
        ax.set_title(title)
    colorbar = figure.colorbar(mesh, ax=ax, pad=0.1, shrink=0.85)
    colorbar.set_label(label)
    return SkyMap(figure, ax, mesh, colorbar, values, grid)


def _grid(grid: SkyGrid | None) -> SkyGrid:
    return sky_grid() if grid is None else grid


def luminance_map(sky: Any, *, grid: SkyGrid | None = None, ax: Any = None, log: bool = False,
                  vmin: float | None = None, vmax: float | None = None, cmap: str = "inferno",
                  title: str | None = None, sun: tuple[float, float] | None = None) -> SkyMap:
    """Polar map of the sky's luminance [cd m^-2] with a colour bar.

    Parameters
    ----------
    sky : sky or array_like
        A sky (``luminance(directions)``) or luminances [cd m^-2] of shape ``grid.shape``.
    grid : SkyGrid, optional
        Map cells (:func:`sky_grid`; default 1 x 1 deg).
    ax : matplotlib polar axes, optional
        Where to draw; a new figure when None.
    log : bool
        Logarithmic colour scale (the sky's range near the sun spans decades).
    vmin, vmax : float, optional
        Colour-bar limits [cd m^-2]; default the values' range.
    sun : (float, float), optional
        Sun zenith and azimuth [rad], drawn as a ring when above the horizon.
    """
    mcolors = _colors()
    grid = _grid(grid)
    values = _evaluate(sky, "luminance", grid, (), "sky")
    finite = values[np.isfinite(values)]
    if log:
        positive = finite[finite > 0]
        lo = vmin if vmin is not None else (float(positive.min()) if positive.size else 1e-3)
        hi = vmax if vmax is not None else (float(positive.max()) if positive.size else 1.0)
        norm = mcolors.LogNorm(vmin=lo, vmax=hi)
    else:
        lo = vmin if vmin is not None else (float(finite.min()) if finite.size else 0.0)
        hi = vmax if vmax is not None else (float(finite.max()) if finite.size else 1.0)
        norm = mcolors.Normalize(vmin=lo, vmax=hi)
    return _draw(values, grid, ax, cmap=cmap, norm=norm, label=LUMINANCE_LABEL, title=title, sun=sun)


def chromaticity_map(sky: Any, *, grid: SkyGrid | None = None, axes: Sequence[Any] | None = None,
                     cmap: str = "viridis", title: str | None = None,
                     sun: tuple[float, float] | None = None) -> tuple[SkyMap, SkyMap]:
    """Polar maps of the CIE 1931 chromaticity x and y of the sky, side by side, each with its colour bar.

    Parameters
    ----------
    sky : sky or array_like
        A sky (``xyz(directions)``, CIE 1931 XYZ [cd m^-2]) or XYZ of shape ``grid.shape + (3,)``.
    axes : two matplotlib polar axes, optional
        Where to draw x and y; a new figure with two panels when None.
    title : str, optional
        Figure title (the panels are titled x and y).
    sun : (float, float), optional
        Sun zenith and azimuth [rad], marked on both maps.

    Returns
    -------
    (SkyMap, SkyMap)
        The x map and the y map (values dimensionless).
    """
    plt, mcolors = _pyplot(), _colors()
    grid = _grid(grid)
    xy = xyz_to_chromaticity(_evaluate(sky, "xyz", grid, (3,), "sky"))
    if axes is None:
        figure = plt.figure(figsize=(10.4, 4.6))
        axes = [figure.add_subplot(1, 2, k + 1, projection="polar") for k in range(2)]
    if len(axes) != 2:
        raise InvalidParameterError(f"axes must hold 2 polar axes (x and y), got {len(axes)}")
    maps = []
    for k, name in enumerate("xy"):
        values = xy[..., k]
        norm = mcolors.Normalize(vmin=float(np.nanmin(values)), vmax=float(np.nanmax(values)))
        maps.append(_draw(values, grid, axes[k], cmap=cmap, norm=norm, label=f"CIE 1931 chromaticity {name} [-]",
                          title=f"chromaticity {name}", sun=sun))
    if title:
        maps[0].figure.suptitle(title)
    return maps[0], maps[1]


def error_map(sky: Any, reference: Any, *, wavelength: float | None = None, grid: SkyGrid | None = None,
              ax: Any = None, limit: float | None = None, cmap: str = "RdBu_r", title: str | None = None,
              sun: tuple[float, float] | None = None) -> SkyMap:
    """Polar map of the relative error ``sky / reference - 1`` [%], on a symmetric diverging colour bar.

    Parameters
    ----------
    sky, reference : sky or array_like
        Two skies (model against model), or a sky and reference values on ``grid`` (model against a
        reference, e.g. Monte Carlo radiances), or two arrays of shape ``grid.shape``.
    wavelength : float, optional
        Compare spectral radiance at this wavelength [nm] (``spectral_radiance(directions, [wavelength])``)
        instead of luminance. Arrays are then spectral radiances [W m^-2 sr^-1 nm^-1] at that wavelength.
    limit : float, optional
        Colour-bar half range [%]; default the largest absolute error (1 % if every error is 0).
        Cells where the reference is 0 or not finite are left blank.
    """
    mcolors = _colors()
    grid = _grid(grid)
    if wavelength is None:
        a = _evaluate(sky, "luminance", grid, (), "sky")
        b = _evaluate(reference, "luminance", grid, (), "reference")
        what = "luminance"
    else:
        wl = float(wavelength)
        if not math.isfinite(wl) or not 360.0 <= wl <= 830.0:
            raise InvalidParameterError(f"wavelength {wavelength!r} must be a number of nm in 360-830")
        a, b = (_spectral_on_grid(s, grid, wl, name) for s, name in ((sky, "sky"), (reference, "reference")))
        what = f"spectral radiance at {wl:g} nm"
    with np.errstate(divide="ignore", invalid="ignore"):
        err = np.where((b != 0) & np.isfinite(b), 100.0 * (a / b - 1.0), np.nan)
    if limit is None:
        peak = float(np.nanmax(np.abs(err))) if np.isfinite(err).any() else 0.0
        limit = peak if peak > 0 else 1.0
    elif not (math.isfinite(limit) and limit > 0):
        raise InvalidParameterError(f"limit {limit!r} must be a positive number of percent")
    norm = mcolors.Normalize(vmin=-limit, vmax=limit)
    return _draw(err, grid, ax, cmap=cmap, norm=norm, label=f"relative error of the {what} [%]", title=title,
                 sun=sun)


def _spectral_on_grid(source: Any, grid: SkyGrid, wavelength: float, what: str) -> NDArray[np.float64]:
    if hasattr(source, "spectral_radiance"):
        out = np.asarray(source.spectral_radiance(grid.directions.reshape(-1, 3), [wavelength]), dtype=float)
        return out.reshape(grid.shape)
    return _evaluate(source, "spectral_radiance", grid, (), what)


def _label(source: Any, k: int) -> str:
    name = getattr(source, "model_name", None)
    return name or (type(source).__name__ if hasattr(source, "spectral_radiance") else f"values {k + 1}")


def spectra(sources: Any, directions: ArrayLike, wavelengths: ArrayLike | None = None, *,
            labels: Sequence[str] | None = None, ax: Any = None, log: bool = False,
            title: str | None = None) -> SpectraPlot:
    """Spectral radiance [W m^-2 sr^-1 nm^-1] against wavelength [nm]: one line per source and direction.

    Parameters
    ----------
    sources : sky, array_like, or a list of them
        Skies (``spectral_radiance(directions, wavelengths)``) or spectral radiances of shape
        (n_directions, n_wavelengths) [W m^-2 sr^-1 nm^-1].
    directions : array_like, shape (3,) or (n, 3)
        View directions (ENU unit vectors); the legend gives each one's zenith and azimuth [deg].
    wavelengths : array_like, optional
        [nm]; default :data:`skyscatter.spectral.DEFAULT_WAVELENGTHS` (380-780 nm, 10 nm). Needed with arrays.
    labels : sequence of str, optional
        One name per source (default the model's registry name).
    log : bool
        Logarithmic radiance axis.
    """
    plt = _pyplot()
    single = hasattr(sources, "spectral_radiance") or (not isinstance(sources, list | tuple))
    items = [sources] if single else list(sources)
    if labels is not None and len(labels) != len(items):
        raise InvalidParameterError(f"labels must give one name per source ({len(items)}), got {len(labels)}")
    d = np.asarray(directions, dtype=float).reshape(-1, 3)
    norms = np.linalg.norm(d, axis=-1)
    if not np.all(np.isfinite(d)) or np.any(norms == 0):
        raise InvalidParameterError("directions must be finite, non-zero ENU vectors of shape (3,) or (n, 3)")
    d = d / norms[:, None]
    wl = np.asarray(DEFAULT_WAVELENGTHS if wavelengths is None else wavelengths, dtype=float).ravel()
    values = []
    for k, source in enumerate(items):
        if hasattr(source, "spectral_radiance"):
            v = np.asarray(source.spectral_radiance(d, wl), dtype=float).reshape(d.shape[0], wl.size)
        else:
            v = np.asarray(source, dtype=float)
            if v.shape == (wl.size,) and d.shape[0] == 1:
                v = v[None, :]
            if v.shape != (d.shape[0], wl.size):
                raise InvalidParameterError(
                    f"source {k + 1} must be a sky (an object with spectral_radiance) or an array of shape "
                    f"({d.shape[0]}, {wl.size}) (directions x wavelengths), got shape {v.shape}")
        values.append(v)
    if ax is None:
        figure = plt.figure(figsize=(6.4, 4.2))
        ax = figure.add_subplot()
    zen = np.degrees(np.arccos(np.clip(d[:, 2], -1.0, 1.0)))
    azi = np.degrees(np.arctan2(d[:, 0], d[:, 1])) % 360.0
    lines = []
    for k, (source, v) in enumerate(zip(items, values, strict=True)):
        name = labels[k] if labels is not None else _label(source, k)
        for j in range(d.shape[0]):
            (line,) = ax.plot(wl, v[j], label=f"{name}, zenith {zen[j]:.0f}°, azimuth {azi[j]:.0f}°")
            lines.append(line)
    ax.set_xlabel(WAVELENGTH_LABEL)
    ax.set_ylabel(SPECTRAL_RADIANCE_LABEL)
    if log:
        ax.set_yscale("log")
    ax.grid(True, alpha=0.35)
    ax.legend(fontsize="small")
    if title:
        ax.set_title(title)
    return SpectraPlot(ax.figure, ax, lines, np.stack(values), wl)
