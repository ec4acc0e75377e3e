"""A family of precomputed tables over a grid of atmosphere parameters, interpolated per sample.

One set of tables (:class:`~skyscatter.precomputed.tables.PrecomputedAtmosphere`) costs about 12-20 s to build;
an hourly weather record asks for a different atmosphere every hour. A :class:`TableFamily` builds (and caches,
through :func:`~skyscatter.precomputed.cache.cached_atmosphere`) the tables at the nodes of a small grid over
the parameters that change from hour to hour, and gives any quantity computed from tables (sky radiance of
patches, irradiance, the sun) at intermediate parameters by multilinear interpolation between the ``2^k`` nodes
of the grid cell that holds them. Interpolating the quantity is the same as interpolating the tables (every
lookup is linear in the table values), so the result is the sky of the interpolated tables; with the sun below the
horizon or within the cell across it (up to +0.78 deg with the default tables), where the lookups read sub-texels
that are not linear in the stored texels or are computed (:func:`.lookup.refine_sun_zenith`), it is the
interpolation of the nodes' skies. The ground-only nodes (two rows, the second repeating the ground's) compute the
single scattering's sub-texels at the ground in both rows (``ground_rows``).

**Axes.** A :class:`GridAxis` names one parameter and its node values (increasing). The parameter is set on the
family's base atmosphere by the axis's *setter*, one function registered by name in :data:`AXIS_SETTERS`:

=================================  =====================================================================
``aerosol_optical_depth``           vertical aerosol optical depth at 550 nm [-] of the base's aerosol
                                    (Angstrom aerosol: ``beta = tau 0.55^alpha`` with the base's alpha; an
                                    OPAC type or mixture: its number densities scaled to it)
``aerosol_single_scattering_albedo``  the Angstrom aerosol's single-scattering albedo [-]
=================================  =====================================================================

A new axis (the cloud optical depth of the cloudy-skies work, a pressure scale of the Rayleigh optical depth
for high sites) is one more setter in :data:`AXIS_SETTERS` (:func:`register_axis`) and one more
:class:`GridAxis` in the family: nodes, cells, weights and evaluation are dimension-free. The interface is
documented in ``docs/architecture.md`` ("A family of tables").

**Memory.** The nodes' tables are loaded on demand and at most ``max_in_memory`` of them are kept (least recently
used first out); :meth:`TableFamily.interpolate` visits the samples cell by cell so that every node is loaded
about once. Nodes are not kept in the process-wide memory cache of :mod:`.cache`.

**Ground observers** (``ground_only=True``, what sky matrices need): a node keeps only the ground level of its
4D scattering tables (duplicated to the two levels of a ``scattering_r = 2`` table, so that the lookups of an
observer on the ground, which read level 0 with weight 1, are unchanged; the transmittance and irradiance tables
stay whole, so the sun and the irradiance are unchanged everywhere). 2 of 32 levels: 4.5 MB instead of 290 MB
for 23 wavelengths. The reduced node is cached beside the full tables (``family-ground-<key>.npz``, verified
when loaded) and is exact for ground observers only: anything above the ground must use the full tables
(``tests/test_spectral_skymatrix.py`` checks the equality).
"""

from __future__ import annotations

import dataclasses
import itertools
import warnings
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import FileFormatError, InvalidParameterError, OutputError
from .cache import cached_atmosphere
from .parameters import AtmosphereParameters
from .sizes import DEFAULT_ORDERS, TableSizes
from .tables import PrecomputedAtmosphere

__all__ = ["AXIS_SETTERS", "FAMILY_WAVELENGTHS", "GridAxis", "TableFamily", "register_axis"]

#: Table wavelengths [nm] of a family by default: the centres of the 20 bands 380-780 nm (390, 410, ..., 770)
#: and the ends of the medium's data (360 nm: ozone cross-sections; 800, 830 nm) so that broadband quantities
#: can be extended beyond the visible (:mod:`skyscatter.fit.weather`).
FAMILY_WAVELENGTHS = (360.0, *(float(w) for w in range(390, 771, 20)), 800.0, 830.0)


