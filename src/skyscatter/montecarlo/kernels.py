"""Numba kernels of the spectral path tracer: geometry in spherical shells, optical depth, paths.

Geometry. Positions are planet-centred Cartesian [m]; the observer is at ``(0, 0, r_obs)`` so that the local ENU
frame of the observer is the global frame (x east, y north, z up). The atmosphere is the shell
``bottom_radius <= r <= top_radius``; the ground is the sphere ``r = bottom_radius``. A straight ray
``p + t d`` meets the sphere of radius ``R`` where ``t = -b -+ sqrt(b^2 - (r^2 - R^2))``, ``b = p . d``.

Medium. Two kinds of matter:

* *shell components*, whose density depends on the altitude only: Rayleigh, the aerosol and ozone (indices 0,
  1, 2, as in the Bruneton tables) and any further particle components of the medium (cloud layers, more
  aerosol layers; indices 3 ...), each a :class:`~skyscatter.atmosphere.DensityProfile` of layers
  ``max(0, a exp(s h) + l h + c)`` with an extinction and a scattering coefficient per wavelength at relative
  density 1 and a phase function (Rayleigh, Cornette-Shanks, Henyey-Greenstein or a table per wavelength);
* at most one *cloud field*, a 3D voxel grid (:mod:`.tracking`), with its own spectral scales and phase
  function.

Optical depth of the shells. Along a ray the column ``int rho_c(h(t)) dt`` of each component is integrated
piecewise: the ray is cut where it crosses the spheres of a set of "quadrature shells" (every layer boundary,
every zero of a linear layer and altitudes one scale height apart for each exponential layer, two scale heights
apart), and each piece is integrated by 4-point Gauss-Legendre quadrature. Inside a piece the integrand is
analytic and varies by at most a factor ``e^2`` in the vertical (it is constant in a cloud layer, whose base
and top are shell boundaries); the relative error of a column is below 3e-7 for steep rays and below 2e-6 for
grazing ones (checked in the tests against adaptive quadrature), three orders of magnitude below the Monte Carlo
error the reference is run at. It is deterministic, so shadow rays through the shells add no variance. The
columns are per component and wavelength independent; the optical depth at any wavelength is
``sum_c k_c(lambda) col_c``. Free paths in the shells are sampled by inverting this optical depth (``tau(t) =
-ln(1 - xi)``, Newton with bisection safeguard inside the piece where the target is crossed), so the collision
density ``sigma_t(x) T(x)`` is known exactly for every wavelength, which spectral MIS needs. From inside a cloud
layer (a shell where a component's density is constant: ``ushell``, ``driver.uniform_shells``) the same density is
sampled by decomposition ([Kutz2017]; :func:`_uniform_free_path`): the layer's free path in closed form, the air
up to it with a target of its own (one piece, no Newton), and a shadow ray from there ends without a march once the
layer alone passes its depth (:func:`_uniform_lower_bound`). A piece of a ray inside the layer up to 2 km long
(the air along such a free path, or up to the layer's top along a shadow ray) takes its columns in closed form
about its midpoint (:func:`_short_piece_columns`; within 1e-9 relative) instead of Gauss-Legendre. Through the cloud
field, free paths are sampled by decomposition and delta tracking against a block majorant grid and shadow rays
by residual ratio tracking (:mod:`.tracking`); the two are combined by decomposition: the shell free path
``t_s`` is drawn first, the field is tracked up to ``t_s``, and whichever collides first is the collision.

Estimator (backward paths from the observer; [Veach1997] Ch. 8-9):

* forced first collision ([CashwellEverett1959]): when the view ray leaves the atmosphere without hitting the
  ground and does not meet the cloud field's box, its first collision is drawn from ``sigma_t T / (1 -
  T_total)`` on the ray, so no path is wasted on clear sky;
* next-event estimation to the sun at every medium and ground vertex: a direction uniform over the solar disc
  (angular radius from the parameters), the transmittance to the top of the atmosphere (zero when the planet
  blocks it; through the field by ratio tracking), phase function or ``albedo / pi * cos``. The sun is reached
  only by NEE, so the sky radiance never contains the directly transmitted sun (reported separately);
* forward peak (cloudy media; the driver's ``peak_lobe``, ``PEAK_ANGLE``): the cloud's tabulated phase function
  ``P = P_rest + P_peak`` is split at a node 10 deg from the forward direction (``P_peak = P - c`` above it, ``c``
  just below the table's smallest value there; 0 below; the driver's ``forward_peak``), which is exact for the
  interpolant. A light path from the observer ``x_1 ... x_n`` to the sun is counted once, at its last vertex
  ``x_j`` that is not a peak scattering (the first vertex and ground vertices always count as such): (a) ``j = n``:
  the next-event estimate at ``x_j`` with ``P_rest`` in place of ``P`` (``P`` itself at the first vertex); (b) ``j <
  n``: the chain ``x_{j+1} ... x_n`` of ``L = n - j`` peak scatterings, estimated at ``x_j`` by a *peak probe*
  (``_peak_probe``): ``L`` drawn from ``(1 - c) c^(L-1)``, a point ``w`` on the solar disc, the directions drawn
  backwards from the sun (``omega_L`` about ``w``, ``omega_{L-1}`` about ``omega_L``, ... from the hero's normalised
  peak, so every link's peak value over its density is the constant ``a_i P_peak,i / P_peak,hero`` with ``a`` the
  peak's fraction), the positions forwards (free paths from ``x_j`` along ``omega_1``, ...; each collision weighted
  by the cloud's scattering coefficient over the hero's collision density; an escaping free path ends the probe
  with 0), and the transmittance from ``x_L`` to the sun; ``x_j``'s own phase value (``P_rest`` or the ground's
  ``albedo cos / pi``) is taken at ``omega_1``. Every factor is bounded (``P_rest <= c``, about 0.6 sr^-1 for 10 um
  droplets), where plain NEE multiplies by the diffraction peak (some 10^3 sr^-1) whenever a path heads within a
  degree of the sun: the paths and their distribution are unchanged, only what is added at each vertex
  ([Veach1997] Ch. 8: a partition of path space; the problem is [BurasMayer2011]'s). Unbiased (tested against the
  analytic lobe without the split, and against DISORT); a probe costs a few rays, so where the vertex's own NEE
  found the sun hidden it is made with probability ``max(0.1, min(1, 100 T))`` and divided by it (roulette). The
  per-path relative standard deviation of the radiance under water clouds fell from 13-14 to about 2;
* shadow rays of cloudy media by Russian roulette ([ArvoKirk1990]; ``_sun_transmittance``): once the least
  extinguished wavelength's optical depth along a shadow ray reaches the driver's ``NEE_ROULETTE_DEPTH`` (8: the
  sun's light below 3e-4 there), the ray survives to optical depth ``tau`` with probability ``exp(-(tau - 8))``
  and its transmittance is divided by that (drawn once: the ray is marched to 8 plus an exponential depth of mean
  1, and ends there; a survivor's estimate is at most ``e^-8`` of the unshadowed one). Unbiased (tested against
  the estimator without it); deep in a thick cloud most shadow rays would otherwise march through every shell
  above the cloud for nothing (overcast of optical depth 15: 1.6x the paths per CPU-second with a fixed survival
  probability 0.1 beyond depth 8, which re-marched a survivor from its start; the exponential survival about 5 %
  more, docs/clouds.md). Clear media do not use it:
  their kernel is compiled without the cloud code (``trace_block``'s ``cloudy``), and pays nothing for it;
* shadow rays of cloudy media from below the top of the cloud layers (and field) are marched only up to the sphere
  of that top (``_shadow_march``): in spherical shells the columns from there to the top of the atmosphere depend
  on the ray's cosine to the vertical there only, and come from a table over it (``driver.columns_above``: the
  kernels' own march at 512 cosines uniform in ``ln mu`` from 0.005 to 1, 4-point Lagrange interpolation; the
  columns agree with adaptive quadrature within the bounds above, tested). Near the top of an overcast layer a
  shadow ray's ten-odd pieces through the air above become one or two;
* absorption (particle albedos, ozone) enters as a weight, never as termination;
* directional importance sampling towards the sun (the "DDIS" of [BurasMayer2011] Sec. 3.3, here for backward
  paths), optional: with probability ``ddis`` the new direction is drawn from the cloud's own phase function (the
  hero's table) centred on the sun, otherwise from the medium's lobes, and every wavelength's direction density
  is the mixture of the two. With the forward peak split off, the directions about the sun are drawn from the
  cloud's phase function without its peak (``dval``, the lobe of the next-event estimates), and the driver's
  ``DDIS_DEPTH`` restricts them to vertices whose shadow ray's transmittance (largest over the wavelengths, the
  same for every hero) exceeds ``ddis_gate``: the mixture's weight is then a function of the path so far, the same
  for every wavelength's density. Unbiased; measured not to pay under overcast layers (0.6-0.7x the efficiency
  at equal CPU time everywhere with the full table, 0.6-0.85x near the top with the table without its peak,
  docs/clouds.md), so the driver passes ``ddis = 0`` and the paths are those of plain sampling;
* splitting and roulette by importance (cloudy media, optional; [ArvoKirk1990]; the driver's ``SPLIT_FACTOR``,
  ``SPLIT_DEPTHS``): a medium vertex is in class ``k`` when its shadow ray's transmittance (largest over the
  wavelengths) exceeds ``k`` of the bounds ``split[1:]``; a copy whose class is ``k`` above the class of its path's
  first medium vertex should carry ``split[0]^-k`` of the path's weight (``ws``): with more it is split into
  ``round(ws / target)`` copies (each ``ws / m``; each new copy draws its own direction at the vertex and waits on a
  stack of at most ``_SPLIT_STACK``), with less it survives with probability ``ws / target`` and is divided by it.
  Every copy's estimates are multiplied by its ``ws``, and the path's estimate is the sum over its copies. The
  decisions depend on the path only (not on the hero), so the spectral MIS weights are untouched. Unbiased
  (tested against the estimator without it). The driver splits in two where the shadow ray's optical depth is
  below 4 (+7-13 % efficiency under the overcast of optical depth 15, docs/clouds.md);
* scattering direction: the lobe (Rayleigh, each particle component, the cloud field) chosen by the hero's
  scattering coefficients at the collision point, the cosine drawn by the exact inverse CDFs of
  :mod:`skyscatter.atmosphere.phase` (Rayleigh; Henyey-Greenstein; a Cornette-Shanks aerosol is sampled as
  Henyey-Greenstein of the same ``g`` and its density enters the path weight, i.e. the weight
  ``cornette_shanks_hg_weight`` in ``[3 / (2 (2 + g^2)), 3 / (2 + g^2)]``) or, for a tabulated phase function,
  the exact inverse CDF of the hero wavelength's table (:mod:`skyscatter.atmosphere.phase_table`: linear in
  ``cos theta`` between nodes, a closed-form root per segment; its diffraction peak is sampled, never
  truncated), the direction built about the current one by ``direction_about_axis`` ([Duff2017]);
  Lambertian ground: cosine-weighted hemisphere;
* Russian roulette ([ArvoKirk1990]) from the second vertex when the largest weight falls below 0.5, survival
  probability ``w_max / 0.5``; a hard cap of 100000 vertices (never reached in the tests; a path through a cloud
  of optical depth 100 scatters some 10^3-10^4 times).

Hero wavelengths ([Wilkie2014]): one path serves all the wavelengths of its group. The hero drives every decision; each
wavelength's estimate is weighted with the balance heuristic over the group, i.e.
``F_i(path) / mean_k p_k(path)`` where ``p_k`` is the density the path would have had with wavelength ``k`` as
hero (one-sample MIS, Veach 1997, Sec. 9.2.4). The direction density under hero ``k`` is the mixture of the
lobes' sampling densities weighted by ``k``'s scattering coefficients, and through the field ``p_k`` includes
``k``'s probabilities of the null-collision decisions (:mod:`.tracking`). Plain ratio weights ``F_i / p_hero``
would be unbounded between 320 and 720 nm (Rayleigh differs by a factor 25); the balance heuristic bounds them
by ``n_group * F_i / p_i``. The shared cost (geometry, columns of every shadow ray) is paid once per path.
The heroes are stratified: path ``m`` of a batch takes hero ``(h0 + m) mod n``, with the batch's offset ``h0``
uniform, so every path's hero is uniform (the one-sample estimate stays unbiased) and a batch holds each hero
``floor(B / n)`` or one more times (the multi-sample model of Veach 1997, Sec. 9.2.2-9.2.3, in proportional
allocation). The estimates are summed per hero, and the standard error is the stratified one, ``sqrt(sum_h n_h
s_h^2) / N`` with ``s_h^2`` each hero's sample variance (``driver.reduce_strata``): the spread between the heroes'
estimates, which uniformly drawn heroes add to the variance, is gone from both (under the overcast of optical depth
15 about 0.9 of the variance with uniformly drawn heroes, docs/clouds.md). The counts' dependence on ``h0`` (one
path more for ``r = B mod n`` of the heroes) adds to the mean's variance a term the stratified error leaves out, at
most ``(n / 4) s / ((1 - s) B)`` of it with ``s`` the heroes' share of the per-path variance (sampling ``r`` of ``n``
without replacement): about 1e-3 at ``B = 512``, ``n = 11`` and the overcast's ``s`` of 0.1-0.15. Checked: the
spread of 24 seeds' means against the reported errors, 0.995-1.03 (tests/test_montecarlo_almucantars.py).

Almucantars. A medium of spherical shells without a field, seen from a point on the planet's axis through it,
is unchanged by any rotation ``R`` about that axis; so is the estimator, whose every density is built from the
geometry. A path traced for the view ``d`` with the sun ``s`` is therefore, turned by ``R``, a path for the view
``R d`` with the sun ``R s``, drawn with the same density, and its estimate with the sun ``R^-1 s`` is an unbiased
estimate of the radiance seen along ``R d`` with the sun ``s``. Views of one zenith angle (an almucantar: a row
of an equirectangular map, a ring of a sky scan) are traced as one entry whose next-event estimates and peak probes
are made once per view, each towards its own turned sun (``suns``, ``sun_ptr``), while the free paths, the
scattering and the roulette (under the overcast of optical depth 15 some 45 % of a path traced alone, measured by
ablation) are shared. Each view's estimate has the distribution it would have had traced alone (the splitting's
classes follow the first sun, a rule that depends on the path only, so they stay unbiased for the others); the
views' estimates are correlated, each standard error is its own. The turned suns' shadow rays share one roulette
depth (``_sun_transmittance``'s ``end_in``), and at a vertex where the uniform shell around it already passes that
depth along the steepest direction of any of their discs (:func:`_suns_hidden`) no shadow ray is drawn and their
peak probes share one draw: deep in an overcast most vertices, where twenty suns would each have drawn a disc
point, an exit distance and a bound to learn the same (the job of docs/clouds.md 1.4x faster). Correlated draws
across the views change no view's distribution. The driver forms the almucantars (``driver.almucantars``).

Orders. The next-event estimate at a path's vertex number ``k`` (counted from the observer; a ground reflection is
a vertex) is the radiance of the light paths of exactly ``k`` scatterings and reflections through it, so the estimates
of the vertices ``lo .. hi`` alone estimate those orders alone ([Veach1997] Ch. 8: the path integral split by path
length), with the same paths: a path ends after vertex ``hi``, and what the vertices below ``lo`` added is taken
back. A forward peak's probe estimates a chain of any length from one vertex, so a window is refused there. The
precomputed tables count their orders the same way (Bruneton & Neyret 2008, Sec. 4: the ground's reflection of
order ``k - 1`` light is in the density of order ``k``).

Observers. Each entry ``j`` of a block has an origin (planet frame), a direction and a mode: 0 - the radiance
arriving from ``-dirs[j]`` travelling along ... i.e. seen looking along ``dirs[j]``; 1 - a direction drawn per
path from the cosine distribution about ``dirs[j]``, each path's estimate multiplied by pi, so that the mean is
the irradiance on a plane facing ``dirs[j]``. The origin can be jittered per path uniformly over an x-y
footprint (a pixel of a cloud domain).
"""

from __future__ import annotations

import math

import numpy as np

from ..atmosphere.phase import (
    cornette_shanks_scalar,
    direction_about_axis,
    henyey_greenstein_inverse_cdf_scalar,
    henyey_greenstein_scalar,
    rayleigh_inverse_cdf_scalar,
    rayleigh_phase_scalar,
)
from ..atmosphere.phase_table import (
    phase_table_inverse_cdf,
    phase_table_inverse_cdf_segment,
    phase_table_segment,
    phase_table_segment_near,
    phase_table_values,
    phase_table_values_at,
)
from ..jit import helper, inline, kernel
from ..vecmath import exp_lane
from .rng import next_uniform, sample_state, stream_key
from .tracking import field_box_hit, field_density_at, field_free_path, field_transmittance

__all__ = ["column_along", "disc_transmittance", "trace_block", "MAX_ORDER", "LOBE_NONE", "LOBE_RAYLEIGH",
           "LOBE_CORNETTE_SHANKS", "LOBE_HENYEY_GREENSTEIN", "LOBE_TABLE"]

# Small per-collision helpers with many array arguments are inlined (``inline``): a call passes 7 words per array
# argument, about what their loops over a dozen wavelengths cost. They are inlined into helpers only (the paths'
# loop is :func:`_trace_paths`, not the kernel that allocates its buffers): inlined into a kernel, numba counts
# every array argument's references up and down at each call (two atomic operations per array), which took some
# 15 % of a cloudy path's time.

# 4-point Gauss-Legendre nodes and weights on [-1, 1] ([Abramowitz1964] Table 25.4)
_GX = (-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526)
_GW = (0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538)
_MAX_VERTICES = 100_000
#: The highest order a window of orders can name (``trace_block``'s ``order_hi`` for every order).
MAX_ORDER = _MAX_VERTICES
_RR_THRESHOLD = 0.5
#: Optical depth of the least extinguished wavelength at which a shadow ray stops (transmittance < 2e-22): deep
#: in a thick cloud the sun is not marched to; in clear air it is never reached.
_NEE_STOP = 50.0

#: Lobe (phase function) codes of the components: an absorber, Rayleigh, Cornette-Shanks(g),
#: Henyey-Greenstein(g), a table per wavelength.
LOBE_NONE, LOBE_RAYLEIGH, LOBE_CORNETTE_SHANKS, LOBE_HENYEY_GREENSTEIN, LOBE_TABLE = range(5)


@inline
def _layer_index(h: float, layers: np.ndarray, nlay: np.ndarray, comp: int) -> int:
    """Index of the layer of component ``comp`` that :func:`_density` uses at altitude ``h`` [m] (-1: the
    component has no layers)."""
    start = 0.0
    n = nlay[comp]
    for k in range(n):
        w = layers[comp, k, 0]
        if k == n - 1 or h < start + w:
            return k
        start += w
    return n - 1


@inline
def _density(h: float, layers: np.ndarray, nlay: np.ndarray, comp: int) -> float:
    """Relative density of component ``comp`` at altitude ``h`` [m] (DensityProfile semantics): the layer search of
    :func:`_layer_index` with the density computed where the layer is found. Written out, not through
    :func:`_layer_index`: through it the clear sky's march (:func:`_march` with :func:`_piece_columns3`) took 1.10x the
    CPU time of the kernels before the clouds, written out 1.02x (the same bits; docs/clouds.md, "Speed")."""
    start = 0.0
    n = nlay[comp]
    for k in range(n):
        w = layers[comp, k, 0]
        if k == n - 1 or h < start + w:
            v = layers[comp, k, 3] * h + layers[comp, k, 4]
            a = layers[comp, k, 1]
            if a != 0.0:
                v += a * math.exp(layers[comp, k, 2] * h)
            return v if v > 0.0 else 0.0
        start += w
    return 0.0


