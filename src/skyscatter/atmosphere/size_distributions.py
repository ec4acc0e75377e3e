"""Size distributions of spherical particles (radius [m]) and their quadrature nodes for Mie integrals.

Each distribution is a number density per unit radius normalised to one particle over all radii (0 to
infinity); the radius limits ``r_min``, ``r_max`` then remove the particles outside them without renormalising,
the convention of OPAC ([Hess1998] Sec. 3c: with it the cross-sections of OPAC's components are
reproduced to 0.2 %, tests/test_mie_optics.py, where renormalising on the range made the water-soluble and soot
components 4 % and 13 % too strong). :meth:`radius_nodes` gives the nodes and weights that :mod:`.mie_optics`
integrates cross-sections with.

* :class:`LogNormalMode` - ``n(r) = exp(-(ln r - ln r_mod)^2 / (2 ln^2 sigma)) / (sqrt(2 pi) ln sigma r)``: the
  modes of aerosol climatologies ([Hess1998] Eq. 3), with ``r_mod`` the number median radius and ``sigma > 1``
  the geometric standard deviation, optionally truncated to ``[r_min, r_max]`` as OPAC does.
* :class:`ModifiedGammaMode` - ``n(r) = a r^alpha exp(-b r^gamma)`` ([Deirmendjian1969] Eq. 2.3; OPAC's cloud
  droplets, [Hess1998] Eq. 4), for cloud
  droplets; :meth:`ModifiedGammaMode.from_effective` builds the gamma distribution (``gamma = 1``) of a given
  effective radius ``r_eff = <r^3> / <r^2>`` and effective variance ``v_eff`` ([HansenTravis1974] Eqs. 2.53-2.56:
  ``alpha = (1 - 3 v_eff) / v_eff``, ``b = 1 / (r_eff v_eff)``).

**Nodes.** Trapezoidal rule in ``ln r`` over the range that carries the scattering: for a log-normal mode from
``r_mod sigma^-5`` (number weighting) to ``r_mod exp(4 ln^2 sigma) sigma^5`` (the ``r^4`` weighting of the
diffraction peak), for a gamma mode from ``1e-3`` to 6 times the radius where ``r^4 n(r)`` peaks, each cut to
``[r_min, r_max]``; ``nodes_per_e`` nodes per unit of ``ln r`` (default 24). The trapezoidal rule in ``ln r`` of a
smooth, rapidly decaying integrand converges faster than any power of the step; the Mie ripple of single sizes
is averaged out by the width of the modes. tests/test_mie_optics.py measures the convergence.
"""

from __future__ import annotations

import abc
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import FileFormatError, InvalidParameterError

__all__ = ["LogNormalMode", "ModifiedGammaMode", "SizeDistribution", "size_distribution_from_dict"]

#: Default quadrature density: nodes per unit of ln r.
NODES_PER_E = 24


