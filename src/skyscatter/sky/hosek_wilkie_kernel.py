"""The Hosek & Wilkie (2012) sky's closed form compiled over directions: :class:`~.hosek_wilkie.HosekWilkieSky`'s
radiance, colour and luminance in one pass per block of directions instead of a dozen numpy passes over all of
them.

Per direction: the view zenith cosine ``cos theta`` and the angle ``gamma`` to the sun (atan2 of the cross and
dot products, accurate near the sun, as :meth:`.base.SunSkyMixin._gamma`), then for each band ``b``
``F(theta, gamma; A..I of b) L_M[b]`` (Eqs. 9-11 of [HosekWilkie2012]: the gradation
``1 + A exp(B / (cos theta + 0.01))`` of :func:`.perez_family.gradation` times the indicatrix
``C + D exp(E gamma) + F cos^2 gamma + G chi(H, gamma) + I sqrt(cos theta)`` of :func:`.perez_family.indicatrix`),
and finally each output as a weighted sum of at most two bands (the linear interpolation between bands of
``arhosekskymodel_radiance``, or one band with weight 1). Directions are normalised here; zero, NaN or infinite
ones are flagged for the caller, which then raises the error of :func:`skyscatter.conventions.as_directions`.

Speed. libm's ``atan2`` and ``exp`` are calls that keep a loop scalar (numba finds no vector math library here),
and they were most of the cost (about 20 and 8 ns each per call). :func:`atan2_nonnegative` and :func:`exp_parts`
are the Cephes algorithms of [Moshier1989] (``atan.c``: reduction to ``|x| <= 0.66`` and a rational function of
degree 4/5; ``exp.c``: reduction by ``ln 2`` in two parts and a Pade form), written without branches or calls; the
power of two of ``exp`` is written as the bits of a double and read through a float64 view in the next loop (a
product of powers selected by the exponent's bits, tried first: the kernel took 38 instead of 34 ns per
direction). Within 1 and 2 units in the last place of libm (``tests/test_hosek_wilkie.py``), and the loops over
directions that use them run on SIMD lanes. The kernel works in blocks of :data:`BLOCK` directions: one pass for
the geometry of every direction, two per band, one for the outputs.

This module imports numba: :mod:`.hosek_wilkie` imports it on the first evaluation of many directions, so that
``import skyscatter`` stays free of numba.

References: [HosekWilkie2012], [Moshier1989].
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import CONTRACT_ARCP, inline, kernel
from .perez_family import HOSEK_WILKIE_OFFSET as OFFSET

#: Directions per block (the per-direction buffers stay in the L1 cache).
BLOCK = 256

# Cephes atan.c [Moshier1989]: atan(x) = x + x z P(z) / Q(z), z = x^2, for |x| <= 0.66 after reduction.
_AP = (-8.750608600031904122785e-1, -1.615753718733365076637e1, -7.500855792314704667340e1,
       -1.228866684490136173410e2, -6.485021904942025371773e1)
_AQ = (2.485846490142306297962e1, 1.650270098316988542046e2, 4.328810604912902668951e2,
       4.853903996359136964868e2, 1.945506571482613964425e2)
_T3P8 = 2.41421356237309504880  # tan(3 pi / 8)
_MOREBITS = 6.123233995736765886130e-17  # pi / 2 - its double
# Cephes exp.c [Moshier1989]: exp(r) = 1 + 2 r P(r^2) / (Q(r^2) - r P(r^2)), |r| <= ln(2) / 2.
_EP = (1.26177193074810590878e-4, 3.02994407707441961300e-2, 9.99999999999999999910e-1)
_EQ = (3.00198505138664455042e-6, 2.52448340349684104192e-3, 2.27265548208155028766e-1, 2.00000000000000000009e0)
_C1 = 6.93145751953125e-1  # ln 2 in two parts: exact times any integer below 2^11
_C2 = 1.42860682030941723212e-6
_LOG2E = 1.4426950408889634073599


@inline(fastmath=CONTRACT_ARCP)
def atan2_nonnegative(c, d):
    """``atan2(c, d)`` [rad] for ``c >= 0`` (an angle in [0, pi]; Cephes ``atan`` of ``c / |d|``, [Moshier1989])."""
    x = c / abs(d)
    big = x > _T3P8
    mid = x > 0.66
    y0 = 0.5 * math.pi if big else (0.25 * math.pi if mid else 0.0)
    xr = (-1.0 / x) if big else ((x - 1.0) / (x + 1.0) if mid else x)
    z = xr * xr
    p = (((_AP[0] * z + _AP[1]) * z + _AP[2]) * z + _AP[3]) * z + _AP[4]
    q = ((((z + _AQ[0]) * z + _AQ[1]) * z + _AQ[2]) * z + _AQ[3]) * z + _AQ[4]
    a = y0 + ((xr * (z * p / q) + xr) + (_MOREBITS if big else (0.5 * _MOREBITS if mid else 0.0)))
    return a if d >= 0.0 else math.pi - a


@inline(fastmath=CONTRACT_ARCP)
def exp_parts(x):
    """``e^x`` for finite ``x`` as ``(m, bits)``: ``e^x = m 2^n`` with ``bits`` the int64 bits of the double
    ``2^n`` (Cephes ``exp``, [Moshier1989]; the caller reads ``bits`` through a float64 view, a loop apart, so
    that both loops run on SIMD lanes). Arguments are held in [-708, 709] (outside, the result is that of the
    bound: 3e-308 or 8e307)."""
    x = 709.0 if x > 709.0 else (-708.0 if x < -708.0 else x)
    k = np.floor(_LOG2E * x + 0.5)
    r = (x - k * _C1) - k * _C2
    rr = r * r
    p = r * ((_EP[0] * rr + _EP[1]) * rr + _EP[2])
    m = 1.0 + 2.0 * (p / ((((_EQ[0] * rr + _EQ[1]) * rr + _EQ[2]) * rr + _EQ[3]) - p))
    return m, (np.int64(k) + 1023) << 52


@kernel(fastmath=CONTRACT_ARCP)
def radiance_kernel(dirs, sun, params, scale, band_index, band_weight, clip_bands, clip_out, out, bad, start,
                    stop):
    """Sky values for directions ``start..stop - 1``.

    Parameters
    ----------
    dirs : (n, 3) float64
        View directions (any length > 0; normalised here).
    sun : (3,) float64
        Unit vector towards the sun.
    params : (n_bands, 9) float64
        A, B, C, D, E, F, G, I, H of each band (the stored order, :data:`.perez_family.HOSEK_WILKIE_PARAMETER_ORDER`).
    scale : (n_bands,) float64
        Radiance scale L_M of each band (times 683 for luminance).
    band_index : (n_out, 2) int64
        The two bands of each output.
    band_weight : (n_out, 2) float64
        Their weights (an output of one band: weight 1 and 0).
    clip_bands, clip_out : bool
        Set negative band values / outputs to 0.
    out : (n, n_out) float64
        Result; 0 below the horizon (the form is defined on the upper hemisphere only).
    bad : (n,) bool
        Set for zero, NaN or infinite directions.
    """
    n_b = params.shape[0]
    n_out = out.shape[1]
    flat = dirs.reshape(dirs.shape[0] * 3)  # x, y, z triples: a constant stride (docs/architecture.md)
    sx, sy, sz = sun[0], sun[1], sun[2]
    gam = np.empty(BLOCK)
    cg = np.empty(BLOCK)
    sq = np.empty(BLOCK)
    inv_ct = np.empty(BLOCK)
    sky = np.empty(BLOCK)
    band = np.empty((n_b, BLOCK))
    m_ray = np.empty(BLOCK)  # e^(E gamma) and e^(B / (cos theta + 0.01)) as mantissa and power of two
    m_grad = np.empty(BLOCK)
    bits_ray = np.empty(BLOCK, dtype=np.int64)
    bits_grad = np.empty(BLOCK, dtype=np.int64)
    pow_ray = bits_ray.view(np.float64)
    pow_grad = bits_grad.view(np.float64)
    for b0 in range(start, stop, BLOCK):
        m = min(BLOCK, stop - b0)
        for k in range(m):  # geometry, on SIMD lanes
            x = flat[3 * (b0 + k)]
            y = flat[3 * (b0 + k) + 1]
            z = flat[3 * (b0 + k) + 2]
            n2 = x * x + y * y + z * z
            good = (n2 > 0.0) & (n2 < math.inf)
            inv = 1.0 / math.sqrt(n2) if good else 0.0
            x = x * inv
            y = y * inv
            z = z * inv if good else 1.0  # a bad direction computes the zenith's values, then is flagged
            ct = max(0.0, min(z, 1.0))
            cx, cy, cz = y * sz - z * sy, z * sx - x * sz, x * sy - y * sx
            dot = x * sx + y * sy + z * sz
            gam[k] = atan2_nonnegative(math.sqrt(cx * cx + cy * cy + cz * cz), dot)
            # cos(atan2(|d x s|, d . s)) is d . s for unit vectors (to rounding)
            cg[k] = max(-1.0, min(dot, 1.0))
            sq[k] = math.sqrt(ct)
            inv_ct[k] = 1.0 / (ct + OFFSET)
            sky[k] = 1.0 if (z >= 0.0) & good else 0.0
            bad[b0 + k] = not good
        for bi in range(n_b):  # the form per band, on SIMD lanes
            a_, b_, c_, d_, e_, f_, g_, i_, h_ = (params[bi, 0], params[bi, 1], params[bi, 2], params[bi, 3],
                                                  params[bi, 4], params[bi, 5], params[bi, 6], params[bi, 7],
                                                  params[bi, 8])
            sc = scale[bi]
            aureole = g_ != 0.0
            for k in range(m):
                m_ray[k], bits_ray[k] = exp_parts(e_ * gam[k])
                m_grad[k], bits_grad[k] = exp_parts(b_ * inv_ct[k])
            for k in range(m):
                c2 = cg[k] * cg[k]
                ind = c_ + d_ * (m_ray[k] * pow_ray[k]) + f_ * c2
                qq = 1.0 + h_ * h_ - 2.0 * h_ * cg[k]
                ind += g_ * (1.0 + c2) / (qq * math.sqrt(qq)) if aureole else 0.0
                ind += i_ * sq[k]
                v = (1.0 + a_ * (m_grad[k] * pow_grad[k])) * ind * sc
                band[bi, k] = max(v, 0.0) if clip_bands else v
        for k in range(m):
            for j in range(n_out):
                v = (band_weight[j, 0] * band[band_index[j, 0], k]
                     + band_weight[j, 1] * band[band_index[j, 1], k])
                out[b0 + k, j] = (max(v, 0.0) if clip_out else v) if sky[k] > 0.0 else 0.0
