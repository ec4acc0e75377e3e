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


def gpu_inscatter(ns, tex, r, mu, mu_s, nu, hits):
    """GetInscatter of the GLSL library (RGB), from the manifest's Python mappings ``ns`` and the float32 textures
    ``tex``: the scattering textures read at the view-sun azimuth's two texels, and along the sun zenith the linear
    read, or with the sun -1..25 deg up the three texel columns combined as the library does."""
    if mu_s < ns["MU_S_MIN"] - 1e-6:
        return np.zeros(3)
    mu_s = max(mu_s, ns["MU_S_MIN"])
    cell = ns["scattering_ground_cell"](r, mu, hits)

    def read(name, uvw):
        return ns["scattering_texture"](lambda q: sample_texture(tex[name], q), uvw, cell)

    def at(p_s):
        uvw0, uvw1, w = ns["scattering_uvw"](r, mu, mu_s, nu, hits, p_s)
        parts = [ns["single_scattering_lerp"](read(n, uvw0), read(n, uvw1), r, mu, mu_s, nu, w, n)
                 for n in ("rayleigh", "mie")]
        parts.append(ns["azimuth_lerp"](read("multiple", uvw0), read("multiple", uvw1), w))
        return ns["inscattered_radiance"](*parts, nu)

    j0, t, f = ns["scattering_mu_s_read"](mu_s)
    lin = at(None) if f < 1.0 else None
    if f <= 0.0:
        return np.array(lin)
    return np.array(ns["sun_zenith_lerp"](lin, at(j0), at(j0 + 1), at(j0 + 2), t, f))
