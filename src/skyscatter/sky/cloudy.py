"""Skies under, in and above horizontally uniform cloud layers, fast: :class:`CloudySky`.

The atmosphere of :class:`~skyscatter.atmosphere.AtmosphereParameters` (Rayleigh, aerosol, ozone, Lambertian
ground) with one or more water cloud layers (:class:`~skyscatter.atmosphere.clouds.CloudLayer`: Mie droplets,
tabulated phase function with its diffraction peak) is cut into homogeneous plane-parallel layers (the clouds'
bases and tops and the observer's altitude among the boundaries; each layer's Rayleigh, aerosol, ozone and
cloud optical depths the exact integrals of the medium's density profiles over it) and solved per sun position
and wavelength by the discrete-ordinate method, DISORT ([Stamnes1988]; the ``disortpp`` binding): all orders of
scattering, exactly in optical depth (an optical depth of 60 costs what 1 costs), delta-M scaling of the
droplets' forward peak ([Wiscombe1977]); the Nakajima-Tanaka intensity correction ([NakajimaTanaka1988]) is
requested, but disortpp 1.2.1's flag alone changes no intensity (it acts only with `intensity_corr_buras`;
docs/clouds.md), so its TMS single-scattering correction is added here for the light seen looking up
(:func:`_single_scatter_correction`) and the forward peak's light is restored about the sun
(:func:`_restore_forward_peak`).

Light on the cloud top (``illumination="tables"``, the default, for observers at or below the highest cloud
top; always in twilight): the column is solved from the cloud top down, lit there by the clear sky of the
precomputed tables of the same air ([Bruneton2008]; small tables, cached): the sun's transmittance through the
spherical atmosphere (a sun 2 deg high) and the sky's radiance with its angular distribution as the column's
upper boundary (:meth:`CloudySky._sky_light`: parallel beams on Gauss nodes in the cosine, the azimuth by
Fourier series; the sky seen through the cloud unscattered or in the droplets' forward peak is the tables'
radiance), plus the cloud's light the air above sends back (adding method, [Liou2002], with the air's plane
albedo for the angles the cloud reflects into: :meth:`CloudySky._interreflection`).
``illumination="column"`` (and observers above the clouds) solve the whole air in DISORT with the sun's beam
attenuated along its chord through spherical shells (the pseudo-spherical beam of [Dahlback1991], reached
through an effective cosine: disortpp's own spherical beam
gave negative intensities).

The solution is the radiance at the observer's altitude on a grid of view zenith angles and azimuths from the
sun (:func:`_grid_nodes`: 2 x 5 deg, finer about the sun; the field is symmetric about the sun's vertical
plane) at :data:`GRID_WAVELENGTHS`, with the forward peak's light restored about the sun
(:func:`_restore_forward_peak`); a direction's radiance is the bilinear interpolation on that grid, a
wavelength's the linear interpolation of the radiance per unit solar irradiance times the solar spectrum there
(clamped outside the grid: the clouds are grey). XYZ is computed per grid node from the same spectra, so
``xyz`` and the spectrum agree exactly.

Observers above the highest cloud top see it over a sphere (:meth:`CloudySky._spherical_view`): rays that miss
the cloud shell show the tables' clear air (the limb from orbit), rays that hit it the column's radiance at the
hit point's local angles and sun zenith through the air's chord.

Why this design, its accuracy against the Monte Carlo and its limits (the air's in-scatter above the clouds
plane-parallel at an equivalent angle; radiance under clouds measured against DISORT, not the Monte Carlo):
docs/clouds.md, "Fast cloud layers". In short, the cloud inside the precomputed tables (it fits their spherical
symmetry) was off by +135 to +330 % in the diffuse irradiance under optical depth 15: a 500 m layer falls between
their altitude samples and ray steps, and a thick cloud's orders do not settle into the tables' geometric tail
after six.
"""

from __future__ import annotations

import math
from functools import cached_property, lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere import AtmosphereParameters
from ..conventions import as_directions
from ..errors import InvalidParameterError, MissingDependencyError
from ..spectral import DEFAULT_WAVELENGTHS, REFERENCE_WAVELENGTHS, as_wavelengths, spectrum_to_xyz
from .base import SkyModel, SunSkyMixin, check_sun_angles

__all__ = ["CloudySky", "GRID_WAVELENGTHS", "MAX_CLOUD_OPTICAL_DEPTH", "air_plane_albedo", "air_return_radiance",
           "air_spherical_albedo", "cloud_column", "ozone_read"]

#: Wavelengths [nm] at which the radiance field is solved: 380-780 nm every 25 nm (17).
GRID_WAVELENGTHS = np.arange(380.0, 781.0, 25.0)
#: Largest cloud optical depth at 550 nm accepted (the range measured against the Monte Carlo).
MAX_CLOUD_OPTICAL_DEPTH = 60.0
#: Spacing of the view zenith angles of the radiance grid [deg].
ZENITH_STEP_DEG = 2.0
#: Spacing of the azimuths (relative to the sun) of the radiance grid [deg].
AZIMUTH_STEP_DEG = 5.0
#: Angles [deg] from the sun at which the radiance grid has extra nodes (the aureole).
AUREOLE_OFFSETS_DEG = (0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0)
#: Legendre moments of the phase functions given to DISORT (delta-M keeps the first 2 x streams).
PHASE_MOMENTS = 256
#: Angles from the sun [deg] over which the TMS single-scattering correction fades in (nearer the sun the forward
#: peak's lobe, :func:`_restore_forward_peak`, carries delta-M's missing light).
TMS_FADE_DEG = (5.0, 10.0)
#: Gauss-Legendre nodes in the cosine of the clear sky's light on the cloud top (its angular distribution).
SKY_NODES = 8
#: The column's response to the sky's light on its top is solved at every this many of :data:`GRID_WAVELENGTHS`
#: (and the last), linearly interpolated between.
SKY_WAVELENGTH_STEP = 4
#: Most DISORT streams of the column's response to the sky's light (the model's ``streams`` if fewer).
SKY_STREAMS = 8
#: Sun elevation [rad] below which the direct beam is not traced (twilight: the tables' clear sky lights the
#: cloud top).
MIN_BEAM_ELEVATION = math.radians(0.5)
#: Sizes of the clear-sky tables that light the cloud top (:mod:`skyscatter.precomputed`): only the sun's
#: transmittance and the sky's irradiance at one altitude are read, so the 4D tables are coarser than the
#: defaults (1/8 of their texels; the irradiance at the cloud top within 0.3 % of the default tables, docs).
COUPLING_TABLE_SIZES = {"scattering_r": 16, "scattering_mu": 64, "scattering_nu": 4}
#: Highest observer altitude accepted [m] (as the precomputed sky).
MAX_ALTITUDE = 1.0e8


