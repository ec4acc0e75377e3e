"""Tabulated phase functions: per-wavelength values on a scattering-angle grid, for every solver.

A :class:`PhaseTable` holds, for each of ``n_wl`` wavelengths [nm], a phase function [sr^-1] on a grid of
scattering angles ``0 = theta_0 < ... < theta_{n-1} = pi`` [rad]. Mie theory gives such tables for aerosols and
cloud droplets (their diffraction peak, rainbow and glory are not Henyey-Greenstein); the analytic phase
functions of :mod:`.phase` can be tabulated on the same grid (:meth:`PhaseTable.henyey_greenstein`,
:meth:`PhaseTable.cornette_shanks`, :meth:`PhaseTable.from_analytic`), so that a solver can read every phase
function through one path.

**The interpolant.** Between two nodes the table is *linear in mu = cos theta*. Everything is exact for that
piecewise-linear function, so the solvers all see the same phase function:

* normalisation: each wavelength's values are scaled so that ``2 pi int_{-1}^{1} p(mu) dmu = 1`` for the
  interpolant (the trapezoidal rule in ``mu``, exact for it);
* the cumulative distribution ``F(mu) = 2 pi int_{-1}^{mu} p dmu`` is piecewise quadratic, so its inverse is a
  closed-form root per segment (:meth:`PhaseTable.inverse_cdf`; the stable form
  ``x = 2 c / (p_i + sqrt(p_i^2 + 2 s c))`` of the quadratic ``s x^2 / 2 + p_i x = c``, Press et al. 2007,
  "Numerical Recipes", 3rd ed., Sec. 5.6);
* Legendre moments ``chi_l = 2 pi int p(mu) P_l(mu) dmu`` are integrated exactly per segment with
  ``int P_l = (P_{l+1} - P_{l-1}) / (2 l + 1)`` and ``mu P_l = ((l + 1) P_{l+1} + l P_{l-1}) / (2 l + 1)``
  ([Abramowitz1964] 22.7.10 and 22.8.5); ``chi_0 = 1`` and ``chi_1 = g``, the asymmetry parameter. With
  these the phase function is ``p(mu) = sum_l (2 l + 1) chi_l P_l(mu) / (4 pi)`` (the convention of DISORT:
  [Stamnes1988] Eq. 3, whose ``PMOM`` are these ``chi_l``).

**The grid.** :func:`phase_angle_grid` spaces the nodes from ``forward_step`` at 0 deg, growing linearly to
``step`` at ``ramp_end`` and constant beyond. The default (0.01 deg at the forward direction, 0.25 deg from 15
deg on; 863 nodes) resolves the diffraction peak of a cloud droplet (about 1 deg wide for an effective radius of
10 um in the visible: the first minimum of the Airy pattern lies at ``3.83 / x`` rad for a size parameter ``x =
2 pi r / lambda``, 1.4 deg at 400 nm; [vanDeHulst1957] Sec. 8.31), the
rainbow and the glory. Interpolating linearly in ``mu`` on it reproduces Henyey-Greenstein with ``g = 0.8`` to
1.2e-4 relative and ``g = 0.99`` to 4e-4, and their Legendre moments ``g^l`` to 1e-5 and 5e-5
(tests/test_phase_table.py).

**Delta-M** ([Wiscombe1977] Eqs. 5-7): for ``M`` streams the forward fraction ``f = chi_M`` is taken out as unscattered
light and the rest ``p* = sum_{l<M} (2 l + 1) (chi_l - f) / (1 - f) P_l / (4 pi)`` is scattered; optical depths and
albedos of the
component scale as ``tau* = (1 - omega f) tau`` and ``omega* = (1 - f) omega / (1 - omega f)``. For quadratures
(DISORT, coarse angular integrals) only; a Monte Carlo samples the full table.

**For numba** (:meth:`PhaseTable.numba_arrays`): ``mu`` (n,) ascending from -1 to 1, ``values`` (n_wl, n) and
``cdf`` (n_wl, n), float64 and C-contiguous, on the ascending-``mu`` order (the reverse of :attr:`angles`). The
jitted scalar functions, built on first access as attributes of this module (:mod:`._phase_numba`; importing the
package does not import numba), are

* ``phase_table_segment(mu_nodes, mu) -> (i, w)``: the segment ``mu_nodes[i] <= mu <= mu_nodes[i + 1]`` and the
  weight ``w`` of node ``i + 1`` (bisection, 10 steps for 863 nodes);
* ``phase_table_value(mu_nodes, values, k, mu) -> p`` [sr^-1] at wavelength index ``k``;
* ``phase_table_values(mu_nodes, values, mu, out)``: ``out[k] = p_k(mu)`` for every wavelength (one bisection);
* ``phase_table_inverse_cdf(mu_nodes, values, cdf, k, u) -> mu``: the exact inverse CDF of wavelength ``k``;
  ``phase_table_inverse_cdf_segment`` also returns the segment it found, and ``phase_table_segment_near(mu_nodes,
  mu, i)`` is ``phase_table_segment`` without the bisection when ``mu`` is in segment ``i`` (the same result to the
  bit); ``phase_table_values_at(values, i, w, out)`` interpolates every wavelength at a segment found once (tables
  on the same nodes share it).

Each takes ``mu`` in [-1, 1] and ``u`` in [0, 1] without checking (clamped), never allocates and is compiled
without numba's runtime (docs/architecture.md, numba rules).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import FileFormatError, InvalidParameterError
from ..lazy import lazy_namespace
from ..validation import whole_number

__all__ = [
    "PhaseTable",
    "PhaseTableArrays",
    "phase_angle_grid",
]

_TWO_PI = 2.0 * math.pi
#: Legendre moments computed in this process, by (number of moments, shape and digest of the table's nodes and
#: values), at most :data:`_MOMENTS_KEPT`: the cloudy sky's layer columns (sky.cloudy.cloud_column) ask for the same
#: droplets' moments for every optical depth and sun zenith, each time from a new but equal table (a cloud table's
#: 128 columns took 141 evaluations of the same 257 moments).
_MOMENTS: dict[tuple[int, tuple[int, ...], bytes], NDArray[np.float64]] = {}
_MOMENTS_KEPT = 64


class PhaseTableArrays(NamedTuple):
    """A :class:`PhaseTable` as contiguous float64 arrays for numba kernels (ascending ``mu``).

    ``mu`` (n,) from -1 to 1; ``values`` (n_wl, n) [sr^-1]; ``cdf`` (n_wl, n) from 0 to 1 [-].
    """

    mu: NDArray[np.float64]
    values: NDArray[np.float64]
    cdf: NDArray[np.float64]


def phase_angle_grid(forward_step: float = math.radians(0.01), step: float = math.radians(0.25),
                     ramp_end: float = math.radians(15.0)) -> NDArray[np.float64]:
    """Scattering angles [rad] from 0 to pi, dense near the forward direction.

    The spacing is ``forward_step`` at 0, grows linearly with the angle to ``step`` at ``ramp_end`` and stays
    ``step`` up to pi: nodes ``theta(t) = (s0 / k) (exp(k t) - 1)`` (``k = (step - s0) / ramp_end``, the solution
    of ``dtheta / dt = s0 + k theta``) at equal steps of ``t`` up to ``ramp_end``, then equal steps to pi.

    Parameters
    ----------
    forward_step : float
        Spacing at 0 [rad], > 0 (default 0.01 deg).
    step : float
        Spacing from ``ramp_end`` to pi [rad], >= ``forward_step`` (default 0.25 deg).
    ramp_end : float
        Angle where the spacing reaches ``step`` [rad], in (0, pi) (default 15 deg).

    Returns
    -------
    ndarray, shape (n,)
        Strictly increasing angles, first exactly 0 and last exactly pi.
    """
    s0, s1, tr = (float(v) for v in (forward_step, step, ramp_end))
    if not (math.isfinite(s0) and math.isfinite(s1) and math.isfinite(tr)):
        raise InvalidParameterError("phase angle grid: steps and ramp end must be finite")
    if not 0.0 < s0 <= s1 < 0.5:
        raise InvalidParameterError(
            f"phase angle grid needs 0 < forward_step <= step < 0.5 rad; got {s0:g}, {s1:g}")
    if not 0.0 < tr < math.pi:
        raise InvalidParameterError(f"phase angle grid: ramp_end must be in (0, pi) rad; got {tr:g}")
    k = (s1 - s0) / tr
    if k > 0:
        t_end = math.log1p(k * tr / s0) / k
        n1 = max(1, math.ceil(t_end))
        t = np.linspace(0.0, t_end, n1 + 1)
        ramp = s0 / k * np.expm1(k * t)
    else:
        ramp = np.linspace(0.0, tr, max(1, math.ceil(tr / s0)) + 1)
    ramp[-1] = tr
    n2 = max(1, math.ceil((math.pi - tr) / s1))
    rest = np.linspace(tr, math.pi, n2 + 1)
    out = np.concatenate([ramp, rest[1:]])
    out[0], out[-1] = 0.0, math.pi
    return out


def _legendre_table(mu: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """P_0 .. P_{n-1} at ``mu``, shape (n, len(mu)), by Bonnet's recurrence (Abramowitz & Stegun 22.7.10)."""
    p = np.empty((max(n, 2), mu.size))
    p[0] = 1.0
    p[1] = mu
    for ell in range(1, n - 1):
        p[ell + 1] = ((2 * ell + 1) * mu * p[ell] - ell * p[ell - 1]) / (ell + 1)
    return p[:n]


