"""Density profiles of the medium's components: relative density (1 = the reference density of a component's
coefficients) as a function of altitude [m] above the ground.

A :class:`DensityProfile` is a stack of :class:`DensityLayer` s, each ``max(0, a exp(b h) + c h + d)``: the form
of [Bruneton2017], the rewrite of [Bruneton2008] (Sec. 2.1, Eqs. 1 and 3 for the exponential
profiles), which covers exponential, tent (ozone), box (a cloud or a well-mixed layer)
and boundary-layer profiles. Re-exported by :mod:`.medium`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError

__all__ = ["DensityLayer", "DensityProfile"]


@dataclass(frozen=True)
class DensityLayer:
    """One layer of a density profile: ``max(0, exp_term * exp(exp_scale * h) + linear_term * h + constant_term)``.

    ``h`` is the altitude above the planet surface [m]; ``width`` [m] is the thickness of the layer (ignored
    for the last layer of a profile, which extends upwards without limit).
    """

    width: float = 0.0
    exp_term: float = 0.0
    exp_scale: float = 0.0
    linear_term: float = 0.0
    constant_term: float = 0.0

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if not math.isfinite(v):
                raise InvalidParameterError(f"density layer {f.name} must be finite; got {v!r}")
        if self.width < 0:
            raise InvalidParameterError(f"density layer width must be >= 0 m; got {self.width!r}")


@dataclass(frozen=True)
class DensityProfile:
    """Relative density (1 = the reference density of the coefficients) as a stack of :class:`DensityLayer`."""

    layers: tuple[DensityLayer, ...]

    def __post_init__(self) -> None:
        if not self.layers:
            raise InvalidParameterError("a density profile needs at least one layer")
        object.__setattr__(self, "layers", tuple(self.layers))

    @classmethod
    def exponential(cls, scale_height: float) -> DensityProfile:
        """``exp(-h / scale_height)`` (Eqs. 1 and 3); ``scale_height`` [m] > 0."""
        if not (math.isfinite(scale_height) and scale_height > 0):
            raise InvalidParameterError(f"scale height must be > 0 m; got {scale_height!r}")
        return cls((DensityLayer(0.0, 1.0, -1.0 / scale_height, 0.0, 0.0),))

    @classmethod
    def tent(cls, bottom: float, peak: float, top: float) -> DensityProfile:
        """Piecewise-linear layer: 0 below ``bottom``, rising to 1 at ``peak``, 0 again from ``top`` [m]."""
        if not (0 <= bottom < peak < top and math.isfinite(top)):
            raise InvalidParameterError(f"tent profile needs 0 <= bottom < peak < top [m]; got {bottom}, {peak}, {top}")
        up = 1.0 / (peak - bottom)
        down = 1.0 / (top - peak)
        return cls((DensityLayer(peak, 0.0, 0.0, up, -bottom * up), DensityLayer(0.0, 0.0, 0.0, -down, top * down)))

    @classmethod
    def box(cls, bottom: float, top: float) -> DensityProfile:
        """Density 1 from ``bottom`` to ``top`` [m] above the surface, 0 elsewhere (a cloud, a well-mixed layer);
        ``0 <= bottom < top``, finite."""
        b, t = float(bottom), float(top)
        if not (math.isfinite(b) and math.isfinite(t) and 0.0 <= b < t):
            raise InvalidParameterError(f"box profile needs 0 <= bottom < top [m], finite; got {bottom!r}, {top!r}")
        layers = [DensityLayer(b, 0.0, 0.0, 0.0, 0.0)] if b > 0 else []
        layers += [DensityLayer(t - b, 0.0, 0.0, 0.0, 1.0), DensityLayer(0.0, 0.0, 0.0, 0.0, 0.0)]
        return cls(tuple(layers))

    @classmethod
    def boundary_layer(cls, height: float, scale_height: float) -> DensityProfile:
        """Density 1 up to ``height`` [m] (a well-mixed boundary layer), ``exp(-(h - height) / scale_height)``
        above it; ``height`` >= 0 and ``scale_height`` > 0 [m], ``height / scale_height`` <= 600."""
        z, hs = float(height), float(scale_height)
        if not (math.isfinite(z) and z >= 0 and math.isfinite(hs) and hs > 0):
            raise InvalidParameterError(
                f"boundary-layer profile needs height >= 0 m and scale height > 0 m; got {height!r}, {scale_height!r}")
        if z / hs > 600:
            raise InvalidParameterError(f"boundary-layer profile: height / scale height must be <= 600; got {z / hs:g}")
        if z == 0:
            return cls.exponential(hs)
        return cls((DensityLayer(z, 0.0, 0.0, 0.0, 1.0), DensityLayer(0.0, math.exp(z / hs), -1.0 / hs, 0.0, 0.0)))

    @classmethod
    def uniform(cls) -> DensityProfile:
        """Density 1 at every altitude."""
        return cls((DensityLayer(0.0, 0.0, 0.0, 0.0, 1.0),))

    def __call__(self, altitude: ArrayLike) -> NDArray[np.float64]:
        """Relative density at ``altitude`` [m] above the surface."""
        h = np.asarray(altitude, dtype=float)
        out = np.zeros_like(h)
        start = 0.0
        done = np.zeros(h.shape, dtype=bool)
        for k, layer in enumerate(self.layers):
            last = k == len(self.layers) - 1
            sel = ~done if last else (~done & (h < start + layer.width))
            v = layer.exp_term * np.exp(layer.exp_scale * h) + layer.linear_term * h + layer.constant_term
            out = np.where(sel, np.maximum(v, 0.0), out)
            done |= sel
            start += layer.width
        return out

    def column(self, height: float) -> float:
        """Integral of the relative density from the surface to ``height`` [m] (an equivalent thickness [m])."""
        return _profile_column(self, float(height))

    def as_array(self) -> NDArray[np.float64]:
        """Layers as an (n_layers, 5) array: width, exp_term, exp_scale, linear_term, constant_term."""
        return np.array([[la.width, la.exp_term, la.exp_scale, la.linear_term, la.constant_term] for la in self.layers])

    def to_dict(self) -> list[dict[str, float]]:
        return [dataclasses.asdict(la) for la in self.layers]

    @classmethod
    def from_dict(cls, data: list[dict[str, float]]) -> DensityProfile:
        return cls(tuple(DensityLayer(**la) for la in data))


@lru_cache(maxsize=64)
def _profile_column(profile: DensityProfile, height: float) -> float:
    # Fine trapezoid with the layer boundaries as nodes: exact for linear layers, better than 1e-6 relative
    # for exponential ones with scale heights of 1 km and more.
    edges = list(np.cumsum([0.0] + [lay.width for lay in profile.layers[:-1]]))
    # zero crossings of linear layers are kinks of max(0, .)
    edges += [-lay.constant_term / lay.linear_term for lay in profile.layers
              if lay.linear_term != 0 and lay.exp_term == 0]
    e = np.array(edges)
    nodes = np.unique(np.concatenate([np.linspace(0.0, height, 40001), e[(e > 0) & (e < height)]]))
    column = float(np.trapezoid(profile(nodes), nodes))
    # A layer boundary where the density jumps (a box, a cloud's base and top): the node there takes the upper
    # layer's value, so the cell below it is corrected to the lower layer's limit. Continuous profiles (all the
    # defaults) are left untouched, bit for bit.
    start = 0.0
    for below, above in zip(profile.layers[:-1], profile.layers[1:], strict=False):
        start += below.width
        if not 0.0 < start < height:
            continue
        jump = _layer_value(below, start) - _layer_value(above, start)
        if abs(jump) > 1e-9:
            k = int(np.searchsorted(nodes, start))
            column += 0.5 * (nodes[k] - nodes[k - 1]) * jump
    return column


def _layer_value(layer: DensityLayer, h: float) -> float:
    return max(0.0, layer.exp_term * math.exp(layer.exp_scale * h) + layer.linear_term * h + layer.constant_term)
