"""Scattering phase functions [sr^-1], each normalised to 1 over the sphere, and their sampling.

The one description of the phase functions in skyscatter; every model (the Preetham aerial perspective, the
precomputed Bruneton tables, the path tracer) uses this module.

* Rayleigh: ``3 / (16 pi) (1 + mu^2)`` ([Preetham1999] A.3; [Bruneton2008] Eq. 2).
* Henyey-Greenstein [HenyeyGreenstein1941]: ``(1 - g^2) / (4 pi (1 + g^2 - 2 g mu)^(3/2))``.
* Cornette-Shanks [CornetteShanks1992] (the Mie phase of [Bruneton2008] Eq. 4):
  ``3 (1 - g^2) (1 + mu^2) / (8 pi (2 + g^2) (1 + g^2 - 2 g mu)^(3/2))``.

``mu`` is the cosine of the scattering angle (1 = forward scattering). The numpy functions take ``cos_theta``
of any shape and return that shape. Each formula is written once, as a plain arithmetic function that numpy
evaluates on arrays and numba compiles for scalars. The jitted scalar versions are attributes of this module
built on first access (in :mod:`._phase_numba`), so importing :mod:`skyscatter.atmosphere` does not import
numba:

* densities ``rayleigh_phase_scalar(mu)``, ``henyey_greenstein_scalar(mu, g)``, ``cornette_shanks_scalar(mu,
  g)`` and ``aerosol_phase_scalar(mu, g, kind)`` with ``kind`` from :func:`aerosol_phase_kind`;
* inverse CDFs ``rayleigh_inverse_cdf_scalar(u)`` and ``henyey_greenstein_inverse_cdf_scalar(u, g)`` (the
  same formulas as :func:`rayleigh_inverse_cdf` and :func:`henyey_greenstein_inverse_cdf`, without their
  validation);
* ``direction_about_axis(ax, ay, az, mu, phi)``: the unit vector at angle ``acos(mu)`` from a unit axis and at
  azimuth ``phi`` about it, in the orthonormal basis of [Duff2017] Listing 3.

Sampling (cosines of the scattering angle; the azimuth about the incident direction is uniform):

* Rayleigh: exact inverse CDF. ``F(mu) = (mu^3 + 3 mu + 4) / 8``; the one real root of the cubic
  ``mu^3 + 3 mu - z = 0``, ``z = 4 u - 2``, is ``mu = a - 1 / a`` with ``a = cbrt(z + sqrt(z^2 + 1))``
  (Cardano; [Frisvad2011] Eq. 13 without
  depolarisation). The root is odd in ``z``; it is evaluated as
  ``sign(z) (a - 1 / a)`` with ``a = cbrt(|z| + sqrt(z^2 + 1))``, a sum of positive terms (no cancellation), so
  ``u = 0`` and ``u = 1`` give exactly -1 and 1 and ``F(mu(u)) - u`` stays within a few 1e-16.
* Henyey-Greenstein: exact inverse CDF ``mu = (1 + g^2 - ((1 - g^2) / (1 - g + 2 g u))^2) / (2 g)``
  (from integrating the density; [Witt1977]
  Eq. 7); its limit for ``g -> 0``, ``mu = 2 u - 1``, is used for ``|g| < 1e-6``. Both are increasing in ``u``.
* Cornette-Shanks: from Henyey-Greenstein with the same ``g`` and the weight
  :func:`cornette_shanks_hg_weight` ``w(mu) = p_CS / p_HG = 3 (1 + mu^2) / (2 (2 + g^2))``, which lies in
  ``[3 / (2 (2 + g^2)), 3 / (2 + g^2)]`` (0.57-1.14 for g = 0.8; the bound is reached at ``mu = 0`` and
  ``mu = +-1``). :func:`sample_cornette_shanks` samples it exactly by rejection (a Henyey-Greenstein sample is
  accepted with probability ``w(mu) / max w = (1 + mu^2) / 2``; acceptance rate ``(2 + g^2) / 3 >= 2/3``); a path
  tracer may instead keep every sample and multiply its weight by ``w``, which is what the Monte Carlo
  reference does (:mod:`skyscatter.montecarlo.kernels`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ..lazy import lazy_namespace

__all__ = [
    "AEROSOL_PHASE_FUNCTIONS",
    "aerosol_phase",
    "aerosol_phase_kind",
    "cornette_shanks",
    "cornette_shanks_hg_weight",
    "henyey_greenstein",
    "henyey_greenstein_inverse_cdf",
    "rayleigh_inverse_cdf",
    "rayleigh_phase",
    "sample_aerosol_phase",
    "sample_cornette_shanks",
    "sample_henyey_greenstein",
    "sample_rayleigh",
]

#: Names of the aerosol (Mie) phase functions, in the order of their integer ``kind`` for the numba kernels.
AEROSOL_PHASE_FUNCTIONS = ("cornette-shanks", "henyey-greenstein")

_FOUR_PI = 4.0 * math.pi
#: Smallest value of ``1 + g^2 - 2 g mu`` used (keeps the forward peak finite for |g| -> 1 in float64).
_MIN_DENOMINATOR = 1e-12
#: Below this |g| the Henyey-Greenstein density is uniform to 3 |g| (relative) and sampled as ``mu = 2 u - 1``.
_ISOTROPIC_G = 1e-6


# ------------------------------------------------------------------ the formulas (numpy arrays and numba scalars)


def _rayleigh_formula(mu):
    return 3.0 / (16.0 * math.pi) * (1.0 + mu * mu)


def _henyey_greenstein_formula(mu, g):
    den = np.maximum(1.0 + g * g - 2.0 * g * mu, _MIN_DENOMINATOR)
    return (1.0 - g * g) / (_FOUR_PI * den * np.sqrt(den))


def _cornette_shanks_formula(mu, g):
    den = np.maximum(1.0 + g * g - 2.0 * g * mu, _MIN_DENOMINATOR)
    return 3.0 * (1.0 - g * g) * (1.0 + mu * mu) / (8.0 * math.pi * (2.0 + g * g) * den * np.sqrt(den))


def _cornette_shanks_hg_weight_formula(mu, g):
    return 3.0 * (1.0 + mu * mu) / (2.0 * (2.0 + g * g))


def _rayleigh_inverse_cdf_formula(u):
    # Cardano's root of mu^3 + 3 mu - z = 0, odd in z: sign(z) (a - 1/a), a = cbrt(|z| + sqrt(z^2 + 1)) >= 1
    z = 4.0 * u - 2.0
    a = np.cbrt(np.abs(z) + np.sqrt(z * z + 1.0))
    return np.minimum(np.maximum(np.copysign(a - 1.0 / a, z), -1.0), 1.0)


def _henyey_greenstein_inverse_cdf_formula(u, g):
    if abs(g) < _ISOTROPIC_G:
        return 2.0 * u - 1.0
    t = (1.0 - g * g) / (1.0 - g + 2.0 * g * u)
    return np.minimum(np.maximum((1.0 + g * g - t * t) / (2.0 * g), -1.0), 1.0)


# ------------------------------------------------------------------ validation


def _cos(cos_theta: ArrayLike) -> NDArray[np.float64]:
    mu = np.asarray(cos_theta, dtype=float)
    if np.any(np.isnan(mu)) or np.any(np.abs(mu) > 1.0 + 1e-12):
        raise InvalidParameterError("cos_theta must be the cosine of a scattering angle, in [-1, 1] (no NaN)")
    return np.clip(mu, -1.0, 1.0)


def _asymmetry(g: float) -> float:
    try:
        g = float(g)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"asymmetry parameter g must be a number in (-1, 1); got {g!r}") from None
    if not -1.0 < g < 1.0:
        raise InvalidParameterError(f"asymmetry parameter g must be in (-1, 1); got {g}")
    return g


def aerosol_phase_kind(name: str) -> int:
    """Integer code of an aerosol phase-function name for the numba kernels (index in
    :data:`AEROSOL_PHASE_FUNCTIONS`); raises InvalidParameterError for an unknown name."""
    try:
        return AEROSOL_PHASE_FUNCTIONS.index(name)
    except ValueError:
        raise InvalidParameterError(
            f"aerosol phase function must be one of {', '.join(AEROSOL_PHASE_FUNCTIONS)}; got {name!r}"
        ) from None


# ------------------------------------------------------------------ densities


def rayleigh_phase(cos_theta: ArrayLike) -> NDArray[np.float64]:
    """Rayleigh phase function ``3 / (16 pi) (1 + cos^2 theta)`` [sr^-1].

    Preetham (1999) A.3 (the angular/total ratio of the molecular coefficients); Bruneton & Neyret (2008),
    Eq. 2. Depolarisation is ignored in the angular shape, as in both papers.

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the scattering angle [-].
    """
    return _rayleigh_formula(_cos(cos_theta))


def henyey_greenstein(cos_theta: ArrayLike, g: float) -> NDArray[np.float64]:
    """Henyey-Greenstein (1941) phase function [sr^-1].

    ``(1 - g^2) / (4 pi (1 + g^2 - 2 g cos theta)^(3/2))``, as given in Preetham's course notes (Mie
    scattering section).

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the scattering angle [-].
    g : float
        Asymmetry parameter (mean cosine) in (-1, 1) [-]; positive values scatter forwards.
    """
    return _henyey_greenstein_formula(_cos(cos_theta), _asymmetry(g))


def cornette_shanks(cos_theta: ArrayLike, g: float) -> NDArray[np.float64]:
    """Cornette & Shanks (1992) phase function [sr^-1], the Mie phase of Bruneton & Neyret (2008), Eq. 4.

    ``3 (1 - g^2) (1 + cos^2 theta) / (8 pi (2 + g^2) (1 + g^2 - 2 g cos theta)^(3/2))``.

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the scattering angle [-].
    g : float
        Asymmetry parameter in (-1, 1) [-] (Bruneton's default 0.8). Its mean cosine is not ``g`` but
        ``3 g (4 + g^2) / (5 (2 + g^2))`` (Cornette & Shanks 1992).
    """
    return _cornette_shanks_formula(_cos(cos_theta), _asymmetry(g))


def cornette_shanks_hg_weight(cos_theta: ArrayLike, g: float) -> NDArray[np.float64]:
    """Ratio of the Cornette-Shanks to the Henyey-Greenstein phase function of the same ``g`` [-].

    ``p_CS / p_HG = 3 (1 + cos^2 theta) / (2 (2 + g^2))``: the two phase functions (Cornette & Shanks 1992;
    Henyey & Greenstein 1941) share the factor ``(1 - g^2) / (1 + g^2 - 2 g cos theta)^(3/2)``. The weight lies
    in ``[3 / (2 (2 + g^2)), 3 / (2 + g^2)]``, the smallest value at ``cos theta = 0`` and the largest at
    ``cos theta = +-1`` (0.57-1.14 for g = 0.8, 0.75-1.5 for g = 0). Weighting Henyey-Greenstein samples by it
    gives Cornette-Shanks expectations with a weight bounded by ``3 / (2 + g^2) <= 1.5``; divided by that bound
    it is the acceptance probability of :func:`sample_cornette_shanks`.

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the scattering angle [-].
    g : float
        Asymmetry parameter in (-1, 1) [-].
    """
    return _cornette_shanks_hg_weight_formula(_cos(cos_theta), _asymmetry(g))


def aerosol_phase(cos_theta: ArrayLike, g: float, kind: str = "cornette-shanks") -> NDArray[np.float64]:
    """The aerosol phase function named ``kind`` (one of :data:`AEROSOL_PHASE_FUNCTIONS`) [sr^-1]."""
    if aerosol_phase_kind(kind) == 1:
        return henyey_greenstein(cos_theta, g)
    return cornette_shanks(cos_theta, g)


# ------------------------------------------------------------------ sampling


def _uniform(u: ArrayLike) -> NDArray[np.float64]:
    x = np.asarray(u, dtype=float)
    if np.any(~np.isfinite(x)) or np.any(x < 0.0) or np.any(x > 1.0):
        raise InvalidParameterError("u must be uniform random numbers in [0, 1]")
    return x


def _rng(rng: Any) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    return np.random.default_rng(rng)


def _size(size: Any) -> tuple[int, ...]:
    shape = (size,) if isinstance(size, (int, np.integer)) else tuple(size)
    if any(isinstance(s, bool) or int(s) != s or s < 0 for s in shape):
        raise InvalidParameterError(f"size must be a whole number >= 0 or a shape of them; got {size!r}")
    return tuple(int(s) for s in shape)


def rayleigh_inverse_cdf(u: ArrayLike) -> NDArray[np.float64]:
    """Cosine of the scattering angle with CDF ``u`` under the Rayleigh phase function (module docstring).

    Parameters
    ----------
    u : array_like
        Uniform numbers in [0, 1] [-].

    Returns
    -------
    ndarray, shape of ``u``
        ``mu`` in [-1, 1] [-].
    """
    return _rayleigh_inverse_cdf_formula(_uniform(u))


def henyey_greenstein_inverse_cdf(u: ArrayLike, g: float) -> NDArray[np.float64]:
    """Cosine of the scattering angle with CDF ``u`` under the Henyey-Greenstein phase function.

    Parameters
    ----------
    u : array_like
        Uniform numbers in [0, 1] [-].
    g : float
        Asymmetry parameter in (-1, 1) [-].

    Returns
    -------
    ndarray, shape of ``u``
        ``mu`` in [-1, 1] [-], increasing in ``u``. For ``|g| < 1e-6`` the density is uniform to within
        ``3 |g| < 3e-6`` (relative) and ``mu = 2 u - 1`` is used.
    """
    return _henyey_greenstein_inverse_cdf_formula(_uniform(u), _asymmetry(g))


def sample_rayleigh(size: int | tuple[int, ...], rng: Any = None) -> NDArray[np.float64]:
    """``size`` cosines of the scattering angle distributed as the Rayleigh phase function.

    Parameters
    ----------
    size : int or tuple of int
        Number (shape) of samples.
    rng : numpy.random.Generator or seed, optional
        Source of random numbers.
    """
    return rayleigh_inverse_cdf(_rng(rng).random(_size(size)))


def sample_henyey_greenstein(size: int | tuple[int, ...], g: float, rng: Any = None) -> NDArray[np.float64]:
    """``size`` cosines of the scattering angle distributed as Henyey-Greenstein with asymmetry ``g`` [-]."""
    g = _asymmetry(g)
    return henyey_greenstein_inverse_cdf(_rng(rng).random(_size(size)), g)


def sample_cornette_shanks(size: int | tuple[int, ...], g: float, rng: Any = None) -> NDArray[np.float64]:
    """``size`` cosines of the scattering angle distributed as Cornette-Shanks with parameter ``g`` [-].

    Exact rejection sampling from Henyey-Greenstein with the same ``g`` (module docstring): each candidate
    ``mu`` is kept with probability ``w(mu) / (3 / (2 + g^2)) = (1 + mu^2) / 2``, ``w`` the bounded weight
    :func:`cornette_shanks_hg_weight`; on average ``3 / (2 + g^2)`` candidates per sample.
    """
    g = _asymmetry(g)
    bound = _cornette_shanks_hg_weight_formula(1.0, g)  # the largest weight, 3 / (2 + g^2), at mu = +-1
    gen = _rng(rng)
    shape = _size(size)
    n = math.prod(shape)
    out = np.empty(n)
    filled = 0
    while filled < n:
        want = n - filled
        batch = int(want * 1.6) + 16
        mu = _henyey_greenstein_inverse_cdf_formula(gen.random(batch), g)
        keep = mu[bound * gen.random(batch) < _cornette_shanks_hg_weight_formula(mu, g)][:want]
        out[filled:filled + keep.size] = keep
        filled += keep.size
    return out.reshape(shape)


def sample_aerosol_phase(size: int | tuple[int, ...], g: float, kind: str = "cornette-shanks",
                         rng: Any = None) -> NDArray[np.float64]:
    """Samples of the aerosol phase function named ``kind`` (see :func:`aerosol_phase`)."""
    if aerosol_phase_kind(kind) == 1:
        return sample_henyey_greenstein(size, g, rng)
    return sample_cornette_shanks(size, g, rng)


# ------------------------------------------------------------------ numba scalar versions (built on first use)

if TYPE_CHECKING:
    from ._phase_numba import (
        aerosol_phase_scalar as aerosol_phase_scalar,
    )
    from ._phase_numba import (
        cornette_shanks_scalar as cornette_shanks_scalar,
    )
    from ._phase_numba import (
        direction_about_axis as direction_about_axis,
    )
    from ._phase_numba import (
        henyey_greenstein_inverse_cdf_scalar as henyey_greenstein_inverse_cdf_scalar,
    )
    from ._phase_numba import (
        henyey_greenstein_scalar as henyey_greenstein_scalar,
    )
    from ._phase_numba import (
        rayleigh_inverse_cdf_scalar as rayleigh_inverse_cdf_scalar,
    )
    from ._phase_numba import (
        rayleigh_phase_scalar as rayleigh_phase_scalar,
    )

_LAZY = {name: "_phase_numba" for name in (
    "rayleigh_phase_scalar", "henyey_greenstein_scalar", "cornette_shanks_scalar", "aerosol_phase_scalar",
    "rayleigh_inverse_cdf_scalar", "henyey_greenstein_inverse_cdf_scalar", "direction_about_axis")}

__getattr__ = lazy_namespace(globals(), _LAZY)[0]
