"""numba kernel of :mod:`.cloudy`: bilinear lookup of a radiance grid over (view zenith, azimuth from the sun)."""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..jit import parallel_kernel

__all__ = ["grid_lookup"]


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