@helper
def _densities(r, rb, layers, nlay, out):
    """Relative densities of every shell component at radius ``r`` [m] into ``out`` (n_comp,)."""
    h = r - rb
    for c in range(out.shape[0]):
        out[c] = _density(h, layers, nlay, c)


@helper
def _roulette(f, n, vertices, st):
    """Russian roulette on a path's throughput ``f`` (n wavelengths) after its vertex number ``vertices``: False
    ends the path (no throughput left, or it lost the draw); below :data:`_RR_THRESHOLD` (largest wavelength) from
    the second vertex on it survives with probability ``wmax / _RR_THRESHOLD`` and ``f`` is divided by that, so
    the estimate stays unbiased."""
    wmax = 0.0
    for i in range(n):
        if f[i] > wmax:
            wmax = f[i]
    if wmax <= 0.0:
        return False
    if vertices >= 2 and wmax < _RR_THRESHOLD:
        q = wmax / _RR_THRESHOLD
        if next_uniform(st) >= q:
            return False
        for i in range(n):
            f[i] /= q
    return True


@helper
def _roulette_max(f, n, vertices, st, wmax):
    """:func:`_roulette` with the largest weight ``wmax`` of ``f`` already known (the clear sky's vertices find it
    in the loop that normalises the weights: one loop over the wavelengths fewer)."""
    if wmax <= 0.0:
        return False
    if vertices >= 2 and wmax < _RR_THRESHOLD:
        q = wmax / _RR_THRESHOLD
        if next_uniform(st) >= q:
            return False
        for i in range(n):
            f[i] /= q
    return True


@helper
def _exit_distance(px, py, pz, dx, dy, dz, rb, rt):
    """Distance [m] along the ray to the ground or out of the top of the atmosphere, and whether it is the ground."""
    r2 = px * px + py * py + pz * pz
    b = px * dx + py * dy + pz * dz
    disc = b * b - (r2 - rb * rb)
    if b < 0.0 and disc >= 0.0:
        t = -b - math.sqrt(disc)
        return (t if t > 0.0 else 0.0), True
    disc2 = b * b - (r2 - rt * rt)
    t = -b + math.sqrt(disc2 if disc2 > 0.0 else 0.0)
    return (t if t > 0.0 else 0.0), False



#: Largest ``|s| L`` (exponential rate [m^-1] times piece length [m]) and piece length [m] of the closed-form
#: columns (:func:`_short_piece_columns`): their truncation is then below 1e-9 relative (its docstring).
_SHORT_SL = 2.0
_SHORT_LEN = 2000.0
#: Largest curvature term ``kappa L`` [-] of the closed-form columns (Earth's at ``_SHORT_LEN``: 1.57e-4).
_SHORT_KL = 1.6e-4
#: How far inside a piece's altitude range [m] its layers are read (its ends lie on layer boundaries up to rounding).
_SHORT_EDGE = 1e-3


@inline
def _short_piece_columns(r2, b, a, c, rb, layers, nlay, out):
    """Columns [m] of every component over ``[a, c]`` [m] of a ray with ``|p|^2 = r2`` [m^2], ``p.d = b`` [m], in closed
    form about the piece's midpoint, for short pieces; False (``out`` unchanged) where it does not apply.

    With ``u`` the distance [m] from the midpoint (radius ``r_m``, cosine to the vertical ``mu_m``), the altitude is
    ``h(u) = h_m + mu_m u + kappa u^2 + O(u^3 / r_m^2)``, ``kappa = (1 - mu_m^2) / (2 r_m)`` (Taylor expansion of
    ``sqrt(r_m^2 + 2 r_m mu_m u + u^2)``). A layer ``a e^(s h)`` ([m] density law of ``DensityProfile``) then integrates
    over the piece of length ``L`` to ``a e^(s h_m) L [S(x) + s kappa L^2 C(x)]`` with ``x = s mu_m L / 2``, ``S(x) =
    sinh(x) / x`` and ``C(x) = int_{-1/2}^{1/2} v^2 e^(2 x v) dv`` (their Taylor series, [Abramowitz1964] 4.5.62; the
    first-order term of ``e^(s kappa u^2)``), and a linear layer ``l h + c`` to ``L (l h_m + c) + l kappa L^3 / 12`` (0
    where it is negative: ``max(0, .)``). Applies where each component keeps one layer over the piece's altitude range
    and a linear layer keeps its sign there (no kink of ``max(0, .)``), a layer with ``e^(s h)`` has no linear part,
    ``|s| L <= _SHORT_SL`` (2), ``L <= _SHORT_LEN`` (2 km) and ``kappa L <= _SHORT_KL`` (1.6e-4): with ``|x| <= 1`` the
    truncated terms are then ``x^14 / 15! < 1e-12`` in ``S``, ``x^8 / 1774080`` in ``C`` (times the curvature term,
    itself ``<= |s| L kappa L / 12 < 3e-5``) and ``(s kappa L^2)^2 / 160 < 1e-9``, where the 4-point Gauss-Legendre sum
    of :func:`_piece_columns` is within 3e-7 (module docstring). Inside a cloud layer a free path of some 30 m costs one
    square root per end and one exponential per exponential component instead of four square roots and four exponentials
    per component."""
    ln = c - a
    if not (0.0 < ln <= _SHORT_LEN):
        return False
    tm = 0.5 * (a + c)
    rm2 = r2 + 2.0 * b * tm + tm * tm
    rm = math.sqrt(rm2)
    hm = rm - rb
    mum = (b + tm) / rm
    kap = (1.0 - mum * mum) / (2.0 * rm)
    if kap * ln > _SHORT_KL:
        return False  # a small planet's curvature (on Earth kappa L <= 1.6e-4 at 2 km)
    # the altitude range of the piece: its ends, and the tangent point where the ray passes it
    ha = math.sqrt(max(r2 + 2.0 * b * a + a * a, 0.0)) - rb
    hc = math.sqrt(max(r2 + 2.0 * b * c + c * c, 0.0)) - rb
    hlo = min(ha, hc)
    hhi = max(ha, hc)
    if a < -b < c:
        hlo = min(hlo, math.sqrt(max(r2 - b * b, 0.0)) - rb)
    # a piece ends on a layer boundary (a quadrature shell) up to rounding: the layers are those 1 mm inside its
    # range (as for the Gauss-Legendre nodes, which lie 7 % of the piece inside its ends)
    if hhi - hlo > 2.0 * _SHORT_EDGE:
        hlo += _SHORT_EDGE
        hhi -= _SHORT_EDGE
    else:
        hlo = hm
        hhi = hm
    for q in range(out.shape[0]):
        k = _layer_index(hlo, layers, nlay, q)
        if _layer_index(hhi, layers, nlay, q) != k:
            return False
        ea = layers[q, k, 1]
        es = layers[q, k, 2]
        el = layers[q, k, 3]
        ec = layers[q, k, 4]
        if ea != 0.0 and es != 0.0:
            if el != 0.0 or ec != 0.0 or ea < 0.0 or abs(es) * ln > _SHORT_SL:
                return False
        elif (el * hlo + ec + ea < 0.0) != (el * hhi + ec + ea < 0.0):
            return False  # a zero inside the piece: the kink of max(0, .)
    hk = min(max(hm, hlo), hhi)
    for q in range(out.shape[0]):
        k = _layer_index(hk, layers, nlay, q)
        ea = layers[q, k, 1]
        es = layers[q, k, 2]
        el = layers[q, k, 3]
        ec = layers[q, k, 4]
        if ea != 0.0 and es != 0.0:
            x = 0.5 * es * mum * ln
            x2 = x * x
            sx = 1.0 + x2 * (1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (1.0 / 5040.0 + x2 * (1.0 / 362880.0 + x2 * (
                1.0 / 39916800.0 + x2 * (1.0 / 6227020800.0))))))
            cx = 1.0 / 12.0 + x2 * (1.0 / 40.0 + x2 * (1.0 / 672.0 + x2 * (1.0 / 25920.0)))
            out[q] = ea * math.exp(es * hm) * ln * (sx + es * kap * ln * ln * cx)
        elif el * hk + ec + ea < 0.0:
            out[q] = 0.0  # negative over the whole piece (checked above): the density's max(0, .)
        else:
            out[q] = ln * (el * hm + ec + ea) + el * kap * ln * ln * ln / 12.0
    return True


@helper
def _piece_columns3(r2, b, a, c, rb, layers, nlay, out):
    """:func:`_piece_columns` for the clear sky's three components (``out`` (3,) [m]; ``r2`` [m^2], ``b``, ``a``, ``c``,
    ``rb`` [m]), unrolled (a run-time trip count keeps LLVM from doing it). Its own function, called directly by
    :func:`_march` and :func:`_invert_in_piece` when there are three components: through :func:`_piece_columns`,
    whose cloud branches need many registers saved at every call, the clear sky's march took 1.10x the CPU time of
    the kernels before the clouds, called directly 1.02x (with :func:`_density` written out; docs/clouds.md,
    "Speed"). 4-point Gauss-Legendre, [Abramowitz1964] Table 25.4."""
    half = 0.5 * (c - a)
    mid = 0.5 * (c + a)
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    for k in range(4):
        t = mid + half * _GX[k]
        h = math.sqrt(max(r2 + 2.0 * b * t + t * t, 0.0)) - rb
        w = _GW[k]
        s0 += w * _density(h, layers, nlay, 0)
        s1 += w * _density(h, layers, nlay, 1)
        s2 += w * _density(h, layers, nlay, 2)
    out[0] = s0 * half
    out[1] = s1 * half
    out[2] = s2 * half


@helper
def _piece_columns(r2, b, a, c, rb, layers, nlay, out):
    """Gauss-Legendre columns of every component over ``[a, c]`` of a ray with ``|p|^2 = r2``, ``p.d = b``."""
    half = 0.5 * (c - a)
    mid = 0.5 * (c + a)
    nc = out.shape[0]
    if nc == 3:
        _piece_columns3(r2, b, a, c, rb, layers, nlay, out)  # the clear sky's three components
        return
    if nc == 4:
        # one further component (a cloud layer): the same sums in registers, in the same order as the loop below
        # (the same bits), where the loop keeps them in ``out`` across the calls to exp
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        s3 = 0.0
        for k in range(4):
            t = mid + half * _GX[k]
            h = math.sqrt(max(r2 + 2.0 * b * t + t * t, 0.0)) - rb
            w = _GW[k]
            s0 += w * _density(h, layers, nlay, 0)
            s1 += w * _density(h, layers, nlay, 1)
            s2 += w * _density(h, layers, nlay, 2)
            s3 += w * _density(h, layers, nlay, 3)
        out[0] = s0 * half
        out[1] = s1 * half
        out[2] = s2 * half
        out[3] = s3 * half
        return
    for q in range(nc):
        out[q] = 0.0
    for k in range(4):
        t = mid + half * _GX[k]
        h = math.sqrt(max(r2 + 2.0 * b * t + t * t, 0.0)) - rb
        w = _GW[k]
        for q in range(nc):
            out[q] += w * _density(h, layers, nlay, q)
    for q in range(nc):
        out[q] *= half


@helper
def _dot(k, cols):
    if cols.shape[0] == 3:
        return k[0] * cols[0] + k[1] * cols[1] + k[2] * cols[2]
    s = 0.0
    for q in range(cols.shape[0]):
        s += k[q] * cols[q]
    return s


@helper
def _dot_row(coef, i, cols):
    """``coef[i] . cols`` without a view of the row (no reference counting in the kernels' loops)."""
    if cols.shape[0] == 3:
        return coef[i, 0] * cols[0] + coef[i, 1] * cols[1] + coef[i, 2] * cols[2]
    s = 0.0
    for q in range(cols.shape[0]):
        s += coef[i, q] * cols[q]
    return s


@helper
def _invert_in_piece(r2, b, a, c, rem, dtau, target, k, rb, layers, nlay, tmp):
    """Distance ``s`` in ``[a, c]`` where the optical depth ``k . col`` from ``a`` reaches ``rem`` (``dtau`` over
    the whole piece); Newton on the Gauss-Legendre integral with a bisection safeguard. ``tmp`` gets the columns
    over ``[a, s]``."""
    lo = a
    hi = c
    s = a + (c - a) * (rem / dtau if dtau > 0.0 else 0.5)
    nc = tmp.shape[0]
    for _ in range(60):
        if nc == 3:
            _piece_columns3(r2, b, a, s, rb, layers, nlay, tmp)
        else:
            _piece_columns(r2, b, a, s, rb, layers, nlay, tmp)
        f = _dot(k, tmp) - rem
        if f > 0.0:
            hi = s
        else:
            lo = s
        if abs(f) <= 1e-12 * target + 1e-300 or hi - lo <= 1e-9 * (1.0 + s):
            break
        h = math.sqrt(max(r2 + 2.0 * b * s + s * s, 0.0)) - rb
        if nc == 3:
            deriv = (k[0] * _density(h, layers, nlay, 0) + k[1] * _density(h, layers, nlay, 1)
                     + k[2] * _density(h, layers, nlay, 2))
        else:
            deriv = 0.0
            for q in range(nc):
                deriv += k[q] * _density(h, layers, nlay, q)
        s_new = s - f / deriv if deriv > 0.0 else 0.5 * (lo + hi)
        if not (lo < s_new < hi):
            s_new = 0.5 * (lo + hi)
        s = s_new
    return s


@inline
def _next_crossing(r2, b, a, t_end, edges, i_in, i_out, inward):
    """The next crossing after ``a`` [m] of a shell edge (``edges`` [m], ascending) by the ray of squared start radius
    ``r2`` [m^2] and ``b`` = start . direction [m], or ``t_end`` [m] if none comes before it: the inward crossings
    of the spheres below the start (``i_in`` down to 0, while ``inward``), then the outward ones (``i_out`` up).
    Returns ``(c, i_in, i_out, inward)``, the search's state for the next piece (the ray-sphere roots
    ``t = -b -+ sqrt(b^2 - r^2 + R^2)``; shared by :func:`_march_pieces` and :func:`_march3_pieces`)."""
    ne = edges.shape[0]
    c = t_end
    found = False
    while inward and i_in >= 0:
        re = edges[i_in]
        disc = b * b - (r2 - re * re)
        if disc < 0.0:
            inward = False
            break
        tc = -b - math.sqrt(disc)
        i_in -= 1
        if tc > a:
            if tc < t_end:
                c = tc
                found = True
            break
    if not found:
        inward = False
        while i_out < ne:
            re = edges[i_out]
            disc = b * b - (r2 - re * re)
            i_out += 1
            if disc < 0.0:
                continue
            tc = -b + math.sqrt(disc)
            if tc > a:
                if tc < t_end:
                    c = tc
                else:
                    i_out = ne
                break
    return c, i_in, i_out, inward


@inline
def _ray_start(px, py, pz, dx, dy, dz, edges):
    """Where a march along ``p + t d`` starts: ``r^2`` [m^2], ``b = p . d`` [m], the index of the first quadrature
    sphere the ray can cross inwards (the largest below ``r``; -1 if none) and whether it heads inwards. The
    crossings come in increasing ``t``: inward ones of the spheres below ``r`` (descending radius), then outward
    ones (:func:`_next_crossing`). Shared by :func:`_march_pieces` and :func:`_march3_pieces`."""
    r2 = px * px + py * py + pz * pz
    r = math.sqrt(r2)
    b = px * dx + py * dy + pz * dz
    i_in = edges.shape[0] - 1
    while i_in >= 0 and edges[i_in] >= r:
        i_in -= 1
    return r2, b, i_in, b < 0.0


@inline
def _march_pieces(px, py, pz, dx, dy, dz, t_end, target, k, rb, edges, layers, nlay, cols, tmp, rec, locate):
    """The body of :func:`_march` (its docstring), inlined into it and into :func:`_march_locate`, where ``locate``
    is a constant."""
    nc = cols.shape[0]
    for q in range(nc):
        cols[q] = 0.0
    if t_end <= 0.0:
        return 0.0, False, 0
    r2, b, i_in, inward = _ray_start(px, py, pz, dx, dy, dz, edges)
    tau = 0.0
    a = 0.0
    npc = 0
    i_out = 0
    while True:
        c, i_in, i_out, inward = _next_crossing(r2, b, a, t_end, edges, i_in, i_out, inward)
        if nc == 3:
            _piece_columns3(r2, b, a, c, rb, layers, nlay, tmp)
        else:
            _piece_columns(r2, b, a, c, rb, layers, nlay, tmp)
        dtau = _dot(k, tmp)
        if tau + dtau >= target:
            if not locate:
                for q in range(nc):
                    cols[q] += tmp[q]
                return c, True, npc
            s = _invert_in_piece(r2, b, a, c, target - tau, dtau, target, k, rb, layers, nlay, tmp)
            for q in range(nc):
                cols[q] += tmp[q]
            return s, True, npc
        tau += dtau
        rec[npc, 0] = c
        rec[npc, 1] = tau
        if nc == 3:
            # the clear sky, unrolled (this runs once per piece of every ray)
            c0 = cols[0] + tmp[0]
            c1 = cols[1] + tmp[1]
            c2 = cols[2] + tmp[2]
            cols[0] = c0
            cols[1] = c1
            cols[2] = c2
            rec[npc, 2] = c0
            rec[npc, 3] = c1
            rec[npc, 4] = c2
        else:
            for q in range(nc):
                cols[q] += tmp[q]
                rec[npc, 2 + q] = cols[q]
        npc += 1
        if c >= t_end:
            return t_end, False, npc
        a = c


@helper
def _march(px, py, pz, dx, dy, dz, t_end, target, k, rb, edges, layers, nlay, cols, tmp, rec, locate):
    """:func:`column_along`; also records, per piece ``j``, its end ``t``, the cumulative optical depth and the
    cumulative columns in ``rec[j, 0]``, ``rec[j, 1]``, ``rec[j, 2:]`` (``rec`` has at least ``2 len(edges) + 2``
    rows). Returns ``(t, reached, n_pieces)``: with ``reached`` the pieces recorded are those before the one
    where the target is reached. Without ``locate`` a reached target is not located in its piece (``t`` and
    ``cols`` are those of the piece's end): a shadow ray needs only whether it is reached."""
    return _march_pieces(px, py, pz, dx, dy, dz, t_end, target, k, rb, edges, layers, nlay, cols, tmp, rec, locate)


@helper
def _march_locate(px, py, pz, dx, dy, dz, t_end, target, k, rb, edges, layers, nlay, cols, tmp, rec):
    """:func:`_march` with ``locate``, compiled with it a constant (the cloudy kernel's free paths in the shells;
    the clear kernel's take :func:`_march3_locate`)."""
    return _march_pieces(px, py, pz, dx, dy, dz, t_end, target, k, rb, edges, layers, nlay, cols, tmp, rec, True)


@helper
def _invert_in_piece3(r2, b, a, c, rem, dtau, target, k0, k1, k2, rb, layers, nlay, tmp):
    """:func:`_invert_in_piece` for the clear sky's three components, their coefficients ``k0``, ``k1``, ``k2``
    [m^-1] as scalars (in registers) and no test of the component count in its loop; the same operations in the
    same order (the same bits)."""
    lo = a
    hi = c
    s = a + (c - a) * (rem / dtau if dtau > 0.0 else 0.5)
    for _ in range(60):
        _piece_columns3(r2, b, a, s, rb, layers, nlay, tmp)
        f = k0 * tmp[0] + k1 * tmp[1] + k2 * tmp[2] - rem
        if f > 0.0:
            hi = s
        else:
            lo = s
        if abs(f) <= 1e-12 * target + 1e-300 or hi - lo <= 1e-9 * (1.0 + s):
            break
        h = math.sqrt(max(r2 + 2.0 * b * s + s * s, 0.0)) - rb
        deriv = (k0 * _density(h, layers, nlay, 0) + k1 * _density(h, layers, nlay, 1)
                 + k2 * _density(h, layers, nlay, 2))
        s_new = s - f / deriv if deriv > 0.0 else 0.5 * (lo + hi)
        if not (lo < s_new < hi):
            s_new = 0.5 * (lo + hi)
        s = s_new
    return s


