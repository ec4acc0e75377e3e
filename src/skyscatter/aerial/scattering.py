"""Light scattered towards the viewer at ground level: S^0 of Preetham, Shirley & Smits (1999), Sec. 4.2.

``S_i^0(theta, phi) = int L^s(omega) beta_i^0(omega, theta, phi) d omega`` [W m^-3 sr^-1 nm^-1] for haze
(i = 1, Mie) and molecules (i = 2, Rayleigh), where ``L^s`` is the radiance of the sun and sky and
``beta_i^0(omega, ...)`` the sea-level angular scattering coefficient [m^-1 sr^-1] (A.3) for the angle between
the source direction omega and the view direction (theta, phi); that angle is the scattering angle, so
looking towards the sun is forward scattering.

* Sun: a delta of irradiance ``E_sun = L_sun Omega_sun`` in the sun's direction, so its share is
  ``E_sun(lambda) beta_i^0(gamma, lambda)`` with gamma the angle between view and sun. It depends on gamma
  only and is tabulated on a fine gamma grid (0.25 deg).
* Sky: integrated numerically over the upper hemisphere (Gauss-Legendre in cos theta x uniform azimuth,
  2048 directions by default) and tabulated on a (view zenith, azimuth from the sun) grid, 3 deg x 5 deg.
  The sky is assumed symmetric about the sun's meridian (true of every analytic model in skyscatter), so
  the relative azimuth is folded into [0, pi].

The angular coefficients are :func:`skyscatter.atmosphere.rayleigh_angular_scattering` and
:func:`skyscatter.atmosphere.mie_angular_scattering` (A.3 with Table 1 eta), tabulated once on a 0.25-degree
grid of scattering angles and interpolated linearly inside the integration kernel.

Reference: [Preetham1999].
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere import mie_angular_scattering, rayleigh_angular_scattering
from ..conventions import as_directions, direction_from_angles
from ..errors import InvalidParameterError
from ..jit import parallel_kernel
from ..sky.base import SkyModel
from ..spectral import as_wavelengths

__all__ = ["ScatteringTable", "hemisphere_quadrature"]

_N_GAMMA = 721  # 0.25-degree steps of the scattering angle
_GAMMA_STEP = math.pi / (_N_GAMMA - 1)


def hemisphere_quadrature(n_zenith: int = 32, n_azimuth: int = 64) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Directions (n, 3) and weights [sr] (n,) that integrate over the upper hemisphere.

    Gauss-Legendre in ``cos theta`` on [0, 1] times the midpoint rule in azimuth; the weights sum to 2 pi.
    """
    if n_zenith < 1 or n_azimuth < 1:
        raise InvalidParameterError("hemisphere quadrature needs at least one node in each direction")
    x, w = np.polynomial.legendre.leggauss(int(n_zenith))
    mu = 0.5 * (x + 1.0)
    wmu = 0.5 * w
    phi = (np.arange(n_azimuth) + 0.5) * (2 * np.pi / n_azimuth)
    zen = np.arccos(mu)
    d = direction_from_angles(zen[:, None], phi[None, :]).reshape(-1, 3)
    weights = (wmu[:, None] * np.full(n_azimuth, 2 * np.pi / n_azimuth)[None, :]).reshape(-1)
    return d, weights


@parallel_kernel
def _sky_kernel(views, dirs, radiance, weights, tab1, tab2, step, out1, out2):
    """out_i[v, l] = sum_d w_d L[d, l] tab_i(angle(view_v, dir_d), l)."""
    nv = views.shape[0]
    nd = dirs.shape[0]
    nl = radiance.shape[1]
    ng = tab1.shape[0]
    for v in numba.prange(nv):
        acc1 = np.zeros(nl)
        acc2 = np.zeros(nl)
        vx, vy, vz = views[v, 0], views[v, 1], views[v, 2]
        for d in range(nd):
            c = vx * dirs[d, 0] + vy * dirs[d, 1] + vz * dirs[d, 2]
            c = min(1.0, max(-1.0, c))
            g = math.acos(c) / step
            i = min(int(g), ng - 2)
            f = g - i
            wd = weights[d]
            for k in range(nl):
                lw = wd * radiance[d, k]
                acc1[k] += lw * (tab1[i, k] * (1.0 - f) + tab1[i + 1, k] * f)
                acc2[k] += lw * (tab2[i, k] * (1.0 - f) + tab2[i + 1, k] * f)
        for k in range(nl):
            out1[v, k] = acc1[k]
            out2[v, k] = acc2[k]