def _finite_positive(name: str, value: Any, allow_inf: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a number; got {value!r}") from None
    if math.isnan(v) or v <= 0 or (math.isinf(v) and not allow_inf):
        raise InvalidParameterError(f"{name} must be > 0{'' if allow_inf else ' and finite'}; got {value!r}")
    return v


class SizeDistribution(abc.ABC):
    """A number distribution of particle radii [m], normalised to one particle over all radii and cut to
    ``[r_min, r_max]`` (module docstring)."""

    r_min: float
    r_max: float

    @abc.abstractmethod
    def pdf(self, radius: NDArray[np.float64]) -> NDArray[np.float64]:
        """Number density per unit radius [m^-1] at ``radius`` [m] (0 outside ``[r_min, r_max]``)."""

    @abc.abstractmethod
    def _support(self) -> tuple[float, float]:
        """Radius range [m] that carries the scattering (before the cut to ``[r_min, r_max]``)."""

    @abc.abstractmethod
    def to_dict(self) -> dict[str, Any]:
        """JSON-compatible description with a ``"kind"`` key."""

    def _check_limits(self) -> None:
        lo = float(self.r_min)
        hi = float(self.r_max)
        if math.isnan(lo) or lo < 0 or math.isnan(hi) or hi <= lo:
            raise InvalidParameterError(
                f"radius limits need 0 <= r_min < r_max [m]; got {self.r_min!r}, {self.r_max!r}")
        object.__setattr__(self, "r_min", lo)
        object.__setattr__(self, "r_max", hi)

    def radius_nodes(self, nodes_per_e: float = NODES_PER_E) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Radii [m] and weights [-] (number fractions; they sum to the fraction of particles inside the limits,
        1 without limits) of the quadrature (module docstring)."""
        lo, hi = self._support()
        lo, hi = max(lo, self.r_min), min(hi, self.r_max)
        if not hi > lo:
            raise InvalidParameterError("the size distribution has no particles between r_min and r_max")
        n = max(41, math.ceil(math.log(hi / lo) * float(nodes_per_e)) + 1)  # >= 4 per sigma of a narrow mode
        t = np.linspace(math.log(lo), math.log(hi), n)
        r = np.exp(t)
        w = self.pdf(r) * r * (t[1] - t[0])
        w[0] *= 0.5
        w[-1] *= 0.5
        if not w.sum() > 0:
            raise InvalidParameterError("the size distribution has no particles between r_min and r_max")
        return r, w

    def moment(self, p: float, nodes_per_e: float = NODES_PER_E) -> float:
        """``<r^p>`` [m^p] of the particles inside the limits, over the quadrature nodes."""
        r, w = self.radius_nodes(nodes_per_e)
        return float(np.sum(w * r ** p) / np.sum(w))

    @property
    def effective_radius(self) -> float:
        """``<r^3> / <r^2>`` [m] (Hansen & Travis 1974, Eq. 2.53), on the quadrature nodes."""
        return self.moment(3.0) / self.moment(2.0)


@dataclass(frozen=True)
class LogNormalMode(SizeDistribution):
    """Log-normal number distribution (module docstring).

    Parameters
    ----------
    median_radius : float
        Number median (mode) radius ``r_mod`` [m], > 0.
    sigma : float
        Geometric standard deviation [-], > 1.
    r_min, r_max : float
        Truncation radii [m] (default 0 and infinity); particles outside them are left out (not renormalised).
    """

    median_radius: float
    sigma: float
    r_min: float = 0.0
    r_max: float = math.inf

    def __post_init__(self) -> None:
        object.__setattr__(self, "median_radius", _finite_positive("median radius", self.median_radius))
        try:
            s = float(self.sigma)
        except (TypeError, ValueError):
            raise InvalidParameterError(f"mode width sigma must be a number > 1; got {self.sigma!r}") from None
        if not (math.isfinite(s) and s > 1.0):
            raise InvalidParameterError(f"mode width sigma (geometric standard deviation) must be > 1; got {s!r}")
        object.__setattr__(self, "sigma", s)
        self._check_limits()

    def pdf(self, radius: NDArray[np.float64]) -> NDArray[np.float64]:
        r = np.asarray(radius, dtype=float)
        ls = math.log(self.sigma)
        with np.errstate(divide="ignore"):
            z = (np.log(r) - math.log(self.median_radius)) / ls
        out = np.exp(-0.5 * z * z) / (math.sqrt(2 * math.pi) * ls * r)
        return np.where((r >= self.r_min) & (r <= self.r_max) & (r > 0), out, 0.0)

    def _support(self) -> tuple[float, float]:
        ls = math.log(self.sigma)
        return self.median_radius * math.exp(-5 * ls), self.median_radius * math.exp(4 * ls * ls + 5 * ls)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "lognormal", "median_radius": self.median_radius, "sigma": self.sigma,
                "r_min": self.r_min, "r_max": self.r_max if math.isfinite(self.r_max) else None}


@dataclass(frozen=True)
class ModifiedGammaMode(SizeDistribution):
    """Modified gamma distribution ``a r^alpha exp(-b r^gamma)`` (module docstring), ``r`` in metres.

    Parameters
    ----------
    alpha : float
        Power of the radius [-], > -1.
    b : float
        Rate [m^-gamma], > 0.
    gamma : float
        Power in the exponent [-], > 0 (1: Hansen's gamma distribution).
    r_min, r_max : float
        Truncation radii [m] (default 0 and infinity).
    """

    alpha: float
    b: float
    gamma: float = 1.0
    r_min: float = 0.0
    r_max: float = math.inf

    def __post_init__(self) -> None:
        try:
            a = float(self.alpha)
        except (TypeError, ValueError):
            raise InvalidParameterError(f"gamma distribution alpha must be a number > -1; got {self.alpha!r}") from None
        if not (math.isfinite(a) and a > -1):
            raise InvalidParameterError(f"gamma distribution alpha must be > -1; got {self.alpha!r}")
        object.__setattr__(self, "alpha", a)
        object.__setattr__(self, "b", _finite_positive("gamma distribution rate b", self.b))
        object.__setattr__(self, "gamma", _finite_positive("gamma distribution exponent gamma", self.gamma))
        self._check_limits()

    @classmethod
    def from_effective(cls, effective_radius: float, effective_variance: float, r_min: float = 0.0,
                       r_max: float = math.inf) -> ModifiedGammaMode:
        """The gamma distribution (``gamma = 1``) of effective radius ``r_eff`` [m] > 0 and effective variance
        ``v_eff`` in (0, 1/3) [-] (Hansen & Travis 1974, Eq. 2.56; 0.1 is a typical water cloud)."""
        r_eff = _finite_positive("effective radius", effective_radius)
        try:
            v = float(effective_variance)
        except (TypeError, ValueError):
            raise InvalidParameterError(f"effective variance must be a number; got {effective_variance!r}") from None
        if not (math.isfinite(v) and 0.0 < v < 1.0 / 3.0):
            raise InvalidParameterError(f"effective variance must be in (0, 1/3); got {effective_variance!r}")
        return cls((1.0 - 3.0 * v) / v, 1.0 / (r_eff * v), 1.0, r_min, r_max)

    def _log_pdf_unnormalised(self, r: NDArray[np.float64]) -> NDArray[np.float64]:
        with np.errstate(divide="ignore"):
            return self.alpha * np.log(r) - self.b * r ** self.gamma

    def pdf(self, radius: NDArray[np.float64]) -> NDArray[np.float64]:
        r = np.asarray(radius, dtype=float)
        # normalisation over (0, inf): gamma * b^((alpha + 1) / gamma) / Gamma((alpha + 1) / gamma)
        s = (self.alpha + 1.0) / self.gamma
        log_c = math.log(self.gamma) + s * math.log(self.b) - math.lgamma(s)
        out = np.exp(log_c + self._log_pdf_unnormalised(np.maximum(r, 1e-300)))
        return np.where((r >= self.r_min) & (r <= self.r_max) & (r > 0), out, 0.0)

    def _support(self) -> tuple[float, float]:
        # r^4 n(r) peaks where d/dr [(alpha + 4) ln r - b r^gamma] = 0
        peak = ((self.alpha + 4.0) / (self.b * self.gamma)) ** (1.0 / self.gamma)
        return peak * 1e-3, peak * 6.0

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "modified_gamma", "alpha": self.alpha, "b": self.b, "gamma": self.gamma,
                "r_min": self.r_min, "r_max": self.r_max if math.isfinite(self.r_max) else None}


def size_distribution_from_dict(data: dict[str, Any]) -> SizeDistribution:
    """Inverse of ``to_dict`` of the distributions (FileFormatError if malformed)."""
    try:
        r_max = math.inf if data.get("r_max") is None else float(data["r_max"])
        if data["kind"] == "lognormal":
            return LogNormalMode(data["median_radius"], data["sigma"], data.get("r_min", 0.0), r_max)
        if data["kind"] == "modified_gamma":
            return ModifiedGammaMode(data["alpha"], data["b"], data.get("gamma", 1.0), data.get("r_min", 0.0), r_max)
    except (KeyError, TypeError) as exc:
        raise FileFormatError(f"size distribution description is malformed: {exc}") from None
    raise FileFormatError(f"unknown size distribution kind {data.get('kind')!r}")
