"""Perez-family sky distribution kernels, vectorised over directions and parameter sets.

This module holds (for now) the extended Perez form of Hosek & Wilkie 2012. It is meant to be merged with the
shared Perez-family kernel module (Preetham's F, Perez 1993, CIE gradation/indicatrix) of the same name.

References
----------
L. Hosek and A. Wilkie, "An Analytic Model for Full Spectral Sky-Dome Radiance", ACM Trans. Graph. 31(4), 95
(2012), https://doi.org/10.1145/2185520.2185591.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError

__all__ = ["HOSEK_WILKIE_PARAMETER_ORDER", "hosek_wilkie_f", "hosek_wilkie_f_jacobian", "hosek_wilkie_f_scalar"]

#: The order of the nine parameters in the published datasets and in ``hosek_wilkie_f``'s last axis: the
#: paper's A-I with I (the zenith term) stored before H (the aerosol anisotropy), exactly as the authors'
#: reference code reads them (``configuration[7]`` multiplies sqrt(cos theta), ``configuration[8]`` is H).
HOSEK_WILKIE_PARAMETER_ORDER = ("A", "B", "C", "D", "E", "F", "G", "I", "H")


def hosek_wilkie_f(cos_theta: ArrayLike, gamma: ArrayLike, params: ArrayLike) -> NDArray[np.float64]:
    """Extended Perez distribution of Hosek & Wilkie 2012 (Eq. 9 with the anisotropy term chi of Eq. 10).

    ::

        F = (1 + A exp(B / (cos theta + 0.01)))
            * (C + D exp(E gamma) + F cos^2 gamma + G chi(H, gamma) + I sqrt(cos theta))
        chi(H, gamma) = (1 + cos^2 gamma) / (1 + H^2 - 2 H cos gamma)^(3/2)

    The 0.01 in the gradation term is the reference code's (``ArHosekSkyModel_GetRadianceInternal``, v1.4a), as
    is the coefficient order A, B, C, D, E, F, G, I, H of ``params`` (see :data:`HOSEK_WILKIE_PARAMETER_ORDER`).
    The result is relative: the model's radiance is this times the per-band radiance scale L_M (Eq. 11).

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the view zenith angle (dimensionless). The form is defined on the upper hemisphere only
        (sqrt(cos theta) is NaN below, and ``cos theta + 0.01`` passes through 0 at 90.6 deg): values are
        clipped to [0, 1], so a direction below the horizon gets the horizon value; sky models return zero there.
    gamma : array_like
        Angle between the view direction and the sun [rad], 0 to pi.
    params : array_like, shape (..., 9)
        A, B, C, D, E, F, G, I, H. ``params[..., k]`` broadcasts against ``cos_theta`` and ``gamma``, so
        ``cos_theta[:, None]`` with ``params`` of shape (n_bands, 9) gives (n_directions, n_bands).

    Returns
    -------
    ndarray
        F (dimensionless), the broadcast shape of ``cos_theta``, ``gamma`` and ``params[..., 0]``.
    """
    p = np.asarray(params, dtype=np.float64)
    if p.shape[-1:] != (9,):
        raise InvalidParameterError(f"params must have a last axis of length 9 (A..I); got shape {p.shape}")
    return _hosek_wilkie_ufunc(
        np.asarray(cos_theta, dtype=np.float64), np.asarray(gamma, dtype=np.float64), *(p[..., k] for k in range(9))
    )


def hosek_wilkie_f_jacobian(cos_theta: ArrayLike, gamma: ArrayLike, params: ArrayLike) -> NDArray[np.float64]:
    """Partial derivatives of :func:`hosek_wilkie_f` with respect to its nine parameters, shape (..., 9).

    Same arguments and broadcasting as :func:`hosek_wilkie_f`; the last axis follows the parameter order
    A, B, C, D, E, F, G, I, H. With gradation ``Q = 1 + A exp(B / (cos theta + 0.01))`` and
    ``S = C + D exp(E gamma) + F cos^2 gamma + G chi + I sqrt(cos theta)``: dF/dA = exp(...) S,
    dF/dB = A exp(...) S / (cos theta + 0.01), dF/dC = Q, dF/dD = Q exp(E gamma), dF/dE = Q D gamma exp(E gamma),
    dF/dF = Q cos^2 gamma, dF/dG = Q chi, dF/dI = Q sqrt(cos theta),
    dF/dH = -3 Q G (1 + cos^2 gamma) (H - cos gamma) / (1 + H^2 - 2 H cos gamma)^(5/2).
    """
    p = np.asarray(params, dtype=np.float64)
    if p.shape[-1:] != (9,):
        raise InvalidParameterError(f"params must have a last axis of length 9 (A..I); got shape {p.shape}")
    a, b, c, d, e, f, g, i, h = (p[..., k] for k in range(9))
    ct = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)
    gam = np.asarray(gamma, dtype=np.float64)
    cg = np.cos(gam)
    cg2 = cg * cg
    q = 1.0 + h * h - 2.0 * h * cg
    chi = (1.0 + cg2) / (q * np.sqrt(q))
    grad_exp = np.exp(b / (ct + 0.01))
    ray = np.exp(e * gam)
    sq = np.sqrt(ct)
    big_q = 1.0 + a * grad_exp
    s = c + d * ray + f * cg2 + g * chi + i * sq
    parts = [
        grad_exp * s,
        a * grad_exp * s / (ct + 0.01),
        big_q,
        big_q * ray,
        big_q * d * gam * ray,
        big_q * cg2,
        big_q * chi,
        big_q * sq,
        -3.0 * big_q * g * (1.0 + cg2) * (h - cg) / (q * q * np.sqrt(q)),
    ]
    shape = np.broadcast_shapes(*(x.shape for x in parts))
    return np.stack([np.broadcast_to(x, shape) for x in parts], axis=-1)


@numba.njit(cache=True, nogil=True, inline="always")
def hosek_wilkie_f_scalar(cos_theta, gamma, a, b, c, d, e, f, g, i, h):  # pragma: no cover - compiled
    """:func:`hosek_wilkie_f` for one direction and one parameter set (numba; callable from compiled loops)."""
    ct = min(max(cos_theta, 0.0), 1.0)
    cg = math.cos(gamma)
    cg2 = cg * cg
    q = 1.0 + h * h - 2.0 * h * cg
    mie = (1.0 + cg2) / (q * math.sqrt(q))  # q^1.5 (equal to pow(q, 1.5) to rounding, and faster)
    gradation = 1.0 + a * math.exp(b / (ct + 0.01))
    return gradation * (c + d * math.exp(e * gamma) + f * cg2 + g * mie + i * math.sqrt(ct))


@numba.vectorize(["float64(float64, float64, float64, float64, float64, float64, float64, float64, float64, "
                  "float64, float64)"], nopython=True, cache=True)
def _hosek_wilkie_ufunc(cos_theta, gamma, a, b, c, d, e, f, g, i, h):  # pragma: no cover - compiled
    return hosek_wilkie_f_scalar(cos_theta, gamma, a, b, c, d, e, f, g, i, h)