class PhaseTable:
    """Per-wavelength phase functions [sr^-1] on a grid of scattering angles (module docstring).

    Parameters
    ----------
    wavelengths : array_like, shape (n_wl,)
        Strictly increasing wavelengths [nm], > 0.
    angles : array_like, shape (n,)
        Strictly increasing scattering angles [rad], the first 0 and the last pi; n >= 3.
    values : array_like, shape (n_wl, n) or (n,)
        Phase function at each wavelength and angle, >= 0 and finite [sr^-1 up to a factor]; a 1-D array is
        the same at every wavelength.
    normalise : bool
        Scale each wavelength so that the interpolant integrates to 1 over the sphere (default). With False
        the values must already do so to 1e-6, else InvalidParameterError.

    Raises
    ------
    InvalidParameterError
        For a grid or values outside what is allowed (the message says which), or a wavelength whose values
        are all zero.
    """

    __slots__ = ("_wavelengths", "_angles", "_values", "_mu", "_values_mu", "_cdf")

    def __init__(self, wavelengths: ArrayLike, angles: ArrayLike, values: ArrayLike, normalise: bool = True):
        wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
        th = np.asarray(angles, dtype=float)
        v = np.asarray(values, dtype=float)
        if wl.ndim != 1 or wl.size < 1 or not np.all(np.isfinite(wl)) or np.any(wl <= 0):
            raise InvalidParameterError("phase table: wavelengths must be a 1-D array of finite values > 0 nm")
        if np.any(np.diff(wl) <= 0):
            raise InvalidParameterError("phase table: wavelengths must be strictly increasing")
        if th.ndim != 1 or th.size < 3 or not np.all(np.isfinite(th)):
            raise InvalidParameterError("phase table: angles must be a 1-D array of at least 3 finite values [rad]")
        if th[0] != 0.0 or abs(th[-1] - math.pi) > 1e-12 or np.any(np.diff(th) <= 0):
            raise InvalidParameterError(
                "phase table: angles must increase strictly from exactly 0 to pi rad "
                f"(got {th[0]:g} .. {th[-1]:.17g})")
        th = th.copy()
        th[-1] = math.pi
        if v.ndim == 1:
            v = np.broadcast_to(v, (wl.size, v.size))
        if v.shape != (wl.size, th.size):
            raise InvalidParameterError(
                f"phase table: values must have shape (n_wavelengths, n_angles) = ({wl.size}, {th.size}); "
                f"got {v.shape}")
        if not np.all(np.isfinite(v)) or np.any(v < 0):
            raise InvalidParameterError("phase table: values must be finite and >= 0")
        mu = np.cos(th[::-1])
        mu[0], mu[-1] = -1.0, 1.0
        if np.any(np.diff(mu) <= 0):
            raise InvalidParameterError("phase table: angles too close together to be told apart in cos(theta)")
        v_mu = np.ascontiguousarray(v[:, ::-1], dtype=float)
        integral = _TWO_PI * np.sum(0.5 * (v_mu[:, 1:] + v_mu[:, :-1]) * np.diff(mu), axis=-1)
        if np.any(integral <= 0):
            raise InvalidParameterError("phase table: a wavelength's phase function is zero everywhere")
        if normalise:
            v_mu = v_mu / integral[:, None]
        elif np.any(np.abs(integral - 1.0) > 1e-6):
            raise InvalidParameterError(
                "phase table: values integrate to "
                f"{integral.min():.7g}-{integral.max():.7g} over the sphere, not 1 (pass normalise=True)")
        self._set(wl, th, mu, v_mu)

    def _set(self, wl: NDArray[np.float64], th: NDArray[np.float64], mu: NDArray[np.float64],
             v_mu: NDArray[np.float64]) -> None:
        """Keep the validated grid and values (read-only) and the cumulative distribution over ``mu``."""
        seg = 0.5 * (v_mu[:, 1:] + v_mu[:, :-1]) * np.diff(mu) * _TWO_PI
        cdf = np.zeros_like(v_mu)
        cdf[:, 1:] = np.cumsum(seg, axis=-1)
        cdf /= cdf[:, -1:]
        cdf[:, -1] = 1.0
        for a in (wl, th, mu, v_mu, cdf):
            a.setflags(write=False)
        self._wavelengths = wl
        self._angles = th
        self._mu = mu
        self._values_mu = v_mu
        self._cdf = np.ascontiguousarray(cdf)
        self._values = None

    # ------------------------------------------------------------------ constructors

    @classmethod
    def from_cosines(cls, wavelengths: ArrayLike, mu: ArrayLike, values: ArrayLike) -> PhaseTable:
        """The table whose :meth:`numba_arrays` are ``mu`` (n,) ascending cosines of the scattering angle from -1
        to 1 and ``values`` (n_wl, n) [sr^-1], normalised: those arrays kept bit for bit (the angles are their arc
        cosines), so that its moments, :meth:`delta_m` included, are those of the table they came from. For a
        table read back from a file without its angles (the precomputed tables' aerosol phase)."""
        m = np.asarray(mu, dtype=float)
        v = np.asarray(values, dtype=float)
        if m.ndim != 1 or m.size < 3 or m[0] != -1.0 or m[-1] != 1.0 or np.any(np.diff(m) <= 0):
            raise InvalidParameterError("phase table: mu must increase strictly from exactly -1 to 1")
        th = np.arccos(m[::-1])
        th[0], th[-1] = 0.0, math.pi
        table = cls(wavelengths, th, np.asarray(v)[..., ::-1], normalise=False)  # validates the values
        table._set(table._wavelengths, table._angles, np.array(m), np.array(v, dtype=float))  # copies: frozen
        return table

    @classmethod
    def from_function(cls, func: Any, wavelengths: ArrayLike, angles: ArrayLike | None = None) -> PhaseTable:
        """Tabulate ``func(cos_theta) -> (n,)`` or ``func(cos_theta, wavelength_index) -> (n,)`` [sr^-1].

        ``func`` is called with the cosines of ``angles`` (default :func:`phase_angle_grid`); with one argument
        the result is used at every wavelength. The table is normalised (the interpolant integrates to 1).
        """
        th = phase_angle_grid() if angles is None else np.asarray(angles, dtype=float)
        wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
        mu = np.cos(th)
        import inspect

        try:
            n_args = len(inspect.signature(func).parameters)
        except (TypeError, ValueError):
            n_args = 1
        if n_args >= 2:
            vals = np.stack([np.asarray(func(mu, k), dtype=float) for k in range(wl.size)])
        else:
            vals = np.asarray(func(mu), dtype=float)
        return cls(wl, th, vals)

    @classmethod
    def from_analytic(cls, kind: str, g: ArrayLike, wavelengths: ArrayLike,
                      angles: ArrayLike | None = None) -> PhaseTable:
        """Tabulate the analytic aerosol phase function ``kind`` (:data:`.phase.AEROSOL_PHASE_FUNCTIONS`).

        ``g`` [-] in (-1, 1), one value or one per wavelength; ``angles`` [rad] default :func:`phase_angle_grid`.
        """
        from . import phase

        wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
        gs = np.broadcast_to(np.asarray(g, dtype=float), wl.shape)
        phase.aerosol_phase_kind(kind)
        return cls.from_function(lambda mu, k: phase.aerosol_phase(mu, float(gs[k]), kind), wl, angles)

    @classmethod
    def henyey_greenstein(cls, g: ArrayLike, wavelengths: ArrayLike, angles: ArrayLike | None = None) -> PhaseTable:
        """Henyey & Greenstein (1941) tabulated (:func:`.phase.henyey_greenstein`); ``g`` [-] per wavelength or one."""
        return cls.from_analytic("henyey-greenstein", g, wavelengths, angles)

    @classmethod
    def cornette_shanks(cls, g: ArrayLike, wavelengths: ArrayLike, angles: ArrayLike | None = None) -> PhaseTable:
        """Cornette & Shanks (1992) tabulated (:func:`.phase.cornette_shanks`); ``g`` [-] per wavelength or one."""
        return cls.from_analytic("cornette-shanks", g, wavelengths, angles)

    @classmethod
    def from_legendre_moments(cls, moments: ArrayLike, wavelengths: ArrayLike, angles: ArrayLike | None = None,
                              clip_negative: bool = False) -> PhaseTable:
        """The series ``p(mu) = sum_l (2 l + 1) chi_l P_l(mu) / (4 pi)`` tabulated on ``angles``.

        ``moments`` (n_wl, L) or (L,) with ``chi_0 = 1``. A truncated series can be slightly negative at some
        angles: InvalidParameterError unless ``clip_negative`` (then set to 0 and renormalised).
        """
        chi = np.atleast_2d(np.asarray(moments, dtype=float))
        wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
        if chi.shape[0] == 1 and wl.size > 1:
            chi = np.broadcast_to(chi, (wl.size, chi.shape[1]))
        if chi.shape[0] != wl.size or chi.shape[1] < 1 or not np.all(np.isfinite(chi)):
            raise InvalidParameterError("Legendre moments must be finite, shape (n_wavelengths, n_moments)")
        th = phase_angle_grid() if angles is None else np.asarray(angles, dtype=float)
        pl = _legendre_table(np.cos(th), chi.shape[1])
        vals = (chi * (2 * np.arange(chi.shape[1]) + 1)) @ pl / (4.0 * math.pi)
        if np.any(vals < 0):
            if not clip_negative:
                raise InvalidParameterError(
                    f"the Legendre series is negative down to {vals.min():.3g} sr^-1 at some angles "
                    "(pass clip_negative=True to set those to 0)")
            vals = np.maximum(vals, 0.0)
        return cls(wl, th, vals)

    @classmethod
    def mixture(cls, tables: list[PhaseTable], weights: ArrayLike) -> PhaseTable:
        """The phase function of a mixture: ``sum_i w_i p_i / sum_i w_i`` per wavelength.

        ``weights`` (n_tables, n_wl) or (n_tables,): the components' scattering coefficients [m^-1] (or
        scattering optical depths). Every table must have the same wavelengths; the result is tabulated on the
        union of their angle grids (each table evaluated by its own interpolant).
        """
        if not tables:
            raise InvalidParameterError("a phase mixture needs at least one table")
        wl = tables[0].wavelengths
        for t in tables[1:]:
            if t.wavelengths.shape != wl.shape or np.any(t.wavelengths != wl):
                raise InvalidParameterError("phase mixture: every table must have the same wavelengths")
        w = np.asarray(weights, dtype=float)
        if w.ndim == 1:
            w = np.broadcast_to(w[:, None], (len(tables), wl.size))
        if w.shape != (len(tables), wl.size) or not np.all(np.isfinite(w)) or np.any(w < 0):
            raise InvalidParameterError("phase mixture: weights must be finite, >= 0, shape (n_tables, n_wl)")
        total = w.sum(axis=0)
        if np.any(total <= 0):
            raise InvalidParameterError("phase mixture: the weights of some wavelength are all zero")
        th = np.unique(np.concatenate([t.angles for t in tables]))
        mu = np.cos(th)
        vals = sum(w[i][:, None] * t.evaluate(mu).T for i, t in enumerate(tables)) / total[:, None]
        return cls(wl, th, vals)

    # ------------------------------------------------------------------ properties

    @property
    def wavelengths(self) -> NDArray[np.float64]:
        """(n_wl,) wavelengths [nm] (read-only)."""
        return self._wavelengths

    @property
    def angles(self) -> NDArray[np.float64]:
        """(n,) scattering angles [rad], 0 to pi (read-only)."""
        return self._angles

    @property
    def values(self) -> NDArray[np.float64]:
        """(n_wl, n) normalised phase function at :attr:`angles` [sr^-1] (read-only)."""
        if self._values is None:
            v = np.ascontiguousarray(self._values_mu[:, ::-1])
            v.setflags(write=False)
            self._values = v
        return self._values

    @property
    def n_wavelengths(self) -> int:
        return int(self._wavelengths.size)

    def numba_arrays(self) -> PhaseTableArrays:
        """``(mu, values, cdf)`` as C-contiguous float64 arrays on ascending ``mu`` (module docstring)."""
        return PhaseTableArrays(self._mu, self._values_mu, self._cdf)

    def __repr__(self) -> str:
        return (f"PhaseTable({self.n_wavelengths} wavelengths {self._wavelengths[0]:g}-{self._wavelengths[-1]:g} nm, "
                f"{self._angles.size} angles)")

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PhaseTable):
            return NotImplemented
        return (np.array_equal(self._wavelengths, other._wavelengths) and np.array_equal(self._angles, other._angles)
                and np.array_equal(self._values_mu, other._values_mu))

    def __hash__(self) -> int:
        return hash((self._wavelengths.tobytes(), self._angles.tobytes(), self._values_mu.tobytes()))

    # ------------------------------------------------------------------ evaluation

    def _wavelength_index(self, wavelength_index: int) -> int:
        if isinstance(wavelength_index, bool) or int(wavelength_index) != wavelength_index:
            raise InvalidParameterError(f"wavelength index must be a whole number; got {wavelength_index!r}")
        k = int(wavelength_index)
        if not 0 <= k < self.n_wavelengths:
            raise InvalidParameterError(
                f"wavelength index must be in [0, {self.n_wavelengths - 1}]; got {wavelength_index!r}")
        return k

    def evaluate(self, cos_theta: ArrayLike, wavelength_index: int | None = None) -> NDArray[np.float64]:
        """The phase function [sr^-1] at ``cos_theta`` [-] (in [-1, 1], no NaN).

        Returns shape (..., n_wl), or the shape of ``cos_theta`` for one ``wavelength_index``.
        """
        from .phase import _cos

        mu = _cos(cos_theta)
        i = np.clip(np.searchsorted(self._mu, mu, side="right") - 1, 0, self._mu.size - 2)
        w = (mu - self._mu[i]) / (self._mu[i + 1] - self._mu[i])
        if wavelength_index is not None:
            v = self._values_mu[self._wavelength_index(wavelength_index)]
            return (1.0 - w) * v[i] + w * v[i + 1]
        v = self._values_mu
        # the wavelength axis moved last (``.T`` would also reverse the axes of a 2D or higher ``cos_theta``)
        return (1.0 - w)[..., None] * np.moveaxis(v[:, i], 0, -1) + w[..., None] * np.moveaxis(v[:, i + 1], 0, -1)

    def __call__(self, cos_theta: ArrayLike) -> NDArray[np.float64]:
        """Same as :meth:`evaluate` for every wavelength: shape (..., n_wl) [sr^-1]."""
        return self.evaluate(cos_theta)

    def at_wavelengths(self, wavelengths: ArrayLike) -> PhaseTable:
        """The table at other wavelengths [nm] inside its range, linear in wavelength (stays normalised).

        InvalidParameterError for a wavelength outside the table's range (no extrapolation).
        """
        wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
        lo, hi = float(self._wavelengths[0]), float(self._wavelengths[-1])
        if not np.all(np.isfinite(wl)) or np.any(wl < lo - 1e-9) or np.any(wl > hi + 1e-9):
            raise InvalidParameterError(
                f"phase table covers {lo:g}-{hi:g} nm; asked for {np.min(wl):g}-{np.max(wl):g} nm")
        if wl.shape == self._wavelengths.shape and np.all(wl == self._wavelengths):
            return self
        if self.n_wavelengths == 1:
            vals = np.broadcast_to(self.values[0], (wl.size, self._angles.size))
        else:
            j = np.clip(np.searchsorted(self._wavelengths, wl, side="right") - 1, 0, self.n_wavelengths - 2)
            t = np.clip((wl - self._wavelengths[j]) / (self._wavelengths[j + 1] - self._wavelengths[j]), 0.0, 1.0)
            vals = (1.0 - t)[:, None] * self.values[j] + t[:, None] * self.values[j + 1]
        return PhaseTable(wl, self._angles, vals)

    def on_angles(self, angles: ArrayLike) -> PhaseTable:
        """The table re-tabulated on another angle grid [rad] (its interpolant sampled there, renormalised)."""
        th = np.asarray(angles, dtype=float)
        if th.ndim != 1:
            raise InvalidParameterError("phase table: angles must be a 1-D array [rad]")
        return PhaseTable(self._wavelengths, th, self.evaluate(np.cos(th)).T)

    # ------------------------------------------------------------------ sampling

    def cdf(self, cos_theta: ArrayLike, wavelength_index: int = 0) -> NDArray[np.float64]:
        """``F(mu) = 2 pi int_{-1}^{mu} p dmu'`` [-] of the interpolant at ``cos_theta`` (exact: piecewise
        quadratic)."""
        from .phase import _cos

        k = self._wavelength_index(wavelength_index)
        mu = _cos(cos_theta)
        i = np.clip(np.searchsorted(self._mu, mu, side="right") - 1, 0, self._mu.size - 2)
        v = self._values_mu[k]
        x = mu - self._mu[i]
        s = (v[i + 1] - v[i]) / (self._mu[i + 1] - self._mu[i])
        return np.minimum(self._cdf[k, i] + _TWO_PI * (v[i] * x + 0.5 * s * x * x), 1.0)

    def inverse_cdf(self, u: ArrayLike, wavelength_index: int = 0) -> NDArray[np.float64]:
        """Cosine of the scattering angle with CDF ``u`` (uniform numbers in [0, 1]) at one wavelength [-].

        Exact for the interpolant: ``cdf(inverse_cdf(u)) = u`` to rounding (module docstring); increasing in u.
        """
        from .phase import _uniform

        k = self._wavelength_index(wavelength_index)
        uu = _uniform(u)
        c_k = self._cdf[k]
        i = np.clip(np.searchsorted(c_k, uu, side="right") - 1, 0, self._mu.size - 2)
        v = self._values_mu[k]
        dmu = self._mu[i + 1] - self._mu[i]
        s = (v[i + 1] - v[i]) / dmu
        c = (uu - c_k[i]) / _TWO_PI
        den = v[i] + np.sqrt(np.maximum(v[i] * v[i] + 2.0 * s * c, 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.where(den > 0, 2.0 * c / den, 0.0)
        return np.clip(self._mu[i] + np.clip(x, 0.0, dmu), -1.0, 1.0)

    def sample(self, size: int | tuple[int, ...], wavelength_index: int = 0, rng: Any = None) -> NDArray[np.float64]:
        """``size`` cosines of the scattering angle drawn from the table at one wavelength (inverse CDF)."""
        from .phase import _rng, _size

        return self.inverse_cdf(_rng(rng).random(_size(size)), wavelength_index)

    # ------------------------------------------------------------------ moments

    def legendre_moments(self, n_moments: int) -> NDArray[np.float64]:
        """Legendre moments ``chi_0 .. chi_{n-1}`` (n_wl, n_moments) [-], exact for the interpolant.

        ``chi_l = 2 pi int_{-1}^{1} p(mu) P_l(mu) dmu`` (module docstring): ``chi_0 = 1``, ``chi_1 = g``; DISORT's
        ``PMOM`` (Stamnes et al. 1988).
        """
        import hashlib

        n = whole_number("number of Legendre moments", n_moments, 1, integral_floats=True)
        mu = self._mu
        digest = hashlib.blake2b(mu.tobytes() + self._values_mu.tobytes(), digest_size=20).digest()
        key = (n, self._values_mu.shape, digest)
        kept = _MOMENTS.get(key)
        if kept is not None:
            return kept.copy()
        a, b = mu[:-1], mu[1:]
        pl = _legendre_table(mu, n + 2)  # P_0 .. P_{n+1} at the nodes
        # I_l = int_a^b P_l dmu per segment, l = 0 .. n
        big_i = np.empty((n + 1, a.size))
        big_i[0] = b - a
        ell = np.arange(1, n + 1)[:, None]
        big_i[1:] = ((pl[2:n + 2, 1:] - pl[2:n + 2, :-1]) - (pl[0:n, 1:] - pl[0:n, :-1])) / (2 * ell + 1)
        # J_l = int_a^b mu P_l dmu, l = 0 .. n - 1
        big_j = np.empty((n, a.size))
        big_j[0] = 0.5 * (b * b - a * a)
        if n > 1:
            e = np.arange(1, n)[:, None]
            big_j[1:] = ((e + 1) * big_i[2:n + 1] + e * big_i[0:n - 1]) / (2 * e + 1)
        v = self._values_mu
        s = (v[:, 1:] - v[:, :-1]) / (b - a)
        c0 = v[:, :-1] - s * a  # p = c0 + s mu on each segment
        chi = _TWO_PI * (c0 @ big_i[:n].T + s @ big_j.T)
        chi[:, 0] = 1.0
        if len(_MOMENTS) >= _MOMENTS_KEPT:
            _MOMENTS.pop(next(iter(_MOMENTS)))  # the oldest
        _MOMENTS[key] = chi
        return chi.copy()

    @property
    def asymmetry(self) -> NDArray[np.float64]:
        """Asymmetry parameter ``g = <cos theta>`` per wavelength (n_wl,) [-] (exact for the interpolant)."""
        return self.legendre_moments(2)[:, 1]

    def delta_m(self, n_streams: int, angles: ArrayLike | None = None,
                clip_negative: bool = True) -> tuple[PhaseTable, NDArray[np.float64]]:
        """Delta-M truncation for ``n_streams`` streams (Wiscombe 1977; module docstring).

        Returns ``(table, f)``: the truncated phase function ``p*`` tabulated on ``angles`` (default this table's
        grid) from its moments ``chi*_l = (chi_l - f) / (1 - f)``, ``l < n_streams``, and the forward fraction
        ``f = chi_{n_streams}`` per wavelength (n_wl,) [-]. A truncated series can dip slightly below zero where
        the original is small; those values are set to 0 and the table renormalised unless ``clip_negative`` is
        False (then InvalidParameterError).
        """
        m = whole_number("the number of delta-M streams", n_streams, 2, integral_floats=True)
        chi = self.legendre_moments(m + 1)
        f = chi[:, m].copy()
        if np.any(f >= 1.0):
            raise InvalidParameterError("delta-M: the forward fraction is 1 (a delta function); nothing is left")
        trunc = (chi[:, :m] - f[:, None]) / (1.0 - f[:, None])
        th = self._angles if angles is None else angles
        return PhaseTable.from_legendre_moments(trunc, self._wavelengths, th, clip_negative), f

    # ------------------------------------------------------------------ serialisation

    def to_dict(self) -> dict[str, Any]:
        """JSON-compatible description (repr-exact floats) that :meth:`from_dict` reads back."""
        return {"kind": "phase_table", "wavelengths": self._wavelengths.tolist(), "angles": self._angles.tolist(),
                "values": self.values.tolist()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> PhaseTable:
        try:
            if data.get("kind") != "phase_table":
                raise KeyError("kind")
            # written normalised: read back as is, so that a round trip is exact
            return cls(data["wavelengths"], data["angles"], data["values"], normalise=False)
        except (KeyError, TypeError, AttributeError) as exc:
            raise FileFormatError(f"phase table description is incomplete or malformed: {exc}") from None


# ------------------------------------------------------------------ numba functions (built on first use)

if TYPE_CHECKING:
    from ._phase_numba import (
        phase_table_inverse_cdf as phase_table_inverse_cdf,
    )
    from ._phase_numba import (
        phase_table_inverse_cdf_segment as phase_table_inverse_cdf_segment,
    )
    from ._phase_numba import (
        phase_table_segment as phase_table_segment,
    )
    from ._phase_numba import (
        phase_table_segment_near as phase_table_segment_near,
    )
    from ._phase_numba import (
        phase_table_value as phase_table_value,
    )
    from ._phase_numba import (
        phase_table_values as phase_table_values,
    )
    from ._phase_numba import (
        phase_table_values_at as phase_table_values_at,
    )

_LAZY = {name: "_phase_numba" for name in (
    "phase_table_segment", "phase_table_value", "phase_table_values", "phase_table_inverse_cdf",
    "phase_table_segment_near", "phase_table_values_at", "phase_table_inverse_cdf_segment")}

__getattr__ = lazy_namespace(globals(), _LAZY)[0]
