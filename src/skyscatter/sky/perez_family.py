"""The Perez family of sky distributions: one kernel for Preetham's F, Perez 1993, the CIE skies and Hosek-Wilkie.

Every analytic sky in skyscatter is a product of a *gradation* (how the sky brightens or darkens towards the
horizon) and an *indicatrix* (how it brightens towards the sun). The most general published form is Hosek and
Wilkie's extension ([HosekWilkie2012] Eq. 9) of the Perez et al. (1993) formula ([Perez1993]):

    F(theta, gamma) = (1 + A exp(B / (cos theta + o)))
                      * (C + D exp(E gamma) + F cos^2 gamma + G chi(H, gamma) + I sqrt(cos theta))

    chi(H, gamma) = (1 + cos^2 gamma) / (1 + H^2 - 2 H cos gamma)^(3/2)

with theta the view zenith angle and gamma the angle between the view and the sun [rad]. The older models are
special cases (:func:`perez_parameters_from_abcde`, :func:`cie_parameters`, :func:`kittler_parameters`,
:func:`kittler_turbid_parameters`):

============================================  ==========================================================
Perez 1993 Eq. 1 / Preetham 1999 Eq. 3        A..E = a..e, C = 1, G = I = 0
CIE S 011/E:2003 general sky                  A = a, B = b, C = 1 - c exp(d pi/2), D = c, E = d, F = e
CIE 1973 clear sky (Kittler)                  A = -1, B = -0.32, C = 0.91, D = 10, E = -3, F = 0.45
CIE 1973 clear sky, turbid (Kittler)          A = -1, B = -0.32, C = 0.856, D = 16, E = -3, F = 0.3
Hosek & Wilkie 2012                           their nine fitted values, o = 0.01 (their published form)
============================================  ==========================================================

**The one horizon rule.** The gradation's denominator never falls below 0.01: the classic models floor
``cos theta`` at :data:`HORIZON_COS` = 0.01 (as Radiance's ``perezlum.cal`` does; for the negative B of every
valid clear sky the term is already below 1e-13 there, and for the positive B some Perez bins produce, it keeps F
finite), and Hosek-Wilkie adds its published offset 0.01 to ``cos theta`` clamped at 0. Directions below the
horizon are each model's business (zero or the horizon value, as its docstring says); the kernel sees only
``cos theta`` >= 0 after the floor.

The kernel is written once, in numpy (:func:`gradation` and :func:`indicatrix`, whose product is
:func:`extended_perez`): every model and the sky matrix evaluate whole arrays of directions through it. numpy's
vectorised exp/arccos/sqrt are faster per direction than numba's scalar libm calls on this formula, and the
sky package then needs no compiled kernel at all: a command-line call pays neither numba's import nor its
first-use set-up (about 0.35 s; docs/architecture.md, "Start-up").
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError

__all__ = [
    "HORIZON_COS",
    "HOSEK_WILKIE_OFFSET",
    "HOSEK_WILKIE_PARAMETER_ORDER",
    "cie_parameters",
    "extended_perez",
    "gradation",
    "indicatrix",
    "hosek_wilkie_f",
    "hosek_wilkie_f_jacobian",
    "kittler_parameters",
    "kittler_turbid_parameters",
    "perez_f",
    "perez_parameters_from_abcde",
]

#: Floor of cos(theta) in the gradation of the classic Perez-family models (Radiance perezlum.cal).
HORIZON_COS = 0.01
#: Offset added to cos(theta) in Hosek & Wilkie's gradation (their Eq. 9 as the v1.4a reference code has it).
HOSEK_WILKIE_OFFSET = 0.01
#: The order of the nine parameters in Hosek & Wilkie's datasets and in ``hosek_wilkie_f``'s last axis: the
#: paper's A-I with I (the zenith term) stored before H (the aerosol anisotropy), exactly as the authors'
#: reference code reads them (``configuration[7]`` multiplies sqrt(cos theta), ``configuration[8]`` is H).
HOSEK_WILKIE_PARAMETER_ORDER = ("A", "B", "C", "D", "E", "F", "G", "I", "H")
# index into (A..G, I, H) for each alphabetical parameter A..I
_HW_TO_ALPHABETICAL = np.array([0, 1, 2, 3, 4, 5, 6, 8, 7])


def gradation(cos_theta: ArrayLike, a: ArrayLike, b: ArrayLike, offset: float = 0.0) -> NDArray[np.float64]:
    """The gradation ``1 + A exp(B / d)``, ``d = max(cos theta, 0.01)`` (offset 0) or ``cos theta + offset``.

    ``cos theta`` is clipped to [0, 1] first (the one horizon rule, module docstring). Arguments broadcast;
    ``offset`` is one number (0: the classic models; Hosek-Wilkie: :data:`HOSEK_WILKIE_OFFSET`).
    """
    ct = np.array(cos_theta, dtype=np.float64)  # a copy: clipped in place
    np.clip(ct, 0.0, 1.0, out=ct)
    if offset > 0.0:
        ct += offset
    else:
        np.maximum(ct, HORIZON_COS, out=ct)
    out = np.empty(np.broadcast_shapes(ct.shape, np.shape(a), np.shape(b)))
    np.divide(b, ct, out=out)
    np.exp(out, out=out)
    out *= a
    out += 1.0
    return out


def indicatrix(cos_theta: ArrayLike, gamma: ArrayLike, cos_gamma: ArrayLike, c: ArrayLike, d: ArrayLike,
               e: ArrayLike, f: ArrayLike, g: ArrayLike = 0.0, h: ArrayLike = 0.0, i: ArrayLike = 0.0, *,
               out: NDArray[np.float64] | None = None, work: NDArray[np.float64] | None = None
               ) -> NDArray[np.float64]:
    """The indicatrix ``C + D exp(E gamma) + F cos^2 gamma + G chi(H, gamma) + I sqrt(cos theta)``.

    ``gamma`` [rad] and its cosine are both given (callers have both; computing one from the other costs an
    arccos or a cos per direction). Arguments broadcast. The chi and sqrt terms are left out where G or I is
    0 (the classic models), so a zero G never meets chi's pole at H = 1, gamma = 0.

    ``out`` and ``work``, float64 arrays of the result's shape, receive the result and the cos^2 gamma term;
    ``out`` may be ``gamma`` itself (read first), ``work`` must be an array of its own. A loop over large blocks
    of directions passes them and allocates nothing (fresh temporaries of a few hundred kB cost more than the
    arithmetic here).
    """
    shapes = [x.shape if isinstance(x, np.ndarray) else np.shape(x)
              for x in (cos_theta, gamma, cos_gamma, c, d, e, f, g, h, i) if not isinstance(x, float)]
    shape = np.broadcast_shapes(*shapes)
    cg = cos_gamma if isinstance(cos_gamma, np.ndarray) else np.asarray(cos_gamma, dtype=np.float64)
    out = np.empty(shape) if out is None else out
    work = np.empty(shape) if work is None else work
    np.multiply(e, gamma, out=out)
    np.exp(out, out=out)
    out *= d
    out += c
    np.multiply(f, cg, out=work)
    work *= cg
    out += work
    g = np.asarray(g, dtype=np.float64)
    if g.any():  # Hosek-Wilkie's aureole term
        q = 1.0 + h * h - 2.0 * h * cg
        with np.errstate(divide="ignore", invalid="ignore"):
            term = g * (1.0 + cg * cg) / (q * np.sqrt(q))  # q^1.5, equal to pow(q, 1.5) to rounding
        out += term if g.all() else np.where(g != 0.0, term, 0.0)
    i = np.asarray(i, dtype=np.float64)
    if i.any():
        out += i * np.sqrt(np.clip(cos_theta, 0.0, 1.0))
    return out


def extended_perez(cos_theta: ArrayLike, gamma: ArrayLike, parameters: ArrayLike, *, offset: float = 0.0
                   ) -> NDArray[np.float64]:
    """The extended Perez distribution F (module formula), broadcasting angles against parameter arrays.

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the view zenith angle (negative values are treated as 0, the horizon).
    gamma : array_like
        Angle between the view direction and the sun [rad].
    parameters : array_like, shape (..., 9)
        A, B, C, D, E, F, G, H, I (alphabetical; Hosek and Wilkie's files store them as A..G, I, H). The leading
        axes broadcast against the angles' shape, so many sun positions or hours evaluate in one call.
    offset : float
        0 (default): the classic models' floor ``max(cos theta, 0.01)``; > 0: ``cos theta + offset`` (Hosek-Wilkie
        uses 0.01).
    """
    p = np.asarray(parameters, dtype=float)
    if p.shape[-1:] != (9,):
        raise InvalidParameterError(f"parameters must have a last axis of 9 (A..I); got shape {p.shape}")
    ct = np.asarray(cos_theta, dtype=float)
    gam = np.asarray(gamma, dtype=float)
    a, b, c, d, e, f, g, h, i = (p[..., k] for k in range(9))
    out = gradation(ct, a, b, float(offset))
    out = out * indicatrix(ct, gam, np.cos(gam), c, d, e, f, g, h, i)
    return out[()] if out.ndim == 0 else out


def perez_parameters_from_abcde(coefficients: ArrayLike) -> NDArray[np.float64]:
    """(..., 5) Perez / Preetham coefficients a..e -> (..., 9) extended parameters (C = 1, G = H = I = 0)."""
    k = np.asarray(coefficients, dtype=float)
    out = np.zeros(k.shape[:-1] + (9,))
    out[..., 0], out[..., 1] = k[..., 0], k[..., 1]
    out[..., 2] = 1.0
    out[..., 3], out[..., 4], out[..., 5] = k[..., 2], k[..., 3], k[..., 4]
    return out


def perez_f(cos_theta: ArrayLike, gamma: ArrayLike, coefficients: ArrayLike) -> NDArray[np.float64]:
    """Perez et al. 1993 Eq. 1 in Preetham's form (Preetham 1999, Eq. 3), under the one horizon rule.

    ``F = (1 + A exp(B / max(cos theta, 0.01))) (1 + C exp(D gamma) + E cos^2 gamma)``; ``coefficients`` (..., 5)
    are A..E, broadcast against the angles.
    """
    return extended_perez(cos_theta, gamma, perez_parameters_from_abcde(coefficients))


def cie_parameters(a: float, b: float, c: float, d: float, e: float) -> NDArray[np.float64]:
    """CIE S 011/E:2003 gradation (a, b) and indicatrix (c, d, e) as extended parameters.

    ``phi(Z) f(chi) = (1 + a exp(b / cos Z)) (1 + c [exp(d chi) - exp(d pi/2)] + e cos^2 chi)`` (the standard's
    Eqs. for the gradation and the indicatrix), i.e. C = 1 - c exp(d pi/2).
    """
    return np.array([a, b, 1.0 - c * math.exp(d * math.pi / 2.0), c, d, e, 0.0, 0.0, 0.0])


def kittler_parameters() -> NDArray[np.float64]:
    """CIE 1973 clear sky (Kittler; Preetham 1999 Eq. 1): ``(1 - exp(-0.32 / cos theta))
    (0.91 + 10 exp(-3 gamma) + 0.45 cos^2 gamma)`` as extended parameters."""
    return np.array([-1.0, -0.32, 0.91, 10.0, -3.0, 0.45, 0.0, 0.0, 0.0])


def kittler_turbid_parameters() -> NDArray[np.float64]:
    """CIE 1973 clear sky for a turbid (polluted) atmosphere (Kittler): ``(1 - exp(-0.32 / cos theta))
    (0.856 + 16 exp(-3 gamma) + 0.3 cos^2 gamma)`` as extended parameters.

    The "clear turbid sky" of the DOE-2.1E / EnergyPlus daylighting model (EnergyPlus Engineering Reference,
    "Sky Luminance Distributions"; LBNL DElight ``dskylu``, sky type 2) and, to rounding, CIE S 011/E:2003 type 13
    ("CIE standard clear sky, polluted atmosphere": a = -1, b = -0.32, c = 16, d = -3, e = 0.3, so
    C = 1 - 16 exp(-3 pi/2) = 0.8563).
    """
    return np.array([-1.0, -0.32, 0.856, 16.0, -3.0, 0.3, 0.0, 0.0, 0.0])


# ------------------------------------------------------------------------------------------ Hosek & Wilkie 2012


def hosek_wilkie_f(cos_theta: ArrayLike, gamma: ArrayLike, params: ArrayLike) -> NDArray[np.float64]:
    """Extended Perez distribution of Hosek & Wilkie 2012 (Eq. 9 with the anisotropy term chi of Eq. 10).

    ``F = (1 + A exp(B / (cos theta + 0.01))) (C + D exp(E gamma) + F cos^2 gamma + G chi(H, gamma)
    + I sqrt(cos theta))``: the module's kernel with the offset 0.01 of the reference code
    (``ArHosekSkyModel_GetRadianceInternal``, v1.4a). The result is relative: the model's radiance is this times
    the per-band radiance scale L_M (Eq. 11).

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the view zenith angle; clipped to [0, 1] (the form is defined on the upper hemisphere only:
        sqrt(cos theta) is NaN below, and ``cos theta + 0.01`` passes through 0 at 90.6 deg), so a direction
        below the horizon gets the horizon value; sky models return zero there.
    gamma : array_like
        Angle between the view direction and the sun [rad], 0 to pi.
    params : array_like, shape (..., 9)
        A, B, C, D, E, F, G, I, H (:data:`HOSEK_WILKIE_PARAMETER_ORDER`), broadcast against the angles.
    """
    p = np.asarray(params, dtype=np.float64)
    if p.shape[-1:] != (9,):
        raise InvalidParameterError(f"params must have a last axis of length 9 (A..I); got shape {p.shape}")
    return extended_perez(cos_theta, gamma, p[..., _HW_TO_ALPHABETICAL], offset=HOSEK_WILKIE_OFFSET)


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
    grad_exp = np.exp(b / (ct + HOSEK_WILKIE_OFFSET))
    ray = np.exp(e * gam)
    sq = np.sqrt(ct)
    big_q = 1.0 + a * grad_exp
    s = c + d * ray + f * cg2 + g * chi + i * sq
    parts = [
        grad_exp * s,
        a * grad_exp * s / (ct + HOSEK_WILKIE_OFFSET),
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