@inline
def _march3_pieces(px, py, pz, dx, dy, dz, t_end, target, k0, k1, k2, rb, edges, layers, nlay, cols, tmp, rec,
                   locate, stop=True):
    """:func:`_march_pieces` for the clear sky's three components (``cols``, ``tmp`` (3,) [m]), their coefficients
    ``k0``, ``k1``, ``k2`` [m^-1] as scalars: the march of the kernels before the clouds, with no test of the
    component count and no array of coefficients read at every piece. The same operations in the same order as
    :func:`_march_pieces` (the same bits). Without ``stop`` (a constant: :func:`_march3_columns`) the columns to
    ``t_end`` only: no optical depth summed, no target, no record."""
    cols[0] = 0.0
    cols[1] = 0.0
    cols[2] = 0.0
    if t_end <= 0.0:
        return 0.0, False, 0
    r2, b, i_in, inward = _ray_start(px, py, pz, dx, dy, dz, edges)
    tau = 0.0
    a = 0.0
    npc = 0
    i_out = 0
    while True:
        c, i_in, i_out, inward = _next_crossing(r2, b, a, t_end, edges, i_in, i_out, inward)
        _piece_columns3(r2, b, a, c, rb, layers, nlay, tmp)
        if stop:
            dtau = k0 * tmp[0] + k1 * tmp[1] + k2 * tmp[2]
            if tau + dtau >= target:
                if locate:
                    c = _invert_in_piece3(r2, b, a, c, target - tau, dtau, target, k0, k1, k2, rb, layers, nlay, tmp)
                cols[0] += tmp[0]
                cols[1] += tmp[1]
                cols[2] += tmp[2]
                return c, True, npc
            tau += dtau
        c0 = cols[0] + tmp[0]
        c1 = cols[1] + tmp[1]
        c2 = cols[2] + tmp[2]
        cols[0] = c0
        cols[1] = c1
        cols[2] = c2
        if stop:
            rec[npc, 0] = c
            rec[npc, 1] = tau
            rec[npc, 2] = c0
            rec[npc, 3] = c1
            rec[npc, 4] = c2
        npc += 1
        if c >= t_end:
            return t_end, False, npc
        a = c


@helper
def _march3_locate(px, py, pz, dx, dy, dz, t_end, target, k0, k1, k2, rb, edges, layers, nlay, cols, tmp, rec):
    """:func:`_march_locate` for the clear sky's three components, the coefficients as scalars
    (:func:`_march3_pieces`): the clear kernel's free paths."""
    return _march3_pieces(px, py, pz, dx, dy, dz, t_end, target, k0, k1, k2, rb, edges, layers, nlay, cols, tmp, rec,
                          True)


@helper
def _march3_reach(px, py, pz, dx, dy, dz, t_end, target, k0, k1, k2, rb, edges, layers, nlay, cols, tmp, rec):
    """:func:`_march3_locate` without ``locate`` (:func:`_march`): the clear kernel's first (forced) march, whose
    target is infinite."""
    return _march3_pieces(px, py, pz, dx, dy, dz, t_end, target, k0, k1, k2, rb, edges, layers, nlay, cols, tmp, rec,
                          False)


@kernel
def column_along(px, py, pz, dx, dy, dz, t_end, target, k, rb, edges, layers, nlay, cols, tmp):
    """March along ``p + t d`` for ``0 <= t <= t_end`` [m] until the optical depth ``k . col`` reaches ``target``.

    ``k`` (n_comp,) coefficients [m^-1]; ``cols`` (n_comp,) receives the columns [m] of the components from
    ``t = 0`` to the returned distance; ``tmp`` is an (n_comp,) work array. Returns ``(t, reached)``; with
    ``target = inf`` it returns ``(t_end, False)`` and the total columns.
    """
    rec = np.empty((2 * edges.shape[0] + 2, 2 + cols.shape[0]))
    t, reached, _ = _march(px, py, pz, dx, dy, dz, t_end, target, k, rb, edges, layers, nlay, cols, tmp, rec, True)
    return t, reached


@helper
def _columns_at(px, py, pz, dx, dy, dz, t, rb, layers, nlay, rec, npc, cols, tmp):
    """Columns from 0 to ``t`` on a ray whose first ``npc`` pieces are recorded in ``rec`` by :func:`_march`
    (``t`` inside a recorded piece or in the one after them), without integrating the recorded pieces again."""
    r2 = px * px + py * py + pz * pz
    b = px * dx + py * dy + pz * dz
    nc = cols.shape[0]
    a = 0.0
    k = 0
    while k < npc and rec[k, 0] < t:
        a = rec[k, 0]
        k += 1
    _piece_columns(r2, b, a, t, rb, layers, nlay, tmp)
    for q in range(nc):
        cols[q] = tmp[q] + (rec[k - 1, 2 + q] if k > 0 else 0.0)


@helper
def _forced_from_record(px, py, pz, dx, dy, dz, t_end, target, k, rb, layers, nlay, rec, npc, cols, tmp):
    """Collision at hero optical depth ``target`` on a ray already marched to its end (pieces in ``rec``), without
    integrating it again: the same pieces, cumulative sums and inversion as :func:`_march`."""
    r2 = px * px + py * py + pz * pz
    b = px * dx + py * dy + pz * dz
    nc = cols.shape[0]
    a = 0.0
    tau = 0.0
    for j in range(npc):
        if rec[j, 1] >= target:
            s = _invert_in_piece(r2, b, a, rec[j, 0], target - tau, rec[j, 1] - tau, target, k, rb, layers,
                                 nlay, tmp)
            for q in range(nc):
                cols[q] = (rec[j - 1, 2 + q] if j > 0 else 0.0) + tmp[q]
            return s, True
        a = rec[j, 0]
        tau = rec[j, 1]
    for q in range(nc):
        cols[q] = rec[npc - 1, 2 + q] if npc > 0 else 0.0
    return t_end, False


@helper
def _march3_columns(px, py, pz, dx, dy, dz, t_end, rb, edges, layers, nlay, cols, tmp, rec):
    """The clear sky's columns ``cols`` (3,) [m] along ``p + t d`` for ``0 <= t <= t_end`` [m] (:func:`_march3_pieces`
    without ``stop``; ``rec`` is not written): a shadow ray's, whose stop at ``_NEE_STOP`` the caller tests on the
    whole ray (:func:`_opaque3`). Where that is not reached the columns are those of :func:`_march3_reach` to the bit
    (the same pieces and sums; an opaque ray is marched to its end, and the test on the ray's sum can differ from
    the pieces' running sum by a rounding at exp(-50)); without the optical depth summed and tested at every piece
    and the pieces recorded, the shadow rays' march took
    0.96x the CPU time of the kernels before the clouds in a micro-benchmark, with them 1.02-1.04x
    (``benchmarks/bench_march_ab.py``; docs/clouds.md, "Speed")."""
    _march3_pieces(px, py, pz, dx, dy, dz, t_end, np.inf, 0.0, 0.0, 0.0, rb, edges, layers, nlay, cols, tmp, rec,
                   False, False)


@inline
def _opaque3(kmin, tot):
    """Whether the least extinguished wavelength's optical depth ``kmin . tot`` (coefficients [m^-1], columns [m])
    reaches ``_NEE_STOP`` (a shadow ray whose transmittance, below exp(-50), is taken as 0)."""
    return kmin[0] * tot[0] + kmin[1] * tot[1] + kmin[2] * tot[2] >= _NEE_STOP


@helper
def _forced_from_record3(px, py, pz, dx, dy, dz, t_end, target, k0, k1, k2, rb, layers, nlay, rec, npc, cols, tmp):
    """:func:`_forced_from_record` for the clear sky's three components, their coefficients ``k0``, ``k1``, ``k2``
    [m^-1] as scalars (:func:`_invert_in_piece3`); the same operations in the same order (the same bits)."""
    r2 = px * px + py * py + pz * pz
    b = px * dx + py * dy + pz * dz
    a = 0.0
    tau = 0.0
    for j in range(npc):
        if rec[j, 1] >= target:
            s = _invert_in_piece3(r2, b, a, rec[j, 0], target - tau, rec[j, 1] - tau, target, k0, k1, k2, rb, layers,
                                  nlay, tmp)
            if j > 0:
                cols[0] = rec[j - 1, 2] + tmp[0]
                cols[1] = rec[j - 1, 3] + tmp[1]
                cols[2] = rec[j - 1, 4] + tmp[2]
            else:
                cols[0] = 0.0 + tmp[0]
                cols[1] = 0.0 + tmp[1]
                cols[2] = 0.0 + tmp[2]
            return s, True
        a = rec[j, 0]
        tau = rec[j, 1]
    for q in range(3):
        cols[q] = rec[npc - 1, 2 + q] if npc > 0 else 0.0
    return t_end, False


@helper
def _sun_sample(sx, sy, sz, cos_max, u1, u2):
    """Direction uniform in solid angle over the cone of half-angle ``acos(cos_max)`` about the sun."""
    mu = 1.0 - u1 * (1.0 - cos_max)
    return direction_about_axis(sx, sy, sz, mu, 2.0 * math.pi * u2)


@helper
def _add_columns_above(sgeo, stab, mu, cols):
    """Adds to ``cols`` (n_comp,) the columns [m] of the shells above the radius ``sgeo[0]`` along a ray leaving that
    sphere at the cosine ``mu`` to the local vertical, from the table ``stab`` (n, n_comp) of :func:`.driver.
    columns_above` (nodes uniform in ``ln mu`` from ``sgeo[1]`` by ``1 / sgeo[2]``): 4-point Lagrange interpolation
    in ``ln mu`` ([Abramowitz1964] 25.2.13). Returns False (``cols`` unchanged) below the table's smallest cosine."""
    if not mu > 0.0:
        return False
    u = (math.log(mu) - sgeo[1]) * sgeo[2]
    if u < 0.0:
        return False
    nt = stab.shape[0]
    j = min(max(int(u), 1), nt - 3)
    s = u - j
    # weights of the nodes j - 1, j, j + 1, j + 2 at s (s = 0 at node j)
    w0 = -s * (s - 1.0) * (s - 2.0) / 6.0
    w1 = (s + 1.0) * (s - 1.0) * (s - 2.0) / 2.0
    w2 = -(s + 1.0) * s * (s - 2.0) / 2.0
    w3 = (s + 1.0) * s * (s - 1.0) / 6.0
    for q in range(cols.shape[0]):
        cols[q] += w0 * stab[j - 1, q] + w1 * stab[j, q] + w2 * stab[j + 1, q] + w3 * stab[j + 2, q]
    return True


@helper
def _shadow_march(px, py, pz, wx, wy, wz, te, target, kmin, rb, edges, layers, nlay, sgeo, stab, tot, tmp, rec):
    """The shells' columns ``tot`` [m] of a shadow ray over ``[0, te]`` (to the top of the atmosphere) unless the
    optical depth ``kmin . tot`` reaches ``target`` first (returns True then; ``tot`` undefined): :func:`_march`
    without locating the end, except that a ray from below the radius ``sgeo[0]`` (> 0: the top of the cloud layers)
    is marched only up to that sphere and the columns above it come from the table of :func:`_add_columns_above`
    (they depend on the cosine there only, the shells being spherically symmetric). The table's nodes are the
    same pieces and Gauss-Legendre sums as the march (the sphere is a quadrature shell), so the only difference is
    the interpolation (within 5e-10 relative, docs/clouds.md). Near the top of a cloud the ray's 10-odd pieces
    above it become one or two; a ray going outwards with no quadrature shell below that sphere is one piece, taken
    without the march (in closed form, :func:`_short_piece_columns`, where that applies)."""
    rc = sgeo[0]
    r2 = px * px + py * py + pz * pz
    if rc > 0.0 and r2 < rc * rc:
        b = px * wx + py * wy + pz * wz
        tc = -b + math.sqrt(max(b * b - (r2 - rc * rc), 0.0))
        if tc < te:
            # outwards with no quadrature shell between r and rc, the ray up to rc is one piece: taken without the
            # march's search for crossings (the same piece and sum)
            one = b >= 0.0
            if one:
                for e in range(edges.shape[0]):
                    if r2 < edges[e] * edges[e] < rc * rc:
                        one = False
            if one:
                if not _short_piece_columns(r2, b, 0.0, tc, rb, layers, nlay, tot):
                    _piece_columns(r2, b, 0.0, tc, rb, layers, nlay, tot)
                if _dot(kmin, tot) >= target:
                    return True
            else:
                _, deep, _ = _march(px, py, pz, wx, wy, wz, tc, target, kmin, rb, edges, layers, nlay, tot, tmp, rec,
                                    False)
                if deep:
                    return True
            if _add_columns_above(sgeo, stab, (b + tc) / rc, tot):
                return _dot(kmin, tot) >= target
    _, deep, _ = _march(px, py, pz, wx, wy, wz, te, target, kmin, rb, edges, layers, nlay, tot, tmp, rec, False)
    return deep


@helper
def _uniform_shell(r2, ushell):
    """Index of the first uniform shell of ``ushell`` (rows ``r_lo, r_hi, rho_0 ... rho_C-1``: radii [m] and the
    relative densities of the components that are constant between them) strictly containing the radius
    ``sqrt(r2)`` [m], -1 if none."""
    for s in range(ushell.shape[0]):
        if ushell[s, 0] * ushell[s, 0] < r2 < ushell[s, 1] * ushell[s, 1]:
            return s
    return -1


@helper
def _shell_exit(px, py, pz, dx, dy, dz, rlo, rhi):
    """Distance [m] along ``p + t d`` from a point strictly between the spheres ``rlo < r < rhi`` [m] to where the
    ray leaves that shell (through the inner sphere when it meets it, else the outer one)."""
    r2 = px * px + py * py + pz * pz
    b = px * dx + py * dy + pz * dz
    disc = b * b - (r2 - rlo * rlo)
    if b < 0.0 and disc >= 0.0:
        return max(-b - math.sqrt(disc), 0.0)
    return max(-b + math.sqrt(max(b * b - (r2 - rhi * rhi), 0.0)), 0.0)


@helper
def _uniform_free_path(px, py, pz, dx, dy, dz, t_end, target, kh, s, ushell, rb, edges, layers, nlay, cols, tmp,
                       rec, kha, cseg, st):
    """A free path from ``p`` [m] inside the uniform shell ``s`` (:func:`_uniform_shell`) along ``d`` up to ``t_end``
    [m], for the hero's coefficients ``kh`` [m^-1]: the same collision density ``sigma_t T`` as :func:`_march` with
    ``target``, sampled by decomposition ([Kutz2017], decomposition tracking: the first of two independent collisions
    wins): the shell's constant part ``K = sum_q kh_q rho_q`` has the closed-form free path ``target / K`` inside the
    shell, the rest of the medium (the air) is marched with its own exponential target (coefficients ``kha``: ``kh``
    without the shell's constant components) up to that distance. Inside a thick cloud the air's optical depth over a
    free path is some 1e-3 of the cloud's, so the march is one piece without Newton's inversion; where no quadrature
    shell cuts the uniform one it is that piece alone (no search for crossings), its columns in closed form
    (:func:`_short_piece_columns`) where that applies, and the air's target ``-ln(1 - u) >= u`` is computed only when
    the uniform ``u`` is below the air's optical depth (the same decision as the march's, one logarithm fewer per free
    path). A path that leaves the shell without a collision draws a fresh free path from the shell's boundary (the
    exponential law is memoryless). Returns ``(t, reached)`` and, in ``cols``, the shell columns [m] from ``p`` to
    ``t``; ``cseg`` (n_comp,) is a work array."""
    nc = cols.shape[0]
    k_uni = 0.0
    for q in range(nc):
        rho = ushell[s, 2 + q]
        k_uni += kh[q] * rho
        kha[q] = kh[q] if rho == 0.0 else 0.0
    d_shell = min(_shell_exit(px, py, pz, dx, dy, dz, ushell[s, 0], ushell[s, 1]), t_end)
    t_c = target / k_uni if k_uni > 0.0 else np.inf
    t_lim = min(t_c, d_shell)
    u_a = next_uniform(st)
    rlo = ushell[s, 0]
    rhi = ushell[s, 1]
    inner = False  # a quadrature shell inside the uniform one: the ray up to t_lim may be more than one piece
    for e in range(edges.shape[0]):
        if rlo < edges[e] < rhi:
            inner = True
    if inner:
        target_a = -math.log1p(-u_a)
        t, reached, _ = _march(px, py, pz, dx, dy, dz, t_lim, target_a, kha, rb, edges, layers, nlay, cols, tmp, rec,
                               True)
        if reached:
            return t, True
    else:
        # the ray stays in the shell up to t_lim, which no quadrature shell cuts: one piece, as the march would
        # have it, without the march's search for crossings; the air's exponential target -ln(1 - u_a) >= u_a is
        # taken (one logarithm) only when u_a does not already exceed the air's optical depth, some 1e-3 here
        r2 = px * px + py * py + pz * pz
        b = px * dx + py * dy + pz * dz
        if not _short_piece_columns(r2, b, 0.0, t_lim, rb, layers, nlay, cols):
            _piece_columns(r2, b, 0.0, t_lim, rb, layers, nlay, cols)
        tau_a = _dot(kha, cols)
        if u_a <= tau_a:
            target_a = -math.log1p(-u_a)
            if tau_a >= target_a:
                t = _invert_in_piece(r2, b, 0.0, t_lim, target_a, tau_a, target_a, kha, rb, layers, nlay, cols)
                return t, True
    if t_c < d_shell:
        return t_c, True
    if d_shell >= t_end:
        return t_end, False
    # no collision inside the shell: a new free path from its boundary, the columns added up
    for q in range(nc):
        cseg[q] = cols[q]
    qx = px + d_shell * dx
    qy = py + d_shell * dy
    qz = pz + d_shell * dz
    target2 = -math.log1p(-next_uniform(st))
    t2, reached2, _ = _march(qx, qy, qz, dx, dy, dz, t_end - d_shell, target2, kh, rb, edges, layers, nlay, cols, tmp,
                             rec, True)
    for q in range(nc):
        cols[q] += cseg[q]
    if reached2:
        return d_shell + t2, True
    return t_end, False


@helper
def _uniform_lower_bound(px, py, pz, wx, wy, wz, te, kmin, ushell):
    """A lower bound of the optical depth ``kmin . col`` along ``p + t w``, ``0 <= t <= te`` [m]: the constant
    components of the uniform shell containing ``p`` over the ray's length inside that shell (the other
    components and the rest of the ray add to it); 0 outside every uniform shell."""
    s = _uniform_shell(px * px + py * py + pz * pz, ushell)
    if s < 0:
        return 0.0
    k = 0.0
    for q in range(kmin.shape[0]):
        k += kmin[q] * ushell[s, 2 + q]
    return k * min(_shell_exit(px, py, pz, wx, wy, wz, ushell[s, 0], ushell[s, 1]), te)