@lru_cache(maxsize=4)
def _gauss_legendre(n: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Gauss-Legendre nodes and weights on [-1, 1] (``numpy.polynomial.legendre.leggauss``, kept: computing the 48
    of :func:`_profile_integral` took 2.5 ms, some 13 times a sky's solve)."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w


@lru_cache(maxsize=1)
def _blas_controller() -> Any:
    """threadpoolctl's controller, made once (each ``threadpool_limits`` call looks for the loaded libraries
    again: 0.5 ms)."""
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


def _profile_integral(profile: Any, lo: NDArray[np.float64], hi: NDArray[np.float64], n: int = 48
                      ) -> NDArray[np.float64]:
    """Integral [m] of a density profile over each altitude interval [lo, hi] (Gauss-Legendre, n nodes; the
    intervals never straddle a cloud's base or top, so the integrands are smooth)."""
    x, w = _gauss_legendre(n)
    z = 0.5 * (lo + hi)[:, None] + 0.5 * (hi - lo)[:, None] * x[None, :]
    return (profile(z) * w[None, :]).sum(axis=1) * 0.5 * (hi - lo)


def _grid_nodes(sun_zenith: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """View zenith angles [rad] and azimuths from the sun [deg] of the radiance grid: every
    :data:`ZENITH_STEP_DEG` from 0 to 88 deg, 89.5 and 90.5 deg, every step from 92 to 180 deg; azimuths every
    :data:`AZIMUTH_STEP_DEG` from 0 to 180 deg; and, for a sun above the horizon, nodes at
    :data:`AUREOLE_OFFSETS_DEG` from it in both (the droplets' diffraction peak, about a degree wide, carries up
    to a quarter of the diffuse light under a thin cloud: without these nodes the grid lost 25 % of the
    diffuse irradiance at optical depth 1)."""
    up = np.arange(0.0, 89.0, ZENITH_STEP_DEG)
    deg = np.concatenate([up, [89.5, 90.5], 180.0 - up[::-1]])
    phi = np.arange(0.0, 180.0 + 1e-9, AZIMUTH_STEP_DEG)
    sz = math.degrees(sun_zenith)
    if sz < 89.0:
        off = np.asarray(AUREOLE_OFFSETS_DEG)
        near = np.concatenate([[sz], sz - off, sz + off])
        deg = _distinct(np.concatenate([deg, near[(near > 0.0) & (near < 89.0)]]))
        stretch = max(math.sin(sun_zenith), 0.2)  # an angle from the sun across azimuths is dphi sin(theta)
        phi = _distinct(np.concatenate([phi, np.minimum(off / stretch, 180.0)]))
    return np.radians(deg), phi


def _distinct(values: NDArray[np.float64], gap: float = 0.05) -> NDArray[np.float64]:
    """Sorted values [deg] without those within ``gap`` of the previous one kept (DISORT wants increasing
    cosines)."""
    v = np.sort(values)
    keep = [v[0]]
    for x in v[1:]:
        if x - keep[-1] > gap:
            keep.append(x)
    return np.array(keep)


def _ozone_slant_column(atmosphere: AtmosphereParameters, sun_zenith: float, altitude: float) -> float:
    """Ozone column [m of relative density 1] along the sun's ray from ``altitude`` [m] to the top of the
    atmosphere (the vertical column times the relative optical mass of the ozone profile,
    :func:`~skyscatter.atmosphere.gas_absorption.slant_optical_masses`; the sun at 90 deg from the zenith at most)."""
    from ..atmosphere.gas_absorption import slant_optical_masses

    h = min(max(altitude, 0.0), 0.5 * atmosphere.thickness)
    mass = float(slant_optical_masses(atmosphere, [min(sun_zenith, 0.5 * math.pi)], h).ozone[0])
    vertical = float(_profile_integral(atmosphere.ozone_density, np.array([h]), np.array([atmosphere.thickness]),
                                       96)[0])
    return mass * vertical


def ozone_read(values: NDArray[np.float64], nodes: NDArray[np.float64], wavelengths: NDArray[np.float64],
               column: float, atmosphere: AtmosphereParameters) -> NDArray[np.float64]:
    """``values`` (..., n_nodes) at the wavelengths ``nodes`` [nm] read at ``wavelengths`` [nm] (within the nodes'
    range) linearly, as their ratio to the ozone transmittance ``O = exp(-k_oz column)`` ([Beer-Lambert]; ``k_oz``
    :meth:`~skyscatter.atmosphere.AtmosphereParameters.ozone_absorption_at`, ``column`` [m] of relative density
    1) that is then taken at the asked wavelength: ``v(l) = lin(v / O)(l) O(l)``.

    Why: the ozone cross-section (the Chappuis band) has kinks a few nm apart that a linear read between nodes
    20-25 nm apart crosses: at 550 nm it is 4.9 % below the chord between 540 and 560 nm. Light that came down
    along a grazing sun's path (sun 2 deg high: an ozone air mass near 11, ozone optical depth about 0.3 at 550 nm)
    was read 1.5 % too dark there per linear read (two reads: tables to grid, grid to the asked wavelength), 2-4.7 %
    too bright at 575 / 600 nm; against the spherical forward photons the cloudy sky's ground diffuse light at 550 nm
    was -2.9..-3.8 % (docs/clouds.md, "The 550 nm deficit is the ozone's wavelength sampling"). With ``column`` 0 it
    is the plain linear read."""
    v = np.asarray(values, dtype=float)
    x = np.asarray(wavelengths, dtype=float)
    i = np.clip(np.searchsorted(nodes, x) - 1, 0, nodes.size - 2)
    w = (x - nodes[i]) / (nodes[i + 1] - nodes[i])
    if column <= 0.0:
        return v[..., i] * (1.0 - w) + v[..., i + 1] * w
    o_nodes = np.exp(-atmosphere.ozone_absorption_at(nodes) * column)
    o_x = np.exp(-atmosphere.ozone_absorption_at(x) * column)
    r = v / o_nodes
    return (r[..., i] * (1.0 - w) + r[..., i + 1] * w) * o_x


def cloud_column(atmosphere: AtmosphereParameters, wavelengths: ArrayLike, observer_altitude: float = 0.0,
                 *, air_layers: int = 24, cloud_sublayers: int = 8
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The medium as plane-parallel layers for DISORT: ``(edges, tau, ssa, moments)``.

    ``edges`` (n + 1,) [m] altitudes from the top of the atmosphere down to the ground (every cloud layer's base
    and top and the observer's altitude among them; the air above the clouds in layers thickening upwards);
    ``tau`` and ``ssa`` (n, n_wl) each layer's optical depth and single-scattering albedo; ``moments``
    (n, n_wl, :data:`PHASE_MOMENTS` + 1) the Legendre moments of its phase function (Rayleigh ``chi_2 = 1/10``,
    the aerosol's and the clouds' tables, :meth:`~skyscatter.atmosphere.phase_table.PhaseTable.legendre_moments`)
    weighted by each component's scattering optical depth.
    """
    wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
    top = atmosphere.thickness
    comps = atmosphere.particle_components
    boxes = [c for c in atmosphere.particles if hasattr(c, "base") and hasattr(c, "top")]
    marks = {0.0, top}
    for c in boxes:
        marks.update(np.linspace(c.base, min(c.top, top), cloud_sublayers + 1).tolist())
    highest = max([c.top for c in boxes] + [0.0])
    marks.update((highest + (top - highest) * (np.geomspace(1.0, 201.0, air_layers + 1) - 1.0) / 200.0).tolist())
    lowest = min([c.base for c in boxes] + [top])
    marks.update(np.linspace(0.0, min(lowest, top), 5).tolist())
    if 0.0 < observer_altitude < top:
        marks.add(float(observer_altitude))
    edges = np.array(sorted(marks))[::-1]
    edges = edges[np.concatenate([[True], np.diff(edges) < -1e-6])]
    hi, lo = edges[:-1], edges[1:]
    rayleigh = _profile_integral(atmosphere.rayleigh_density, lo, hi)[:, None] * atmosphere.rayleigh_scattering_at(wl)
    ozone = _profile_integral(atmosphere.ozone_density, lo, hi)[:, None] * atmosphere.ozone_absorption_at(wl)
    ext = rayleigh + ozone
    sca = rayleigh.copy()
    chi_r = np.zeros(PHASE_MOMENTS + 1)
    chi_r[0], chi_r[2] = 1.0, 0.1
    weighted = rayleigh[:, :, None] * chi_r[None, None, :]
    for comp in comps:
        column = _profile_integral(comp.density, lo, hi)
        if hasattr(comp, "base") and hasattr(comp, "top"):  # a box: the exact overlap with each layer
            column = np.clip(np.minimum(hi, comp.top) - np.maximum(lo, comp.base), 0.0, None)
        if not np.any(column > 0):
            continue
        c_ext = column[:, None] * comp.extinction_at(wl)[None, :]
        c_sca = column[:, None] * comp.scattering_at(wl)[None, :]
        if not np.any(c_sca > 0):
            ext += c_ext
            continue
        chi = comp.phase_table(wl).legendre_moments(PHASE_MOMENTS + 1)  # (n_wl, m + 1)
        ext += c_ext
        sca += c_sca
        weighted += c_sca[:, :, None] * chi[None, :, :]
    ext = np.maximum(ext, 1e-12)
    moments = weighted / np.maximum(sca, 1e-300)[:, :, None]
    moments[..., 0] = 1.0
    ssa = np.clip(sca / ext, 0.0, 1.0 - 1e-9)
    return edges, ext, ssa, moments


def _exact_phase(atmosphere: AtmosphereParameters, wl: NDArray[np.float64], edges: NDArray[np.float64],
                 cos_scat: NDArray[np.float64]) -> NDArray[np.float64]:
    """Each layer's phase function [sr^-1] at the scattering cosines ``cos_scat`` (any shape), (n, n_wl, ...):
    Rayleigh's ``3 / (16 pi) (1 + cos^2)`` and each particle component's full table (diffraction peak included),
    weighted by their scattering optical depths in the layers of :func:`cloud_column` (the same integrals; the
    full tables, where ``cloud_column`` gives their Legendre moments)."""
    hi, lo = edges[:-1], edges[1:]
    c = np.asarray(cos_scat, dtype=float)
    sca = _profile_integral(atmosphere.rayleigh_density, lo, hi)[:, None] * atmosphere.rayleigh_scattering_at(wl)
    total = sca.reshape(sca.shape + (1,) * c.ndim) * (3.0 / (16.0 * math.pi) * (1.0 + c * c))
    sca_sum = sca.copy()
    for comp in atmosphere.particle_components:
        column = _profile_integral(comp.density, lo, hi)
        if hasattr(comp, "base") and hasattr(comp, "top"):
            column = np.clip(np.minimum(hi, comp.top) - np.maximum(lo, comp.base), 0.0, None)
        c_sca = column[:, None] * comp.scattering_at(wl)[None, :]
        if not np.any(c_sca > 0):
            continue
        p = np.moveaxis(comp.phase_table(wl).evaluate(c), -1, 0)  # (n_wl, ...)
        total = total + c_sca.reshape(c_sca.shape + (1,) * c.ndim) * p[None]
        sca_sum += c_sca
    return total / np.maximum(sca_sum, 1e-300).reshape(sca_sum.shape + (1,) * c.ndim)


def _legendre_polynomials(x: NDArray[np.float64], count: int) -> NDArray[np.float64]:
    """Legendre polynomials ``P_l(x)``, l < ``count`` (>= 2), (count, ...) of cosines ``x`` [-] (Bonnet's
    recurrence, [Abramowitz1964] Eq. 8.5.3: ``(n + 1) P_(n+1) = (2n + 1) x P_n - n P_(n-1)``)."""
    leg = np.empty((count,) + x.shape)
    leg[0] = 1.0
    leg[1] = x
    for n in range(1, count - 1):
        leg[n + 1] = ((2 * n + 1) * x * leg[n] - n * leg[n - 1]) / (n + 1)
    return leg


def _single_scatter_correction(tau: NDArray[np.float64], ssa: NDArray[np.float64], moments: NDArray[np.float64],
                               phase: NDArray[np.float64], cos_scat: NDArray[np.float64], mu_view: NDArray[np.float64],
                               mu_beam: float, streams: int, legendre: NDArray[np.float64] | None = None
                               ) -> NDArray[np.float64]:
    """The TMS correction of [NakajimaTanaka1988] (Eqs. 14-15) to DISORT's delta-M radiance of downward light at
    the bottom of the layers ``tau``, ``ssa``, ``moments`` (n,) (n,) (n, m + 1) (one wavelength, from the top
    down), per unit beam flux [sr^-1], at scattering cosines ``cos_scat`` (n_v, n_a) of views whose light travels
    down at cosines ``mu_view`` (n_v,) (> 0), the beam at cosine ``mu_beam``: the single scattering with the
    exact phase ``phase`` (n, n_v, n_a) [sr^-1] over ``1 - f`` minus that with delta-M's truncated series (the
    first ``streams`` moments, ``chi* = (chi - f) / (1 - f)``), both through the scaled layers
    (``tau' = (1 - omega f) tau``, ``omega' = (1 - f) omega / (1 - omega f)``, ``f`` the moment of order
    ``streams``, as DISORT scales; [Wiscombe1977]). disortpp 1.2.1's own flag for it acts only with
    ``intensity_corr_buras`` (docs/clouds.md): without it a thin cloud's radiance away from the sun carries
    delta-M's single-scattering error (-15..+10 % at 16 streams under optical depth 1). ``legendre``:
    :func:`_legendre_polynomials` of ``cos_scat`` and ``streams``, if the caller has them (they do not depend on
    the wavelength)."""
    f = moments[:, streams]
    leg = _legendre_polynomials(cos_scat, streams) if legendre is None else legendre
    ell = np.arange(streams)
    chi_star = (moments[:, :streams] - f[:, None]) / (1.0 - f[:, None])
    truncated = np.tensordot(chi_star * (2 * ell + 1), leg, axes=(1, 0)) / (4.0 * math.pi)  # (n, n_v, n_a)
    tau_s = (1.0 - ssa * f) * tau
    ssa_s = (1.0 - f) * ssa / (1.0 - ssa * f)
    depth = np.concatenate([[0.0], np.cumsum(tau_s)])
    a, b = depth[:-1, None], depth[1:, None]
    # the beam to depth t, scattered there, then to the bottom: exp(-t / mu_beam - (D - t) / mu) integrated over
    # the layer [a, b], written without exp(+...) (no overflow at grazing views)
    mv = mu_view[None, :]
    k = 1.0 / mu_beam - 1.0 / mv  # (1, n_v)
    small = np.abs(k) < 1e-9
    e_a = np.exp(-a / mu_beam - (depth[-1] - a) / mv)
    e_b = np.exp(-b / mu_beam - (depth[-1] - b) / mv)
    atten = np.where(small, (b - a) * np.exp(-depth[-1] / mv), (e_a - e_b) / np.where(small, 1.0, k)) / mv
    excess = phase / (1.0 - f)[:, None, None] - truncated
    return np.einsum("i,iva,iv->va", ssa_s, excess, atten)


def slant_optical_depth(edges: NDArray[np.float64], tau: NDArray[np.float64], bottom_radius: float,
                        altitude: float, mu: float) -> NDArray[np.float64]:
    """Optical depth (n_wl,) from ``altitude`` [m] to the top along a ray of cosine ``mu`` > 0 with the zenith,
    through the spherical shells of ``edges`` [m] (descending) with layer optical depths ``tau`` (n, n_wl):
    each layer's extinction times the ray's chord through its shell (the pseudo-spherical beam)."""
    r0 = bottom_radius + altitude
    hi, lo = edges[:-1], edges[1:]
    b2 = (r0 * r0) * (1.0 - mu * mu)

    def dist(h: NDArray[np.float64]) -> NDArray[np.float64]:
        r = bottom_radius + np.maximum(h, altitude)
        return -r0 * mu + np.sqrt(np.maximum(r * r - b2, 0.0))

    chord = np.maximum(dist(hi) - dist(lo), 0.0)
    k = tau / np.maximum(hi - lo, 1e-9)[:, None]
    return (k * chord[:, None]).sum(axis=0)


def air_spherical_albedo(atmosphere: AtmosphereParameters, wavelengths: ArrayLike, altitude: float, *,
                         streams: int = 16) -> NDArray[np.float64]:
    """Spherical albedo from below (n_wl,) [-] of the air above ``altitude`` [m]: the fraction of an isotropic
    (Lambertian) upward irradiance at ``altitude`` that the air above sends back down through it (the ``s`` of the
    adding method, [Liou2002] Sec. 6.2: a surface of albedo ``r`` under the air receives ``F / (1 - r s)``).

    The air (molecules, aerosol, ozone; ``atmosphere``'s cloud layers left out) above ``altitude`` as the
    plane-parallel layers of :func:`cloud_column`, turned upside down (a plane-parallel medium whose phase functions
    depend on the scattering angle only, lit from below, is the reversed stack lit from above), solved by DISORT
    ([Stamnes1988], flux only, ``streams`` streams) with isotropic light of unit flux on its top and a black floor:
    the reflected flux. Exact for the plane-parallel air, absorption included; the sphere's curvature is left
    out (the upward light of a field tens of kilometres wide meets the air within a few scale heights)."""
    return _air_from_below(atmosphere, wavelengths, altitude, None, streams)[0]


def air_plane_albedo(atmosphere: AtmosphereParameters, wavelengths: ArrayLike, altitude: float, cosines: ArrayLike,
                     *, streams: int = 16) -> NDArray[np.float64]:
    """Plane albedo from below (n_mu, n_wl) [-] of the air above ``altitude`` [m]: the fraction of a parallel
    upward beam's flux at ``altitude`` travelling at the cosines ``cosines`` (n_mu,) (> 0) with the vertical that the
    air above sends back down through it; as :func:`air_spherical_albedo` (DISORT on the reversed stack,
    [Stamnes1988]) for a beam in place of isotropic light, every cosine from one solve per wavelength in DISORT's
    albedo mode (:func:`_air_from_below`). Its mean over the cosines weighted by ``2 mu`` is the
    spherical albedo ([Liou2002] Sec. 6.2); grazing light is sent back more than Lambertian light (its long path)."""
    return _air_from_below(atmosphere, wavelengths, altitude, np.atleast_1d(np.asarray(cosines, dtype=float)),
                           streams)


def air_return_radiance(atmosphere: AtmosphereParameters, wavelengths: ArrayLike, altitude: float,
                        cosines: ArrayLike, *, streams: int = 16) -> NDArray[np.float64]:
    """Radiance [sr^-1] (n_mu, n_wl) that the air above ``altitude`` [m] sends back down at the cosines ``cosines``
    (n_mu,) (> 0, with the downward vertical) per unit of isotropic (Lambertian) upward flux at ``altitude``: the
    angular shape of :func:`air_spherical_albedo`'s light (the same DISORT solve on the reversed stack,
    [Stamnes1988], with intensities), brightest near the horizon (the long paths through the air)."""
    c = np.atleast_1d(np.asarray(cosines, dtype=float))
    return _air_from_below(atmosphere, wavelengths, altitude, None, streams, c)[1]


def _air_from_below(atmosphere: AtmosphereParameters, wavelengths: ArrayLike, altitude: float,
                    cosines: NDArray[np.float64] | None, streams: int, user: NDArray[np.float64] | None = None,
                    column: tuple[NDArray[np.float64], ...] | None = None) -> Any:
    """The reflectance (n_mu, n_wl) of the reversed air stack above ``altitude`` [m] for beams at ``cosines``
    (isotropic light if None: one row) (:func:`air_spherical_albedo`, :func:`air_plane_albedo`); with ``user``
    cosines (isotropic light only), also the reflected radiance there (n_user, n_wl) (:func:`air_return_radiance`).
    ``column``: :func:`cloud_column` of the air without its particles' cloud layers at ``wavelengths`` and
    ``altitude``, if the caller has it.

    The plane albedo for all ``cosines`` is one DISORT solve per wavelength in its special mode for the albedo
    of the whole medium against the incident angle (``ibcnd = 1``, [Stamnes1988]: the albedo at the user angles
    from the solution for isotropic light by reciprocity), not one beam per cosine and wavelength: the same
    discrete-ordinate solution (within 3e-10 of the beams' reflected fluxes at 16 streams), at the cost of
    one solve."""
    import disortpp

    wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
    if column is None:
        column = cloud_column(atmosphere.replace(particles=()), wl, observer_altitude=altitude)
    edges, tau, ssa, moments = column
    above = np.flatnonzero(edges[1:] >= altitude - 1e-6)  # layers whose lower edge is at or above ``altitude``
    out = np.zeros((1 if cosines is None else cosines.size, wl.size))
    radiance = None if user is None else np.zeros((user.size, wl.size))
    if above.size == 0:
        return out if user is None else (out, radiance)
    rev = above[::-1]  # the layer next to ``altitude`` first
    angles = user if cosines is None else cosines
    sort = None if angles is None else np.argsort(angles)
    for k in range(wl.size):
        cfg = disortpp.DisortConfig(int(rev.size), streams, streams)
        cfg.flags.use_lambertian_surface = True
        if cosines is not None:
            cfg.flags.ibcnd = disortpp.BoundaryConditionType.Special  # albedo against the incident angle
        else:
            cfg.flags.comp_only_fluxes = user is None
        if angles is not None:
            cfg.flags.use_user_mu = True
            cfg.num_user_mu = int(angles.size)
            cfg.num_phi = 1
        if user is not None:
            cfg.flags.use_user_tau = True
            cfg.num_user_tau = 1
        cfg.allocate()
        if angles is not None and sort is not None:
            cfg.mu_user = [float(v) for v in angles[sort]]
            cfg.phi_user = [0.0]
        if user is not None:
            cfg.tau_user = [0.0]
        cfg.delta_tau = [float(t) for t in tau[rev, k]]
        cfg.single_scat_albedo = [float(w) for w in ssa[rev, k]]
        cfg.phase_function_moments = moments[rev, k, : streams + 1].tolist()
        if cosines is None:
            cfg.bc.direct_beam_flux = 0.0
            cfg.bc.direct_beam_mu = 0.5
            cfg.bc.isotropic_flux_top = 1.0 / math.pi  # radiance 1 / pi: a flux of 1
        cfg.bc.surface_albedo = 0.0
        res = disortpp.DisortSolver().solve(cfg)
        if cosines is not None and sort is not None:
            out[sort, k] = np.asarray(res.albedo_medium)[: cosines.size]  # the albedo at the user cosines
            continue
        out[0, k] = float(res.flux_up[0])
        if radiance is not None and sort is not None:
            radiance[sort, k] = np.asarray(res.intensity)[0, :, 0]  # [level][user mu][azimuth]
    return out if user is None else (out, radiance)


def _beam_config(disortpp: Any, tau: NDArray[np.float64], ssa: NDArray[np.float64], moments: NDArray[np.float64],
                 n_moments: int, streams: int, tau_user: list[float], mu_user: NDArray[np.float64],
                 phi_user: NDArray[np.float64], beam_flux: float, beam_mu: float, albedo: float) -> Any:
    """The disortpp set-up ([Stamnes1988]) the cloudy sky's column solves share: layers top down of optical depths
    ``tau``, single-scattering albedos ``ssa`` and phase moments ``moments`` (n_layers, n_moments + 1 or more) over a
    Lambertian ground of ``albedo``, a beam of flux ``beam_flux`` [per unit of the caller's flux] at cosine
    ``beam_mu``, ``streams`` streams, radiances at the optical depths ``tau_user``, the cosines ``mu_user`` (DISORT's
    sign: positive travels up) and the azimuths ``phi_user`` [deg]. The caller adds any further flag and solves."""
    cfg = disortpp.DisortConfig(int(len(tau)), streams, n_moments)
    cfg.flags.use_user_mu = True
    cfg.flags.use_user_tau = True
    cfg.flags.use_lambertian_surface = True
    cfg.num_user_tau = len(tau_user)
    cfg.num_user_mu = int(len(mu_user))
    cfg.num_phi = int(len(phi_user))
    cfg.allocate()
    cfg.delta_tau = [float(t) for t in tau]
    cfg.single_scat_albedo = [float(v) for v in ssa]
    cfg.phase_function_moments = np.asarray(moments).tolist()
    cfg.tau_user = [float(t) for t in tau_user]
    cfg.mu_user = [float(v) for v in mu_user]
    cfg.phi_user = [float(v) for v in phi_user]
    cfg.bc.direct_beam_flux = float(beam_flux)
    cfg.bc.direct_beam_mu = float(beam_mu)
    cfg.bc.direct_beam_phi = 0.0
    cfg.bc.surface_albedo = float(albedo)
    return cfg


@lru_cache(maxsize=1)
def _hemisphere_quadrature() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Midpoint quadrature of the upper hemisphere, 0.5 deg x 0.5 deg: unit directions (64800, 3) and their
    weights ``cos(theta) dOmega`` [sr] (the irradiance's; made once)."""
    n_t, n_p = 180, 360
    t = (np.arange(n_t) + 0.5) * (0.5 * math.pi / n_t)
    p = (np.arange(n_p) + 0.5) * (2.0 * math.pi / n_p)
    tt, pp = np.meshgrid(t, p, indexing="ij")
    dirs = np.stack([np.sin(tt) * np.sin(pp), np.sin(tt) * np.cos(pp), np.cos(tt)], axis=-1).reshape(-1, 3)
    weight = (np.cos(tt) * np.sin(tt)).reshape(-1) * (0.5 * math.pi / n_t) * (2.0 * math.pi / n_p)
    weight.setflags(write=False)  # (``dirs`` stays writable: numba compiles read-only arrays separately)
    return dirs, weight


def _restore_forward_peak(rad: NDArray[np.float64], theta: NDArray[np.float64], phi: NDArray[np.float64],
                          sun_zenith: float, down: NDArray[np.float64], peak_limit: NDArray[np.float64],
                          width: float = math.radians(1.5)) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The grid's radiance with the light of the droplets' forward peak put back around the sun.

    Delta-M ([Wiscombe1977]) moves the phase function's forward peak into the direct beam; its light is in
    DISORT's diffuse flux and in none of the intensities disortpp 1.2.1 returns (its Nakajima-Tanaka flag
    changes nothing) (measured: the intensities integrated to
    75 % of the flux under optical depth 1, 99 % under 5, 99.99 % under 15). That light reaches the observer
    within the peak's width of the sun, so the difference between DISORT's downward diffuse flux ``down`` (n_wl,)
    and the grid's integral is added as a lobe ``exp(-(gamma / width)^2)`` about the sun, scaled so that the
    grid (as the lookup interpolates it) integrates to the flux. ``rad`` (n_theta, n_phi, n_wl) per unit solar
    irradiance; ``theta`` [rad], ``phi`` [rad] its nodes.

    The lobe carries at most ``peak_limit`` (n_wl,): the light delta-M can have moved, the beam scattered only into
    the truncated peak, ``mu F0 (exp(-tau' / mu) - exp(-tau / mu))`` with the scaled optical depth ``tau' = sum (1 -
    omega f) tau`` (the delta-M scaling of [Wiscombe1977]). Beyond it the difference between the flux and the grid's
    integral is the quadrature's error, not peak light: under a thick cloud and a low sun (optical depth 20, sun 4
    deg) that error, some 1e-4 of the flux, made a spot three times the overcast's radiance about a sun the cloud
    hides entirely. Returns the restored grid and the lobe's flux (n_wl,) (the same units as ``down``)."""
    from .cloudy_kernels import grid_lookup

    dirs, weight = _hemisphere_quadrature()
    gt, gp = np.meshgrid(theta, phi, indexing="ij")
    cos_gamma = np.cos(gt) * math.cos(sun_zenith) + np.sin(gt) * math.sin(sun_zenith) * np.cos(gp)
    lobe = np.exp(-(np.arccos(np.clip(cos_gamma, -1.0, 1.0)) / width) ** 2)
    lobe[theta >= 0.5 * math.pi] = 0.0
    both = np.concatenate([rad, lobe[:, :, None]], axis=2)
    out = np.empty((dirs.shape[0], both.shape[2]))
    grid_lookup(dirs, 0.0, theta, phi, np.ascontiguousarray(both), out)
    integral = weight @ out  # (n_wl + 1,)
    missing = np.minimum(np.maximum(down - integral[:-1], 0.0), np.maximum(peak_limit, 0.0))
    if integral[-1] <= 0:
        return rad, np.zeros_like(missing)
    return rad + lobe[:, :, None] * (missing / integral[-1])[None, None, :], missing


class CloudySky(SunSkyMixin, SkyModel):
    """Sky under, in or above a horizontally uniform water cloud layer (module docstring: DISORT on the medium).

    Parameters
    ----------
    sun_zenith, sun_azimuth : float
        Sun position at the observer [rad]; zenith in [0, pi] (below the horizon: twilight, lit at the cloud top
        by the precomputed clear sky).
    cloud_optical_depth : float
        Optical depth at 550 nm of the water cloud layer, in [0, :data:`MAX_CLOUD_OPTICAL_DEPTH`] (default 15,
        a stratus; 0 = no cloud).
    cloud_base, cloud_top : float
        Altitudes of the layer's base and top [m], ``0 <= base < top <= 20 km`` (default 1000 and 1500 m).
    cloud_effective_radius : float
        The droplets' effective radius [m], in [1, 50] um (default 10 um; effective variance 0.1; Mie optics).
    ground_albedo : float, optional
        Ground albedo [-] in [0, 1] (default: the atmosphere's, 0.1 for the Earth defaults).
    altitude : float
        Observer altitude [m], 0 to 1e8 (above the atmosphere's top: the radiance leaving its top).
    atmosphere : AtmosphereParameters, optional
        The air (default: the Earth defaults); its own ``particles`` (further cloud layers) are kept.
    streams : int
        DISORT streams (even, 4 to 64; default 16).

    Raises
    ------
    InvalidParameterError
        A parameter outside its range (one message each), base not below top.
    """

    model_name = "cloudy"
    renders_ground = True

    def __init__(self, sun_zenith: float, sun_azimuth: float = 0.0, *, cloud_optical_depth: float = 15.0,
                 cloud_base: float = 1000.0, cloud_top: float = 1500.0, cloud_effective_radius: float = 10e-6,
                 ground_albedo: float | None = None, altitude: float = 0.0,
                 atmosphere: AtmosphereParameters | None = None, streams: int = 16,
                 illumination: str = "tables") -> None:
        zen, azi = check_sun_angles(sun_zenith, sun_azimuth, allow_below_horizon=True)
        from ..atmosphere.clouds import CloudLayer

        try:
            import disortpp  # noqa: F401
        except ImportError:
            raise MissingDependencyError("the cloudy sky needs the package 'disortpp', a dependency of skyscatter: "
                                         "this install is incomplete (pip install disortpp)") from None

        tau = _number("cloud_optical_depth", cloud_optical_depth, 0.0, MAX_CLOUD_OPTICAL_DEPTH, "")
        base = _number("cloud_base", cloud_base, 0.0, 20000.0, "m")
        top = _number("cloud_top", cloud_top, 0.0, 20000.0, "m")
        radius = _number("cloud_effective_radius", cloud_effective_radius, 1e-6, 50e-6, "m")
        layer = CloudLayer(base, top, tau, effective_radius=radius)  # refuses base >= top
        alt = _number("altitude", altitude, 0.0, MAX_ALTITUDE, "m")
        if ground_albedo is not None:
            ground_albedo = _number("ground_albedo", ground_albedo, 0.0, 1.0, "")
        if isinstance(streams, bool) or not isinstance(streams, (int, np.integer)) or streams % 2 \
                or not 4 <= streams <= 64:
            raise InvalidParameterError(f"streams must be an even whole number, 4 to 64; got {streams!r}")
        if illumination not in ("column", "tables"):
            raise InvalidParameterError(f"illumination must be 'column' or 'tables'; got {illumination!r}")
        self.illumination = illumination
        air = AtmosphereParameters() if atmosphere is None else atmosphere
        if not isinstance(air, AtmosphereParameters):
            raise InvalidParameterError(f"atmosphere must be AtmosphereParameters; got {type(air).__name__}")
        if top >= air.thickness:
            raise InvalidParameterError(f"cloud_top ({top:g} m) must be below the atmosphere's top "
                                        f"({air.thickness:g} m)")
        # A layer of optical depth 0 is kept (an empty shell): the sky is then the tables' clear sky carried down
        # through the clear column as for any layer, continuous in the optical depth. Without it the whole clear
        # column was solved by DISORT with its pseudo-spherical beam, which at a low sun is far too dark (sun 2 deg:
        # 0.60-0.67 of the sky of optical depth 0.001 at 450-650 nm; docs/clouds.md).
        changes: dict[str, Any] = {"particles": (*air.particles, layer)}
        if ground_albedo is not None:
            changes["ground_albedo"] = ground_albedo
        self.atmosphere = air.replace(**changes) if changes else air
        self.sun_zenith = zen
        self.sun_azimuth = azi
        self.altitude = alt
        self.cloud_layer = layer
        self.streams = int(streams)
        self.sun_angular_radius = self.atmosphere.sun_angular_radius
        self._remember(cloud_optical_depth=tau, cloud_base=base, cloud_top=top, cloud_effective_radius=radius,
                       ground_albedo=ground_albedo, altitude=alt, atmosphere=atmosphere, streams=self.streams,
                       illumination=illumination)

    def __repr__(self) -> str:
        tau = 0.0 if self.cloud_layer is None else self.cloud_layer.optical_depth_550
        return (f"CloudySky(sun_zenith={self.sun_zenith:.6g}, sun_azimuth={self.sun_azimuth:.6g}, "
                f"cloud_optical_depth={tau:g}, altitude={self.altitude:g})")

    # ------------------------------------------------------------------ the solution

    @cached_property
    def _field(self) -> dict[str, NDArray[np.float64]]:
        """The DISORT solution: radiance per unit solar irradiance on the (zenith, relative azimuth) grid
        (n_theta, n_phi, n_wl) [sr^-1], the direct transmittance to the sun (n_wl,), the diffuse down and up
        fluxes per unit solar irradiance (n_wl,) at the observer."""
        # The products here are small (the TMS correction's Legendre sums: (36 x 16) by (16 x 2610) per
        # wavelength): one BLAS thread runs them at full speed, where OpenBLAS's two threads on the busy 2-core
        # machine took 15 ms per product instead of 0.1 ms (three solves of tests/test_cloudy_radiance.py, 16
        # streams: 1.33 instead of 0.70 CPU-s, load 4.6).
        # The products are the same (OpenBLAS splits the output among its threads, not the sums).
        with _blas_controller().limit(limits=1, user_api="blas"):
            return self._solve()

    def _solve(self) -> dict[str, NDArray[np.float64]]:
        """:attr:`_field`, computed."""
        import disortpp

        atm = self.atmosphere
        wl = GRID_WAVELENGTHS
        top = atm.thickness
        obs = min(self.altitude, top)
        edges, tau, ssa, moments = self._column
        mu0 = math.cos(self.sun_zenith)
        beam = mu0 > math.sin(MIN_BEAM_ELEVATION)
        ref = max((c.top for c in atm.particles if hasattr(c, "top")), default=0.0)
        # the coupling with the tables needs a cloud and an observer at or below its top (twilight: always)
        fed = ref > 0 and (not beam or (self.illumination == "tables" and obs <= ref))
        if fed:
            # the column starts at the highest cloud top, lit there by the clear sky of the tables (twilight)
            keep = int(np.argmin(np.abs(edges - ref)))
            if keep >= edges.size - 1:
                keep = 0
            edges, tau, ssa, moments = edges[keep:], tau[keep:], ssa[keep:], moments[keep:]
            obs = min(obs, float(edges[0]))
        cum = np.concatenate([np.zeros((1, wl.size)), np.cumsum(tau, axis=0)])
        level = int(np.argmin(np.abs(edges - obs)))
        theta, phi = _grid_nodes(self.sun_zenith)
        mu_user = -np.cos(theta)  # DISORT: mu < 0 travels down (seen looking up)
        order = np.argsort(mu_user, kind="stable")
        if beam and not fed:
            # the spherical beam: DISORT's beam takes the cosine mu_eff whose plane-parallel attenuation down to
            # the highest cloud top equals the chord through the spherical shells, and the flux that keeps
            # the irradiance there right (mu0 F0 T_sph)
            above = cum[int(np.argmin(np.abs(edges - ref)))]
            slant = slant_optical_depth(edges, tau, atm.bottom_radius, ref, mu0)
            mu_eff = np.clip(np.divide(above, slant, out=np.full(wl.size, mu0), where=slant > 0), mu0, 1.0)
        else:
            mu_eff = np.ones(wl.size)
        albedo = atm.ground_albedo_at(wl)
        rad = np.zeros((theta.size, phi.size, wl.size))
        down = np.zeros(wl.size)
        up = np.zeros(wl.size)
        if fed:
            sun_top, sky_iso = self._table_illumination(wl, ref)
            beam_flux = sun_top if beam else np.zeros(wl.size)
            mu_eff = np.full(wl.size, max(mu0, 1e-3))
            # the clear sky's light on the cloud top with its angular distribution (:meth:`_sky_light`)
            sky = self._sky_light(wl, ref, theta, np.radians(phi), tau, ssa, moments, level, albedo, sky_iso)
        else:
            beam_flux = mu0 / mu_eff if beam else np.zeros(wl.size)
        top_up = np.zeros(wl.size)  # the column's upward flux at its top under the sun's beam (fed only)
        rising = np.nonzero(theta > 0.5 * math.pi)[0]  # the rows of light travelling up
        top_rising = np.zeros((rising.size, wl.size))  # its azimuthal mean radiance there [sr^-1]
        for k in range(wl.size):
            if fed and beam_flux[k] <= 0.0:
                continue  # twilight: the sky alone lights the column (:meth:`_sky_light`)
            cfg = _beam_config(disortpp, tau[:, k], ssa[:, k], moments[:, k, :], PHASE_MOMENTS, self.streams,
                               [0.0, float(cum[level, k])] if fed else [float(cum[level, k])], mu_user[order], phi,
                               beam_flux[k], mu_eff[k], albedo[k])
            cfg.flags.intensity_corr_nakajima = True
            cfg.bc.isotropic_flux_top = 0.0
            res = disortpp.DisortSolver().solve(cfg)
            lu = 1 if fed else 0
            vals = np.asarray(res.intensity)[lu]  # (n_theta, n_phi): [level][user mu][azimuth] in one copy
            rad[order, :, k] = vals
            down[k] = res.flux_down[lu]
            up[k] = res.flux_up[lu]
            if fed:
                top_up[k] = res.flux_up[0]
                mean = np.empty(theta.size)
                mean[order] = np.asarray(res.intensity_azimuth_avg)[0]
                top_rising[:, k] = mean[rising]
        if fed:
            # the cloud's light that the air above sends back down (:meth:`_interreflection`), with the angular
            # shape of the air's return (uniform in azimuth, brightest near the horizon): through the column as
            # the sky's beams (their m = 0 terms) and seen through it
            top_down = mu_eff * beam_flux + math.pi * sky_iso
            up_rows = np.nonzero(theta < 0.5 * math.pi)[0]
            clear_up, clear_rising = self._clear_below(wl, ref, theta, np.radians(phi), beam_flux, mu_eff, albedo,
                                                       sky_iso)
            extra, shape_nodes, shape_rows = self._interreflection(
                wl, ref, top_up + sky["top_up"], top_down, -np.cos(theta[rising]), top_rising + sky["top_rising"],
                sky["nodes"], np.cos(theta[up_rows]), clear_up, clear_rising)
            boundary = sky["ring"][:, None] * shape_nodes * extra[None, :]  # (n_mu, n_wl): each ring's beam flux
            rad += sky["radiance"] + np.einsum("ik,itk->tk", boundary, sky["g0"])[:, None, :]
            rad[up_rows] += (shape_rows * extra[None, :] * sky["through"])[:, None, :]
            node_down, node_up, _ = np.einsum("ik,ick->ck", boundary, sky["node_fluxes"])
            down += sky["down"] + node_down
            up += sky["up"] + node_up
        if beam and level > 0:
            # delta-M's single scattering replaced by the exact phase's (TMS) for the light seen looking up,
            # faded in from 5 to 10 deg from the sun (nearer, the forward peak's lobe below carries that light)
            up_rows = np.nonzero(theta < 0.5 * math.pi)[0]
            gt, gp = np.meshgrid(theta[up_rows], np.radians(phi), indexing="ij")
            cos_scat = np.cos(gt) * mu0 + np.sin(gt) * math.sin(self.sun_zenith) * np.cos(gp)
            gamma = np.degrees(np.arccos(np.clip(cos_scat, -1.0, 1.0)))
            fade = np.clip((gamma - TMS_FADE_DEG[0]) / (TMS_FADE_DEG[1] - TMS_FADE_DEG[0]), 0.0, 1.0)
            phase = _exact_phase(atm, wl, edges[:level + 1], cos_scat)  # (level, n_wl, n_up, n_phi)
            mu_view = np.cos(theta[up_rows])
            leg = _legendre_polynomials(cos_scat, self.streams)  # the same at every wavelength
            for k in range(wl.size):
                corr = _single_scatter_correction(tau[:level, k], ssa[:level, k], moments[:level, k], phase[:, k],
                                                  cos_scat, mu_view, float(mu_eff[k]), self.streams, leg)
                rad[up_rows, :, k] += beam_flux[k] * fade * corr
        rad = np.maximum(rad, 0.0)
        smooth = rad  # without the forward peak's lobe (a table on a coarser grid puts that light back itself)
        peak = np.zeros(wl.size)
        if beam:
            # delta-M's truncated fraction per layer is the moment of order `streams` (DISORT's f = PMOM(NSTR))
            f = moments[:, :, self.streams]
            scaled = np.concatenate([np.zeros((1, wl.size)), np.cumsum((1.0 - ssa * f) * tau, axis=0)])[level]
            peak_limit = mu_eff * beam_flux * (np.exp(-scaled / mu_eff) - np.exp(-cum[level] / mu_eff))
            rad, peak = _restore_forward_peak(rad, theta, np.radians(phi), self.sun_zenith, down, peak_limit)
        return {"radiance": rad, "radiance_smooth": smooth, "forward_peak": peak, "theta": theta,
                "phi": np.radians(phi), "diffuse_down": down, "diffuse_up": up}

    @cached_property
    def _column(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """:func:`cloud_column` of the sky's medium at :data:`GRID_WAVELENGTHS` with the observer's altitude (capped
        at the atmosphere's top) among its edges: made once for the solve and the sun's transmittance."""
        return cloud_column(self.atmosphere, GRID_WAVELENGTHS, min(self.altitude, self.atmosphere.thickness))

    @cached_property
    def _direct(self) -> NDArray[np.float64]:
        """The sun's direct transmittance to the observer at :data:`GRID_WAVELENGTHS` (n_wl,): ``exp(-tau)``
        along its chord through the column's spherical shells (no DISORT solve: the sun alone is cheap)."""
        atm = self.atmosphere
        mu0 = math.cos(self.sun_zenith)
        if mu0 <= math.sin(MIN_BEAM_ELEVATION):
            return np.zeros(GRID_WAVELENGTHS.size)
        obs = min(self.altitude, atm.thickness)
        edges, tau, _, _ = self._column
        return np.exp(-slant_optical_depth(edges, tau, atm.bottom_radius, obs, mu0))

    def _sky_light(self, wl: NDArray[np.float64], ref: float, theta: NDArray[np.float64], phi: NDArray[np.float64],
                   tau: NDArray[np.float64], ssa: NDArray[np.float64], moments: NDArray[np.float64],
                   level: int, albedo: NDArray[np.float64], sky_iso: NDArray[np.float64]
                   ) -> dict[str, NDArray[np.float64]]:
        """The column lit on its top by the clear sky of the tables with its angular distribution, per unit solar
        irradiance: ``radiance`` (n_theta, n_phi, n_wl) [sr^-1] at the observer (optical depth ``depth`` (n_wl,)
        below the top) on the grid's view zenith angles ``theta`` and azimuths from the sun ``phi`` [rad], the
        diffuse ``down`` and ``up`` fluxes there and ``top_up``, the upward flux at the column's top (n_wl,) [-],
        ``top_rising`` the azimuthal mean of the upward radiance there on the grid's rows of rising light (n_up,
        n_wl); and, for other light on the top that is uniform in azimuth, the beams' responses: ``nodes`` (n_mu,)
        and ``ring`` (n_mu,) the nodes' cosines and weights [sr], ``g0`` (n_mu, n_theta, n_wl) [sr^-1] and
        ``node_fluxes`` (n_mu, 3, n_wl) (down, up at the observer, up at the top) per unit beam flux, ``through``
        (n_up, n_wl) the scaled transmittance ``exp(-tau' / mu)`` of the rows of light seen looking up.
        The column: layers ``tau``, ``ssa``, ``moments`` of :func:`cloud_column` (n, n_wl[, m + 1]) from the top, the
        observer at the edge ``level``; ``albedo`` (n_wl,) the ground's; ``sky_iso`` (n_wl,) [sr^-1] the sky's
        irradiance over pi.

        The sky's radiance at the cloud top ``S(mu', phi')`` ([Bruneton2008] Eq. 16, its shape; scaled to the
        flux ``pi sky_iso``, which :meth:`_table_illumination` takes from the same radiance and quadrature, so the
        scale is 1 there) is
        the column's upper boundary. DISORT takes one parallel beam per solve ([Stamnes1988]), so the incident
        field is a sum of beams: :data:`SKY_NODES` Gauss-Legendre nodes ``mu_i`` in the cosine on (0, 1) and, in
        azimuth, the Fourier series of both factors. A beam of unit flux at ``mu_i`` gives the radiance
        ``G_i(theta, phi - phi') = sum_m g_im(theta) cos(m (phi - phi'))``, m < the streams (DISORT's azimuthal
        expansion, [Stamnes1988] Eq. 6; the ``g_im`` from its values at as many azimuths, a cosine transform), and
        the sky ``S(mu_i, phi') = sum_m s_im cos(m phi')``, so that the light scattered towards the observer is
        ``int S G dOmega' = sum_i w_i (2 pi s_i0 g_i0 + pi sum_(m>0) s_im g_im cos(m phi))``. The sky's light that
        reaches the observer unscattered or inside the droplets' forward peak (which delta-M keeps in the beam,
        [Wiscombe1977]) is the sky's radiance seen through the layers' scaled optical depth,
        ``S(theta, phi) exp(-tau' / mu)``, ``tau' = sum (1 - omega f) tau``. Replaces an isotropic sky with
        flux corrections, which under optical depth 1 with the sun 10 deg high was 27 % off at 10-30 deg
        elevation (docs/clouds.md)."""
        import disortpp

        streams = min(self.streams, SKY_STREAMS)
        depth = np.concatenate([np.zeros((1, wl.size)), np.cumsum(tau, axis=0)])[level]
        x, w = np.polynomial.legendre.leggauss(SKY_NODES)
        mu, wmu = 0.5 * (x + 1.0), 0.5 * w
        fine = np.radians(np.arange(0.0, 180.0 + 1e-9, 2.5))
        sky = self._table_sky(wl, ref, np.arccos(mu), fine)  # (n_mu, n_fine, n_wl)
        irr = 2.0 * math.pi * np.einsum("i,ik->k", mu * wmu, np.trapezoid(sky, fine, axis=1) / math.pi)
        norm = np.divide(math.pi * sky_iso, irr, out=np.zeros(wl.size), where=irr > 0)
        m = np.arange(streams)
        # the sky's azimuthal Fourier coefficients s_im (n_mu, n_m, n_wl) (the field is even in phi')
        s_m = np.trapezoid(sky[:, None, :, :] * np.cos(m[:, None] * fine[None, :])[None, :, :, None], fine,
                           axis=2) / math.pi
        s_m[:, 1:] *= 2.0
        s_m *= norm[None, None, :]
        # the azimuths whose DISORT values give the beams' coefficients g_m: a square cosine system
        az = np.linspace(0.0, 180.0, streams)
        inv = np.linalg.inv(np.cos(np.radians(az)[:, None] * m[None, :]))
        mu_user = -np.cos(theta)
        order = np.argsort(mu_user, kind="stable")
        rising = np.nonzero(theta > 0.5 * math.pi)[0]
        # the beams are solved every SKY_WAVELENGTH_STEP grid wavelengths and their responses interpolated
        # linearly between (the column under the cloud top changes slowly with wavelength; the sky's spectrum,
        # which does not, multiplies them at every wavelength)
        solved = np.unique(np.concatenate([np.arange(0, wl.size, SKY_WAVELENGTH_STEP), [wl.size - 1]]))
        g = np.zeros((mu.size, theta.size, streams, solved.size))  # per unit beam flux [sr^-1]
        fluxes = np.zeros((mu.size, 3, solved.size))  # down and up at the observer, up at the top
        top_mean = np.zeros((mu.size, rising.size, solved.size))
        for q, k in enumerate(solved):
            for i in range(mu.size):
                cfg = _beam_config(disortpp, tau[:, k], ssa[:, k], moments[:, k, : streams + 1], streams, streams,
                                   [0.0, max(float(depth[k]), 1e-9)], mu_user[order], az, 1.0, mu[i], albedo[k])
                res = disortpp.DisortSolver().solve(cfg)
                vals = np.asarray(res.intensity)[1]
                g[i, order, :, q] = vals @ inv.T
                fluxes[i, :, q] = (res.flux_down[1] + res.flux_direct_beam[1], res.flux_up[1], res.flux_up[0])
                mean = np.empty(theta.size)
                mean[order] = np.asarray(res.intensity_azimuth_avg)[0]
                top_mean[i, :, q] = mean[rising]
        lo = np.clip(np.searchsorted(solved, np.arange(wl.size), side="right") - 1, 0, max(solved.size - 2, 0))
        hi = np.minimum(lo + 1, solved.size - 1)
        t = np.where(hi > lo, (wl - wl[solved[lo]]) / (wl[solved[hi]] - wl[solved[lo]] + 1e-300), 0.0)

        def at_grid(a: NDArray[np.float64]) -> NDArray[np.float64]:
            return a[..., lo] * (1.0 - t) + a[..., hi] * t

        weight = np.where(m == 0, 2.0 * math.pi, math.pi)
        # sum_i w_i weight_m s_im g_im(theta) (n_theta, n_m, n_wl); each node's ring carries 2 pi w_i s_i0 of flux
        coef = np.einsum("i,m,imk,itmk->tmk", wmu, weight, s_m, at_grid(g))
        share = wmu[:, None] * 2.0 * math.pi * s_m[:, 0, :]  # (n_mu, n_wl)
        node_fluxes = at_grid(fluxes)
        down, up, top_up = np.einsum("ik,ick->ck", share, node_fluxes)
        top_rising = np.einsum("ik,irk->rk", share, at_grid(top_mean))
        radiance = np.einsum("tmk,pm->tpk", coef, np.cos(phi[:, None] * m[None, :]))
        # the sky seen through the layers (unscattered or in the droplets' forward peak)
        rows = np.nonzero(theta < 0.5 * math.pi)[0]
        f = moments[:, :, streams]
        scaled = np.concatenate([np.zeros((1, wl.size)), np.cumsum((1.0 - ssa * f) * tau, axis=0)])
        seen = scaled[level]
        through = self._table_sky(wl, ref, theta[rows], phi) * norm[None, None, :]
        seen_t = np.exp(-seen[None, :] / np.cos(theta[rows])[:, None])  # (n_up, n_wl)
        radiance[rows] += through * seen_t[:, None, :]
        return {"radiance": radiance, "down": down, "up": up, "top_up": top_up, "top_rising": top_rising,
                "nodes": mu, "ring": 2.0 * math.pi * wmu, "g0": at_grid(g[:, :, 0, :]), "node_fluxes": node_fluxes,
                "through": seen_t}

    def _clear_below(self, wl: NDArray[np.float64], ref: float, theta: NDArray[np.float64],
                     phi: NDArray[np.float64], beam_flux: NDArray[np.float64], mu_beam: NDArray[np.float64],
                     albedo: NDArray[np.float64], sky_iso: NDArray[np.float64]
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The light that the clear air below ``ref`` [m] (the highest cloud top) and the ground (albedo ``albedo``
        (n_wl,)) send up through ``ref`` when the cloud is absent, per unit solar irradiance: ``(up, rising)``, the
        upward flux there (n_wl,) [-] and its azimuthal mean radiance (n_up, n_wl) [sr^-1] on the grid's rows of
        rising light (view zenith angles ``theta`` > 90 deg; ``phi`` the grid's azimuths [rad]). Lit as the cloud
        column is: the tables' sun (``beam_flux`` (n_wl,) [-] at the cosines ``mu_beam`` (n_wl,)) and sky
        (:meth:`_sky_light` with ``sky_iso`` (n_wl,) [sr^-1]); the clear air's layers of :func:`cloud_column` below
        ``ref``, solved by DISORT ([Stamnes1988]) at :data:`SKY_STREAMS` streams.

        The tables' sky at the cloud top already holds this light as the air above sent it back; the adding method
        (:meth:`_interreflection`) takes it out before it adds the cloud's. Its reflectance is not the ground's
        albedo ``a``: the air below the top scatters the sun's light up too, most of it at low elevations, which the
        air above returns more than Lambertian light (sun 10 deg, 1500 m, 450 nm: 0.26 against 0.2, and twice the
        Lambertian return)."""
        import disortpp

        column = cloud_column(self.atmosphere.replace(particles=()), wl, observer_altitude=ref)
        edges, tau, ssa, moments = column
        below = np.flatnonzero(edges[:-1] <= ref + 1e-6)  # layers whose top edge is at or below the cloud top
        tau, ssa, moments = tau[below], ssa[below], moments[below]
        sky = self._sky_light(wl, ref, theta, phi, tau, ssa, moments, 0, albedo, sky_iso)
        up, rising = sky["top_up"].copy(), sky["top_rising"].copy()
        streams = min(self.streams, SKY_STREAMS)
        rows = np.nonzero(theta > 0.5 * math.pi)[0]
        mu_up = -np.cos(theta[rows])  # DISORT: mu > 0 travels up
        order = np.argsort(mu_up, kind="stable")
        for k in range(wl.size):
            if beam_flux[k] <= 0.0:
                continue
            cfg = _beam_config(disortpp, tau[:, k], ssa[:, k], moments[:, k, : streams + 1], streams, streams, [0.0],
                               mu_up[order], np.zeros(1), beam_flux[k], mu_beam[k], albedo[k])
            res = disortpp.DisortSolver().solve(cfg)
            up[k] += res.flux_up[0]
            mean = np.empty(rows.size)
            mean[order] = np.asarray(res.intensity_azimuth_avg)[0]
            rising[:, k] += mean
        return up, rising

    def _interreflection(self, wl: NDArray[np.float64], ref: float, up: NDArray[np.float64],
                         down: NDArray[np.float64], mu: NDArray[np.float64], rising: NDArray[np.float64],
                         nodes: NDArray[np.float64], views: NDArray[np.float64],
                         clear_up: NDArray[np.float64], clear_rising: NDArray[np.float64]
                         ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """The light the cloud reflects that the air above sends back down, by the adding method ([Liou2002] Sec.
        6.2): ``(extra, at_nodes, at_views)``, ``extra`` (n_wl,) its flux on the cloud top per unit solar
        irradiance [-], and its radiance per unit of that flux [sr^-1] at the cosines ``nodes`` (n_nodes,) and
        ``views`` (n_views,) of light travelling down (the air's own angular shape, :func:`air_return_radiance`:
        brightest near the horizon; neither isotropic nor the clear sky's shape about the sun, which under optical
        depth 15 were 10-20 % off 10-80 deg high just below the cloud top against the whole column in DISORT).

        ``down`` (n_wl,): the downward flux at the top (the tables' sun and sky, which already hold the light that
        the clear air below the top and the ground sent up and the air above sent back; ``D0`` is the light without
        it); ``up``
        (n_wl,): the column's upward flux there, ``r = up / down`` its reflectance; ``rising`` (n_mu, n_wl)
        [sr^-1]: the azimuthal mean of that upward radiance at the cosines ``mu`` (n_mu,) > 0. The air sends back
        the fraction ``R`` of it, its plane albedo from below (:func:`air_plane_albedo`) averaged over the reflected
        light's angles: a thin cloud under a low sun sends its light up at low elevations, which the air returns
        more than Lambertian light (optical depth 1, sun 10 deg: twice as much at 650 nm); the light returned again
        is nearly diffuse (the spherical albedo ``s``, :func:`air_spherical_albedo`). Then
        ``F = D0 (1 + r R / (1 - r s))`` (``D0 / (1 - r s)`` where ``R = s``) and ``extra = F - down``.

        ``D0``: the same adding applied to the clear column below the top (``clear_up``, ``clear_rising``:
        :meth:`_clear_below`), whose return the tables' sky holds, ``down = D0 (1 + r_c R_c / (1 - r_c s))``; so a
        vanishing cloud gives the tables' sky back (``F = down``). Until 2026-12-04 ``D0 = down (1 - a s)``, the
        ground's albedo ``a`` alone under the top (the first-order term of that adding for a Lambertian floor):
        with the sun 10 deg high the clear air below 1500 m and the ground reflect ``r_c`` = 0.26 / 0.24 / 0.22 at
        450 / 550 / 650 nm, mostly at low elevations, so the cloud top's light was 1.5 / 0.6 / 0.3 % too bright
        (docs/clouds.md)."""
        cos = np.concatenate([nodes, views])
        # the clear air's layers once, for both solves (their values per wavelength do not depend on the others)
        column = cloud_column(self.atmosphere.replace(particles=()), wl, observer_altitude=ref)
        s_row, ret = _air_from_below(self.atmosphere, wl, ref, None, self.streams, cos, column)
        s = s_row[0]
        shape = np.divide(ret, s[None, :], out=np.zeros_like(ret), where=s[None, :] > 0)
        x, w = np.polynomial.legendre.leggauss(SKY_NODES)
        quad = 0.5 * (x + 1.0)
        # the plane albedo's ratio to the spherical albedo changes slowly with wavelength: solved every
        # SKY_WAVELENGTH_STEP grid wavelengths (and the last), interpolated linearly between
        solved = np.unique(np.concatenate([np.arange(0, wl.size, SKY_WAVELENGTH_STEP), [wl.size - 1]]))
        edges, tau, ssa, moments = column
        at_solved = (edges, tau[:, solved], ssa[:, solved], moments[:, solved])
        ratio = _air_from_below(self.atmosphere, wl[solved], ref, quad, self.streams, None, at_solved) / np.maximum(
            s[solved], 1e-12)[None, :]
        plane = np.stack([np.interp(wl, wl[solved], row) for row in ratio]) * s[None, :]  # (n_quad, n_wl)
        order = np.argsort(mu)
        m = mu[order]

        def returned(up_flux: NDArray[np.float64], rising_mu: NDArray[np.float64]) -> NDArray[np.float64]:
            # r R / (1 - r s): the adding method's light sent back down per unit of light without it
            flux = 2.0 * math.pi * rising_mu[order] * m[:, None]  # (n_mu, n_wl): the upward flux per unit cosine
            total_flux = np.trapezoid(flux, m, axis=0)
            back = np.divide(np.trapezoid(flux * r_mu, m, axis=0), total_flux, out=s.copy(), where=total_flux > 0)
            r = np.divide(up_flux, down, out=np.zeros(wl.size), where=down > 0)
            return r * back / np.maximum(1.0 - r * s, 1e-6)

        r_mu = np.stack([np.interp(m, quad, plane[:, k]) for k in range(wl.size)], axis=1)
        d0 = down / (1.0 + returned(clear_up, clear_rising))
        total = d0 * (1.0 + returned(up, rising))
        return total - down, shape[: nodes.size], shape[nodes.size:]

    def _table_illumination(self, wl: NDArray[np.float64], height: float
                            ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The clear sky's light at ``height`` [m] (the highest cloud top) from the precomputed tables
        ([Bruneton2008]): the sun's transmittance (spherical, the disc's visible fraction) and the sky's
        downward irradiance as an isotropic radiance (irradiance / pi), both per unit solar irradiance.

        The irradiance is the tables' sky radiance (Eq. 16) integrated over the upper hemisphere, ``E = int S mu
        dOmega`` (:meth:`~skyscatter.precomputed.evaluation.TableLookups.sky_irradiance_integral`: 8 Gauss-Legendre
        nodes in the cosine, the trapezoid rule every 2.5 deg in azimuth, the quadrature of :meth:`_sky_light`),
        not the tables' irradiance table (Eq. 15):
        that table is made for the ground, its rows linear in the altitude every 4 km (16 rows over 60 km), so at a
        cloud top 1500 m high it interpolated between the ground and 4 km across an aerosol of scale height 1.2 km
        (AOD 0.1, albedo 0.9: +11 / +48 % against DISORT's clear air at 405 / 655 nm, sun 30 deg from the zenith,
        which made the sky under a thick cloud 2-3 % too bright; the radiance tables' rows follow ``rho`` and are
        200-1300 m apart there: -0.5 / +1.6 %; docs/clouds.md)."""
        from ..precomputed.cache import cached_atmosphere

        clear = self.atmosphere.replace(particles=())
        tables = cached_atmosphere(clear, sizes=COUPLING_TABLE_SIZES, progress=False)
        pos = [[0.0, 0.0, clear.bottom_radius + height]]
        sun = [[math.sin(self.sun_zenith), 0.0, math.cos(self.sun_zenith)]]
        t_sun = tables.sun_transmittance(pos, sun)
        column = _ozone_slant_column(clear, self.sun_zenith, height)
        tw = tables.wavelengths
        t_sun = self._from_tables(t_sun[0], tw, wl, column, np.interp(wl, tw, t_sun[0]))
        e_sky = tables.sky_irradiance_integral(pos, sun, nodes=SKY_NODES)[0] / clear.solar_irradiance_at(tw)
        e_sky = self._from_tables(e_sky, tables.wavelengths, wl, column, np.zeros(wl.size))
        return np.maximum(t_sun, 0.0), np.maximum(e_sky, 0.0) / math.pi

    def _table_sky(self, wl: NDArray[np.float64], height: float, theta: NDArray[np.float64],
                   phi: NDArray[np.float64]) -> NDArray[np.float64]:
        """The clear sky's radiance at ``height`` [m] from the tables ([Bruneton2008] Eq. 16) towards view zenith
        angles ``theta`` (n,) and azimuths from the sun ``phi`` (m,) [rad], per unit solar irradiance (n, m, n_wl)."""
        from ..precomputed.cache import cached_atmosphere

        clear = self.atmosphere.replace(particles=())
        tables = cached_atmosphere(clear, sizes=COUPLING_TABLE_SIZES, progress=False)
        t, p = np.meshgrid(theta, phi, indexing="ij")
        # the sun in the x-z plane (azimuth pi/2 in ENU terms: x east); directions at azimuth phi from it
        d = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
        sun = np.array([math.sin(self.sun_zenith), 0.0, math.cos(self.sun_zenith)])
        pos = np.array([0.0, 0.0, clear.bottom_radius + height])
        rad = tables.sky_radiance(np.broadcast_to(pos, d.shape), d, sun)
        # read linearly between the tables' wavelengths: the column takes only this light's angular shape (its flux
        # is :meth:`_table_illumination`'s, read through the ozone), and per direction the ozone's path differs from
        # the sun's (the ozone read here moved the ground's diffuse light by less than 0.05 % and one direction on a
        # cloud top at sun 2 deg from 4.6 to 5.04 % off the backward paths)
        return np.maximum(tables.resample(rad, wl), 0.0) / clear.solar_irradiance_at(wl)

    def _from_tables(self, values: NDArray[np.float64], table_wl: NDArray[np.float64], wl: NDArray[np.float64],
                     column: float, outside: NDArray[np.float64]) -> NDArray[np.float64]:
        """Values per unit solar irradiance at the tables' wavelengths ``table_wl`` (..., n_table) [nm] read at the
        grid's ``wl`` [nm] by :func:`ozone_read` (the ozone ``column`` [m] the light crossed) inside the tables'
        range; ``outside`` (..., n_wl) elsewhere (the tables' spectral mode holds no light outside their range)."""
        out = np.array(outside, dtype=float, copy=True)
        inside = (wl >= table_wl[0]) & (wl <= table_wl[-1])
        out[..., inside] = ozone_read(values, table_wl, wl[inside], column, self.atmosphere)
        return out

    @cached_property
    def _xyz_grid(self) -> NDArray[np.float64]:
        """XYZ [cd m^-2] on the radiance grid (n_theta, n_phi, 3), from the spectra at the reference wavelengths."""
        f = self._field["radiance"]
        spec = self._spectra(f.reshape(-1, f.shape[-1]), REFERENCE_WAVELENGTHS)
        return spectrum_to_xyz(spec, REFERENCE_WAVELENGTHS).reshape(*f.shape[:2], 3)

    def _spectra(self, normalised: NDArray[np.float64], wl: NDArray[np.float64]) -> NDArray[np.float64]:
        """Grid-wavelength values per unit solar irradiance (..., 17) to spectra [W m^-2 ... nm^-1] at ``wl``:
        read linearly between the grid's wavelengths as their ratio to the ozone transmittance of
        :meth:`_ozone_path` (:func:`ozone_read`)."""
        g = GRID_WAVELENGTHS
        x = np.clip(wl, g[0], g[-1])
        vals = ozone_read(normalised, g, x, self._ozone_path(), self.atmosphere)
        return vals * self.atmosphere.solar_irradiance_at(wl)

    def _ozone_path(self) -> float:
        """The ozone column [m of relative density 1] that the light of an observer at or below the highest cloud
        top has crossed: the sun's slant path to the cloud top (or the ground) through the ozone layer
        (:func:`~skyscatter.atmosphere.gas_absorption.slant_optical_masses`, the sun at 90 deg from the zenith
        at most: in twilight the light still enters along a grazing path); 0 above the cloud top (the light seen
        there has crossed the ozone on other paths: a plain linear read)."""
        if self._spherical:
            return 0.0
        return _ozone_slant_column(self.atmosphere, self.sun_zenith, self._cloud_top)

    def _interpolate(self, grid: NDArray[np.float64], directions: ArrayLike) -> NDArray[np.float64]:
        """Bilinear interpolation of ``grid`` (n_theta, n_phi, c) at ``directions`` (..., 3): (..., c)."""
        from .cloudy_kernels import grid_lookup

        d = np.asarray(directions) if isinstance(directions, np.ndarray) else None
        if d is None or d.dtype.kind != "f" or d.ndim == 0 or d.shape[-1] != 3:
            d = as_directions(directions)  # the shape and type checks (and their errors)
        shape = d.shape[:-1]
        flat = np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float64)
        out = np.empty((flat.shape[0], grid.shape[-1]))
        f = self._field
        # the kernel normalises and flags bad vectors (NaN): validating 2 M directions in numpy took 1.4 s
        grid_lookup(flat, float(self.sun_azimuth), f["theta"], f["phi"],
                    np.ascontiguousarray(grid), out)
        if out.size and not np.isfinite(out[:, 0]).all():
            as_directions(d)  # raises the specific InvalidDirectionError
        return out.reshape(*shape, grid.shape[-1])

    # ------------------------------------------------------------------ the protocol

    def spectral_radiance(self, directions: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] of sky, clouds and ground (no solar disc), (..., n_wl).
        Observers above the cloud top see it over a sphere (:meth:`_spherical_view`)."""
        wl = DEFAULT_WAVELENGTHS if wavelengths is None else as_wavelengths(wavelengths)
        normalised = self._interpolate(self._field["radiance"], directions)
        out = self._spectra(normalised, wl)
        if self._spherical:
            d = self._unit(directions)
            hit, limb, vals = self._spherical_view(d)
            out[hit] = self._spectra(vals, wl)
            if limb.any():
                out[limb] = self._limb_sky.spectral_radiance(d[limb], wl)
        return out

    def xyz(self, directions: ArrayLike) -> NDArray[np.float64]:
        """CIE XYZ [cd m^-2] (..., 3): the grid's XYZ interpolated (equal to integrating ``spectral_radiance``);
        above the cloud top the spherical view's spectra integrated (:meth:`_spherical_view`)."""
        out = self._interpolate(self._xyz_grid, directions)
        if self._spherical:
            d = self._unit(directions)
            hit, limb, vals = self._spherical_view(d)
            out[hit] = vals @ self._grid_to_xyz
            if limb.any():
                out[limb] = self._limb_sky.xyz(d[limb])
        return out

    # ------------------------------------------------------------------ the spherical view from above the cloud

    @cached_property
    def _grid_to_xyz(self) -> NDArray[np.float64]:
        """The linear map (n_grid_wl, 3) from values per unit solar irradiance at :data:`GRID_WAVELENGTHS` to XYZ
        [cd m^-2]: each grid wavelength's spectrum (:meth:`_spectra`) integrated (the same as ``_xyz_grid``)."""
        eye = np.eye(GRID_WAVELENGTHS.size)
        return spectrum_to_xyz(self._spectra(eye, REFERENCE_WAVELENGTHS), REFERENCE_WAVELENGTHS)

    @cached_property
    def _cloud_top(self) -> float:
        """Altitude [m] of the highest cloud top (0 without clouds)."""
        return max((c.top for c in self.atmosphere.particles if hasattr(c, "top")), default=0.0)

    @property
    def _spherical(self) -> bool:
        """Whether the view is spherical: an observer above the highest cloud top with the sun's beam traced
        (in twilight the column is solved from the cloud top down and the observer put there: not done)."""
        return (self._cloud_top > 0.0 and self.altitude > self._cloud_top + 1.0
                and math.cos(self.sun_zenith) > math.sin(MIN_BEAM_ELEVATION))

    @staticmethod
    def _unit(directions: ArrayLike) -> NDArray[np.float64]:
        """Unit vectors (..., 3) of directions already checked by :meth:`_interpolate`."""
        d = np.asarray(directions, dtype=np.float64)
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    @cached_property
    def _limb_sky(self) -> Any:
        """The clear air's sky from the precomputed tables ([Bruneton2008]) at the observer: what rays that miss
        the cloud shell see (the limb)."""
        from .bruneton import BrunetonSky

        return BrunetonSky(self.sun_zenith, self.sun_azimuth, altitude=self.altitude,
                           atmosphere=self.atmosphere.replace(particles=()))

    #: Spacing [deg] of the sun zenith angles at which the cloud top's field is solved for the spherical view.
    LOCAL_SUN_STEP_DEG = 5.0

    def _top_field(self, sun_zenith: float) -> dict[str, NDArray[np.float64]]:
        """The column's solution at the highest cloud top for the sun at ``sun_zenith`` [rad] there (the same
        DISORT solve as the observer's, the whole air above with the spherical beam; cached per sun zenith):
        the cloud's upwelling radiance."""
        cache = self.__dict__.setdefault("_top_fields", {})
        key = round(float(sun_zenith), 12)
        if key not in cache:
            other = object.__new__(type(self))
            other.__dict__.update({k: v for k, v in self.__dict__.items()
                                   if k not in ("_field", "_xyz_grid", "_direct", "_column", "_top_fields",
                                                "_air_chords", "_limb_sky")})
            other.altitude = self._cloud_top
            other.illumination = "column"
            other.sun_zenith = float(sun_zenith)
            cache[key] = other._field
        return cache[key]

    @cached_property
    def _air_chords(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """The air between the cloud top and the observer: its vertical optical depth (n_wl,) and, on nodes of
        the cosine ``mu`` (n_mu,) of a ray's angle with the local zenith at the cloud top, the optical depth
        along its chord through the spherical shells up to the observer (n_mu, n_wl) (:func:`slant_optical_depth`
        per node: a table, not a loop over directions)."""
        atm = self.atmosphere
        obs = min(self.altitude, atm.thickness)
        edges, tau, _, _ = self._column
        keep = (edges[1:] >= self._cloud_top - 1e-6) & (edges[:-1] <= obs + 1e-6)
        e = np.concatenate([edges[:-1][keep], [edges[1:][keep][-1]]])
        t = tau[keep]
        mu = np.linspace(0.0, 1.0, 513) ** 2
        chord = np.array([slant_optical_depth(e, t, atm.bottom_radius, self._cloud_top, float(m)) for m in mu])
        return t.sum(axis=0), mu, chord

    def _spherical_view(self, d: NDArray[np.float64]
                        ) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.float64]]:
        """The view over a sphere from above the highest cloud top, for unit directions ``d`` (..., 3) (ENU at the
        observer): ``(hit, limb, values)``, ``hit`` the rays that meet the sphere of the cloud top (radius
        ``R + z_top``), ``values`` (n_hit, n_grid_wl) their radiance per unit solar irradiance, and ``limb`` the
        rays that miss it below the observer's horizontal (and, from above the atmosphere, every ray that
        misses it): they see the clear air of the tables (:attr:`_limb_sky`). Upward rays from inside the
        atmosphere keep the plane-parallel field.

        A ray of nadir angle ``eta`` from radius ``r0`` meets the cloud top at the local zenith angle
        ``asin(r0 sin(eta) / R_c)`` (the line-sphere intersection). The layer is horizontally uniform, so the
        cloud's radiance there is the column's upwelling radiance ``L_top`` at the local view zenith angle, the
        local azimuth from the sun and the local sun zenith (:meth:`_top_field`, solved every
        :attr:`LOCAL_SUN_STEP_DEG` from the observer's sun zenith and interpolated linearly), attenuated by the
        air's optical depth along the chord (``T_s``). The air's in-scatter is the plane-parallel one,
        ``L_obs - T_pp L_top`` (the observer's and the cloud top's fields of the same solve, [Stamnes1988]),
        taken at the angle ``theta_e`` whose plane-parallel optical depth equals the chord's (at 555 nm):
        ``L = L_obs(theta_e) + T_s L_top(theta) - T_pp(theta_e) L_top(theta_e)``, which at the nadir is the
        plane-parallel field exactly. Approximations (docs/clouds.md): the air's in-scatter keeps the
        plane-parallel geometry at ``theta_e`` and the observer's sun zenith; the limb's air is lit by the
        tables' ground (albedo), not by the cloud; where the local sun is lower than :data:`MIN_BEAM_ELEVATION`
        the cloud is dark (its twilight is not modelled in this view)."""
        from .cloudy_kernels import grid_lookup

        atm = self.atmosphere
        flat = d.reshape(-1, 3)
        r0 = atm.bottom_radius + self.altitude
        rc = atm.bottom_radius + self._cloud_top
        b = r0 * flat[:, 2]
        disc = b * b - (r0 * r0 - rc * rc)
        hit = (disc >= 0.0) & (b < 0.0)
        limb = ~hit & ((flat[:, 2] < 0.0) | (self.altitude >= atm.thickness))
        v = flat[hit]
        dist = -b[hit] - np.sqrt(disc[hit])
        p = v * dist[:, None]
        p[:, 2] += r0
        n = p / rc  # the local zenith at the hit point
        cos_loc = np.einsum("ij,ij->i", v, n)  # < 0: the ray goes down
        zs, azs = self.sun_zenith, self.sun_azimuth
        sun = np.array([math.sin(zs) * math.sin(azs), math.sin(zs) * math.cos(azs), math.cos(zs)])
        v_t = v - cos_loc[:, None] * n
        s_t = sun[None, :] - (n @ sun)[:, None] * n
        phi = np.arctan2(np.linalg.norm(np.cross(v_t, s_t), axis=1), np.einsum("ij,ij->i", v_t, s_t))
        mu_loc = np.clip(-cos_loc, 0.0, 1.0)
        vert, mu_nodes, chord = self._air_chords
        nwl = GRID_WAVELENGTHS.size
        t_sph = np.empty((mu_loc.size, nwl))
        for k in range(nwl):  # a loop over 17 wavelengths
            t_sph[:, k] = np.exp(-np.interp(mu_loc, mu_nodes, chord[:, k]))
        k5 = int(np.argmin(np.abs(GRID_WAVELENGTHS - 555.0)))
        slant = np.interp(mu_loc, mu_nodes, chord[:, k5])
        mu_e = np.clip(np.divide(vert[k5], slant, out=np.ones_like(slant), where=slant > 0), 1e-3, 1.0)
        t_pp = np.exp(-vert[None, :] / mu_e[:, None])

        def look_rows(field: dict[str, NDArray[np.float64]], cos_t: NDArray[np.float64], rows: Any = slice(None)
                      ) -> NDArray[np.float64]:
            c = cos_t[rows]
            f = phi[rows]
            sin_t = np.sqrt(np.maximum(1.0 - c * c, 0.0))
            dirs = np.ascontiguousarray(np.stack([sin_t * np.sin(f), sin_t * np.cos(f), c], axis=-1))
            out = np.empty((dirs.shape[0], nwl))
            grid_lookup(dirs, 0.0, field["theta"], field["phi"], np.ascontiguousarray(field["radiance"]), out)
            return out

        def look(field: dict[str, NDArray[np.float64]], cos_t: NDArray[np.float64]) -> NDArray[np.float64]:
            return look_rows(field, cos_t)

        top = self._top_field(zs)
        vals = look(self._field, -mu_e) - t_pp * look(top, -mu_e)
        # the cloud's light at the hit point's own sun zenith: linear between fields solved every
        # LOCAL_SUN_STEP_DEG from the observer's (so that the nadir is the observer's field); dark where the
        # sun is below the lowest traced beam there (the night side: its twilight is not modelled in this view)
        step = math.radians(self.LOCAL_SUN_STEP_DEG)
        last = 0.5 * math.pi - MIN_BEAM_ELEVATION - 1e-6
        local = np.arccos(np.clip(n @ sun, -1.0, 1.0))
        lit = local <= last
        pos = (local - zs) / step
        lo = np.floor(pos)
        cloud = np.zeros_like(vals)
        for j in np.unique(lo[lit]):
            rows = lit & (lo == j)
            node_lo = float(zs + j * step)
            za, zb = max(node_lo, 0.0), min(node_lo + step, last)  # the nodes, clipped to the sky's range
            if zb <= za or abs(local[rows] - za).max() < 1e-12:
                cloud[rows] = look_rows(self._top_field(za), cos_loc, rows)
                continue
            w = np.clip((local[rows] - za) / (zb - za), 0.0, 1.0)[:, None]
            cloud[rows] = ((1.0 - w) * look_rows(self._top_field(za), cos_loc, rows)
                           + w * look_rows(self._top_field(zb), cos_loc, rows))
        vals += t_sph * cloud
        shape = d.shape[:-1]
        return hit.reshape(shape), limb.reshape(shape), np.maximum(vals, 0.0)

    def sun_spectral_radiance(self, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Mean radiance of the solar disc [W m^-2 sr^-1 nm^-1]: the sun's spectrum times the direct
        transmittance along the slant path (air and cloud, ``exp(-tau_slant)``) over the disc's solid angle."""
        from ..sun.disc import solar_disc_solid_angle

        wl = DEFAULT_WAVELENGTHS if wavelengths is None else as_wavelengths(wavelengths)
        t = self._spectra(self._direct, wl)
        return t / solar_disc_solid_angle(self.sun_angular_radius)

    def diffuse_fluxes(self, wavelengths: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """DISORT's diffuse downward and upward irradiance at the observer [W m^-2 nm^-1], each (n_wl,)."""
        wl = DEFAULT_WAVELENGTHS if wavelengths is None else as_wavelengths(wavelengths)
        return self._spectra(self._field["diffuse_down"], wl), self._spectra(self._field["diffuse_up"], wl)


def _number(name: str, value: Any, lo: float, hi: float, unit: str) -> float:
    if isinstance(value, (bool, str)) or value is None:
        raise InvalidParameterError(f"{name} must be a number{f' [{unit}]' if unit else ''}; got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a number; got {value!r}") from None
    if not (math.isfinite(v) and lo <= v <= hi):
        raise InvalidParameterError(f"{name} must be in [{lo:g}, {hi:g}]{f' {unit}' if unit else ''}; got {value!r}")
    return v
