"""numba kernels of :mod:`.cloudy`: bilinear lookup of a radiance grid over (view zenith, azimuth from the sun), and
the patch means of a table of such grids over (cloud optical depth, sun zenith) for many hours."""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..jit import parallel_kernel
from ..precomputed.geometry import bilinear_weights

__all__ = ["grid_lookup", "patch_field_lookup"]


@parallel_kernel
def grid_lookup(dirs, sun_azimuth, theta_nodes, phi_nodes, grid, out):
    """``out[i]`` = ``grid`` (n_theta, n_phi, c) interpolated bilinearly at direction ``dirs[i]`` (any length, ENU;
    NaN where the vector has a NaN, an infinity or zero length):
    its zenith angle among ``theta_nodes`` [rad] (ascending) and its azimuth from ``sun_azimuth`` [rad] folded
    into [0, pi] (the field is symmetric about the sun's vertical plane) among ``phi_nodes`` [rad] (ascending,
    0 to pi)."""
    n = dirs.shape[0]
    nt = theta_nodes.shape[0]
    npf = grid.shape[1]
    nc = grid.shape[2]
    for i in prange(n):
        norm = math.sqrt(dirs[i, 0] * dirs[i, 0] + dirs[i, 1] * dirs[i, 1] + dirs[i, 2] * dirs[i, 2])
        if not (norm > 0.0 and norm < math.inf):  # NaN, infinite or zero: flagged for the caller to refuse
            for c in range(nc):
                out[i, c] = math.nan
            continue
        z = min(1.0, max(-1.0, dirs[i, 2] / norm))
        theta = math.acos(z)
        it = np.searchsorted(theta_nodes, theta) - 1
        it = min(max(it, 0), nt - 2)
        u = (theta - theta_nodes[it]) / (theta_nodes[it + 1] - theta_nodes[it])
        u = min(1.0, max(0.0, u))
        rel = math.atan2(dirs[i, 0], dirs[i, 1]) - sun_azimuth
        rel = abs((rel + math.pi) % (2.0 * math.pi) - math.pi)
        ip = np.searchsorted(phi_nodes, rel) - 1
        ip = min(max(ip, 0), npf - 2)
        v = min(1.0, max(0.0, (rel - phi_nodes[ip]) / (phi_nodes[ip + 1] - phi_nodes[ip])))
        for c in range(nc):
            out[i, c] = ((1.0 - u) * ((1.0 - v) * grid[it, ip, c] + v * grid[it, ip + 1, c])
                         + u * ((1.0 - v) * grid[it + 1, ip, c] + v * grid[it + 1, ip + 1, c]))


@parallel_kernel
def patch_field_lookup(fields, k, a, j, b, sun_azimuth, cell_it, cell_u, cell_azimuth, cell_patch, cell_weight,
                       phi_nodes, out):
    """``out[h, p, :]`` += the weighted sum over patch ``p``'s cells of ``fields`` (n_tau, n_zen, n_theta, n_phi, c)
    interpolated linearly between optical depth nodes ``k[h]``, ``k[h] + 1`` (weight ``a[h]`` of the second),
    zenith nodes ``j[h]``, ``j[h] + 1`` (weight ``b[h]`` of the second) and bilinearly in (view zenith, azimuth
    from the sun folded into [0, pi]): each cell's zenith node ``cell_it`` and weight ``cell_u`` are fixed, its
    azimuth ``cell_azimuth`` [rad] is taken from ``sun_azimuth[h]`` [rad] among ``phi_nodes`` [rad]; each cell
    adds ``cell_weight`` times its value to its patch ``cell_patch``. One hour per thread, no allocation."""
    n = k.shape[0]
    nc = cell_it.shape[0]
    npf = phi_nodes.shape[0]
    nw = fields.shape[4]
    for h in prange(n):
        k0 = k[h]
        j0 = j[h]
        wa = a[h]
        wb = b[h]
        w00, w01, w10, w11 = bilinear_weights(wa, wb)
        for c in range(nc):
            rel = cell_azimuth[c] - sun_azimuth[h]
            rel = abs((rel + math.pi) % (2.0 * math.pi) - math.pi)
            ip = np.searchsorted(phi_nodes, rel) - 1
            ip = min(max(ip, 0), npf - 2)
            v = min(1.0, max(0.0, (rel - phi_nodes[ip]) / (phi_nodes[ip + 1] - phi_nodes[ip])))
            it = cell_it[c]
            u = cell_u[c]
            q00, q01, q10, q11 = bilinear_weights(u, v)
            p = cell_patch[c]
            cw = cell_weight[c]
            for w in range(nw):
                acc = 0.0
                for kk in range(2):
                    for jj in range(2):
                        wt = (w00 if jj == 0 else w01) if kk == 0 else (w10 if jj == 0 else w11)
                        if wt == 0.0:
                            continue
                        f = fields[k0 + kk, j0 + jj]
                        acc += wt * (q00 * f[it, ip, w] + q01 * f[it, ip + 1, w] + q10 * f[it + 1, ip, w]
                                     + q11 * f[it + 1, ip + 1, w])
                out[h, p, w] += cw * acc