@helper
def _suns_hidden(px, py, pz, cos_zen, cos_sun, end, kmin, ushell):
    """Whether every next-event shadow ray of an almucantar's vertex ``p`` [m] ends in the roulette of
    :func:`_sun_transmittance` within the uniform shell containing ``p``: the suns of the entry all have the zenith
    angle ``acos(cos_zen)`` about the planet's axis (the z axis) and the angular radius ``acos(cos_sun)``, so every
    direction of their discs makes an angle with ``p``'s vertical within ``zen -+ (radius + delta)``, ``delta`` the
    angle between that vertical and the axis. When all of them climb (the largest such angle below 90 deg), the
    shell's path length decreases with the cosine, so the shell's optical depth along the steepest of them
    (:func:`_uniform_lower_bound`'s bound at the largest cosine) bounds every ray's from below; when it reaches
    ``end`` [-] (the shared roulette depth) no shadow ray of the vertex survives, and none need be drawn."""
    r2 = px * px + py * py + pz * pz
    s = _uniform_shell(r2, ushell)
    if s < 0:
        return False
    r = math.sqrt(r2)
    delta = math.atan2(math.sqrt(px * px + py * py), pz)
    zen = math.acos(min(max(cos_zen, -1.0), 1.0))
    spread = math.acos(min(max(cos_sun, -1.0), 1.0)) + delta
    if zen + spread >= 0.5 * math.pi:
        return False  # a ray of some disc may head down, through the shell's inner sphere
    b = r * math.cos(max(zen - spread, 0.0))  # the steepest ray's p . w
    rhi = ushell[s, 1]
    t = -b + math.sqrt(max(b * b - (r2 - rhi * rhi), 0.0))
    k = 0.0
    for q in range(kmin.shape[0]):
        k += kmin[q] * ushell[s, 2 + q]
    return k * t * (1.0 - 1e-9) >= end  # the margin covers the rounding of the rays' own bounds


@helper
def _sun_transmittance(px, py, pz, wx, wy, wz, te, field, rr_depth, end_in, kmin, coef_t, rb, edges, layers, nlay, sgeo,
                       stab, ushell, fs, fsmax, fsmin, fvf, fvi, frho, fbmax, fbmin, fxe, fye, fre, st, fstate, tot,
                       tmp, rec, tau, trf, out):
    """The shadow ray of a next-event estimate: ``out[i]`` the transmittance [-] from ``p`` [m] along the unit
    direction ``w`` over ``te`` [m] (to the top of the atmosphere) per wavelength, through the shells (exact) and
    the field (ratio tracking, into ``trf``). Returns False (``out`` not set) where it is zero for every
    wavelength: the field blocks it, or the least extinguished wavelength's optical depth passes ``_NEE_STOP``.
    With ``rr_depth < _NEE_STOP``, Russian roulette on the ray's optical depth ``tau`` (least extinguished
    wavelength) beyond ``rr_depth``: it survives to ``tau`` with probability ``exp(-(tau - rr_depth))`` (one draw: the
    ray is marched only up to the depth ``rr_depth + E``, ``E`` exponential with mean 1, where it ends) and a ray that
    reaches the top is divided by that probability; ``end_in`` >= 0 is that depth drawn by the caller (one draw shared
    by the suns of an almucantar's vertex: :func:`_suns_hidden`), < 0 draws it here. Unbiased, and every surviving
    estimate is at most
    ``exp(-rr_depth)`` times the unshadowed one; deep in a cloud the march stops about one optical depth past
    ``rr_depth``, and a ray is marched to the top only when the sun's light along it is worth it."""
    n = out.shape[0]
    if field:
        field_transmittance(px, py, pz, wx, wy, wz, te, fs, fsmax, fsmin, fvf, fvi, frho, fbmax, fbmin, fxe, fye, fre,
                            trf, st, fstate)
        live = False
        for i in range(n):
            if trf[i] > 0.0:
                live = True
        if not live:
            return False
    w = 1.0
    if rr_depth < _NEE_STOP:
        end = end_in if end_in >= 0.0 else min(rr_depth - math.log1p(-next_uniform(st)), _NEE_STOP)
        if _uniform_lower_bound(px, py, pz, wx, wy, wz, te, kmin, ushell) >= end:
            return False  # the uniform shell alone reaches the depth: no march
        if _shadow_march(px, py, pz, wx, wy, wz, te, end, kmin, rb, edges, layers, nlay, sgeo, stab, tot, tmp, rec):
            return False
        _transmittances(coef_t, tot, tau, out)  # to the top: ``tot`` holds the whole columns
        excess = _dot(kmin, tot) - rr_depth
        if excess > 0.0:
            w = math.exp(excess)
    else:
        if _uniform_lower_bound(px, py, pz, wx, wy, wz, te, kmin, ushell) >= _NEE_STOP:
            return False
        if _shadow_march(px, py, pz, wx, wy, wz, te, _NEE_STOP, kmin, rb, edges, layers, nlay, sgeo, stab, tot, tmp,
                         rec):
            return False
        _transmittances(coef_t, tot, tau, out)
    for i in range(n):
        if field:
            out[i] *= trf[i]
        out[i] *= w
    return True


@helper
def _transmittances(coef_t, cols, tau, out):
    """``out[i] = exp(-tau[i])`` with ``tau`` the optical depths of the columns ``cols`` (:func:`_optical_depths`)."""
    _optical_depths(coef_t, cols, tau)
    for i in range(out.shape[0]):
        out[i] = exp_lane(-tau[i])


@helper
def _transmittances3(coef_t, c0, c1, c2, out):
    """``out[i] = exp(-tau_i)`` with ``tau_i`` the optical depth of the columns ``c0``, ``c1``, ``c2`` [m] of three
    shell components at wavelength ``i`` (``coef_t`` (>= 3, len(out)) [m^-1]): the clear sky's transmittances, in one
    loop that runs in SIMD lanes (:func:`skyscatter.vecmath.exp_lane`; ``out`` a multiple of 4 long leaves no scalar
    remainder), compiled once (not inlined: with the loop inlined at its 4 call sites the clear sky ran at 0.95x
    ``main``'s paths per CPU-second, the path loop's code larger)."""
    for i in range(out.shape[0]):
        out[i] = exp_lane(-(coef_t[0, i] * c0 + coef_t[1, i] * c1 + coef_t[2, i] * c2))


@helper
def _exp_negated(tau, n):
    """``tau[i] = exp(-tau[i])`` in place for ``i < n`` (in SIMD lanes, :func:`skyscatter.vecmath.exp_lane`)."""
    for i in range(n):
        tau[i] = exp_lane(-tau[i])


@helper
def _shells_transmittance(px, py, pz, wx, wy, wz, te, kmin, coef_t, rb, edges, layers, nlay, tot, tmp, rec, tau, out):
    """The shells' part of :func:`_sun_transmittance` (all of it in a clear medium, whose kernel does not call
    that: a call passing the field's arrays at every vertex cost the clear sky some 10 %; at medium vertices it
    marches itself, one call fewer): ``out[i]`` the transmittance along the ray, False where the least extinguished
    wavelength's optical depth passes ``_NEE_STOP`` (exp(-50))."""
    _march3_columns(px, py, pz, wx, wy, wz, te, rb, edges, layers, nlay, tot, tmp, rec)
    if _opaque3(kmin, tot):
        return False
    _transmittances(coef_t, tot, tau, out)
    return True


@helper
def _normalise(f, p, n):
    m = 0.0
    for i in range(n):
        m += p[i]
    m /= n
    if m > 0.0:
        for i in range(n):
            f[i] /= m
            p[i] = p[i] / m


@helper
def _lobe_values(mu, active, lobe, lobe_g, lobe_tab, tmu, tval, ph, qs):
    """Phase function ``ph[c, i]`` [sr^-1] of every active lobe ``c`` (indices ``active``) at every wavelength ``i``
    at ``mu``, and the density ``qs[c, i]`` by which the lobe is sampled (Henyey-Greenstein for a Cornette-Shanks
    lobe, else ``ph``)."""
    n = ph.shape[1]
    for a in range(active.shape[0]):
        c = active[a]
        kind = lobe[c]
        if kind == LOBE_TABLE:
            phase_table_values(tmu, tval[lobe_tab[c]], mu, ph[c])
            for i in range(n):
                qs[c, i] = ph[c, i]
            continue
        if kind == LOBE_RAYLEIGH:
            v = rayleigh_phase_scalar(mu)
            w = v
        elif kind == LOBE_CORNETTE_SHANKS:
            v = cornette_shanks_scalar(mu, lobe_g[c])
            w = henyey_greenstein_scalar(mu, lobe_g[c])
        else:
            v = henyey_greenstein_scalar(mu, lobe_g[c])
            w = v
        for i in range(n):
            ph[c, i] = v
            qs[c, i] = w


@helper
def _sample_lobe(kind, g, tab, hero, u, tmu, tval, tcdf):
    """Cosine of the scattering angle drawn from lobe ``kind`` for the hero wavelength (uniform ``u``)."""
    mu, _ = _sample_lobe_segment(kind, g, tab, hero, u, tmu, tval, tcdf)
    return mu


@helper
def _sample_lobe_segment(kind, g, tab, hero, u, tmu, tval, tcdf):
    """:func:`_sample_lobe` and, for a table, the segment of ``tmu`` the cosine was drawn in (-1 for an analytic
    lobe): the phase sums at that cosine then find their segment without a second bisection
    (:func:`_phase_sums`'s ``hint``)."""
    if kind == LOBE_RAYLEIGH:
        return rayleigh_inverse_cdf_scalar(u), -1
    if kind == LOBE_TABLE:
        return phase_table_inverse_cdf_segment(tmu, tval[tab], tcdf[tab], hero, u)
    return henyey_greenstein_inverse_cdf_scalar(u, g), -1


@helper
def _optical_depths(coef_t, cols, out):
    """``out[i] = sum_q coef_t[q, i] cols[q]``: the optical depth at every wavelength of a ray's columns (the loop
    over wavelengths innermost, on contiguous rows)."""
    n = out.shape[0]
    if cols.shape[0] == 3:
        # the clear sky: one fused loop (each loop over the wavelengths costs about as much as its body)
        c0 = cols[0]
        c1 = cols[1]
        c2 = cols[2]
        for i in range(n):
            out[i] = coef_t[0, i] * c0 + coef_t[1, i] * c1 + coef_t[2, i] * c2
        return
    if cols.shape[0] == 4:
        # one cloud layer: the loop below's sums in its order (the same bits; 0 + x = x for these non-negative terms)
        c0 = cols[0]
        c1 = cols[1]
        c2 = cols[2]
        c3 = cols[3]
        for i in range(n):
            out[i] = coef_t[0, i] * c0 + coef_t[1, i] * c1 + coef_t[2, i] * c2 + coef_t[3, i] * c3
        return
    for i in range(n):
        out[i] = 0.0
    for q in range(cols.shape[0]):
        cq = cols[q]
        for i in range(n):
            out[i] += coef_t[q, i] * cq


@helper
def _medium_at(px, py, pz, rho_f, rb, layers, nlay, coef_t, scat_t, fs, fss, dens, sc, stt, sst):
    """At a point: extinction ``stt[i]`` and scattering ``sst[i]`` [m^-1] per wavelength and the scattering
    coefficient ``sc[c, i]`` of each lobe (shell components, then the field with density ``rho_f``)."""
    rr = math.sqrt(px * px + py * py + pz * pz)
    _densities(rr, rb, layers, nlay, dens)
    nc = dens.shape[0]
    n = stt.shape[0]
    if nc == 3:
        d0 = dens[0]
        d1 = dens[1]
        d2 = dens[2]
        for i in range(n):
            v0 = scat_t[0, i] * d0
            v1 = scat_t[1, i] * d1
            v2 = scat_t[2, i] * d2
            v3 = fss[i] * rho_f
            sc[0, i] = v0
            sc[1, i] = v1
            sc[2, i] = v2
            sc[3, i] = v3
            stt[i] = coef_t[0, i] * d0 + coef_t[1, i] * d1 + coef_t[2, i] * d2 + fs[i] * rho_f
            sst[i] = v0 + v1 + v2 + v3
        return
    if nc == 4:
        # one cloud layer: the loops below fused, their sums in their order (the same bits)
        d0 = dens[0]
        d1 = dens[1]
        d2 = dens[2]
        d3 = dens[3]
        for i in range(n):
            v0 = scat_t[0, i] * d0
            v1 = scat_t[1, i] * d1
            v2 = scat_t[2, i] * d2
            v3 = scat_t[3, i] * d3
            v4 = fss[i] * rho_f
            sc[0, i] = v0
            sc[1, i] = v1
            sc[2, i] = v2
            sc[3, i] = v3
            sc[4, i] = v4
            stt[i] = coef_t[0, i] * d0 + coef_t[1, i] * d1 + coef_t[2, i] * d2 + coef_t[3, i] * d3 + fs[i] * rho_f
            sst[i] = v0 + v1 + v2 + v3 + v4
        return
    for i in range(n):
        stt[i] = 0.0
        sst[i] = 0.0
    for q in range(nc):
        d = dens[q]
        for i in range(n):
            stt[i] += coef_t[q, i] * d
            v = scat_t[q, i] * d
            sc[q, i] = v
            sst[i] += v
    for i in range(n):
        v = fss[i] * rho_f
        sc[nc, i] = v
        stt[i] += fs[i] * rho_f
        sst[i] += v


@helper
def _free_path(px, py, pz, dx, dy, dz, t_end, target, kh, hero, field, rb, edges, layers, nlay, cols, tmp, rec, fs,
               fsmax, fvf, fvi, frho, fbmax, fbmin, fxe, fye, fre, f, p, st, fstate):
    """A free path from ``p`` along ``d`` up to ``t_end`` [m]: the shells' by inverting their optical depth at
    ``target`` for the hero's coefficients ``kh``, then (``field``) the cloud field tracked up to it by
    :func:`.tracking.field_free_path` (the wavelengths' weights ``f``, ``p`` updated there); the decomposition of the
    module docstring. Returns ``(t, reached, rho_f)``: the distance (``t_end`` when nothing is reached), whether a
    collision was reached, the field's density there (0: a shell collision, or none); ``cols`` the shell columns
    from ``p`` to ``t``."""
    t, reached, npc = _march(px, py, pz, dx, dy, dz, t_end, target, kh, rb, edges, layers, nlay, cols, tmp, rec, True)
    if not reached:
        t = t_end
    rho_f = 0.0
    if field:
        tv, hit, rv = field_free_path(px, py, pz, dx, dy, dz, t, hero, fs, fsmax, fvf, fvi, frho, fbmax, fbmin, fxe,
                                      fye, fre, f, p, st, fstate)
        if hit:
            _columns_at(px, py, pz, dx, dy, dz, tv, rb, layers, nlay, rec, npc, cols, tmp)
            t = tv
            reached = True
            rho_f = rv
    return t, reached, rho_f


@inline
def _collide(px, py, pz, dx, dy, dz, t, field, rho_f, fvf, fvi, frho, rb, layers, nlay, coef_t, scat_t, fs, fss, cols,
             dens, sc, stt, sst, tau):
    """A collision at distance ``t`` [m] along ``d`` from ``p``: returns the point; fills the medium there
    (:func:`_medium_at`; the field's density ``rho_f`` looked up unless the field's tracker returned it, i.e. it is
    not 0) and ``tau[i]``, the optical depth of the free path's shell columns ``cols`` at every wavelength. One
    description for the paths' vertices, the peak probe's links and the forward photons."""
    px += t * dx
    py += t * dy
    pz += t * dz
    if field and rho_f == 0.0:
        rho_f = field_density_at(px, py, pz, fvf, fvi, frho)
    _medium_at(px, py, pz, rho_f, rb, layers, nlay, coef_t, scat_t, fs, fss, dens, sc, stt, sst)
    _optical_depths(coef_t, cols, tau)
    return px, py, pz


@helper
def _phase_sums(mu, hint, active, lobe, lobe_g, lobe_tab, tmu, tval, sc, ph, val, val2, density):
    """``val[i] = sum_c sc[c, i] P_c,i(mu)`` [m^-1 sr^-1] over the active lobes and, with ``density``, ``val2[i] =
    sum_c sc[c, i] q_c,i(mu)`` with ``q`` the density by which lobe ``c`` is sampled (Henyey-Greenstein for a
    Cornette-Shanks lobe, else ``P``). A tabulated lobe's values are left in ``ph[c]`` (the forward peak is taken
    off them, :func:`_without_peak`); analytic lobes are one value for every wavelength and are summed directly
    (the clear sky's two lobes in one loop: each loop over the wavelengths costs about as much as its body).
    The tables share the nodes ``tmu``: their segment at ``mu`` is looked up once (no bisection when ``mu`` lies
    in segment ``hint``, e.g. where it was drawn; -1: none; :func:`phase_table_segment_near`, the same segment to
    the bit) and returned as ``(i, w)`` (``i = -1``: no table lobe), for :func:`_without_peak`."""
    n = val.shape[0]
    if active.shape[0] == 2 and lobe[active[0]] != LOBE_TABLE and lobe[active[1]] != LOBE_TABLE:
        c0 = active[0]
        c1 = active[1]
        v0, w0 = _analytic_phase(lobe[c0], lobe_g[c0], mu, density)
        v1, w1 = _analytic_phase(lobe[c1], lobe_g[c1], mu, density)
        for i in range(n):
            val[i] = sc[c0, i] * v0 + sc[c1, i] * v1
        if density:
            for i in range(n):
                val2[i] = sc[c0, i] * w0 + sc[c1, i] * w1
        return -1, 0.0
    for i in range(n):
        val[i] = 0.0
        val2[i] = 0.0
    seg = -1
    sw = 0.0
    for a in range(active.shape[0]):
        c = active[a]
        if lobe[c] == LOBE_TABLE:
            if seg < 0:
                seg, sw = phase_table_segment_near(tmu, mu, hint)
            phase_table_values_at(tval[lobe_tab[c]], seg, sw, ph[c])
            for i in range(n):
                v = sc[c, i] * ph[c, i]
                val[i] += v
                val2[i] += v
            continue
        v, w = _analytic_phase(lobe[c], lobe_g[c], mu, density)
        for i in range(n):
            val[i] += sc[c, i] * v
            val2[i] += sc[c, i] * w
    return seg, sw


@inline
def _analytic_phase(kind, g, mu, density):
    """Phase value [sr^-1] of an analytic lobe at ``mu`` and (with ``density``) the density it is sampled by."""
    if kind == LOBE_RAYLEIGH:
        v = rayleigh_phase_scalar(mu)
        return v, v
    if kind == LOBE_CORNETTE_SHANKS:
        return cornette_shanks_scalar(mu, g), (henyey_greenstein_scalar(mu, g) if density else 0.0)
    v = henyey_greenstein_scalar(mu, g)
    return v, v


#: Continuation probability of the forward-peak chains of :func:`_peak_probe` (chain length L >= 1 drawn with
#: P(L = k) = (1 - c) c^(k - 1)), and their longest length (the tail mass c^(K - 1) goes to L = K: chains of more
#: than K = 64 consecutive peak scatterings are dropped, probability below 1e-25 per vertex for c = 0.4).
_PEAK_CONTINUE = 0.4
_PEAK_MAX_ORDER = 64
#: The chains are probed at a medium vertex with probability ``min(1, max(_PEAK_PROBE_MIN, _PEAK_PROBE_GAIN T))``
#: (``T`` the hero's transmittance to the sun found by the vertex's next-event estimate) and their estimate divided
#: by it (Russian roulette, unbiased): deep in a thick cloud, where the sun is not seen, most probes would find
#: nothing, and they cost several rays each.
_PEAK_PROBE_MIN = 0.1
_PEAK_PROBE_GAIN = 100.0
#: Most copies of a path waiting to be traced (importance splitting; a split that would exceed it is made smaller).
_SPLIT_STACK = 64


