"""Gauss-Legendre rules for the tests' reference integrals, computed once per session.

numpy's ``leggauss`` finds the nodes as eigenvalues of a dense n x n companion matrix: O(n^3), 27 s of CPU for
the 4000-node rule of the DISORT phase moments (measured on the project machine), which twelve test cases used to
recompute each. The rules are returned read-only so a caller cannot alter the shared arrays.
"""

from __future__ import annotations

from functools import cache

import numpy as np


@cache
def gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of the n-point Gauss-Legendre rule on [-1, 1] (numpy's leggauss), read-only."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w