class ScatteringTable:
    """Precomputed ``S_1^0`` (haze) and ``S_2^0`` (molecules) for one sky, turbidity and wavelength grid.

    Parameters
    ----------
    sky : SkyModel
        The sky (its ``spectral_radiance``) and its solar disc ``sky.sun`` (direction and spectral irradiance),
        if it has one.
    turbidity : float
        Turbidity T of the haze whose angular scattering coefficient is used [-].
    wavelengths : array_like, optional
        Wavelengths [nm]; default 380-780 nm every 10 nm.
    include_sun, include_sky : bool
        Which sources to include (both by default; the constant-density model of the course notes uses the
        sun only).
    sky_samples : (int, int)
        Zenith x azimuth nodes of the hemisphere quadrature of the sky.
    grid_step_deg : (float, float)
        Steps [deg] of the (view zenith, relative azimuth) table of the sky term.
    """

    def __init__(self, sky: SkyModel, turbidity: float, wavelengths: ArrayLike | None = None, *,
                 include_sun: bool = True, include_sky: bool = True, sky_samples: tuple[int, int] = (32, 64),
                 grid_step_deg: tuple[float, float] = (3.0, 5.0)) -> None:
        self.wavelengths = as_wavelengths(wavelengths)
        wl = self.wavelengths
        self.turbidity = float(turbidity)
        gamma = np.linspace(0.0, np.pi, _N_GAMMA)
        self._mie = np.ascontiguousarray(mie_angular_scattering(gamma, wl, self.turbidity))
        self._ray = np.ascontiguousarray(rayleigh_angular_scattering(gamma, wl))
        # -- sun: E_sun beta(gamma) on the gamma grid -------------------------------------------------------
        self.sun_direction = None
        self._sun1 = self._sun2 = None
        sun = sky.sun
        if include_sun and sun is not None:
            e_sun = np.asarray(sun.spectral_irradiance_normal(wl), dtype=float)
            if np.any(e_sun > 0):
                self.sun_direction = np.asarray(sun.direction, dtype=float)
                self._sun1 = self._mie * e_sun
                self._sun2 = self._ray * e_sun
        # The sky table is laid out in azimuth relative to the sun's vertical plane (north without a sun).
        axis = None if sun is None else np.asarray(sun.direction, dtype=float)
        self.sun_azimuth = 0.0 if axis is None else float(np.arctan2(axis[0], axis[1]))
        # -- sky: (theta_view, phi_rel) table ---------------------------------------------------------------
        dt, dp = (math.radians(v) for v in grid_step_deg)
        self._theta = np.linspace(0.0, np.pi, int(round(np.pi / dt)) + 1)
        self._phi = np.linspace(0.0, np.pi, int(round(np.pi / dp)) + 1)
        nt, npf, nl = self._theta.size, self._phi.size, wl.size
        self._sky1 = np.zeros((nt, npf, nl))
        self._sky2 = np.zeros((nt, npf, nl))
        if include_sky:
            dirs, weights = hemisphere_quadrature(*sky_samples)
            radiance = np.ascontiguousarray(sky.spectral_radiance(dirs, wl), dtype=np.float64)
            if not np.all(np.isfinite(radiance)):
                raise InvalidParameterError("the sky model returned non-finite radiance; cannot integrate S^0")
            views = direction_from_angles(self._theta[:, None], self.sun_azimuth + self._phi[None, :])
            views = np.ascontiguousarray(views.reshape(-1, 3))
            o1 = np.empty((views.shape[0], nl))
            o2 = np.empty((views.shape[0], nl))
            _sky_kernel(views, dirs, radiance, weights, self._mie, self._ray, _GAMMA_STEP, o1, o2)
            self._sky1 = o1.reshape(nt, npf, nl)
            self._sky2 = o2.reshape(nt, npf, nl)

    def lookup(self, directions: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(S_1^0, S_2^0)`` [W m^-3 sr^-1 nm^-1] for view directions (..., 3), each (..., n_wavelengths).

        Bilinear interpolation of the sky table in (view zenith, relative azimuth) plus linear interpolation
        of the sun's share in the scattering angle.
        """
        d = as_directions(directions)
        shape = d.shape[:-1]
        flat = np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float64)
        nl = self.wavelengths.size
        out1 = np.empty((flat.shape[0], nl))
        out2 = np.empty((flat.shape[0], nl))
        self._lookup(flat, None, None, out1, out2)
        return out1.reshape(shape + (nl,)), out2.reshape(shape + (nl,))

    def inscattered(self, directions: ArrayLike, i1: ArrayLike, i2: ArrayLike) -> NDArray[np.float64]:
        """``L_in = S_1^0 I_1 + S_2^0 I_2`` [W m^-2 sr^-1 nm^-1] (Eq. 8) for view directions (..., 3) and the
        paths' integrals ``I_1``, ``I_2`` [m] (..., n_wavelengths): :meth:`lookup` and the sum in one pass,
        equal to it bit for bit."""
        d = as_directions(directions)
        shape = d.shape[:-1]
        flat = np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float64)
        nl = self.wavelengths.size
        w1 = np.ascontiguousarray(np.broadcast_to(i1, shape + (nl,)), dtype=np.float64).reshape(-1, nl)
        w2 = np.ascontiguousarray(np.broadcast_to(i2, shape + (nl,)), dtype=np.float64).reshape(-1, nl)
        out = np.empty((flat.shape[0], nl))
        self._lookup(flat, w1, w2, out, out)
        return out.reshape(shape + (nl,))

    def _lookup(self, flat, w1, w2, out1, out2) -> None:
        nl = self.wavelengths.size
        has_sun = self._sun1 is not None
        sun = self.sun_direction if has_sun else np.zeros(3)
        sun1 = self._sun1 if has_sun else np.zeros((2, nl))
        sun2 = self._sun2 if has_sun else np.zeros((2, nl))
        combine = w1 is not None
        if not combine:
            w1 = w2 = np.zeros((1, 1))
        _lookup_kernel(flat, self.sun_azimuth, self._theta[1], self._phi[1], self._sky1, self._sky2, has_sun, sun,
                       sun1, sun2, _GAMMA_STEP, combine, w1, w2, out1, out2)


@parallel_kernel
def _lookup_kernel(d, sun_az, dtheta, dphi, sky1, sky2, has_sun, sun, sun1, sun2, dgamma, combine, w1, w2, out1,
                   out2):
    """``(S_1^0, S_2^0)`` of each direction into ``out1``, ``out2``; with ``combine``, ``S_1^0 w1 + S_2^0 w2``
    into ``out1`` (``out2`` unused)."""
    n = d.shape[0]
    nt, npf, nl = sky1.shape
    ng = sun1.shape[0]
    for i in numba.prange(n):
        theta = math.acos(min(1.0, max(-1.0, d[i, 2])))
        phi = math.atan2(d[i, 0], d[i, 1]) - sun_az
        phi = abs((phi + math.pi) % (2.0 * math.pi) - math.pi)
        gt = theta / dtheta
        gp = phi / dphi
        it = min(max(int(gt), 0), nt - 2)
        ip = min(max(int(gp), 0), npf - 2)
        ft = min(max(gt - it, 0.0), 1.0)
        fp = min(max(gp - ip, 0.0), 1.0)
        w00 = (1.0 - ft) * (1.0 - fp)
        w01 = (1.0 - ft) * fp
        w10 = ft * (1.0 - fp)
        w11 = ft * fp
        j = 0
        f = 0.0
        if has_sun:
            c = min(1.0, max(-1.0, d[i, 0] * sun[0] + d[i, 1] * sun[1] + d[i, 2] * sun[2]))
            g = math.acos(c) / dgamma
            j = min(max(int(g), 0), ng - 2)
            f = min(max(g - j, 0.0), 1.0)
        for k in range(nl):
            a1 = (w00 * sky1[it, ip, k] + w01 * sky1[it, ip + 1, k] + w10 * sky1[it + 1, ip, k]
                  + w11 * sky1[it + 1, ip + 1, k])
            a2 = (w00 * sky2[it, ip, k] + w01 * sky2[it, ip + 1, k] + w10 * sky2[it + 1, ip, k]
                  + w11 * sky2[it + 1, ip + 1, k])
            if has_sun:
                a1 += sun1[j, k] * (1.0 - f) + sun1[j + 1, k] * f
                a2 += sun2[j, k] * (1.0 - f) + sun2[j + 1, k] * f
            if combine:
                out1[i, k] = a1 * w1[i, k] + a2 * w2[i, k]
            else:
                out1[i, k] = a1
                out2[i, k] = a2
