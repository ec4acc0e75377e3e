"""A texture read as the GPU does it (GL_LINEAR, CLAMP_TO_EDGE), in numpy: shared by the real-time export tests
and the browser test."""

from __future__ import annotations

import math

import numpy as np


def sample_texture(tex, coords):
    """GL LINEAR + CLAMP_TO_EDGE read of an RGBA texture (2D (h, w, 4) with coords (u, v); 3D (d, h, w, 4) with
    (u, v, w)), texel i centred at (i + 0.5) / n."""
    shape = tex.shape[:-1][::-1]  # sizes along u, v(, w)
    idx, wts = [], []
    for c, n in zip(coords, shape, strict=True):
        x = c * n - 0.5
        i0 = math.floor(x)
        w = x - i0
        idx.append((min(max(i0, 0), n - 1), min(max(i0 + 1, 0), n - 1)))
        wts.append((1.0 - w, w))
    out = np.zeros(4)
    if len(shape) == 2:
        for a in range(2):
            for b in range(2):
                out += wts[0][a] * wts[1][b] * tex[idx[1][b], idx[0][a]]
        return out
    for a in range(2):
        for b in range(2):
            for c in range(2):
                out += wts[0][a] * wts[1][b] * wts[2][c] * tex[idx[2][c], idx[1][b], idx[0][a]]
    return out