def _aerosol_optical_depth(atmosphere: AtmosphereParameters, value: float) -> AtmosphereParameters:
    from ..atmosphere.aerosol_types import OpacAerosol

    if atmosphere.aerosol is not None and not isinstance(atmosphere.aerosol, OpacAerosol):
        raise InvalidParameterError("the aerosol_optical_depth axis scales the Angstrom aerosol (mie_* fields) or an "
                                    "OPAC aerosol; this base atmosphere has another particle-component aerosol")
    if not 0.0 <= value <= 10.0:
        raise InvalidParameterError(f"aerosol optical depth nodes must be in [0, 10]; got {value:g}")
    if atmosphere.aerosol is not None:  # an OPAC type or mixture: its number densities scaled, ratios kept
        return atmosphere.replace(aerosol=dataclasses.replace(atmosphere.aerosol, optical_depth_550=float(value)))
    alpha = atmosphere.mie_angstrom_alpha
    return atmosphere.replace(mie_angstrom_beta=float(value) * 0.55**alpha)


def _aerosol_albedo(atmosphere: AtmosphereParameters, value: float) -> AtmosphereParameters:
    if atmosphere.aerosol is not None:
        raise InvalidParameterError("the aerosol_single_scattering_albedo axis sets the Angstrom aerosol's albedo; "
                                    "a particle-component aerosol has its own")
    return atmosphere.replace(mie_single_scattering_albedo=float(value))


#: Axis name -> ``setter(atmosphere, value) -> atmosphere`` (see the module docstring).
AXIS_SETTERS: dict[str, Callable[[AtmosphereParameters, float], AtmosphereParameters]] = {
    "aerosol_optical_depth": _aerosol_optical_depth,
    "aerosol_single_scattering_albedo": _aerosol_albedo,
}


def register_axis(name: str, setter: Callable[[AtmosphereParameters, float], AtmosphereParameters]) -> None:
    """Make ``name`` usable as a :class:`GridAxis`: ``setter(atmosphere, value)`` returns the atmosphere at that
    value of the parameter (validated there)."""
    if not isinstance(name, str) or not name:
        raise InvalidParameterError("an axis needs a name")
    AXIS_SETTERS[name] = setter


@dataclass(frozen=True)
class GridAxis:
    """One parameter of a :class:`TableFamily`: its name (a key of :data:`AXIS_SETTERS`), node values
    (strictly increasing, at least one) and unit."""

    name: str
    values: tuple[float, ...]
    unit: str = "-"

    def __post_init__(self) -> None:
        if self.name not in AXIS_SETTERS:
            raise InvalidParameterError(f"unknown grid axis {self.name!r}; known: {', '.join(sorted(AXIS_SETTERS))}")
        try:
            v = np.asarray(self.values, dtype=float)
        except (TypeError, ValueError):
            raise InvalidParameterError(f"axis {self.name}: node values must be numbers") from None
        if v.ndim != 1 or v.size < 1 or not np.all(np.isfinite(v)) or np.any(np.diff(v) <= 0):
            raise InvalidParameterError(f"axis {self.name}: node values must be finite and strictly increasing")
        object.__setattr__(self, "values", tuple(float(x) for x in v))