@helper
def _peak_probe(px, py, pz, hero, sx, sy, sz, cos_sun, rb, rt, edges, layers, nlay, sgeo, stab, ushell, kha, cseg,
                coef_t, scat_t, kh,
                kmin, peak_lobe, tmu, pval, pcdf, pa, esun, fvf, fvi, frho, fbmax, fbmin, fxe, fye, fre, fs, fss, fsmax,
                fsmin, rr_depth, st, fstate, cols, tot, tmp, rec, dens, sc, stt, sst, tau, trf, pk, fp, pp, chain, g):
    """The sunlight reaching ``p`` [m] after a chain of L >= 1 forward-peak scatterings (module docstring, "forward
    peak"): draws L, a direction ``w`` uniform over the solar disc, directions ``omega_L`` about ``w``, ...,
    ``omega_1`` about ``omega_2`` from the hero's normalised peak ``pval`` (so each link's peak value over its
    density is ``pa_i pval_i / pval_hero``), then the positions: ``x_1`` the free path from ``p`` along ``omega_1``,
    ..., ``x_L`` along ``omega_L``, each collision weighted by the peak lobe's scattering coefficient over the hero's
    collision density, and the transmittance from ``x_L`` to the sun along ``w`` times the solar irradiance.
    Returns ``(alive, omega_1)`` and ``g`` (n,): per wavelength the estimate of ``int int P_peak ... T E`` over
    everything but the first vertex's phase value at ``omega_1``, divided by ``P(L)``. ``alive`` False: zero
    (a free path escaped, the planet or an opaque column blocks the sun). ``rr_depth``: the shadow ray's roulette
    (:func:`_sun_transmittance`)."""
    n = g.shape[0]
    nl = 1
    while nl < _PEAK_MAX_ORDER and next_uniform(st) < _PEAK_CONTINUE:
        nl += 1
    prob = _PEAK_CONTINUE ** (nl - 1)
    if nl < _PEAK_MAX_ORDER:
        prob *= 1.0 - _PEAK_CONTINUE
    for i in range(n):
        g[i] = 1.0 / prob
    wx, wy, wz = _sun_sample(sx, sy, sz, cos_sun, next_uniform(st), next_uniform(st))
    ax, ay, az = wx, wy, wz
    for k in range(nl - 1, -1, -1):
        mu, seg = phase_table_inverse_cdf_segment(tmu, pval, pcdf, hero, next_uniform(st))
        ax, ay, az = direction_about_axis(ax, ay, az, mu, 2.0 * math.pi * next_uniform(st))
        chain[k, 0] = ax
        chain[k, 1] = ay
        chain[k, 2] = az
        seg, sw = phase_table_segment_near(tmu, mu, seg)
        phase_table_values_at(pval, seg, sw, pk)
        if pk[hero] <= 0.0:
            return False, 0.0, 0.0, 0.0
        for i in range(n):
            g[i] *= pa[i] * pk[i] / pk[hero]
    field = fvf[8] != 0.0
    qx, qy, qz = px, py, pz
    for k in range(nl):
        dx, dy, dz = chain[k, 0], chain[k, 1], chain[k, 2]
        t_end, _ = _exit_distance(qx, qy, qz, dx, dy, dz, rb, rt)
        for i in range(n):
            fp[i] = 1.0
            pp[i] = 1.0
        target = -math.log1p(-next_uniform(st))
        if field:
            t, reached, rho_f = _free_path(qx, qy, qz, dx, dy, dz, t_end, target, kh, hero, field, rb, edges, layers,
                                           nlay, cols, tmp, rec, fs, fsmax, fvf, fvi, frho, fbmax, fbmin, fxe, fye, fre,
                                           fp, pp, st, fstate)
        else:
            # the shells alone, without the call (as in trace_block); inside a uniform shell by decomposition
            rho_f = 0.0
            su = _uniform_shell(qx * qx + qy * qy + qz * qz, ushell)
            if su >= 0:
                t, reached = _uniform_free_path(qx, qy, qz, dx, dy, dz, t_end, target, kh, su, ushell, rb, edges,
                                                layers, nlay, cols, tmp, rec, kha, cseg, st)
            else:
                t, reached, _ = _march(qx, qy, qz, dx, dy, dz, t_end, target, kh, rb, edges, layers, nlay, cols, tmp,
                                       rec, True)
                if not reached:
                    t = t_end
        if not reached:
            return False, 0.0, 0.0, 0.0
        qx, qy, qz = _collide(qx, qy, qz, dx, dy, dz, t, field, rho_f, fvf, fvi, frho, rb, layers, nlay, coef_t,
                              scat_t, fs, fss, cols, dens, sc, stt, sst, tau)
        den = stt[hero] * exp_lane(-tau[hero]) * pp[hero]
        if not den > 0.0 or sc[peak_lobe, hero] <= 0.0:
            return False, 0.0, 0.0, 0.0
        for i in range(n):
            g[i] *= fp[i] * exp_lane(-tau[i]) * sc[peak_lobe, i] / den
    te, blocked = _exit_distance(qx, qy, qz, wx, wy, wz, rb, rt)
    if blocked:
        return False, 0.0, 0.0, 0.0
    if not _sun_transmittance(qx, qy, qz, wx, wy, wz, te, field, rr_depth, -1.0, kmin, coef_t, rb, edges, layers, nlay,
                              sgeo, stab, ushell, fs, fsmax, fsmin, fvf, fvi, frho, fbmax, fbmin, fxe, fye, fre, st,
                              fstate, tot, tmp, rec, tau, trf, fp):
        return False, 0.0, 0.0, 0.0
    for i in range(n):
        g[i] *= esun[i] * fp[i]
    return True, chain[0, 0], chain[0, 1], chain[0, 2]


@helper
def _without_peak(mu, seg, sw, peak_lobe, tmu, pval, pa, pk, sc, ph, val):
    """Take the forward peak ``pa_i pval_i(mu)`` off the peak lobe's phase values ``ph[peak_lobe]`` (never below
    0) in the sums ``val`` of :func:`_phase_sums`; ``(seg, sw)`` the segment of ``mu`` in ``tmu`` that returned
    (``seg = -1``: looked up here)."""
    if seg < 0:
        seg, sw = phase_table_segment(tmu, mu)
    phase_table_values_at(pval, seg, sw, pk)
    for i in range(pk.shape[0]):
        val[i] -= sc[peak_lobe, i] * min(ph[peak_lobe, i], pa[i] * pk[i])


@inline
def _scatter(dx, dy, dz, hero, st, use_ddis, eps, ddis_lobe, ddis_active, sx, sy, sz, active, lobe, lobe_g, lobe_tab,
             tmu, tval, tcdf, sc, sst, ph, val, val2, ph2, qs2, f, p, dval, dcdf):
    """The scattering direction at a medium vertex (incoming direction ``d``, the medium there in ``sc``, ``sst``):
    the lobe chosen by the hero's scattering coefficients and its cosine drawn for the hero, or (with probability
    ``eps``) about the sun; multiplies every wavelength's ``f`` by its phase sum and ``p`` by its density of that
    direction, normalised (module docstring). With a table ``dval``, ``dcdf`` (n_wl, m) on ``tmu`` (more than 2
    nodes; the cloud's phase function without its forward peak) the direction about the sun is drawn from it
    instead. Returns the new direction."""
    n = f.shape[0]
    n_active = active.shape[0]
    drest = dval.shape[1] > 2
    seg = -1
    if use_ddis and eps > 0.0 and next_uniform(st) < eps:
        if drest:
            ms = phase_table_inverse_cdf(tmu, dval, dcdf, hero, next_uniform(st))
        else:
            ms = _sample_lobe(lobe[ddis_lobe], lobe_g[ddis_lobe], lobe_tab[ddis_lobe], hero,
                              next_uniform(st), tmu, tval, tcdf)
        ex, ey, ez = direction_about_axis(sx, sy, sz, ms, 2.0 * math.pi * next_uniform(st))
        mu = min(max(ex * dx + ey * dy + ez * dz, -1.0), 1.0)
        dx, dy, dz = ex, ey, ez
    else:
        u = next_uniform(st) * sst[hero]
        pick = active[n_active - 1]
        acc = 0.0
        for a in range(n_active):
            c = active[a]
            acc += sc[c, hero]
            if u < acc:
                pick = c
                break
        mu, seg = _sample_lobe_segment(lobe[pick], lobe_g[pick], lobe_tab[pick], hero, next_uniform(st), tmu,
                                       tval, tcdf)
        dx, dy, dz = direction_about_axis(dx, dy, dz, mu, 2.0 * math.pi * next_uniform(st))
    _phase_sums(mu, seg, active, lobe, lobe_g, lobe_tab, tmu, tval, sc, ph, val, val2, True)
    if use_ddis and eps > 0.0:
        # each wavelength's density of that direction: the lobes' mixture or, with
        # probability ddis, the cloud's phase function of its own wavelength about the sun
        if drest:
            phase_table_values(tmu, dval, dx * sx + dy * sy + dz * sz, ph2[ddis_lobe])
        else:
            _lobe_values(dx * sx + dy * sy + dz * sz, ddis_active, lobe, lobe_g, lobe_tab, tmu, tval,
                         ph2, qs2)
        for i in range(n):
            f[i] *= val[i]
            lobes = val2[i] / sst[i] if sst[i] > 0.0 else 0.0
            p[i] *= (1.0 - eps) * lobes + eps * ph2[ddis_lobe, i]
    else:
        for i in range(n):
            f[i] *= val[i]
            p[i] *= val2[i] / sst[i] if sst[i] > 0.0 else 0.0
    _normalise(f, p, n)
    return dx, dy, dz


@inline
def _clear_collision(px, py, pz, forced, rb, layers, nlay, coef_t, coef_p, scat_t, a0, a1, cols, tot, sc, sst, f, p,
                     trn):
    """The collision of a clear-sky path (three shell components, the analytic lobes ``a0``, ``a1``) at ``p`` [m]:
    what :func:`_collide` and the weights' update by the free path's transmittance and collision density do there,
    the same operations in the same order (the same bits; the field's terms, 0 here, left out: x + 0 = x), in one
    loop over the wavelengths instead of four (each such loop costs about as much as its body: the clear sky took
    1.08x the CPU time of the kernels before the clouds with them, docs/clouds.md "Speed"). ``cols`` the free path's
    columns [m], ``tot`` (``forced``) the view ray's. Fills ``sc[a0]``, ``sc[a1]``, ``sst`` [m^-1] and the free
    path's transmittances ``trn`` (n_pad,) [-] (computed first by :func:`_transmittances3` from ``coef_p``, the
    (3, n_pad) coefficients [m^-1] padded with zeros to a multiple of 4 wavelengths, in a loop that runs in SIMD lanes
    without a scalar remainder; the fused loop's sum keeps that loop scalar); returns the mean of the updated ``p``
    (:func:`_normalise`'s divisor, applied by :func:`_clear_nee`)."""
    n = f.shape[0]
    h = math.sqrt(px * px + py * py + pz * pz) - rb
    d0 = _density(h, layers, nlay, 0)
    d1 = _density(h, layers, nlay, 1)
    d2 = _density(h, layers, nlay, 2)
    c0 = cols[0]
    c1 = cols[1]
    c2 = cols[2]
    _transmittances3(coef_p, c0, c1, c2, trn)
    m = 0.0
    if forced:
        e0 = tot[0]
        e1 = tot[1]
        e2 = tot[2]
        for i in range(n):
            v0 = scat_t[0, i] * d0
            v1 = scat_t[1, i] * d1
            sc[a0, i] = v0
            sc[a1, i] = v1
            sst[i] = v0 + v1 + scat_t[2, i] * d2
            stt = coef_t[0, i] * d0 + coef_t[1, i] * d1 + coef_t[2, i] * d2
            tr = trn[i]
            pdf = stt * tr
            ttot = -math.expm1(-(coef_t[0, i] * e0 + coef_t[1, i] * e1 + coef_t[2, i] * e2))
            pdf = pdf / ttot if ttot > 0.0 else 0.0
            f[i] *= tr
            q = p[i] * pdf
            p[i] = q
            m += q
    else:
        for i in range(n):
            v0 = scat_t[0, i] * d0
            v1 = scat_t[1, i] * d1
            sc[a0, i] = v0
            sc[a1, i] = v1
            sst[i] = v0 + v1 + scat_t[2, i] * d2
            stt = coef_t[0, i] * d0 + coef_t[1, i] * d1 + coef_t[2, i] * d2
            tr = trn[i]
            f[i] *= tr
            q = p[i] * (stt * tr)
            p[i] = q
            m += q
    return m / n


@inline
def _clear_nee(px, py, pz, dx, dy, dz, m, sun, cos_sun, rb, rt, edges, layers, nlay, coef_p, kmin, a0, a1, lobe,
               lobe_g, esun, sc, f, p, contrib, st, tot, tmp, rec, trn):
    """After :func:`_clear_collision` at ``p`` [m] (reached along ``d``): the weights divided by their mean ``m``
    (:func:`_normalise`) and the next-event estimate to the sun (:func:`_march3_columns`, :func:`_transmittances`,
    :func:`_phase_sums`, the contributions ``contrib``) in one loop over the wavelengths, the same operations in the
    same order (the same bits). The path's copy weight is 1 in a clear medium (no splitting): left out (1 x = x).
    The shadow ray's transmittances are computed first into ``trn`` (n_pad,) [-] from the padded ``coef_p`` (3, n_pad)
    [m^-1], in a loop that runs in SIMD lanes (:func:`_clear_collision`)."""
    n = f.shape[0]
    wx, wy, wz = _sun_sample(sun[0], sun[1], sun[2], cos_sun, next_uniform(st), next_uniform(st))
    te, blocked = _exit_distance(px, py, pz, wx, wy, wz, rb, rt)
    live = False
    if not blocked:
        _march3_columns(px, py, pz, wx, wy, wz, te, rb, edges, layers, nlay, tot, tmp, rec)
        live = not _opaque3(kmin, tot)
    v0 = 0.0
    v1 = 0.0
    if live:
        mw = wx * dx + wy * dy + wz * dz
        v0, _ = _analytic_phase(lobe[a0], lobe_g[a0], mw, False)
        v1, _ = _analytic_phase(lobe[a1], lobe_g[a1], mw, False)
    e0 = tot[0]
    e1 = tot[1]
    e2 = tot[2]
    if live:
        _transmittances3(coef_p, e0, e1, e2, trn)
    if m > 0.0:
        if live:
            for i in range(n):
                fi = f[i] / m
                f[i] = fi
                p[i] = p[i] / m
                contrib[i] += fi * (sc[a0, i] * v0 + sc[a1, i] * v1) * esun[i] * trn[i]
        else:
            for i in range(n):
                f[i] /= m
                p[i] = p[i] / m
    elif live:
        for i in range(n):
            contrib[i] += f[i] * (sc[a0, i] * v0 + sc[a1, i] * v1) * esun[i] * trn[i]


@inline
def _clear_scatter(dx, dy, dz, hero, a0, a1, lobe, lobe_g, sc, sst, f, p, st):
    """The scattering direction at a clear-sky vertex after :func:`_clear_nee`: what :func:`_scatter` does without
    directional sampling (the lobe chosen by the hero's scattering coefficients, its cosine drawn for it; ``f``
    times the phase sums, ``p`` times the direction's density, normalised), the same operations in the same order
    (the same bits), in two loops over the wavelengths instead of five. Returns the new direction and the largest
    weight (for :func:`_roulette_max`)."""
    n = f.shape[0]
    u = next_uniform(st) * sst[hero]
    pick = a0 if u < sc[a0, hero] else a1
    if lobe[pick] == LOBE_RAYLEIGH:
        mu = rayleigh_inverse_cdf_scalar(next_uniform(st))
    else:
        mu = henyey_greenstein_inverse_cdf_scalar(next_uniform(st), lobe_g[pick])
    dx, dy, dz = direction_about_axis(dx, dy, dz, mu, 2.0 * math.pi * next_uniform(st))
    v0, w0 = _analytic_phase(lobe[a0], lobe_g[a0], mu, True)
    v1, w1 = _analytic_phase(lobe[a1], lobe_g[a1], mu, True)
    m = 0.0
    for i in range(n):
        s0 = sc[a0, i]
        s1 = sc[a1, i]
        f[i] *= s0 * v0 + s1 * v1
        s = sst[i]
        q = p[i] * ((s0 * w0 + s1 * w1) / s if s > 0.0 else 0.0)
        p[i] = q
        m += q
    m /= n
    wmax = 0.0
    if m > 0.0:
        for i in range(n):
            fi = f[i] / m
            f[i] = fi
            p[i] = p[i] / m
            if fi > wmax:
                wmax = fi
    else:
        for i in range(n):
            if f[i] > wmax:
                wmax = f[i]
    return dx, dy, dz, wmax


@inline
def _clear_ground(px, py, pz, dx, dy, dz, t_end, sun, cos_sun, rb, rt, edges, layers, nlay, coef_p, kmin, albedo,
                  esun, cols, tot, tmp, rec, f, p, contrib, st, trn):
    """A ground vertex of a clear-sky path (Lambertian; three shell components) where the ray from ``p`` [m] along
    ``d`` meets the ground at ``t_end`` [m]: what :func:`_trace_paths`' ground vertex does, the same operations in the
    same order (the same bits; the copy weight, 1 here, left out), its loops over the wavelengths fused into two
    (:func:`_clear_collision`), the transmittances first into ``trn`` (n_pad,) [-] from the padded ``coef_p`` (3,
    n_pad) [m^-1] (a loop in SIMD lanes). Returns the ground point, the new direction and the largest weight."""
    n = f.shape[0]
    px += t_end * dx
    py += t_end * dy
    pz += t_end * dz
    rr = math.sqrt(px * px + py * py + pz * pz)
    nx, ny, nz = px / rr, py / rr, pz / rr
    px, py, pz = nx * rb, ny * rb, nz * rb
    c0 = cols[0]
    c1 = cols[1]
    c2 = cols[2]
    _transmittances3(coef_p, c0, c1, c2, trn)
    m = 0.0
    for i in range(n):
        tr = trn[i]
        f[i] *= tr
        q = p[i] * tr
        p[i] = q
        m += q
    m /= n
    wx, wy, wz = _sun_sample(sun[0], sun[1], sun[2], cos_sun, next_uniform(st), next_uniform(st))
    cs = wx * nx + wy * ny + wz * nz
    live = False
    if cs > 0.0:
        te, _ = _exit_distance(px, py, pz, wx, wy, wz, rb, rt)
        _march3_columns(px, py, pz, wx, wy, wz, te, rb, edges, layers, nlay, tot, tmp, rec)
        live = not _opaque3(kmin, tot)
    # cosine-weighted hemisphere: weight albedo
    u1 = next_uniform(st)
    mu = math.sqrt(u1)
    dx, dy, dz = direction_about_axis(nx, ny, nz, mu, 2.0 * math.pi * next_uniform(st))
    e0 = tot[0]
    e1 = tot[1]
    e2 = tot[2]
    if live:
        _transmittances3(coef_p, e0, e1, e2, trn)
    norm = m > 0.0
    wmax = 0.0
    for i in range(n):
        fi = f[i]
        if norm:
            fi = fi / m
            p[i] = p[i] / m
        if live:
            contrib[i] += fi * albedo[i] / math.pi * cs * esun[i] * trn[i]
        fi *= albedo[i]
        f[i] = fi
        if fi > wmax:
            wmax = fi
    return px, py, pz, dx, dy, dz, wmax


