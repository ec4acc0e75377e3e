"""numba-compiled scalar versions of the phase functions of :mod:`.phase` and their sampling (the same formula
functions), and the direction about an axis used to turn a sampled cosine into a direction.

Imported on first access of ``skyscatter.atmosphere.phase.<name>`` (``*_scalar``, ``direction_about_axis``) so
that importing the atmosphere package does not import numba.
"""

from __future__ import annotations

import math

from ..jit import helper
from . import phase

#: ``rayleigh_phase_scalar(mu)`` [sr^-1], Bruneton & Neyret (2008) Eq. 2.
rayleigh_phase_scalar = helper(phase._rayleigh_formula)
#: ``henyey_greenstein_scalar(mu, g)`` [sr^-1].
henyey_greenstein_scalar = helper(phase._henyey_greenstein_formula)
#: ``cornette_shanks_scalar(mu, g)`` [sr^-1], Bruneton & Neyret (2008) Eq. 4.
cornette_shanks_scalar = helper(phase._cornette_shanks_formula)
#: ``rayleigh_inverse_cdf_scalar(u)``: ``mu`` [-] with Rayleigh CDF ``u`` in [0, 1] (Frisvad 2011, Eq. 13;
#: :func:`.phase.rayleigh_inverse_cdf` without its validation).
rayleigh_inverse_cdf_scalar = helper(phase._rayleigh_inverse_cdf_formula)
#: ``henyey_greenstein_inverse_cdf_scalar(u, g)``: ``mu`` [-] with Henyey-Greenstein CDF ``u`` in [0, 1]
#: (:func:`.phase.henyey_greenstein_inverse_cdf` without its validation).
henyey_greenstein_inverse_cdf_scalar = helper(phase._henyey_greenstein_inverse_cdf_formula)

_HENYEY_GREENSTEIN = phase.AEROSOL_PHASE_FUNCTIONS.index("henyey-greenstein")


@helper
def aerosol_phase_scalar(mu, g, kind):
    """Aerosol phase function [sr^-1] of integer ``kind`` (:func:`.phase.aerosol_phase_kind`) at ``mu``."""
    if kind == _HENYEY_GREENSTEIN:
        return henyey_greenstein_scalar(mu, g)
    return cornette_shanks_scalar(mu, g)


@helper
def direction_about_axis(ax, ay, az, mu, phi):
    """Unit vector at angle ``acos(mu)`` from the unit vector ``(ax, ay, az)`` and at azimuth ``phi`` [rad] about it.

    The azimuth is measured from the first vector of the branchless orthonormal basis of [Duff2017]
    Listing 3: a fixed, continuous-almost-
    everywhere choice, so that ``phi`` uniform in [0, 2 pi) gives directions uniform in azimuth about the axis.
    ``mu`` in [-1, 1] [-]. Returns the three components (renormalised against rounding).
    """
    sign = 1.0 if az >= 0.0 else -1.0
    a = -1.0 / (sign + az)
    b = ax * ay * a
    # t1, t2 and the axis form a right-handed orthonormal basis (Duff et al. 2017, Listing 3)
    t1x, t1y, t1z = 1.0 + sign * ax * ax * a, sign * b, -sign * ax
    t2x, t2y, t2z = b, sign + ay * ay * a, -ay
    st = math.sqrt(max(0.0, 1.0 - mu * mu))
    c = st * math.cos(phi)
    s = st * math.sin(phi)
    ox = c * t1x + s * t2x + mu * ax
    oy = c * t1y + s * t2y + mu * ay
    oz = c * t1z + s * t2z + mu * az
    n = 1.0 / math.sqrt(ox * ox + oy * oy + oz * oz)
    return ox * n, oy * n, oz * n


# ------------------------------------------------------------------ tabulated phase functions (.phase_table)

@helper
def phase_table_segment(mu_nodes, mu):
    """``(i, w)``: the segment ``mu_nodes[i] <= mu <= mu_nodes[i + 1]`` of ascending nodes and the weight of node
    ``i + 1`` (linear in ``mu``); ``mu`` is clamped to [-1, 1]. Bisection (:mod:`.phase_table`)."""
    n = mu_nodes.shape[0]
    if mu <= mu_nodes[0]:
        return 0, 0.0
    if mu >= mu_nodes[n - 1]:
        return n - 2, 1.0
    lo = 0
    hi = n - 1
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if mu_nodes[mid] <= mu:
            lo = mid
        else:
            hi = mid
    return lo, (mu - mu_nodes[lo]) / (mu_nodes[lo + 1] - mu_nodes[lo])


