"""Extinction and in-scattering integrals of Preetham, Shirley & Smits (1999), Sec. 4 and Appendix A.4.

Flat earth, two kinds of particles (1 = haze, 2 = molecules) with exponential density: the scattering
coefficient at height h is ``beta_i(h) = beta_i^0 exp(-alpha_i h)`` (Eq. 5) with the decay constants of A.4,
``alpha_haze = 0.8333 km^-1`` and ``alpha_molecules = 0.1136 km^-1``. A ray leaves an observer at height h0
[m] with view zenith angle theta (``c = cos theta``, negative looking down) and is followed for a distance s
[m]; ``u_i(x) = exp(-alpha_i (h0 + x c))`` and ``H_i = u_i(0)``.

Domain: observers within +-100 km of sea level (``MAX_OBSERVER_HEIGHT``; InvalidParameterError beyond); a path
is followed only between 200 km below and 500 km above sea level (``PATH_BOTTOM``, ``PATH_TOP``), where the
model's densities are respectively opaque and negligible, so every exponential stays finite.

* Extinction (Eq. 7): ``tau = exp(-K_1 (H_1 - u_1(s))) exp(-K_2 (H_2 - u_2(s)))`` with
  ``K_i = beta_i^0 / (alpha_i c)``. (The paper prints ``K = -beta^0 / (alpha cos theta)`` together with
  ``e^{-K(H - u)}``, which would make tau > 1; the sign here is the one that integrates Eq. 5.) It is
  evaluated as ``exp(-sum_i beta_i^0 L_i)`` with the *effective path length*
  ``L_i = H_i s E(alpha_i c s)`` [m], ``E(a) = (1 - e^-a) / a`` (``E(0) = 1``), which is the same quantity
  without the 0/0 of horizontal rays.
* In-scattering (Eq. 8): ``L_in = S_1^0 I_1 + S_2^0 I_2`` with ``I_i = int_0^s u_i(x) tau(0..x) dx`` [m]
  (Eq. 9). Three ways to compute I:

  (a) ``near_horizon`` -- Eq. 10, for ``|alpha s cos theta| << 1``:
      ``I_1 = H_1 (1 - exp(-(alpha_1 c + beta_1 H_1 + beta_2 H_2) s)) / (alpha_1 c + beta_1 H_1 + beta_2 H_2)``.
      (The extracted text shows ``e^{-H_1}`` as the prefactor; it is ``H_1 = u_1(0)``, as the line above it
      in the derivation, ``u_1(x) = H_1 e^{-alpha_1 x cos theta}``, requires.)
  (b) ``hermite`` -- Eq. 11 / A.4: substitute ``v = u_1(x)``, replace the other species' transmittance
      ``f(x) = exp(-K_2 (H_2 - u_2(x)))`` by the cubic ``g(v)`` that matches f and df/dv at both ends, and
      integrate ``e^{-K_1 (H_1 - v)} g(v)`` in closed form (integration by parts, the A.4 series
      ``g/K - g'/K^2 + g''/K^3 - g'''/K^4``). I_2 is the same with the species swapped. The cubic is written
      in the normalised variable ``w = (v - H_1) / (u_1(s) - H_1)`` in [0, 1], which is the same polynomial
      but avoids the ill-conditioned 4 x 4 system of A.4 for short paths; then ``K_1 (v - H_1) = z w`` with
      ``z = -beta_1 L_1`` (minus the haze optical depth of the path) and
      ``I_1 = L_1 int_0^1 e^{z w} p(w) dw``. The moments ``int_0^1 e^{z w} w^n dw`` are the A.4 series
      (recurrence ``m_n = (e^z - n m_{n-1}) / z``) for ``|z| >= 0.02`` and their Taylor series below, where
      the recurrence loses digits to cancellation.
  (c) ``quadrature`` -- the reference: composite 6-point Gauss-Legendre on segments of at most 0.5
      e-folds of the integrand, stopping once the path's optical depth passes 50.

:func:`in_scattering_integrals` with ``method="analytic"`` uses (a) when ``|alpha_haze s c| <`` the
``horizon_threshold`` (default 1e-3) and (b) otherwise, as the paper prescribes.

Reference: [Preetham1999].
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ..jit import helper, inline, parallel_kernel
from ..validation import whole_number

__all__ = [
    "ALPHA_HAZE",
    "ALPHA_MOLECULES",
    "HORIZON_THRESHOLD",
    "MAX_OBSERVER_HEIGHT",
    "effective_length",
    "extinction",
    "in_scattering_integrals",
]

#: Exponential decay constant of haze density [m^-1] (Preetham 1999, A.4: 0.8333 km^-1).
ALPHA_HAZE = 0.8333e-3
#: Exponential decay constant of molecular density [m^-1] (Preetham 1999, A.4: 0.1136 km^-1).
ALPHA_MOLECULES = 0.1136e-3
#: ``|alpha_haze s cos theta|`` below which the analytic method uses the near-horizon form (Eq. 10).
HORIZON_THRESHOLD = 1e-3
#: Largest optical depth of either species over one piece of the composite analytic form.
SEGMENT_DEPTH = 1.0
#: Largest ``alpha_haze |cos theta| dx`` (haze density change in e-folds) over one piece.
SEGMENT_DECAY = 1.0
#: Largest |observer height| [m] accepted: the flat, exponential atmosphere of Eq. 5 describes the lower
#: atmosphere; far above it the model has no meaning (and its density ratios leave floating point range).
MAX_OBSERVER_HEIGHT = 100_000.0
#: Paths are followed between these heights [m] only. Above PATH_TOP the molecular density is below 3e-25 of
#: sea level (nothing left to scatter or absorb); below PATH_BOTTOM the model's density is > 1e72 times sea
#: level, so any path reaching it is opaque long before. The clip keeps every exponential finite.
PATH_TOP = 500_000.0
PATH_BOTTOM = -200_000.0
#: Optical depth beyond which the rest of a level or descending path is dropped (transmittance < 1e-26).
OPAQUE_DEPTH = 60.0
#: Upper bound on the number of pieces (paths are first cut where they become opaque, see OPAQUE_DEPTH, so
#: it is reached only by paths hundreds of km long; pieces past an optical depth of 50 are skipped).
MAX_SEGMENTS = 2000

_METHODS = {"near_horizon": 0, "hermite": 1, "analytic": 2, "quadrature": 3}

# 6-point Gauss-Legendre nodes and weights on [0, 1].
_GL_X, _GL_W = np.polynomial.legendre.leggauss(6)
_GL_X = 0.5 * (_GL_X + 1.0)
_GL_W = 0.5 * _GL_W


@inline
def _e(a):
    """E(a) = (1 - exp(-a)) / a, with E(0) = 1 (accurate for small |a|)."""
    if abs(a) < 1e-8:
        return 1.0 - 0.5 * a
    return -math.expm1(-a) / a


#: ``|z|`` up to which :func:`_expm1_halved` is used (and the wavelength loop vectorised); beyond it libm's expm1.
EXPM1_RANGE = 4.0
#: Halvings of the argument in :func:`_expm1_halved`: ``|z| / 2^5 <= 1/8`` within EXPM1_RANGE.
_EXPM1_HALVINGS = 5
#: ``1 / k!`` for k = 1..11: the Taylor series of ``expm1(r) / r`` in Horner form.
_INV_FACTORIAL = np.array([1.0 / math.factorial(k) for k in range(1, 12)])


@inline
def _expm1_halved(z):
    """``expm1(z)`` for ``|z| <= EXPM1_RANGE`` in arithmetic only, so that a loop of them vectorises (numba calls
    libm's scalar ``expm1``; llvmlite has no vector math library here): the Taylor series of ``expm1`` to
    ``r^11 / 11!`` at ``r = z / 32`` (truncation below 1e-17 relative for ``|r| <= 1/8``), then five doublings
    ``expm1(2x) = expm1(x) (expm1(x) + 2)`` ([Abramowitz1964] 4.2.1 with ``e^{2x} = (e^x)^2``), which keep the
    relative accuracy of small arguments. For ``z <= 0`` (every use here: minus an optical depth) a doubling
    does not amplify the relative error (its factor is ``2 (e + 1) / (e + 2) <= 1``); measured against libm over
    ``[-4, 0]``: at most 4 ulp."""
    r = z * (1.0 / 32.0)
    c = _INV_FACTORIAL
    p = c[10]
    for k in range(9, -1, -1):
        p = p * r + c[k]
    e = r * p
    for _ in range(_EXPM1_HALVINGS):
        e = e * (e + 2.0)
    return e


#: Taylor coefficients ``1 / (k! (n + k + 1))`` of the moments ``m_n`` (n = 0..3, k = 0..7) of _hermite_integral.
_MOMENT_TAYLOR = np.array([[1.0 / (math.factorial(k) * (n + k + 1)) for k in range(8)] for n in range(4)])


@inline
def _hermite_integral(z, ez, ez1, p0, p1, d0, d1):
    """int_0^1 e^{z w} p(w) dw for the cubic with p(0)=p0, p(1)=p1, p'(0)=d0, p'(1)=d1; ``ez1`` is ``expm1(z)``
    and ``ez`` ``exp(z)`` (the caller has both: ``1 + expm1(z)``, the piece's transmittance of the species,
    within an ulp of ``exp(z)``; one call instead of two).

    Uses the moments ``m_n = int_0^1 e^{z w} w^n dw``: the A.4 integration-by-parts recurrence
    ``m_n = (e^z - n m_{n-1}) / z`` for ``|z| >= 0.02`` (its relative error grows like ``6 eps / |z|^3``,
    below 1e-10 there) and the Taylor series ``m_n = sum_k z^k / (k! (n + k + 1))`` to k = 7 below
    (truncation error < 1e-17), in Horner form with the coefficients tabulated (``_MOMENT_TAYLOR``). Both
    multiply by ``1 / z`` or by constants instead of dividing: a chain of dependent divisions was most of the
    time of the whole kernel (the same values to a few ulp).
    """
    if abs(z) < 0.02:
        t = _MOMENT_TAYLOR
        m0 = t[0, 7]
        m1 = t[1, 7]
        m2 = t[2, 7]
        m3 = t[3, 7]
        for k in range(6, -1, -1):
            m0 = m0 * z + t[0, k]
            m1 = m1 * z + t[1, k]
            m2 = m2 * z + t[2, k]
            m3 = m3 * z + t[3, k]
    else:
        r = 1.0 / z
        m0 = ez1 * r
        m1 = (ez - m0) * r
        m2 = (ez - 2.0 * m1) * r
        m3 = (ez - 3.0 * m2) * r
    c2 = 3.0 * (p1 - p0) - 2.0 * d0 - d1
    c3 = 2.0 * (p0 - p1) + d0 + d1
    return p0 * m0 + d0 * m1 + c2 * m2 + c3 * m3


@inline
def _clip_length(c, h0, s):
    """The part [m] of a path of length s from height h0 [m] (direction cosine c) between PATH_BOTTOM and
    PATH_TOP."""
    if c > 0.0:
        return min(s, max(0.0, (PATH_TOP - h0) / c))
    if c < 0.0:
        return min(s, max(0.0, (PATH_BOTTOM - h0) / c))
    return s


@helper
def _opaque_length(c, h0, s, b1min, b2min, a1, a2):
    """The path length [m] up to where every wavelength's optical depth reaches OPAQUE_DEPTH (or s).

    Beyond it ``u_i tau <= -dtau/dx / beta_i``, so the rest adds less than ``e^-60 / beta_i`` to I_i; dropping
    it lets the pieces of the composite form (and the quadrature's segments) resolve the part that matters.
    The depth ``b1min L_1(x) + b2min L_2(x)`` grows monotonically with x, so bisection finds the point.
    """
    e1 = math.exp(-a1 * h0)
    e2 = math.exp(-a2 * h0)
    if b1min * e1 * s * _e(a1 * c * s) + b2min * e2 * s * _e(a2 * c * s) <= OPAQUE_DEPTH:
        return s
    lo = 0.0
    hi = s
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if b1min * e1 * mid * _e(a1 * c * mid) + b2min * e2 * mid * _e(a2 * c * mid) > OPAQUE_DEPTH:
            hi = mid
        else:
            lo = mid
    return hi


@helper
def _segment_count(c, h0, s, b1max, b2max, a1, a2):
    """Pieces of the composite analytic form: at most SEGMENT_DEPTH optical depth per species (at the
    densest point of the path) and SEGMENT_DECAY e-folds of haze density per piece."""
    hlow = h0 + min(0.0, c * s)
    rate = max(b1max * math.exp(-a1 * hlow), b2max)
    if hlow < 0.0:
        rate = max(rate, b2max * math.exp(-a2 * hlow))
    need = max(rate * s / SEGMENT_DEPTH, a1 * abs(c) * s / SEGMENT_DECAY)
    if need <= 1.0:
        return 1
    if need >= MAX_SEGMENTS:  # compare before int(): need may exceed the integer range
        return MAX_SEGMENTS
    return int(math.ceil(need))


@parallel_kernel
def _integrals_many(cos_t, h0, s, beta1, beta2, a1, a2, method, threshold, segments, out1, out2, out_tau):
    """(I_1, I_2) and the path's transmittance tau for rays i and wavelengths j.

    method: 0 near-horizon (Eq. 10), 1 Hermite (Eq. 11 / A.4), 2 analytic (Eq. 10 where
    |alpha_1 dx c| < threshold, else Eq. 11), 3 quadrature. segments: 0 automatic, n > 0 fixed; the
    near-horizon method always uses one interval. tau is Eq. 7, accumulated piece by piece (exact; once the
    optical depth passes 50 the remaining pieces are skipped, so tau < 2e-22 is not refined further).
    """
    n = cos_t.shape[0]
    nw = beta1.shape[0]
    b1max = 0.0
    b2max = 0.0
    b1min = math.inf
    b2min = math.inf
    for j in range(nw):
        b1max = max(b1max, beta1[j])
        b2max = max(b2max, beta2[j])
        b1min = min(b1min, beta1[j])
        b2min = min(b2min, beta2[j])
    for i in numba.prange(n):
        c = cos_t[i]
        hh = h0[i]
        ss = _opaque_length(c, hh, _clip_length(c, hh, s[i]), b1min, b2min, a1, a2)
        if method == 3:
            e1 = math.exp(-a1 * hh)
            e2 = math.exp(-a2 * hh)
            l1 = e1 * ss * _e(a1 * c * ss)
            l2 = e2 * ss * _e(a2 * c * ss)
            for j in range(nw):
                r1, r2 = _quadrature(c, e1, e2, ss, beta1[j], beta2[j], a1, a2)
                out1[i, j] = r1
                out2[i, j] = r2
                out_tau[i, j] = math.exp(-(beta1[j] * l1 + beta2[j] * l2))
            continue
        if method == 0:
            nseg = 1
        elif segments > 0:
            nseg = segments
        else:
            nseg = _segment_count(c, hh, ss, b1max, b2max, a1, a2)
        dx = ss / nseg
        depth = out_tau[i]  # optical depth so far; exponentiated at the end
        for j in range(nw):
            out1[i, j] = 0.0
            out2[i, j] = 0.0
            depth[j] = 0.0
        near = method == 0 or (method == 2 and abs(a1 * dx * c) < threshold)
        if nseg == 1 and not near:
            # A single piece (every ray of a landscape): its Hermite form for all wavelengths in three loops
            # that vectorise (the expm1 of both species first, kept in the output rows, libm only outside
            # EXPM1_RANGE; then the moments), the same formula as the general loop below, whose first piece
            # needs no attenuation and no optical-depth test.
            _single_piece(c, hh, ss, beta1, beta2, a1, a2, out1[i], out2[i], depth)
            for j in range(nw):
                depth[j] = math.exp(-depth[j])
            continue
        for k in range(nseg):
            hk = hh + k * dx * c
            e1 = math.exp(-a1 * hk)  # H_1, H_2 of this piece
            e2 = math.exp(-a2 * hk)
            l1 = e1 * dx * _e(a1 * c * dx)
            l2 = e2 * dx * _e(a2 * c * dx)
            if l1 == 0.0 and l2 == 0.0:
                continue  # empty piece (zero length)
            # Density ratios u_2/u_1 at both ends as one exponential: e2 / e1 would be 0/0 high up.
            r21_near = math.exp((a1 - a2) * hk)
            r21_far = math.exp((a1 - a2) * (hk + c * dx))
            done = True
            for j in range(nw):
                if depth[j] > 50.0:
                    continue
                done = False
                b1 = beta1[j]
                b2 = beta2[j]
                if near:
                    kk = b1 * e1 + b2 * e2
                    j1 = e1 * dx * _e((a1 * c + kk) * dx)
                    j2 = e2 * dx * _e((a2 * c + kk) * dx)
                else:
                    # the pieces' transmittances t = exp(z) as 1 + expm1(z), which the moments need anyway
                    z1 = -b1 * l1
                    z2 = -b2 * l2
                    em1 = math.expm1(z1)
                    em2 = math.expm1(z2)
                    t1 = 1.0 + em1
                    t2 = 1.0 + em2
                    # I_1: exponential in the haze optical depth, cubic in w for the molecular transmittance
                    # f, with slopes df/dw = -beta_2 u_2 f L_1 / u_1 at both ends ...
                    j1 = l1 * _hermite_integral(z1, t1, em1, 1.0, t2, -b2 * l1 * r21_near, -b2 * l1 * t2 * r21_far)
                    # ... and I_2 the same with the species swapped.
                    j2 = l2 * _hermite_integral(z2, t2, em2, 1.0, t1, -b1 * l2 / r21_near, -b1 * l2 * t1 / r21_far)
                att = math.exp(-depth[j]) if k > 0 else 1.0  # exp(-0) = 1 exactly: no call on the first piece
                out1[i, j] += att * j1
                out2[i, j] += att * j2
                depth[j] += b1 * l1 + b2 * l2
            if done:
                break
        for j in range(nw):
            depth[j] = math.exp(-depth[j])


@inline
def _single_piece(c, hh, ss, beta1, beta2, a1, a2, out1, out2, depth):
    """(I_1, I_2) of a path of one piece (length ``ss`` [m]) from height ``hh`` by the Hermite form for every
    wavelength, into ``out1`` and ``out2``, and its optical depth into ``depth`` (the general loop of
    :func:`_integrals_many` for ``nseg == 1``, arranged so that the wavelength loops vectorise)."""
    nw = beta1.shape[0]
    e1 = math.exp(-a1 * hh)
    e2 = math.exp(-a2 * hh)
    l1 = e1 * ss * _e(a1 * c * ss)
    l2 = e2 * ss * _e(a2 * c * ss)
    r21_near = math.exp((a1 - a2) * hh)
    r21_far = math.exp((a1 - a2) * (hh + c * ss))
    for j in range(nw):
        out1[j] = _expm1_halved(-beta1[j] * l1)
        out2[j] = _expm1_halved(-beta2[j] * l2)
    for j in range(nw):  # outside the polynomial's range (a piece of optical depth > 4: rare)
        if abs(beta1[j] * l1) > EXPM1_RANGE:
            out1[j] = math.expm1(-beta1[j] * l1)
        if abs(beta2[j] * l2) > EXPM1_RANGE:
            out2[j] = math.expm1(-beta2[j] * l2)
    for j in range(nw):
        b1 = beta1[j]
        b2 = beta2[j]
        z1 = -b1 * l1
        z2 = -b2 * l2
        em1 = out1[j]
        em2 = out2[j]
        t1 = 1.0 + em1
        t2 = 1.0 + em2
        out1[j] = l1 * _hermite_integral(z1, t1, em1, 1.0, t2, -b2 * l1 * r21_near, -b2 * l1 * t2 * r21_far)
        out2[j] = l2 * _hermite_integral(z2, t2, em2, 1.0, t1, -b1 * l2 / r21_near, -b1 * l2 * t1 / r21_far)
        depth[j] = b1 * l1 + b2 * l2


@helper
def _quadrature(c, h1, h2, s, b1, b2, a1, a2):
    """Composite Gauss-Legendre reference for (I_1, I_2)."""
    gx = _GL_X
    gw = _GL_W
    # Largest rate of change of the integrand along the path: extinction at the densest end plus the decay
    # of u_i. The integrand changes by at most ~e^0.5 over a segment.
    dens1 = max(h1, h1 * math.exp(-a1 * c * s))
    dens2 = max(h2, h2 * math.exp(-a2 * c * s))
    rate = b1 * dens1 + b2 * dens2 + max(a1, a2) * abs(c)
    need = rate * s / 0.5
    nseg = 100000 if need >= 100000 else max(int(math.ceil(need)), 1)
    dx = s / nseg
    i1 = 0.0
    i2 = 0.0
    for j in range(nseg):
        x0 = j * dx
        depth0 = b1 * h1 * x0 * _e(a1 * c * x0) + b2 * h2 * x0 * _e(a2 * c * x0)
        if depth0 > 50.0:
            break
        for q in range(gx.shape[0]):
            x = x0 + gx[q] * dx
            u1 = h1 * math.exp(-a1 * c * x)
            u2 = h2 * math.exp(-a2 * c * x)
            tau = math.exp(-(b1 * h1 * x * _e(a1 * c * x) + b2 * h2 * x * _e(a2 * c * x)))
            i1 += gw[q] * dx * u1 * tau
            i2 += gw[q] * dx * u2 * tau
    return i1, i2


def _prepare(cos_theta: ArrayLike, distance: ArrayLike, observer_height: ArrayLike):
    c, s, h = np.broadcast_arrays(np.asarray(cos_theta, dtype=float), np.asarray(distance, dtype=float),
                                  np.asarray(observer_height, dtype=float))
    if not np.all(np.isfinite(c)) or np.any(np.abs(c) > 1.0 + 1e-12):
        raise InvalidParameterError("cos_theta must be finite and within [-1, 1]")
    if not np.all(np.isfinite(s)) or np.any(s < 0):
        raise InvalidParameterError("distances must be finite and >= 0 [m]")
    check_observer_height(h)
    return np.clip(c, -1.0, 1.0), s, h


def check_observer_height(h: NDArray[np.float64]) -> None:
    """Raise InvalidParameterError unless every observer height [m] is finite and within +-MAX_OBSERVER_HEIGHT."""
    if not np.all(np.isfinite(h)):
        raise InvalidParameterError("observer heights must be finite [m above sea level]")
    if h.size and np.max(np.abs(h)) > MAX_OBSERVER_HEIGHT:
        raise InvalidParameterError(
            f"observer heights must be within +-{MAX_OBSERVER_HEIGHT:g} m of sea level (the flat exponential "
            f"atmosphere of Preetham et al. 1999 describes the lower atmosphere only); got {np.max(np.abs(h)):.6g} m"
        )


def _clip_lengths(c: NDArray[np.float64], s: NDArray[np.float64], h: NDArray[np.float64]) -> NDArray[np.float64]:
    """numpy twin of ``_clip_length``: the part of each path between PATH_BOTTOM and PATH_TOP [m]."""
    with np.errstate(divide="ignore", invalid="ignore"):
        up = np.where(c > 0, (PATH_TOP - h) / np.where(c > 0, c, 1.0), np.inf)
        down = np.where(c < 0, (PATH_BOTTOM - h) / np.where(c < 0, c, 1.0), np.inf)
    return np.minimum(s, np.maximum(np.minimum(up, down), 0.0))


def _coefficients(beta: ArrayLike, name: str) -> NDArray[np.float64]:
    b = np.atleast_1d(np.asarray(beta, dtype=float))
    if b.ndim != 1 or not np.all(np.isfinite(b)) or np.any(b < 0):
        raise InvalidParameterError(f"{name} must be a 1-D array of finite coefficients >= 0 [m^-1]")
    return np.ascontiguousarray(b)


def effective_length(cos_theta: ArrayLike, distance: ArrayLike, observer_height: ArrayLike,
                     alpha: float) -> NDArray[np.float64]:
    """``L = int_0^s exp(-alpha (h0 + x c)) dx = H s E(alpha c s)`` [m]: the sea-level-equivalent path length.

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the view zenith angle (negative looking down).
    distance : array_like
        Path length s [m].
    observer_height : array_like
        Observer height h0 [m above sea level].
    alpha : float
        Density decay constant [m^-1].
    """
    c, s, h = _prepare(cos_theta, distance, observer_height)
    s = _clip_lengths(c, s, h)
    a = alpha * c * s
    small = np.abs(a) < 1e-8
    with np.errstate(invalid="ignore", divide="ignore"):
        e = np.where(small, 1.0 - 0.5 * a, -np.expm1(-a) / np.where(small, 1.0, a))
    return np.exp(-alpha * h) * s * e


def extinction(cos_theta: ArrayLike, distance: ArrayLike, observer_height: ArrayLike, beta_haze: ArrayLike,
               beta_molecules: ArrayLike, *, alpha_haze: float = ALPHA_HAZE,
               alpha_molecules: float = ALPHA_MOLECULES) -> NDArray[np.float64]:
    """Extinction factor tau of the path (Preetham 1999, Eq. 7), shape (..., n_wavelengths).

    Parameters
    ----------
    cos_theta : array_like, shape (...)
        Cosine of the view zenith angle.
    distance : array_like, shape (...)
        Distance to the object [m].
    observer_height : array_like, shape (...)
        Observer height [m above sea level].
    beta_haze, beta_molecules : array_like, shape (n,)
        Sea-level total scattering coefficients [m^-1] of haze and molecules per wavelength.
    alpha_haze, alpha_molecules : float
        Density decay constants [m^-1] (A.4).
    """
    b1 = _coefficients(beta_haze, "beta_haze")
    b2 = _coefficients(beta_molecules, "beta_molecules")
    l1 = effective_length(cos_theta, distance, observer_height, alpha_haze)
    l2 = effective_length(cos_theta, distance, observer_height, alpha_molecules)
    return np.exp(-(l1[..., None] * b1 + l2[..., None] * b2))


def in_scattering_integrals(cos_theta: ArrayLike, distance: ArrayLike, observer_height: ArrayLike,
                            beta_haze: ArrayLike, beta_molecules: ArrayLike, *, method: str = "analytic",
                            alpha_haze: float = ALPHA_HAZE, alpha_molecules: float = ALPHA_MOLECULES,
                            horizon_threshold: float = HORIZON_THRESHOLD, segments: int | str = "auto",
                            return_transmittance: bool = False) -> tuple[NDArray[np.float64], ...]:
    """The integrals ``I_1`` (haze) and ``I_2`` (molecules) of Preetham 1999 Eq. 8-11 [m].

    Parameters
    ----------
    cos_theta, distance, observer_height : array_like, shape (...)
        View-zenith cosine, path length [m] and observer height [m], broadcast together.
    beta_haze, beta_molecules : array_like, shape (n,)
        Sea-level total scattering coefficients [m^-1].
    method : {"analytic", "hermite", "near_horizon", "quadrature"}
        ``analytic`` is the paper's recipe (Eq. 10 near the horizon, Eq. 11 / A.4 elsewhere); the others force
        one form (see the module docstring).
    alpha_haze, alpha_molecules : float
        Density decay constants [m^-1].
    horizon_threshold : float
        ``|alpha_haze s cos theta|`` below which ``analytic`` uses Eq. 10.
    segments : "auto" or int
        Pieces of the composite analytic/hermite form. 1 is the paper's single interval; ``"auto"`` (default
        for ``analytic``) splits the path into pieces of at most ``SEGMENT_DEPTH`` optical depth per species
        and ``SEGMENT_DECAY`` e-folds of haze density. Ignored by ``near_horizon`` and ``quadrature``.
    return_transmittance : bool
        Also return the extinction factor tau of Eq. 7 (computed in the same pass; equals
        :func:`extinction` to rounding).

    Returns
    -------
    (I_1, I_2) or (I_1, I_2, tau) : ndarrays, shape (..., n)
    """
    if method not in _METHODS:
        raise InvalidParameterError(f"method must be one of {sorted(_METHODS)}; got {method!r}")
    if isinstance(segments, str):
        if segments != "auto":
            raise InvalidParameterError(f"segments must be 'auto' or a whole number in [1, 10000]; got {segments!r}")
        nseg = 0
    else:
        nseg = whole_number("segments ('auto' or)", segments, 1, 10_000)
    c, s, h = _prepare(cos_theta, distance, observer_height)
    b1 = _coefficients(beta_haze, "beta_haze")
    b2 = _coefficients(beta_molecules, "beta_molecules")
    if b1.shape != b2.shape:
        raise InvalidParameterError("beta_haze and beta_molecules must have one value per wavelength each")
    shape = c.shape
    cf, sf, hf = (np.ascontiguousarray(a.reshape(-1)) for a in (c, s, h))
    out1 = np.empty((cf.size, b1.size))
    out2 = np.empty((cf.size, b1.size))
    tau = np.empty((cf.size, b1.size))
    _integrals_many(cf, hf, sf, b1, b2, float(alpha_haze), float(alpha_molecules), _METHODS[method],
                    float(horizon_threshold), nseg, out1, out2, tau)
    out = (out1.reshape(shape + (b1.size,)), out2.reshape(shape + (b1.size,)))
    return (*out, tau.reshape(shape + (b1.size,))) if return_transmittance else out