@kernel
def trace_block(origins, jitter, dirs, mode, dir_index, suns, sun_ptr, cos_sun, rb, rt, edges, layers, nlay, sgeo, stab,
        ushell, coef, scat, lobe, lobe_g, lobe_tab, tmu, tval, tcdf, albedo, esun, fvf, fvi, frho, fbmax, fbmin, fxe,
        fye, fre, fs, fss, ddis, ddis_lobe, peak_lobe, pval, pcdf, pa, nee_roulette, split, dval, dcdf, ddis_gate,
        cloudy, order_lo, order_hi, seed, group, batch0, n_batches, batch_size, sums, sumsq, counts, vertices_out):
    """Trace ``n_batches`` batches of ``batch_size`` paths for each entry of a block; one wavelength group.

    Parameters (all SI; arrays float64 unless stated)
    ----------
    origins : (n, 3) observer positions, planet frame [m]. jitter : (n, 2) x-y footprint [m] over which each
    path's origin is drawn uniformly (0: fixed). dirs : (n, 3) unit directions (view direction, or the axis of the
    cosine distribution). mode : (n,) int64, 0 radiance along ``dirs``, 1 irradiance on the plane facing
    ``dirs`` (cosine-distributed directions, estimates times pi). dir_index : (n,) int64 global entry numbers.
    suns : (m, 3) unit vectors to the sun centre; sun_ptr : (n + 1,) int64: entry ``j`` estimates with the suns
    ``sun_ptr[j] .. sun_ptr[j + 1] - 1`` (at least one; several only for an almucantar of views traced as one, module
    docstring "Almucantars", and only in the kernel with the cloud code), each into its own output row.
    cos_sun : cosine of the solar angular radius.
    rb, rt : planet and top-of-atmosphere radii [m]. edges : sorted radii [m] of the quadrature shells.
    layers : (C, L, 5) density layers of the shell components; nlay : (C,) int64 layer counts.
    sgeo (3,), stab (m, C): the shadow rays' table of the shells' columns [m] above the cloud tops
    (:func:`_shadow_march`, ``driver.columns_above``; ``sgeo[0] = 0``: none, every shadow ray marched).
    ushell (m, 2 + C): uniform shells (cloud layers): radii [m] ``r_lo, r_hi`` and the relative densities of the
    components constant between them (0 for the others); free paths and shadow rays from inside one use that
    (:func:`_uniform_free_path`, :func:`_uniform_lower_bound`). Zero rows: none.
    coef, scat : (n_wl, C) extinction and scattering coefficients at relative density 1 [m^-1].
    lobe, lobe_g, lobe_tab : (C + 1,) phase code (``LOBE_*``), asymmetry and table index of each shell component
    and, last, of the cloud field. tmu (m,), tval and tcdf (n_tab, n_wl, m): the phase tables (ascending mu).
    albedo : (n_wl,) ground albedo; esun : (n_wl,) solar irradiance [W m^-2 nm^-1].
    fvf ... fre : the packed cloud field (:class:`.tracking.PackedField`; ``fvf[PRESENT] = 0`` for none);
    fs, fss : (n_wl,) its extinction and scattering per unit density [-].
    ddis, ddis_lobe : probability of drawing a scattering direction about the sun instead (0: never), from the
    phase function of lobe ``ddis_lobe`` (the cloud's) centred on the sun; see the module docstring. dval, dcdf
    (n_wl, m): with a forward peak split off, that lobe without its peak, normalised (the directions about the sun
    are drawn from it instead). ddis_gate: directions about the sun only at medium vertices whose next-event
    transmittance (largest over the wavelengths) exceeds it (0: everywhere).
    split : (1 + k,) importance splitting (module docstring): the factor (1: off), then the transmittances bounding
    the k classes, ascending.
    peak_lobe : the lobe whose forward peak is split off (-1: none; module docstring, "forward peak"); pval, pcdf
    (n_wl, m): its peak, normalised, as a table on ``tmu`` (0 below the split cosine); pa (n_wl,): the peak's
    fraction of the lobe's scattering.
    nee_roulette : optical depth of the least extinguished wavelength along a shadow ray beyond which it survives
    by Russian roulette only, with probability ``exp(-(tau - nee_roulette))`` (``_sun_transmittance``; inf or >=
    ``_NEE_STOP``: never).
    cloudy : None for a medium without a field, a forward peak or directional sampling (then those are off whatever
    the arguments before say), else any array. Numba compiles a separate kernel for ``None`` in which the tests
    below are the constant False and LLVM removes the cloud code; that kernel marches the clear sky's three shell
    components (Rayleigh, aerosol, ozone: ``C = 3``, else ValueError) with their coefficients as scalars
    (:func:`_march3_locate`).
    order_lo, order_hi : int64, the orders of scattering counted (module docstring, "Orders"): a path's estimate
    takes the next-event estimates of its vertices number ``order_lo .. order_hi`` only (the first vertex is number
    1; ground reflections count as vertices) and ends after vertex ``order_hi``. ``1, _MAX_VERTICES``: every order
    (the paths and their random numbers are then those of a kernel without the window). Not with a forward peak
    split off (``peak_lobe >= 0``), whose probes estimate several orders at once: ValueError.
    seed, group, batch0 : RNG counters (batch numbers batch0 .. batch0 + n_batches - 1).
    sums, sumsq : (m, n_batches, n_wl, n_wl) outputs, one row per sun: per batch, hero and wavelength, sum and sum
    of squares of the per-path estimate (the heroes are the strata of the standard error; a path's wavelengths
    contiguous). counts : (m, n_batches, n_wl) output: per batch and hero, the number of paths. vertices_out : (m,
    n_batches) output: per batch, the number of scattering and ground vertices of the paths of the row's entry.
    """
    n = coef.shape[0]
    nc = coef.shape[1]
    if cloudy is None and nc != 3:
        raise ValueError("the kernel without the cloud code (cloudy None) takes the three shell components")
    ndir = dirs.shape[0]
    for j in range(ndir):
        if sun_ptr[j + 1] <= sun_ptr[j] or (cloudy is None and sun_ptr[j + 1] - sun_ptr[j] != 1):
            raise ValueError("each entry takes one sun or more (one in the kernel without the cloud code)")
    if order_lo < 1 or order_hi < order_lo:
        raise ValueError("the orders counted must satisfy 1 <= order_lo <= order_hi")
    if cloudy is not None and peak_lobe >= 0 and (order_lo > 1 or order_hi < _MAX_VERTICES):
        raise ValueError("a window of orders needs a medium without a forward peak split off")
    st = np.empty(1, dtype=np.uint64)
    f = np.empty(n)
    p = np.empty(n)
    contrib = np.empty(n)
    m_sun = 1
    for j in range(ndir):
        m_sun = max(m_sun, sun_ptr[j + 1] - sun_ptr[j])
    cr = np.empty((m_sun, n))
    sun = np.empty(3)
    cols = np.empty(nc)
    tot = np.empty(nc)
    tmp = np.empty(nc)
    dens = np.empty(nc)
    kh = np.empty(nc)
    coef_t = np.ascontiguousarray(coef.T)
    scat_t = np.ascontiguousarray(scat.T)
    # the clear sky's transmittances run on a multiple of 4 wavelengths (the SIMD lanes of 4 doubles): coef_t padded
    # with zero columns, their transmittances (1) left unused; no scalar remainder after the vector loop
    n_pad = (n + 3) // 4 * 4
    coef_p = np.zeros((nc, n_pad))
    coef_p[:, :n] = coef_t
    trn = np.empty(n_pad)
    sc = np.empty((nc + 1, n))
    ph = np.empty((nc + 1, n))
    tau = np.empty(n)
    tau2 = np.empty(n)
    val = np.empty(n)
    val2 = np.empty(n)
    ph2 = np.empty((nc + 1, n))
    qs2 = np.empty((nc + 1, n))
    ddis_active = np.full(1, max(ddis_lobe, 0), dtype=np.int64)
    stt = np.empty(n)
    sst = np.empty(n)
    trf = np.empty(n)
    fstate = np.zeros(6, dtype=np.int64)
    rec = np.empty((2 * edges.shape[0] + 2, 2 + nc))
    clouds_on = cloudy is not None  # a compile-time constant (docstring)
    field = clouds_on and fvf[8] != 0.0
    use_ddis = clouds_on and ddis > 0.0
    fsmax = 0.0
    fsmin = np.inf
    for i in range(n):
        fsmax = max(fsmax, fs[i])
        fsmin = min(fsmin, fs[i])
    peak = clouds_on and peak_lobe >= 0
    rr_depth = nee_roulette if clouds_on else np.inf
    trs = np.empty(n)
    pk = np.empty(n)
    gch = np.empty(n)
    fp = np.empty(n)
    pp = np.empty(n)
    sc3 = np.empty((nc + 1, n))
    stt3 = np.empty(n)
    sst3 = np.empty(n)
    chain = np.empty((_PEAK_MAX_ORDER, 3))
    split_on = clouds_on and split[0] > 1.0
    stk = np.empty((_SPLIT_STACK, 8))
    keep = np.empty((m_sun + 1, n))  # the estimates before a vertex whose order is not counted
    stk_f = np.empty((_SPLIT_STACK, n))
    stk_p = np.empty((_SPLIT_STACK, n))
    f0 = np.empty(n)
    p0 = np.empty(n)
    kmin = np.empty(nc)
    for q in range(nc):
        kmin[q] = coef[0, q]
        for i in range(n):
            kmin[q] = min(kmin[q], coef[i, q])
    # lobes that scatter (not ozone, not an absent field): the only ones the phase sums visit
    n_active = 0
    for c in range(nc + 1):
        if lobe[c] != LOBE_NONE:
            n_active += 1
    active = np.empty(n_active, dtype=np.int64)
    n_active = 0
    for c in range(nc + 1):
        if lobe[c] != LOBE_NONE:
            active[n_active] = c
            n_active += 1
    kha = np.empty(nc)
    cseg = np.empty(nc)
    _trace_paths(origins, jitter, dirs, mode, dir_index, suns, sun_ptr, sun, cr, cos_sun, rb, rt, edges, layers, nlay,
                     sgeo, stab, ushell, kha, cseg, coef, lobe, lobe_g, lobe_tab, tmu, tval, tcdf, albedo, esun, fvf,
                     fvi, frho, fbmax, fbmin, fxe, fye, fre, fs, fss, ddis, ddis_lobe, peak_lobe, pval, pcdf, pa, split,
                     dval, dcdf, ddis_gate, seed, group, batch0, n_batches, batch_size, sums, sumsq, counts,
                     vertices_out, n, nc, ndir, st, f, p, contrib, cols, tot, tmp, dens, kh, coef_t, scat_t, sc, ph,
                     tau, tau2, val, val2, ph2, qs2, ddis_active, stt, sst, trf, fstate, rec, cloudy, field, use_ddis,
                     fsmax, fsmin, peak, rr_depth, trs, pk, gch, fp, pp, sc3, stt3, sst3, chain, split_on, stk, stk_f,
                     stk_p, f0, p0, kmin, active, coef_p, trn, order_lo, order_hi, keep)


@helper
def _swap_estimates(contrib, cr, ns, keep, clear3, back):
    """Keep the path's estimates so far (``back`` False) or put them back (True): the clear kernel's ``contrib``,
    else the ``ns`` suns' rows of ``cr`` (a vertex outside the window of orders adds nothing; "Orders")."""
    n = contrib.shape[0]
    if clear3:
        for i in range(n):
            if back:
                contrib[i] = keep[0, i]
            else:
                keep[0, i] = contrib[i]
    else:
        for s in range(ns):
            for i in range(n):
                if back:
                    cr[s, i] = keep[s, i]
                else:
                    keep[s, i] = cr[s, i]