@helper
def phase_table_value(mu_nodes, values, k, mu):
    """Tabulated phase function [sr^-1] of wavelength index ``k`` at ``mu`` (``values`` (n_wl, n), ascending mu)."""
    i, w = phase_table_segment(mu_nodes, mu)
    return (1.0 - w) * values[k, i] + w * values[k, i + 1]


@helper
def phase_table_segment_near(mu_nodes, mu, hint):
    """:func:`phase_table_segment` of ``mu``, without the bisection when ``mu`` lies in the segment ``hint`` (an
    index from an earlier look-up, e.g. :func:`phase_table_inverse_cdf_segment`'s; -1: none). Returns the same
    ``(i, w)`` to the bit: the bisection's segment is the only ``i`` with ``mu_nodes[i] <= mu < mu_nodes[i + 1]``
    (strictly ascending nodes), and ``w`` is the same expression."""
    n = mu_nodes.shape[0]
    if 0 <= hint < n - 1 and mu_nodes[0] < mu < mu_nodes[n - 1] and mu_nodes[hint] <= mu < mu_nodes[hint + 1]:
        return hint, (mu - mu_nodes[hint]) / (mu_nodes[hint + 1] - mu_nodes[hint])
    return phase_table_segment(mu_nodes, mu)


@helper
def phase_table_values_at(values, i, w, out):
    """``out[k]`` = tabulated phase function [sr^-1] of every wavelength ``k`` at the point of segment ``i`` with
    weight ``w`` of node ``i + 1`` (:func:`phase_table_segment`): several tables on the same nodes at one ``mu``
    share one look-up."""
    for k in range(values.shape[0]):
        out[k] = (1.0 - w) * values[k, i] + w * values[k, i + 1]


@helper
def phase_table_values(mu_nodes, values, mu, out):
    """``out[k]`` = tabulated phase function [sr^-1] of every wavelength ``k`` at ``mu`` (one bisection)."""
    i, w = phase_table_segment(mu_nodes, mu)
    phase_table_values_at(values, i, w, out)


@helper
def phase_table_inverse_cdf_segment(mu_nodes, values, cdf, k, u):
    """``(mu, i)``: :func:`phase_table_inverse_cdf` and the segment ``i`` of the nodes it was found in (a hint for
    :func:`phase_table_segment_near`; ``mu`` may round onto the segment's end, which that checks)."""
    n = mu_nodes.shape[0]
    if u <= 0.0:
        return -1.0, 0
    if u >= 1.0:
        return 1.0, n - 2
    lo = 0
    hi = n - 1
    while hi - lo > 1:  # largest i with cdf[k, i] <= u
        mid = (lo + hi) >> 1
        if cdf[k, mid] <= u:
            lo = mid
        else:
            hi = mid
    a = mu_nodes[lo]
    dmu = mu_nodes[lo + 1] - a
    v0 = values[k, lo]
    s = (values[k, lo + 1] - v0) / dmu
    c = (u - cdf[k, lo]) / (2.0 * math.pi)
    den = v0 + math.sqrt(max(v0 * v0 + 2.0 * s * c, 0.0))
    x = 2.0 * c / den if den > 0.0 else 0.0
    x = min(max(x, 0.0), dmu)
    return min(max(a + x, -1.0), 1.0), lo


@helper
def phase_table_inverse_cdf(mu_nodes, values, cdf, k, u):
    """``mu`` [-] with CDF ``u`` in [0, 1] under the table of wavelength index ``k``: exact for the interpolant
    linear in ``mu`` (:meth:`.phase_table.PhaseTable.inverse_cdf`, the same formula): the root of the quadratic
    CDF in the segment found by bisection in the cumulative table."""
    mu, _ = phase_table_inverse_cdf_segment(mu_nodes, values, cdf, k, u)
    return mu