class TableFamily:
    """Precomputed tables at the nodes of a parameter grid, and multilinear interpolation between them.

    Parameters
    ----------
    axes : sequence of GridAxis
        The grid (one or more axes; an axis with one node is held fixed).
    base : AtmosphereParameters, optional
        The atmosphere the axes modify (default: the Earth defaults).
    wavelengths : array_like
        Table wavelengths [nm] (default :data:`FAMILY_WAVELENGTHS`).
    sizes : TableSizes or mapping, optional
        Table resolutions (default: the paper's).
    orders : int
        Scattering orders (default 6, with the geometric tail).
    max_in_memory : int
        Nodes kept loaded at once (at least ``2^k`` for k axes with two or more nodes).
    ground_only : bool
        Keep only what an observer on the ground needs (module docstring, "Ground observers").
    """

    def __init__(self, axes: Sequence[GridAxis], *, base: AtmosphereParameters | None = None,
                 wavelengths: ArrayLike = FAMILY_WAVELENGTHS, sizes: TableSizes | dict[str, int] | None = None,
                 orders: int = DEFAULT_ORDERS, max_in_memory: int | None = None, ground_only: bool = False) -> None:
        self.axes = tuple(axes)
        if not self.axes or not all(isinstance(a, GridAxis) for a in self.axes):
            raise InvalidParameterError("a table family needs one or more GridAxis")
        names = [a.name for a in self.axes]
        if len(set(names)) != len(names):
            raise InvalidParameterError(f"repeated grid axis in {names}")
        self.base = AtmosphereParameters() if base is None else base
        self.wavelengths = np.asarray(wavelengths, dtype=float)
        self.sizes = TableSizes.coerce(sizes)
        self.orders = int(orders)
        self.ground_only = bool(ground_only)
        corners = 2 ** sum(len(a.values) > 1 for a in self.axes)
        self.max_in_memory = max(int(max_in_memory or corners), corners)
        self._loaded: OrderedDict[tuple[int, ...], PrecomputedAtmosphere] = OrderedDict()
        for index in self.node_indices():  # every node's parameters are valid before anything is built
            self.parameters(index)

    # ------------------------------------------------------------------ grid

    @property
    def shape(self) -> tuple[int, ...]:
        """Nodes per axis."""
        return tuple(len(a.values) for a in self.axes)

    def node_indices(self) -> list[tuple[int, ...]]:
        """Every node's index tuple, in C order."""
        return list(itertools.product(*(range(n) for n in self.shape)))

    def parameters(self, index: Sequence[int]) -> AtmosphereParameters:
        """The atmosphere at node ``index`` (the base with each axis's setter applied in turn)."""
        p = self.base
        for axis, i in zip(self.axes, index, strict=True):
            p = AXIS_SETTERS[axis.name](p, axis.values[int(i)])
        return p

    def describe(self) -> dict[str, Any]:
        """JSON-compatible description (provenance of results computed from the family)."""
        return {"axes": {a.name: list(a.values) for a in self.axes}, "units": {a.name: a.unit for a in self.axes},
                "wavelengths_nm": self.wavelengths.tolist(), "orders": self.orders,
                "sizes": {k: getattr(self.sizes, k) for k in self.sizes.__dataclass_fields__},
                "ground_only": self.ground_only,
                "base": self.base.to_dict()}

    # ------------------------------------------------------------------ tables

    def node(self, index: Sequence[int], *, progress: bool | None = False) -> PrecomputedAtmosphere:
        """Tables at node ``index``: from the family's memory, the disk cache, or built and cached."""
        key = tuple(int(i) for i in index)
        atm = self._loaded.get(key)
        if atm is not None:
            self._loaded.move_to_end(key)
            return atm
        atmosphere = self.parameters(key)
        atm = (self._ground_node(atmosphere, progress) if self.ground_only else
               cached_atmosphere(atmosphere, orders=self.orders, wavelengths=self.wavelengths, sizes=self.sizes,
                                 progress=progress, keep_in_memory=False))
        self._loaded[key] = atm
        while len(self._loaded) > self.max_in_memory:
            self._loaded.popitem(last=False)
        return atm

    def _ground_node(self, atmosphere: AtmosphereParameters, progress: bool | None) -> PrecomputedAtmosphere:
        from .cache import cache_path
        from .storage import cache_key

        full_key = cache_key(atmosphere, self.orders, self.wavelengths, self.sizes)
        path = cache_path(full_key).with_name(f"family-ground-{full_key[:24]}.npz")
        if path.exists():
            try:
                atm = PrecomputedAtmosphere.load(path)
                if atm.parameters.canonical_json() == atmosphere.canonical_json() and atm.orders == self.orders \
                        and np.array_equal(atm.wavelengths, self.wavelengths):
                    atm.ground_rows = True  # its second row repeats the ground's
                    return atm
            except (FileFormatError, OSError):
                pass  # rebuilt below
        full = cached_atmosphere(atmosphere, orders=self.orders, wavelengths=self.wavelengths, sizes=self.sizes,
                                 progress=progress, keep_in_memory=False)
        tables = dict(full.tables)
        for name in ("single_rayleigh", "single_mie", "multiple"):
            tables[name] = np.repeat(full.tables[name][:1], 2, axis=0)
        sizes = dataclasses.replace(self.sizes, scattering_r=2)
        atm = PrecomputedAtmosphere(atmosphere, full.wavelengths, sizes, full.orders, tables, full.timings,
                                    computed=True, ground_rows=True)
        try:
            atm.save(path)
        except (OSError, OutputError) as exc:
            warnings.warn(f"could not cache the ground-level tables {path}: {exc}", RuntimeWarning, stacklevel=3)
        return atm

    def build(self, *, progress: bool = False) -> None:
        """Make sure every node's tables are in the disk cache (building the missing ones)."""
        for index in self.node_indices():
            self.node(index, progress=progress)

    # ------------------------------------------------------------------ interpolation

    def cells(self, values: ArrayLike) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.bool_]]:
        """Grid cell and position within it of each sample.

        Parameters
        ----------
        values : array_like, shape (n, k)
            Parameter values, one column per axis (in the axes' units).

        Returns
        -------
        lower : ndarray of int, shape (n, k)
            Index of each sample's lower node per axis.
        fraction : ndarray, shape (n, k)
            Position between the lower and the upper node, in [0, 1] (0 on an axis with one node).
        outside : ndarray of bool, shape (n, k)
            Values outside an axis's nodes (clamped to its end).
        """
        v = np.atleast_2d(np.asarray(values, dtype=float))
        if v.shape[1] != len(self.axes):
            raise InvalidParameterError(f"values need {len(self.axes)} columns (one per axis); got {v.shape[1]}")
        if not np.all(np.isfinite(v)):
            raise InvalidParameterError("parameter values to interpolate must be finite")
        n = v.shape[0]
        lower = np.zeros((n, len(self.axes)), dtype=np.int64)
        frac = np.zeros((n, len(self.axes)))
        outside = np.zeros((n, len(self.axes)), dtype=bool)
        for k, axis in enumerate(self.axes):
            nodes = np.asarray(axis.values)
            outside[:, k] = (v[:, k] < nodes[0]) | (v[:, k] > nodes[-1])
            if nodes.size == 1:
                continue
            x = np.clip(v[:, k], nodes[0], nodes[-1])
            i = np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, nodes.size - 2)
            lower[:, k] = i
            frac[:, k] = (x - nodes[i]) / (nodes[i + 1] - nodes[i])
        return lower, frac, outside

    def interpolate(self, values: ArrayLike,
                    evaluate: Callable[[PrecomputedAtmosphere, NDArray[np.int64]], NDArray[np.float64]], *,
                    progress: Callable[[int], None] | None = None, dtype: Any = np.float64) -> NDArray[np.floating]:
        """``sum_corners w_c evaluate(node_c, rows)`` for every sample (multilinear interpolation).

        Parameters
        ----------
        values : array_like, shape (n, k)
            Parameter values of the samples (clamped to the grid; see :meth:`cells`).
        evaluate : callable
            ``evaluate(tables, rows)`` returns the quantity for the samples ``rows`` (indices into ``values``)
            from one node's tables, an array of shape ``(len(rows), ...)``; the trailing shape must not depend
            on the node.
        progress : callable, optional
            Called with the number of samples finished after each cell.
        dtype : numpy dtype
            Of the result (float32 halves the memory of large results).

        Returns
        -------
        ndarray, shape (n, ...)
        """
        lower, frac, _ = self.cells(values)
        active = [k for k, m in enumerate(self.shape) if m > 1]
        n = lower.shape[0]
        out: NDArray[np.float64] | None = None
        if n == 0:
            return np.zeros((0,))
        # visit the cells in index order: consecutive cells share nodes, which then stay loaded
        keys = np.ravel_multi_index(tuple(lower.T), self.shape) if lower.size else np.zeros(n, dtype=np.int64)
        order = np.argsort(keys, kind="stable")
        bounds = np.flatnonzero(np.diff(keys[order])) + 1
        for rows in np.split(order, bounds):
            base = lower[rows[0]]
            for corner in itertools.product((0, 1), repeat=len(active)):
                index = base.copy()
                w = np.ones(rows.size)
                for bit, k in zip(corner, active, strict=True):
                    index[k] += bit
                    w *= frac[rows, k] if bit else 1.0 - frac[rows, k]
                if not np.any(w > 0):
                    continue
                vals = np.asarray(evaluate(self.node(index), rows))
                if out is None:
                    out = np.zeros((n, *vals.shape[1:]), dtype=dtype)
                out[rows] += (w.reshape(-1, *([1] * (vals.ndim - 1))) * vals).astype(dtype, copy=False)
            if progress is not None:
                progress(rows.size)
        assert out is not None
        return out