@helper
def _trace_paths(origins, jitter, dirs, mode, dir_index, suns, sun_ptr, sun, cr, cos_sun, rb, rt, edges, layers, nlay,
                 sgeo, stab, ushell, kha, cseg, coef, lobe, lobe_g, lobe_tab, tmu, tval, tcdf, albedo, esun, fvf, fvi,
                 frho, fbmax, fbmin, fxe, fye, fre, fs, fss, ddis, ddis_lobe, peak_lobe, pval, pcdf, pa, split, dval,
                 dcdf, ddis_gate, seed, group, batch0, n_batches, batch_size, sums, sumsq, counts, vertices_out, n, nc,
                 ndir, st, f, p, contrib, cols, tot, tmp, dens, kh, coef_t, scat_t, sc, ph, tau, tau2, val, val2, ph2,
                 qs2, ddis_active, stt, sst, trf, fstate, rec, cloudy, field, use_ddis, fsmax, fsmin, peak, rr_depth,
                 trs, pk, gch, fp, pp, sc3, stt3, sst3, chain, split_on, stk, stk_f, stk_p, f0, p0, kmin, active,
                 coef_p, trn, order_lo, order_hi, keep):
    """The paths of :func:`trace_block` (its loop over entries, batches and paths), with the buffers it allocated.
    A helper (no reference counting, ``skyscatter.jit``): compiled inside the kernel, every array passed to an
    inlined function was counted up and down at each vertex (atomic operations, some 15 % of the time of a
    cloudy path). ``cloudy`` is the kernel's (None: a separate compilation without the cloud code), so the tests
    below are compile-time constants here too."""
    clouds_on = cloudy is not None
    field = clouds_on and field
    use_ddis = clouds_on and use_ddis
    peak = clouds_on and peak
    split_on = clouds_on and split_on
    # the clear sky's medium (Rayleigh, aerosol, ozone; two analytic lobes): its vertices in fused loops over the
    # wavelengths (_clear_collision, _clear_nee, _clear_scatter, _clear_ground)
    a0 = 0
    a1 = 0
    clear3 = False
    if not clouds_on and nc == 3 and active.shape[0] == 2:
        a0 = active[0]
        a1 = active[1]
        clear3 = lobe[a0] != LOBE_TABLE and lobe[a1] != LOBE_TABLE
    for j in range(ndir):
        ax, ay, az = dirs[j, 0], dirs[j, 1], dirs[j, 2]
        k0 = sun_ptr[j]  # the entry's suns and output rows k0 .. k0 + ns - 1
        ns = sun_ptr[j + 1] - k0
        sx, sy, sz = suns[k0, 0], suns[k0, 1], suns[k0, 2]
        for q in range(3):
            sun[q] = suns[k0, q]
        cosine = mode[j] == 1
        jx, jy = jitter[j, 0], jitter[j, 1]
        for bi in range(n_batches):
            key = stream_key(seed, dir_index[j], group, batch0 + bi)
            # the heroes stratified (module docstring, "Hero wavelengths"): path smp of the batch takes hero
            # (h0 + smp) mod n, the batch's offset h0 uniform, drawn from a sample number no path uses
            st[0] = sample_state(key, batch_size)
            h0 = min(int(next_uniform(st) * n), n - 1)
            nvert = 0
            for smp in range(batch_size):
                st[0] = sample_state(key, smp)
                for i in range(n):
                    f[i] = 1.0
                    p[i] = 1.0
                    contrib[i] = 0.0
                for s in range(ns):
                    for i in range(n):
                        cr[s, i] = 0.0
                hero = (h0 + smp) % n
                for q in range(nc):
                    kh[q] = coef[hero, q]
                kh0, kh1, kh2 = kh[0], kh[1], kh[2]  # the clear kernel's marches take them as scalars
                ox, oy, oz = origins[j, 0], origins[j, 1], origins[j, 2]
                if jx > 0.0 or jy > 0.0:
                    ox += (next_uniform(st) - 0.5) * jx
                    oy += (next_uniform(st) - 0.5) * jy
                d0x, d0y, d0z = ax, ay, az
                if cosine:
                    u1 = next_uniform(st)
                    d0x, d0y, d0z = direction_about_axis(ax, ay, az, math.sqrt(u1), 2.0 * math.pi * next_uniform(st))
                r_o = math.sqrt(ox * ox + oy * oy + oz * oz)
                if r_o > rt:
                    b = ox * d0x + oy * d0y + oz * d0z
                    disc = b * b - (r_o * r_o - rt * rt)
                    if b >= 0.0 or disc < 0.0:
                        continue  # misses the atmosphere: zero radiance
                    t0 = -b - math.sqrt(disc)
                    ox, oy, oz = ox + t0 * d0x, oy + t0 * d0y, oz + t0 * d0z
                px, py, pz = ox, oy, oz
                dx, dy, dz = d0x, d0y, d0z
                first = True
                vertices = 0
                depth = 0  # the vertices of this copy's light path so far (its order; "Orders")
                ws = 1.0  # the copy's share of the path's weight (splitting; 1 without)
                c_ref = -1  # the class of the path's first medium vertex (splitting)
                nstk = 0
                while True:  # the path, then each copy split off it
                    while True:
                        # a vertex whose order is below the window: its estimates are taken back after it
                        drop = depth + 1 < order_lo
                        if drop:
                            _swap_estimates(contrib, cr, ns, keep, clear3, False)
                        t_end, ground = _exit_distance(px, py, pz, dx, dy, dz, rb, rt)
                        collided = False
                        forced = first and not ground
                        if forced and field:
                            ta, tb = field_box_hit(px, py, pz, dx, dy, dz, t_end, fvf)
                            forced = ta >= tb
                        rho_f = 0.0
                        if forced:
                            if clouds_on:
                                _, _, npc = _march_locate(px, py, pz, dx, dy, dz, t_end, np.inf, kh, rb, edges,
                                                          layers, nlay, tot, tmp, rec)
                            else:
                                _, _, npc = _march3_reach(px, py, pz, dx, dy, dz, t_end, np.inf, kh0, kh1, kh2, rb,
                                                          edges, layers, nlay, tot, tmp, rec)
                            tau_tot = _dot(kh, tot)
                            if tau_tot <= 0.0:
                                break
                            u = next_uniform(st)
                            target = -math.log1p(u * math.expm1(-tau_tot))
                            if clouds_on:
                                t, reached = _forced_from_record(px, py, pz, dx, dy, dz, t_end, target, kh, rb, layers,
                                                                 nlay, rec, npc, cols, tmp)
                            else:
                                t, reached = _forced_from_record3(px, py, pz, dx, dy, dz, t_end, target, kh0, kh1, kh2,
                                                                  rb, layers, nlay, rec, npc, cols, tmp)
                            collided = True
                        else:
                            u = next_uniform(st)
                            target = -math.log1p(-u)
                            if field:
                                t, reached, rho_f = _free_path(px, py, pz, dx, dy, dz, t_end, target, kh, hero, field,
                                                               rb, edges, layers, nlay, cols, tmp, rec, fs, fsmax, fvf,
                                                               fvi, frho, fbmax, fbmin, fxe, fye, fre, f, p, st, fstate)
                            else:
                                # the shells alone, without the call (the clear sky's paths: 9 % of their time);
                                # inside a uniform shell (a cloud layer) by decomposition, without Newton's inversion
                                su = -1
                                if clouds_on:
                                    su = _uniform_shell(px * px + py * py + pz * pz, ushell)
                                if su >= 0:
                                    t, reached = _uniform_free_path(px, py, pz, dx, dy, dz, t_end, target, kh, su,
                                                                    ushell, rb, edges, layers, nlay, cols, tmp, rec,
                                                                    kha, cseg, st)
                                elif clouds_on:
                                    t, reached, _ = _march_locate(px, py, pz, dx, dy, dz, t_end, target, kh, rb,
                                                                  edges, layers, nlay, cols, tmp, rec)
                                    if not reached:
                                        t = t_end
                                else:
                                    t, reached, _ = _march3_locate(px, py, pz, dx, dy, dz, t_end, target, kh0, kh1,
                                                                   kh2, rb, edges, layers, nlay, cols, tmp, rec)
                                    if not reached:
                                        t = t_end
                            if reached:
                                collided = True
                            elif not ground:
                                break  # escaped to space; the sun is reached by NEE only
                        wmax = -1.0  # the largest weight after the vertex, when its loops found it
                        if collided and clear3:
                            px, py, pz = px + t * dx, py + t * dy, pz + t * dz
                            m = _clear_collision(px, py, pz, forced, rb, layers, nlay, coef_t, coef_p, scat_t, a0, a1,
                                                 cols, tot, sc, sst, f, p, trn)
                            if sst[hero] <= 0.0:
                                break  # absorbed for the hero: no continuation can be sampled
                            _clear_nee(px, py, pz, dx, dy, dz, m, sun, cos_sun, rb, rt, edges, layers, nlay, coef_p,
                                       kmin, a0, a1, lobe, lobe_g, esun, sc, f, p, contrib, st, tot, tmp, rec, trn)
                            dx, dy, dz, wmax = _clear_scatter(dx, dy, dz, hero, a0, a1, lobe, lobe_g, sc, sst, f, p, st)
                        elif collided:
                            px, py, pz = _collide(px, py, pz, dx, dy, dz, t, field, rho_f, fvf, fvi, frho, rb, layers,
                                                  nlay, coef_t, scat_t, fs, fss, cols, dens, sc, stt, sst, tau)
                            if forced:
                                _optical_depths(coef_t, tot, tau2)
                            # the transmittances in a loop of their own, which runs in SIMD lanes (the loop below
                            # calls expm1 when forced); tau is free after this vertex's collision
                            _exp_negated(tau, n)
                            for i in range(n):
                                tr = tau[i]
                                pdf = stt[i] * tr
                                if forced:
                                    ttot = -math.expm1(-tau2[i])
                                    pdf = pdf / ttot if ttot > 0.0 else 0.0
                                f[i] *= tr
                                p[i] *= pdf
                            _normalise(f, p, n)
                            if sst[hero] <= 0.0:
                                break  # absorbed for the hero: no continuation can be sampled
                            # next-event estimation to the sun, once per sun of the entry (its own and, for an
                            # almucantar of views traced as one, the sun turned about the vertical for each other
                            # view: module docstring, "Almucantars"); the first sun's transmittance steers splitting
                            tm = 0.0
                            # an almucantar's suns share one roulette depth for their shadow rays and, where it
                            # hides all of them (_suns_hidden), one draw for their peak probes
                            end_sh = -1.0
                            hidden = False
                            u_hidden = 0.0
                            if ns > 1 and clouds_on and rr_depth < _NEE_STOP and not field:
                                end_sh = min(rr_depth - math.log1p(-next_uniform(st)), _NEE_STOP)
                                hidden = _suns_hidden(px, py, pz, suns[k0, 2], cos_sun, end_sh, kmin, ushell)
                                if hidden:
                                    u_hidden = next_uniform(st)
                            for s in range(ns):
                                qx, qy, qz = suns[k0 + s, 0], suns[k0 + s, 1], suns[k0 + s, 2]
                                tsun = 0.0
                                live = False
                                blocked = True
                                te = 0.0
                                wx, wy, wz = qx, qy, qz
                                if not hidden:
                                    wx, wy, wz = _sun_sample(qx, qy, qz, cos_sun, next_uniform(st), next_uniform(st))
                                    te, blocked = _exit_distance(px, py, pz, wx, wy, wz, rb, rt)
                                if blocked:
                                    live = False
                                elif clouds_on:
                                    live = _sun_transmittance(px, py, pz, wx, wy, wz, te, field, rr_depth, end_sh,
                                            kmin, coef_t, rb, edges, layers, nlay, sgeo, stab, ushell, fs, fsmax,
                                            fsmin, fvf, fvi, frho, fbmax, fbmin, fxe, fye, fre, st, fstate, tot, tmp,
                                            rec, tau, trf, trs)
                                else:
                                    _march3_columns(px, py, pz, wx, wy, wz, te, rb, edges, layers, nlay, tot, tmp, rec)
                                    live = not _opaque3(kmin, tot)
                                    if live:
                                        _transmittances(coef_t, tot, tau, trs)
                                if live:
                                    mw = wx * dx + wy * dy + wz * dz
                                    seg, sw = _phase_sums(mw, -1, active, lobe, lobe_g, lobe_tab, tmu, tval, sc, ph,
                                            val, val2, False)
                                    if peak and not first:
                                        _without_peak(mw, seg, sw, peak_lobe, tmu, pval, pa, pk, sc, ph, val)
                                    for i in range(n):
                                        cr[s, i] += ws * f[i] * val[i] * esun[i] * trs[i]
                                    tsun = trs[hero]
                                # the sun through a chain of forward-peak scatterings (module docstring), probed with
                                # probability 1 where the sun is seen, _PEAK_PROBE_MIN where it is not
                                qprobe = 1.0
                                if peak:
                                    qprobe = min(1.0, max(_PEAK_PROBE_MIN, _PEAK_PROBE_GAIN * tsun))
                                if peak and (qprobe >= 1.0 or (u_hidden if hidden else next_uniform(st)) < qprobe):
                                    alive, wx, wy, wz = _peak_probe(px, py, pz, hero, qx, qy, qz, cos_sun, rb, rt,
                                            edges, layers, nlay, sgeo, stab, ushell, kha, cseg, coef_t, scat_t, kh,
                                            kmin, peak_lobe, tmu, pval, pcdf, pa, esun, fvf, fvi, frho, fbmax, fbmin,
                                            fxe, fye, fre, fs, fss, fsmax, fsmin, rr_depth, st, fstate, cols, tot, tmp,
                                            rec, dens, sc3, stt3, sst3, tau, trf, pk, fp, pp, chain, gch)
                                    if alive:
                                        mw = wx * dx + wy * dy + wz * dz
                                        seg, sw = _phase_sums(mw, -1, active, lobe, lobe_g, lobe_tab, tmu, tval, sc, ph,
                                                              val, val2, False)
                                        if not first:
                                            _without_peak(mw, seg, sw, peak_lobe, tmu, pval, pa, pk, sc, ph, val)
                                        for i in range(n):
                                            cr[s, i] += ws * f[i] * val[i] * gch[i] / qprobe
                                if s == 0 and (split_on or use_ddis) and live:
                                    for i in range(n):
                                        tm = max(tm, trs[i])
                            # importance splitting / roulette (cloudy media; module docstring, "splitting"), then
                            # the scattering direction of this copy and of each new one
                            m_split = 1
                            eps = ddis if use_ddis and tm > ddis_gate else 0.0
                            if split_on:
                                cls = 0
                                for k in range(1, split.shape[0]):
                                    if tm > split[k]:
                                        cls += 1
                                if c_ref < 0:
                                    c_ref = cls
                                ratio = ws * split[0] ** (cls - c_ref)
                                if ratio < 0.75:
                                    if next_uniform(st) >= ratio:
                                        if drop:
                                            _swap_estimates(contrib, cr, ns, keep, clear3, True)
                                        break  # this copy ends (roulette: it fell to a less important class)
                                    ws /= ratio
                                elif ratio > 1.5:
                                    m_split = min(int(ratio + 0.5), _SPLIT_STACK - nstk + 1)
                                    ws /= m_split
                                    for i in range(n):
                                        f0[i] = f[i]
                                        p0[i] = p[i]
                            for _ in range(m_split - 1):
                                ex, ey, ez = _scatter(dx, dy, dz, hero, st, use_ddis, eps, ddis_lobe, ddis_active, sx,
                                                      sy, sz, active, lobe, lobe_g, lobe_tab, tmu, tval, tcdf, sc, sst,
                                                      ph, val, val2, ph2, qs2, f, p, dval, dcdf)
                                stk[nstk, 0] = px
                                stk[nstk, 1] = py
                                stk[nstk, 2] = pz
                                stk[nstk, 3] = ex
                                stk[nstk, 4] = ey
                                stk[nstk, 5] = ez
                                stk[nstk, 6] = ws
                                stk[nstk, 7] = depth + 1
                                for i in range(n):
                                    stk_f[nstk, i] = f[i]
                                    stk_p[nstk, i] = p[i]
                                    f[i] = f0[i]
                                    p[i] = p0[i]
                                nstk += 1
                            dx, dy, dz = _scatter(dx, dy, dz, hero, st, use_ddis, eps, ddis_lobe, ddis_active, sx, sy,
                                                  sz, active, lobe, lobe_g, lobe_tab, tmu, tval, tcdf, sc, sst, ph, val,
                                                  val2, ph2, qs2, f, p, dval, dcdf)
                        elif clear3:
                            px, py, pz, dx, dy, dz, wmax = _clear_ground(px, py, pz, dx, dy, dz, t_end, sun, cos_sun,
                                                                         rb, rt, edges, layers, nlay, coef_p, kmin,
                                                                         albedo, esun, cols, tot, tmp, rec, f, p,
                                                                         contrib, st, trn)
                        else:
                            # ground (Lambertian)
                            px += t_end * dx
                            py += t_end * dy
                            pz += t_end * dz
                            rr = math.sqrt(px * px + py * py + pz * pz)
                            nx, ny, nz = px / rr, py / rr, pz / rr
                            px, py, pz = nx * rb, ny * rb, nz * rb
                            _optical_depths(coef_t, cols, tau)
                            for i in range(n):
                                tr = exp_lane(-tau[i])
                                f[i] *= tr
                                p[i] *= tr
                            _normalise(f, p, n)
                            for s in range(ns):  # each sun of the entry, as at a medium vertex
                                qx, qy, qz = suns[k0 + s, 0], suns[k0 + s, 1], suns[k0 + s, 2]
                                wx, wy, wz = _sun_sample(qx, qy, qz, cos_sun, next_uniform(st), next_uniform(st))
                                cs = wx * nx + wy * ny + wz * nz
                                if cs > 0.0:
                                    te, blocked = _exit_distance(px, py, pz, wx, wy, wz, rb, rt)
                                    if clouds_on:
                                        live = _sun_transmittance(px, py, pz, wx, wy, wz, te, field, rr_depth, -1.0,
                                                kmin, coef_t, rb, edges, layers, nlay, sgeo, stab, ushell, fs, fsmax,
                                                fsmin, fvf, fvi, frho, fbmax, fbmin, fxe, fye, fre, st, fstate, tot,
                                                tmp, rec, tau, trf, trs)
                                    else:
                                        live = _shells_transmittance(px, py, pz, wx, wy, wz, te, kmin, coef_t, rb,
                                                edges, layers, nlay, tot, tmp, rec, tau, trs)
                                    if live:
                                        for i in range(n):
                                            cr[s, i] += ws * f[i] * albedo[i] / math.pi * cs * esun[i] * trs[i]
                                if peak:
                                    alive, wx, wy, wz = _peak_probe(px, py, pz, hero, qx, qy, qz, cos_sun, rb, rt,
                                            edges, layers, nlay, sgeo, stab, ushell, kha, cseg, coef_t, scat_t, kh,
                                            kmin, peak_lobe, tmu, pval, pcdf, pa, esun, fvf, fvi, frho, fbmax, fbmin,
                                            fxe, fye, fre, fs, fss, fsmax, fsmin, rr_depth, st, fstate, cols, tot, tmp,
                                            rec, dens, sc3, stt3, sst3, tau, trf, pk, fp, pp, chain, gch)
                                    cs = wx * nx + wy * ny + wz * nz
                                    if alive and cs > 0.0:
                                        for i in range(n):
                                            cr[s, i] += ws * f[i] * albedo[i] / math.pi * cs * gch[i]
                            # cosine-weighted hemisphere: weight albedo
                            u1 = next_uniform(st)
                            mu = math.sqrt(u1)
                            dx, dy, dz = direction_about_axis(nx, ny, nz, mu, 2.0 * math.pi * next_uniform(st))
                            for i in range(n):
                                f[i] *= albedo[i]
                        first = False
                        vertices += 1
                        depth += 1
                        if drop:
                            _swap_estimates(contrib, cr, ns, keep, clear3, True)
                        if vertices >= _MAX_VERTICES or depth >= order_hi:
                            break
                        if wmax >= 0.0:
                            if not _roulette_max(f, n, vertices, st, wmax):
                                break
                        elif not _roulette(f, n, vertices, st):
                            break
                    if nstk == 0:
                        break
                    # the next copy split off this path: from its vertex along its own direction
                    nstk -= 1
                    px, py, pz = stk[nstk, 0], stk[nstk, 1], stk[nstk, 2]
                    dx, dy, dz = stk[nstk, 3], stk[nstk, 4], stk[nstk, 5]
                    ws = stk[nstk, 6]
                    depth = int(stk[nstk, 7])
                    for i in range(n):
                        f[i] = stk_f[nstk, i]
                        p[i] = stk_p[nstk, i]
                    first = False
                nvert += vertices
                scale = math.pi if cosine else 1.0
                if clear3:
                    for i in range(n):
                        c = contrib[i] * scale
                        sums[k0, bi, hero, i] += c
                        sumsq[k0, bi, hero, i] += c * c
                else:
                    for s in range(ns):
                        for i in range(n):
                            c = cr[s, i] * scale
                            sums[k0 + s, bi, hero, i] += c
                            sumsq[k0 + s, bi, hero, i] += c * c
                for s in range(ns):
                    counts[k0 + s, bi, hero] += 1.0
            for s in range(ns):
                vertices_out[k0 + s, bi] += nvert


@kernel
def disc_transmittance(origin, sun, sun_radius, rb, rt, edges, layers, nlay, coef, fvf, fvi, frho, fbmax, fbmin, fxe,
                       fye, fre, fs, n_radial, n_angular, out):
    """Mean transmittance over the solar disc seen from ``origin`` (3,) for each wavelength (``out`` (n_wl,)).

    Deterministic midpoint quadrature over the disc, uniform in solid angle (``n_radial`` rings equal in
    ``1 - cos``, ``n_angular`` sectors); directions whose ray hits the planet count as 0. Through a cloud field
    packed with ``exact=True`` the field's transmittance is exact (regular tracking, no random numbers).
    """
    n = coef.shape[0]
    nc = coef.shape[1]
    cols = np.empty(nc)
    tmp = np.empty(nc)
    kz = np.zeros(nc)
    trf = np.empty(n)
    st = np.zeros(1, dtype=np.uint64)
    fstate = np.zeros(6, dtype=np.int64)
    field = fvf[8] != 0.0
    fsmax = 0.0
    fsmin = np.inf
    for i in range(n):
        fsmax = max(fsmax, fs[i])
        fsmin = min(fsmin, fs[i])
    for i in range(n):
        out[i] = 0.0
    cmax = math.cos(sun_radius)
    r_o = math.sqrt(origin[0] ** 2 + origin[1] ** 2 + origin[2] ** 2)
    for a in range(n_radial):
        for k in range(n_angular):
            wx, wy, wz = _sun_sample(sun[0], sun[1], sun[2], cmax, (a + 0.5) / n_radial, (k + 0.5) / n_angular)
            px, py, pz = origin[0], origin[1], origin[2]
            if r_o > rt:
                b = px * wx + py * wy + pz * wz
                disc = b * b - (r_o * r_o - rt * rt)
                if b >= 0.0 or disc < 0.0:
                    for i in range(n):
                        out[i] += 1.0
                    continue
                t0 = -b - math.sqrt(disc)
                px, py, pz = px + t0 * wx, py + t0 * wy, pz + t0 * wz
            te, blocked = _exit_distance(px, py, pz, wx, wy, wz, rb, rt)
            if blocked:
                continue
            column_along(px, py, pz, wx, wy, wz, te, np.inf, kz, rb, edges, layers, nlay, cols, tmp)
            if field:
                field_transmittance(px, py, pz, wx, wy, wz, te, fs, fsmax, fsmin, fvf, fvi, frho, fbmax, fbmin, fxe,
                                    fye, fre, trf, st, fstate)
            for i in range(n):
                v = exp_lane(-_dot_row(coef, i, cols))
                out[i] += v * trf[i] if field else v
    for i in range(n):
        out[i] /= n_radial * n_angular


@helper
def _next_level(px, py, pz, dx, dy, dz, levels, t_end):
    """First crossing after 0 of one of the level spheres (radii ``levels`` [m]) within ``[0, t_end]``: ``(t, k,
    up)`` with ``k`` the level and ``up`` whether it is crossed outwards; ``(t_end, -1, False)`` when there is none.
    Roots closer than ``1e-4 m + 1e-12 R`` to 0 belong to the sphere the point sits on and are skipped."""
    r2 = px * px + py * py + pz * pz
    b = px * dx + py * dy + pz * dz
    best = t_end
    k = -1
    up = False
    for j in range(levels.shape[0]):
        radius = levels[j]
        disc = b * b - (r2 - radius * radius)
        if disc < 0.0:
            continue
        s = math.sqrt(disc)
        eps = 1e-4 + 1e-12 * radius
        t = -b - s
        if t > eps:
            if t <= best:
                best = t
                k = j
                up = False
            continue
        t = -b + s
        if t > eps and t <= best:
            best = t
            k = j
            up = True
    return best, k, up


@helper
def _pixel(px, py, dom):
    """Index of the domain pixel (periodic) under the planet-frame point (px, py); ``dom`` = x0, y0, dx, dy, nx,
    ny."""
    nx = int(dom[4])
    ny = int(dom[5])
    ix = int(math.floor((px - dom[0]) / dom[2])) % nx
    iy = int(math.floor((py - dom[1]) / dom[3])) % ny
    return ix * ny + iy


@kernel
def flux_block(sun, rb, rt, edges, layers, nlay, coef, scat, lobe, lobe_g, lobe_tab, tmu, tval, tcdf, albedo,
               fvf, fvi, frho, fbmax, fbmin, fxe, fye, fre, fs, fss, dom, levels, seed, group, batch0, n_batches,
               batch_size, up, down, absorbed, vertices_out):
    """Forward photons from the sun through a periodic domain: per pixel and level, the upward and downward
    crossings of the level spheres, and the absorption in the column between the lowest and the highest level
    (:mod:`.domain`).

    Photons travel along ``-sun`` on the sun rays that cross the lowest level sphere (``levels[0]``: the field's
    base, or a lower level asked for) uniformly over the domain's cell ``dom`` (x0, y0, dx, dy, nx, ny: pixel corner
    [m], pixel size [m], pixel counts), entering at the top of the atmosphere where those rays do. Why: a sun ray
    entering the top above the domain reaches the base far down-sun (Earth defaults, sun 10 deg high: 418 km), where
    the sun stands lower by that distance over the radius (there 6.2 deg) behind a longer slant path: the base would
    see another sun. Aimed at the base, the beam there has the domain's geometry exactly; a level at height ``h``
    above the base is crossed about ``h / tan(elevation)`` towards the sun, where the sun stands higher by that
    distance over the radius. In the plane-parallel limit both launches are the same uniform beam. The same free
    paths, collision densities, lobes and hero-wavelength weights as :func:`trace_block` (without next-event
    estimation). A free path stops at each level sphere (``levels`` (L,) radii [m], ascending), where the crossing
    adds the photon's weight to ``up`` or ``down`` at that level and the pixel under the crossing, and starts afresh
    (free paths are memoryless); each collision adds ``f sigma_a`` to ``absorbed`` at the pixel under it. Outputs
    ``up``, ``down`` (L, n_pixels, n_wl, 2) and ``absorbed`` (n_pixels, n_wl, 2): per batch the tallies are summed,
    then their sum and sum of squares over batches are added to ``[..., 0]`` and ``[..., 1]``. ``vertices_out`` (1,)
    counts the vertices.
    """
    n = coef.shape[0]
    nc = coef.shape[1]
    npix = absorbed.shape[0]
    nlev = levels.shape[0]
    r_base = levels[0]
    r_top = levels[nlev - 1]
    st = np.empty(1, dtype=np.uint64)
    f = np.empty(n)
    p = np.empty(n)
    cols = np.empty(nc)
    tmp = np.empty(nc)
    dens = np.empty(nc)
    kh = np.empty(nc)
    coef_t = np.ascontiguousarray(coef.T)
    scat_t = np.ascontiguousarray(scat.T)
    sc = np.empty((nc + 1, n))
    ph = np.empty((nc + 1, n))
    stt = np.empty(n)
    sst = np.empty(n)
    tau = np.empty(n)
    val = np.empty(n)
    val2 = np.empty(n)
    bu = np.empty((nlev, npix, n))
    bd = np.empty((nlev, npix, n))
    ba = np.empty((npix, n))
    fstate = np.zeros(6, dtype=np.int64)
    rec = np.empty((2 * edges.shape[0] + 2, 2 + nc))
    field = fvf[8] != 0.0
    fsmax = 0.0
    for i in range(n):
        fsmax = max(fsmax, fs[i])
    n_active = 0
    for c in range(nc + 1):
        if lobe[c] != LOBE_NONE:
            n_active += 1
    active = np.empty(n_active, dtype=np.int64)
    n_active = 0
    for c in range(nc + 1):
        if lobe[c] != LOBE_NONE:
            active[n_active] = c
            n_active += 1
    lx = dom[2] * dom[4]
    ly = dom[3] * dom[5]
    vertices_out[0] += _flux_paths(sun, rb, rt, edges, layers, nlay, coef, lobe, lobe_g, lobe_tab, tmu, tval, tcdf,
                                   albedo, fvf, fvi, frho, fbmax, fbmin, fxe, fye, fre, fs, fss, dom, levels, seed,
                                   group, batch0, n_batches, batch_size, up, down, absorbed, n, nc, npix, nlev, r_base,
                                   r_top, st, f, p, cols, tmp, dens, kh, coef_t, scat_t, sc, ph, stt, sst, tau, val,
                                   val2, bu, bd, ba, fstate, rec, field, fsmax, active, lx, ly)


