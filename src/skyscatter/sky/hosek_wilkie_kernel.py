"""The Hosek & Wilkie (2012) sky's closed form compiled over directions: :class:`~.hosek_wilkie.HosekWilkieSky`'s
radiance, colour and luminance in one pass per direction instead of a dozen numpy passes over all of them.

Per direction: the view zenith cosine ``cos theta`` and the angle ``gamma`` to the sun (atan2 of the cross and
dot products, accurate near the sun, as :meth:`.base.SunSkyMixin._gamma`), then for each band ``b``
``F(theta, gamma; A..I of b) L_M[b]`` (Eqs. 9-11 of [HosekWilkie2012]: the gradation
``1 + A exp(B / (cos theta + 0.01))`` of :func:`.perez_family.gradation` times the indicatrix
``C + D exp(E gamma) + F cos^2 gamma + G chi(H, gamma) + I sqrt(cos theta)`` of :func:`.perez_family.indicatrix`,
the same operations in the same order), and finally each output as a weighted sum of at most two bands (the
linear interpolation between bands of ``arhosekskymodel_radiance``, or one band with weight 1). Directions are
normalised here; zero, NaN or infinite ones are flagged for the caller, which then raises the error of
:func:`skyscatter.conventions.as_directions`.

This module imports numba: :mod:`.hosek_wilkie` imports it on the first evaluation, so that ``import skyscatter``
stays free of numba.

Reference: [HosekWilkie2012].
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import CONTRACT_ARCP, kernel
from .perez_family import HOSEK_WILKIE_OFFSET as OFFSET


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
    band = np.empty(n_b)
    sx, sy, sz = sun[0], sun[1], sun[2]
    for q in range(start, stop):
        x, y, z = dirs[q, 0], dirs[q, 1], dirs[q, 2]
        n2 = x * x + y * y + z * z
        if not (n2 > 0.0 and n2 < math.inf):
            bad[q] = True
            for j in range(n_out):
                out[q, j] = 0.0
            continue
        norm = math.sqrt(n2)
        x, y, z = x / norm, y / norm, z / norm
        if z < 0.0:
            for j in range(n_out):
                out[q, j] = 0.0
            continue
        ct = min(z, 1.0)
        cx, cy, cz = y * sz - z * sy, z * sx - x * sz, x * sy - y * sx
        dot = x * sx + y * sy + z * sz
        gamma = math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), dot)
        # cos(atan2(|d x s|, d . s)) is d . s for unit vectors: the cosine without a libm call (to rounding)
        cg = max(-1.0, min(dot, 1.0))
        cg2 = cg * cg
        sq = math.sqrt(ct)
        inv_ct = 1.0 / (ct + OFFSET)
        for b in range(n_b):
            a_, b_, c_, d_, e_, f_, g_, i_, h_ = (params[b, 0], params[b, 1], params[b, 2], params[b, 3],
                                                  params[b, 4], params[b, 5], params[b, 6], params[b, 7],
                                                  params[b, 8])
            grad = 1.0 + a_ * math.exp(b_ * inv_ct)
            ind = c_ + d_ * math.exp(e_ * gamma) + f_ * cg2
            if g_ != 0.0:
                qq = 1.0 + h_ * h_ - 2.0 * h_ * cg
                ind += g_ * (1.0 + cg2) / (qq * math.sqrt(qq))
            ind += i_ * sq
            v = grad * ind * scale[b]
            band[b] = max(v, 0.0) if clip_bands else v
        for j in range(n_out):
            v = band_weight[j, 0] * band[band_index[j, 0]] + band_weight[j, 1] * band[band_index[j, 1]]
            out[q, j] = max(v, 0.0) if clip_out else v