@inline
def _photon_collision_weights(f, p, stt, tau, n):
    """A forward photon's weights at a collision: the free path's transmittance ``exp(-tau)`` per wavelength (``f``),
    the hero's path density times the extinction there (``p``; the spectral MIS of :func:`_normalise`)."""
    for i in range(n):
        tr = exp_lane(-tau[i])
        f[i] *= tr
        p[i] *= stt[i] * tr
    _normalise(f, p, n)


@inline
def _photon_pass_weights(f, p, tau, n):
    """A forward photon's weights along a free path that reached a boundary without a collision: ``exp(-tau)``."""
    for i in range(n):
        tr = exp_lane(-tau[i])
        f[i] *= tr
        p[i] *= tr
    _normalise(f, p, n)


@inline
def _photon_scatter(dx, dy, dz, hero, st, active, lobe, lobe_g, lobe_tab, tmu, tval, tcdf, sc, ph, val, val2, sst, f,
                    p, n):
    """A forward photon's scattering (``sst[hero] > 0``): the component by its share of the hero's scattering
    coefficient, its phase function sampled exactly (tables by their segment), the new direction and the weights'
    phase ratios (the spectral MIS); returns the direction. The photons of :func:`_flux_paths` and
    :func:`_sphere_paths` share it."""
    n_active = active.shape[0]
    u = next_uniform(st) * sst[hero]
    pick = active[n_active - 1]
    acc = 0.0
    for a in range(n_active):
        c = active[a]
        acc += sc[c, hero]
        if u < acc:
            pick = c
            break
    mu, seg = _sample_lobe_segment(lobe[pick], lobe_g[pick], lobe_tab[pick], hero, next_uniform(st), tmu, tval, tcdf)
    dx, dy, dz = direction_about_axis(dx, dy, dz, mu, 2.0 * math.pi * next_uniform(st))
    _phase_sums(mu, seg, active, lobe, lobe_g, lobe_tab, tmu, tval, sc, ph, val, val2, True)
    for i in range(n):
        f[i] *= val[i]
        p[i] *= val2[i] / sst[i] if sst[i] > 0.0 else 0.0
    _normalise(f, p, n)
    return dx, dy, dz


@helper
def _flux_paths(sun, rb, rt, edges, layers, nlay, coef, lobe, lobe_g, lobe_tab, tmu, tval, tcdf, albedo, fvf, fvi,
                frho, fbmax, fbmin, fxe, fye, fre, fs, fss, dom, levels, seed, group, batch0, n_batches, batch_size, up,
                down, absorbed, n, nc, npix, nlev, r_base, r_top, st, f, p, cols, tmp, dens, kh, coef_t, scat_t, sc, ph,
                stt, sst, tau, val, val2, bu, bd, ba, fstate, rec, field, fsmax, active, lx, ly):
    """The photons of :func:`flux_block` (its loop over batches and photons), with the buffers it allocated; returns
    the number of vertices. A helper (no reference counting, ``skyscatter.jit``), as :func:`_trace_paths`: compiled
    inside the kernel, every array passed to the inlined :func:`_collide` was counted up and down at each collision
    (atomic operations)."""
    nvert = 0
    for bi in range(n_batches):
        key = stream_key(seed, 0, group, batch0 + bi)
        for k in range(npix):
            for i in range(n):
                ba[k, i] = 0.0
                for j in range(nlev):
                    bu[j, k, i] = 0.0
                    bd[j, k, i] = 0.0
        for smp in range(batch_size):
            st[0] = sample_state(key, smp)
            for i in range(n):
                f[i] = 1.0
                p[i] = 1.0
            hero = min(int(next_uniform(st) * n), n - 1)
            for q in range(nc):
                kh[q] = coef[hero, q]
            # aimed at the domain: a point uniform over the cell on the lowest level sphere, and the sun ray through
            # it from the top of the atmosphere (docstring: in a sphere a ray entering the top above the domain
            # would reach the base where the sun is lower)
            x = dom[0] + next_uniform(st) * lx
            y = dom[1] + next_uniform(st) * ly
            bz = math.sqrt(r_base * r_base - x * x - y * y)
            t_up, _ = _exit_distance(x, y, bz, sun[0], sun[1], sun[2], rb, rt)
            px, py, pz = x + t_up * sun[0], y + t_up * sun[1], bz + t_up * sun[2]
            rr = rt / math.sqrt(px * px + py * py + pz * pz)  # exactly on the top sphere (rounding)
            px, py, pz = px * rr, py * rr, pz * rr
            dx, dy, dz = -sun[0], -sun[1], -sun[2]
            vertices = 0
            while True:
                t_end, ground = _exit_distance(px, py, pz, dx, dy, dz, rb, rt)
                t_if, lev, outward = _next_level(px, py, pz, dx, dy, dz, levels, t_end)
                u = next_uniform(st)
                t, reached, rho_f = _free_path(px, py, pz, dx, dy, dz, t_if, -math.log1p(-u), kh, hero, field, rb,
                                               edges, layers, nlay, cols, tmp, rec, fs, fsmax, fvf, fvi, frho, fbmax,
                                               fbmin, fxe, fye, fre, f, p, st, fstate)
                if reached:
                    px, py, pz = _collide(px, py, pz, dx, dy, dz, t, field, rho_f, fvf, fvi, frho, rb, layers, nlay,
                                          coef_t, scat_t, fs, fss, cols, dens, sc, stt, sst, tau)
                    _photon_collision_weights(f, p, stt, tau, n)
                    rr = math.sqrt(px * px + py * py + pz * pz)
                    if r_base <= rr <= r_top:
                        k = _pixel(px, py, dom)
                        for i in range(n):
                            ba[k, i] += f[i] * (stt[i] - sst[i])
                    if sst[hero] <= 0.0:
                        break
                    dx, dy, dz = _photon_scatter(dx, dy, dz, hero, st, active, lobe, lobe_g, lobe_tab, tmu, tval, tcdf,
                                                 sc, ph, val, val2, sst, f, p, n)
                else:
                    px += t * dx
                    py += t * dy
                    pz += t * dz
                    _optical_depths(coef_t, cols, tau)
                    _photon_pass_weights(f, p, tau, n)
                    if lev >= 0:
                        k = _pixel(px, py, dom)
                        if outward:
                            for i in range(n):
                                bu[lev, k, i] += f[i]
                        else:
                            for i in range(n):
                                bd[lev, k, i] += f[i]
                    if lev < 0 or t_if >= t_end:
                        if not ground:
                            break  # out of the top of the atmosphere
                        rr = math.sqrt(px * px + py * py + pz * pz)
                        nx, ny, nz = px / rr, py / rr, pz / rr
                        px, py, pz = nx * rb, ny * rb, nz * rb
                        u1 = next_uniform(st)
                        dx, dy, dz = direction_about_axis(nx, ny, nz, math.sqrt(u1), 2.0 * math.pi * next_uniform(st))
                        for i in range(n):
                            f[i] *= albedo[i]
                    else:
                        continue  # through the interface: same direction, no vertex
                vertices += 1
                if vertices >= _MAX_VERTICES:
                    break
                if not _roulette(f, n, vertices, st):
                    break
            nvert += vertices
        for k in range(npix):
            for i in range(n):
                for j in range(nlev):
                    v = bu[j, k, i]
                    up[j, k, i, 0] += v
                    up[j, k, i, 1] += v * v
                    v = bd[j, k, i]
                    down[j, k, i, 0] += v
                    down[j, k, i, 1] += v * v
                v = ba[k, i]
                absorbed[k, i, 0] += v
                absorbed[k, i, 1] += v * v
    return nvert


@helper
def _bin_of(x, edges):
    """Index ``k`` with ``edges[k] <= x < edges[k + 1]`` (``edges`` ascending; bisection), -1 outside."""
    nb = edges.shape[0] - 1
    if not (edges[0] <= x < edges[nb]):
        return -1
    lo = 0
    hi = nb
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if x >= edges[mid]:
            lo = mid
        else:
            hi = mid
    return lo


@kernel
def sphere_block(rb, rt, edges, layers, nlay, coef, scat, lobe, lobe_g, lobe_tab, tmu, tval, tcdf, albedo,
                 fvf, fvi, frho, fbmax, fbmin, fxe, fye, fre, fs, fss, launch, sedges, muedges, seed, group, batch0,
                 n_batches, batch_size, direct, diffuse, rad, totals, vertices_out):
    """Forward photons from a parallel sun through the whole spherical atmosphere, tallied at the ground by the local
    sun elevation (:mod:`.sphere`).

    The sun stands on the planet frame's +z axis; photons travel along -z from the top sphere ``rt`` [m] with impact
    parameters ``b`` (distance from the axis [m]) uniform in area over ``launch[0] <= b <= launch[1]`` and a uniform
    azimuth, and are tracked with the same free paths, collision densities, lobes and hero-wavelength weights as
    :func:`flux_block`. A horizontally uniform medium is axially symmetric about that axis, so a ground point's
    irradiance depends only on its local sun elevation ``e``, ``sin e = z / r``. Each arrival at the ground adds the
    photon's weight to the ring of ``sin e`` (``sedges`` (nr + 1,) ascending): to ``direct`` when it was never
    scattered nor reflected, else to ``diffuse`` and, with ``1 / mu_v`` (``mu_v`` the cosine of the arrival direction
    to the local vertical), to ``rad`` at the bin of ``mu_v`` (``muedges`` (nm + 1,) ascending) and of the azimuth
    from the local sun's vertical plane folded into ``[0, pi]`` (``rad.shape[2]`` equal bins). ``totals`` (3, n,
    2): weight arriving at the ground anywhere, escaping through the top, absorbed in the medium (energy check).
    Outputs (nr, n, 2), (nr, nm, na, n, 2) and (3, n, 2): per batch the tallies are summed, then their sum and sum
    of squares over batches are added to ``[..., 0]`` and ``[..., 1]`` (the track of a photon is the collision
    estimator's random walk, [SpanierGelbard1969] Ch. 3; arrivals are counted like the boundary-crossing tallies of
    :func:`flux_block`). ``vertices_out`` (1,) counts the vertices.
    """
    n = coef.shape[0]
    nc = coef.shape[1]
    nr = direct.shape[0]
    nm = rad.shape[1]
    na = rad.shape[2]
    st = np.empty(1, dtype=np.uint64)
    f = np.empty(n)
    p = np.empty(n)
    cols = np.empty(nc)
    tmp = np.empty(nc)
    dens = np.empty(nc)
    kh = np.empty(nc)
    coef_t = np.ascontiguousarray(coef.T)
    scat_t = np.ascontiguousarray(scat.T)
    sc = np.empty((nc + 1, n))
    ph = np.empty((nc + 1, n))
    stt = np.empty(n)
    sst = np.empty(n)
    tau = np.empty(n)
    val = np.empty(n)
    val2 = np.empty(n)
    bdir = np.empty((nr, n))
    bdif = np.empty((nr, n))
    brad = np.empty((nr, nm, na, n))
    btot = np.empty((3, n))
    fstate = np.zeros(6, dtype=np.int64)
    rec = np.empty((2 * edges.shape[0] + 2, 2 + nc))
    field = fvf[8] != 0.0
    fsmax = 0.0
    for i in range(n):
        fsmax = max(fsmax, fs[i])
    n_active = 0
    for c in range(nc + 1):
        if lobe[c] != LOBE_NONE:
            n_active += 1
    active = np.empty(n_active, dtype=np.int64)
    n_active = 0
    for c in range(nc + 1):
        if lobe[c] != LOBE_NONE:
            active[n_active] = c
            n_active += 1
    vertices_out[0] += _sphere_paths(rb, rt, edges, layers, nlay, coef, lobe, lobe_g, lobe_tab, tmu, tval, tcdf,
                                     albedo, fvf, fvi, frho, fbmax, fbmin, fxe, fye, fre, fs, fss, launch, sedges,
                                     muedges, seed, group, batch0, n_batches, batch_size, direct, diffuse, rad, totals,
                                     n, nc, nr, nm, na, st, f, p, cols, tmp, dens, kh, coef_t, scat_t, sc, ph, stt, sst,
                                     tau, val, val2, bdir, bdif, brad, btot, fstate, rec, field, fsmax, active)


@helper
def _sphere_paths(rb, rt, edges, layers, nlay, coef, lobe, lobe_g, lobe_tab, tmu, tval, tcdf, albedo, fvf, fvi, frho,
                  fbmax, fbmin, fxe, fye, fre, fs, fss, launch, sedges, muedges, seed, group, batch0, n_batches,
                  batch_size, direct, diffuse, rad, totals, n, nc, nr, nm, na, st, f, p, cols, tmp, dens, kh, coef_t,
                  scat_t, sc, ph, stt, sst, tau, val, val2, bdir, bdif, brad, btot, fstate, rec, field, fsmax, active):
    """The photons of :func:`sphere_block` (its loop over batches and photons) with its buffers; returns the number of
    vertices. A helper, as :func:`_flux_paths` (no reference counting in the loop)."""
    nvert = 0
    b2lo = launch[0] * launch[0]
    b2span = launch[1] * launch[1] - b2lo
    for bi in range(n_batches):
        key = stream_key(seed, 0, group, batch0 + bi)
        for i in range(n):
            for k in range(nr):
                bdir[k, i] = 0.0
                bdif[k, i] = 0.0
                for j in range(nm):
                    for a in range(na):
                        brad[k, j, a, i] = 0.0
            for k in range(3):
                btot[k, i] = 0.0
        for smp in range(batch_size):
            st[0] = sample_state(key, smp)
            for i in range(n):
                f[i] = 1.0
                p[i] = 1.0
            hero = min(int(next_uniform(st) * n), n - 1)
            for q in range(nc):
                kh[q] = coef[hero, q]
            # uniform over the annulus' area: b^2 uniform; on the top sphere, heading down the axis
            bb = math.sqrt(b2lo + next_uniform(st) * b2span)
            phi = 2.0 * math.pi * next_uniform(st)
            px, py = bb * math.cos(phi), bb * math.sin(phi)
            pz = math.sqrt(max(rt * rt - bb * bb, 0.0))
            dx, dy, dz = 0.0, 0.0, -1.0
            scattered = False
            vertices = 0
            while True:
                t_end, ground = _exit_distance(px, py, pz, dx, dy, dz, rb, rt)
                u = next_uniform(st)
                t, reached, rho_f = _free_path(px, py, pz, dx, dy, dz, t_end, -math.log1p(-u), kh, hero, field, rb,
                                               edges, layers, nlay, cols, tmp, rec, fs, fsmax, fvf, fvi, frho, fbmax,
                                               fbmin, fxe, fye, fre, f, p, st, fstate)
                if reached:
                    px, py, pz = _collide(px, py, pz, dx, dy, dz, t, field, rho_f, fvf, fvi, frho, rb, layers, nlay,
                                          coef_t, scat_t, fs, fss, cols, dens, sc, stt, sst, tau)
                    _photon_collision_weights(f, p, stt, tau, n)
                    for i in range(n):
                        btot[2, i] += f[i] * (stt[i] - sst[i])
                    if sst[hero] <= 0.0:
                        break
                    dx, dy, dz = _photon_scatter(dx, dy, dz, hero, st, active, lobe, lobe_g, lobe_tab, tmu, tval, tcdf,
                                                 sc, ph, val, val2, sst, f, p, n)
                    scattered = True
                else:
                    px += t * dx
                    py += t * dy
                    pz += t * dz
                    _optical_depths(coef_t, cols, tau)
                    _photon_pass_weights(f, p, tau, n)
                    if not ground:
                        for i in range(n):
                            btot[1, i] += f[i]
                        break  # out of the top of the atmosphere
                    rr = math.sqrt(px * px + py * py + pz * pz)
                    nx, ny, nz = px / rr, py / rr, pz / rr
                    for i in range(n):
                        btot[0, i] += f[i]
                    k = _bin_of(nz, sedges)  # sin of the local sun elevation (the sun on +z)
                    if k >= 0:
                        if not scattered:
                            for i in range(n):
                                bdir[k, i] += f[i]
                        else:
                            for i in range(n):
                                bdif[k, i] += f[i]
                            mu_v = -(dx * nx + dy * ny + dz * nz)
                            j = _bin_of(mu_v, muedges)
                            if j >= 0 and mu_v > 0.0:
                                # azimuth of the arrival (towards where the light comes from, -d) from the local
                                # sun's vertical plane: both projected on the tangent plane
                                vx, vy, vz = -dx - mu_v * nx, -dy - mu_v * ny, -dz - mu_v * nz
                                sx, sy, sz = -nz * nx, -nz * ny, 1.0 - nz * nz
                                nv = math.sqrt(vx * vx + vy * vy + vz * vz)
                                ns = math.sqrt(sx * sx + sy * sy + sz * sz)
                                ca = 1.0
                                if nv > 0.0 and ns > 0.0:
                                    ca = (vx * sx + vy * sy + vz * sz) / (nv * ns)
                                ca = min(1.0, max(-1.0, ca))
                                a = min(int(math.acos(ca) / math.pi * na), na - 1)
                                for i in range(n):
                                    brad[k, j, a, i] += f[i] / mu_v
                    px, py, pz = nx * rb, ny * rb, nz * rb
                    u1 = next_uniform(st)
                    dx, dy, dz = direction_about_axis(nx, ny, nz, math.sqrt(u1), 2.0 * math.pi * next_uniform(st))
                    for i in range(n):
                        f[i] *= albedo[i]
                    scattered = True
                vertices += 1
                if vertices >= _MAX_VERTICES:
                    break
                if not _roulette(f, n, vertices, st):
                    break
            nvert += vertices
        for i in range(n):
            for k in range(nr):
                v = bdir[k, i]
                direct[k, i, 0] += v
                direct[k, i, 1] += v * v
                v = bdif[k, i]
                diffuse[k, i, 0] += v
                diffuse[k, i, 1] += v * v
                for j in range(nm):
                    for a in range(na):
                        v = brad[k, j, a, i]
                        rad[k, j, a, i, 0] += v
                        rad[k, j, a, i, 1] += v * v
            for k in range(3):
                v = btot[k, i]
                totals[k, i, 0] += v
                totals[k, i, 1] += v * v
    return nvert
