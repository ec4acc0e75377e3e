"""Broken 3D cloud fields in the clear sky of the precomputed tables: the ``broken-cloud`` sky model.

A :class:`~skyscatter.atmosphere.clouds.CloudField` (procedural Perlin-Worley clouds by cover fraction, or a
field from a NetCDF/Zarr file) seen from one observer (on the ground, inside or above the field) by ray marching
each view ray through the voxels, spectrally at the precomputed tables' wavelengths ([Bruneton2008]; 16 from 400
to 700 nm by default), then to XYZ like every spectral sky. It is a sky model, not a renderer function, because
the ray march is a radiance per direction from one eye: the registry, the CLI's options (``skyscatter sky
--model broken-cloud --cloud-cover 0.4``), ``sky_image`` (equirect, fisheye, pinhole, the solar disc),
illuminance and ``to_dict`` then serve it unchanged.

Light at a point of the cloud (per wavelength; ``sigma_e = rho k``, ``rho`` the voxel's extinction at 550 nm and
``k`` the droplets' extinction relative to 550 nm, albedo ``omega``; :func:`.broken_cloud_kernels.march_rays`):

* **The sun, single and multiple scattering by octaves** ([Wrenninge2013] Sec. "multiple scattering
  approximation"): ``J_sun = omega E_0 T_air(h, mu_s) sum_{i=0}^{N-1} b^i p_i(theta) exp(-a^i tau_sun k)``,
  ``N`` = 8. Octave 0 is single scattering exactly: the droplets' tabulated Mie phase function
  (:func:`skyscatter.atmosphere.mie_optics.water_droplets`, diffraction peak kept) and ``tau_sun`` the field's
  optical depth from the point to the sun; octaves ``i >= 1`` (multiple scattering) scatter ``b^i`` as much,
  see an extinction ``a^i`` as large and a phase of asymmetry ``c^i g``: since 2026-12-03 the droplets' phase
  convolved with itself ``1 + i ln(c) / ln(g)`` times (:func:`octave_phases`, [GoudsmitSaunderson1940]; the
  light scattered a few times keeps the droplets' narrow core near the sun), before it [Wrenninge2013]'s
  Henyey-Greenstein lobe of that asymmetry (:data:`OCTAVE_PHASE`), and are weighted by
  ``(1 - exp(-tau_c))^i`` with ``tau_c`` the vertical optical depth of the point's column (thin wisps do not
  multiply-scatter: without it a layer of optical depth 1 came out 2-3x the DISORT layer's radiance).
  Octaves ``i >= 1`` are further scaled by the energy the sun puts into the cloud (:func:`entry_factors`):
  ``(K(mu_0) / K(mu_ref))^e`` for light entering through the cloud's top and ``(K(s_0) / K(s_ref))^e`` through
  a side facing the sun (``s = sqrt(1 - mu^2)``, the cosine on a vertical face), ``K(mu) = mu (1 + 3/2 mu)``:
  in the Eddington approximation a thick non-absorbing layer lit at the cosine ``mu`` transmits the diffuse
  flux ``mu E_0 (2 + 3 mu) / (4 + 3 (1 - g) tau)`` (the Eddington equations of [Joseph1976] without the
  delta scaling, solved for single-scattering albedo 1 with no light entering from below, the limit ``tau -> inf``;
  tests/test_broken_cloud.py solves those equations numerically), so the light scattered many times
  grows with the cosine and more, while the octaves as [Wrenninge2013] wrote them barely depend on the sun's
  elevation (their extinction ``a^i`` is small). The two are blended per sample by the share of the sun's path
  through the cloud above the point, ``min(tau_sun mu_s / tau_top, 1)`` (1 under a horizontally uniform top).
  ``e = 1`` is the slab's limit, ``e = 0`` the octaves unscaled; ``mu_ref`` = cos 55 deg, the sun of the
  Monte Carlo fisheye, where both factors are 1.
  ``a, b, c, e`` are **fitted to the Monte Carlo** (:data:`FITTED_OCTAVES`; docs/clouds.md).
* **The diffused light near a thick cloud's base** (:data:`BASE_PROFILE`, since 2026-12-04): the octaves' source
  has no depth profile where they have saturated (their ``exp(-a^i tau_sun)`` near 1 deep in a thick cloud), so
  a closed deck's base came out equally bright at every elevation. Octaves ``i >= 1`` are shaped there as the
  conservative Eddington layer's source ``I1 (2/3 + (1 - g) tau_b + g mu)`` ([Joseph1976]'s equations without the
  delta scaling; ``tau_b`` the optical depth above the base, ``mu`` the cosine of the light's downward travel
  towards the eye), relative to the octaves' flat source taken as ``4/3 I1`` (the flux leaving the base kept; the
  radiance leaving it ``~ 2/3 + mu``, limb-darkened); the mean part capped at 1, the anisotropy fading above the
  base as ``g mu / (2/3 + (1 - g) tau_b)``; phased in over ``(1 - g) tau_c`` from 0.7 to 1.4 (columns of optical
  depth about 5 to 10; thinner ones keep the octaves as fitted, measured against DISORT, docs/clouds.md).
* **The droplets' forward peak, delta-M** (an option, off: :data:`TRUNCATION_STREAMS` = 0; [Wiscombe1977];
  :func:`delta_m_octaves`): with ``N`` = 16 the fraction ``f = chi_16`` of the scattering in the diffraction peak
  (0.44-0.46) goes on in the light's own
  direction, so the march (to the sun and along the view ray) sees the scaled extinction ``k (1 - omega f)``,
  octave 0 keeps the full tabulated phase on the scaled beam (the TMS correction of [NakajimaTanaka1988]: the
  light that passed the cloud through the peak stays near the sun) and the octaves ``i >= 1`` the truncated
  phase's asymmetry ``g* = (g - f) / (1 - f)``: ``c^i g*``. Without it the octaves' broad lobes spread the
  peak's light over the sky (a uniform layer of optical depth 5: 0.3 of DISORT's radiance within 2 deg of the
  sun, 1.2-1.3 beyond 45 deg). The ground's shadows, the shafts and the solar disc keep the full extinction.
  Refitted, it brought the broken fields' fisheye closer to the Monte Carlo but the uniform layer further from
  DISORT (docs/clouds.md), so it is off.
* **The sun's path through the field: a precomputed shadow volume.** ``tau_sun`` of every voxel centre is
  integrated once per sky along the sun's ray exactly (regular tracking through the voxel-constant grid, the
  Monte Carlo's :func:`~skyscatter.montecarlo.tracking.field_transmittance`); the march reads it at the voxel
  it is in. A light march per sample would cost (march samples) x (light steps) per ray; the volume costs
  (voxels) x (crossings) once, a few tenths of a second, because the sun's rays are parallel.
* **The sun above the field and the sky's light: the clear-sky tables.** ``T_air(h, mu_s)`` is the tables'
  transmittance from the point's altitude to the sun and the ambient light the tables' sky irradiance there
  (their sky radiance integrated over the hemisphere, :func:`_sky_irradiance_levels`), isotropic:
  ``J_amb = omega (E_down exp(-d tau_above k) + rho_g E_ground exp(-d tau_below k)) / (2 pi)`` with the
  vertical optical depths to the field's top and base and the ground's upward light ``E_up`` (below); ``d`` is
  fitted with ``a, b, c``.
* **Along the view ray**: midpoint steps of half a voxel along the axis the ray crosses fastest (growing as
  0.002 x the distance, about a pixel of a 2048-wide panorama), empty blocks of 4^3 voxels crossed in one
  step, the march stopping once
  every wavelength's transmittance is below 1e-3. Each step adds ``T (1 - exp(-sigma_e dt)) J``.
* **The clear air in front of and behind the cloud** ([Bruneton2008] Eq. 16): with ``p`` the cloud's mean
  depth along the ray (weights ``T (1 - exp(-sigma dt))``), ``L = L_sky(eye) - T_air(eye, p) (1 - T_cloud)
  L_sky(p) + T_air(eye, p) L_cloud``: the clear sky seen from the eye, less what the cloud hides of the sky
  behind it, plus the cloud's light dimmed by the air between. Rays that meet no cloud are the clear sky of
  the same tables (:class:`~skyscatter.sky.bruneton.BrunetonSky`), bit for bit.
* **Shadows on the ground** (views that meet the ground): the ground's sunlit part ``albedo / pi E_sun``
  times ``1 - exp(-tau k)``, ``tau`` the field's optical depth from the ground point to the sun, is taken away.
* **The solar disc**: the clear sky's disc times the field's transmittance from the eye to the sun.

* **Light shafts** (the clouds' shadows on the air in front of the cloud, :meth:`BrokenCloudSky._shafts`,
  :func:`.broken_cloud_kernels.shaft_loss`): the air's single-scattered sunlight times ``1 - exp(-tau k)`` is
  taken away along the view ray below the field's top, and the clouds' light the air there scatters added (on;
  docs/clouds.md has the accuracy with and without).
* **The ground's light on the cloud bases** (:attr:`BrokenCloudSky._ground_up`): the ground (Lambertian, the
  air's ground albedo) sends up its albedo times the domain-mean direct and diffuse light it receives under the
  field, the diffuse part the model's own (the cloud bases' light included, solved with the bounces between
  ground and bases); the march adds it as an isotropic source ``omega E_up / (2 pi)`` in the cloud.
* **The air above the field sends back the clouds' light** (the cloud-top-air coupling, :meth:`_ground_coupling`):
  the extra downward irradiance ``D = s dU`` at the field's top ([Liou2002] Sec. 6.2, the adding method; ``dU``
  the field's change of the upward irradiance there, ``s`` the spherical albedo of the air above from below,
  :func:`.cloudy.air_spherical_albedo`), isotropic, in the march's sky source and through the gaps; solved with
  the ground coupling.

Renderers of terrain take the field's shadows from :meth:`BrokenCloudSky.sun_shadow` (the landscape's
:class:`~skyscatter.render.scene.Scene`). Not modelled: the clouds' light scattered by the air (in the Monte
Carlo), the sun's cosine varying across the field with the planet's curvature (taken at each
point for the air's transmittance, but the field's shadow volume is for the observer's sun direction).

The irradiance on the ground under the field, at points or averaged over the field's domain (direct through the
field, diffuse from this sky): :meth:`BrokenCloudSky.ground_irradiance`,
:meth:`BrokenCloudSky.domain_ground_irradiance`.
"""

from __future__ import annotations

import math
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere import AtmosphereParameters
from ..conventions import as_directions
from ..errors import InvalidParameterError
from ..spectral import DEFAULT_WAVELENGTHS, as_wavelengths
from . import registry
from .base import SkyModel, SunSkyMixin, check_sun_angles

__all__ = ["BrokenCloudSky", "FITTED_OCTAVES", "MU_REFERENCE", "OCTAVES", "OCTAVE_PHASE", "TRUNCATION_STREAMS",
           "delta_m_octaves", "entry_factors", "octave_phases"]

#: Octaves of the multiple-scattering approximation ([Wrenninge2013]).
OCTAVES = 8
#: ``(a, b, c, d, e)``: the octaves' extinction, scattering and eccentricity factors, the ambient light's
#: extinction factor and the exponent of the octaves' entering-energy factors (:func:`entry_factors`), fitted by least
#: squares to Monte Carlo radiances and irradiances (``benchmarks/fit_broken_cloud.py``; docs/clouds.md) with the
#: Henyey-Greenstein lobes, and kept with the convolved phases (:data:`OCTAVE_PHASE`: ``c`` keeps its meaning, the
#: octaves' asymmetry; their refit, benchmarks/fit_broken_cloud_convolved_irradiance.json, was not adopted).
FITTED_OCTAVES = (0.3245, 0.693, 0.6334, 0.0, 0.5)
#: Sun cosine at which :func:`entry_factors` are 1: cos 55 deg, the sun of the Monte Carlo fisheye
#: (tests/data/broken_cloud_montecarlo.npz).
MU_REFERENCE = math.cos(math.radians(55.0))


def entry_factors(mu0: float, exponent: float) -> tuple[float, float]:
    """Factors of the octaves ``i >= 1`` for the sun's energy entering the cloud through its top and through its
    sides, ``((K(mu0) / K(mu_ref))^e, (K(s0) / K(s_ref))^e)``: ``K(mu) = mu (1 + 3/2 mu)`` is the diffuse flux a
    thick non-absorbing layer lit at the cosine ``mu`` transmits in the Eddington approximation,
    ``mu E0 (2 + 3 mu) / (4 + 3 (1 - g) tau)`` (the conservative solution of the Eddington equations of
    [Joseph1976] for ``tau -> inf``; derived here, checked numerically in the tests), the cloud top lit at
    ``mu0`` and a side facing the sun at ``s0 = sqrt(1 - mu0^2)``; each relative to the reference sun
    :data:`MU_REFERENCE` (both 1 there). ``mu0``: the sun's cosine at the field [-] (clamped to [1e-3, 1]);
    ``exponent`` ``e`` [-] (0: no factor, the octaves of [Wrenninge2013]; 1: the slab's diffusion limit)."""
    def k(mu: float) -> float:
        return mu * (1.0 + 1.5 * mu)

    mu = min(max(mu0, 1e-3), 1.0)
    side = max(math.sqrt(1.0 - mu * mu), 1e-3)
    side_ref = math.sqrt(1.0 - MU_REFERENCE**2)
    return (k(mu) / k(MU_REFERENCE)) ** exponent, (k(side) / k(side_ref)) ** exponent
#: Delta-M truncation of the droplets' forward peak in the march (:func:`delta_m_octaves`): ``N`` > 0 takes the
#: forward fraction ``f = chi_N`` (16: DISORT's stream count in :mod:`.cloudy`); 0, shipped, no truncation (the
#: octaves of [Wrenninge2013]; within rounding, 4.4e-16, of the march before the option). Measured with ``N`` = 16
#: and the octaves refitted (docs/clouds.md, "The forward peak kept near the sun"): the fits to the broken fields'
#: Monte Carlo and the uniform layer against DISORT pulled ``b`` apart, and a joint fit of ``a, b, c, e`` against
#: every accuracy guard (``benchmarks/fit_broken_cloud_joint.py``) found no octaves that pass them all, so it is
#: not switched on.
TRUNCATION_STREAMS = 0


#: The octaves' phase functions (:func:`octave_phases`): "convolved" (shipped), the droplets' phase convolved with
#: itself; "henyey-greenstein", the lobes of [Wrenninge2013] (before 2026-12-03).
OCTAVE_PHASE = "convolved"
#: Legendre moments of the convolved phases: the droplets' (10 um) vanish beyond l = 800 at 400 nm (below 1e-5),
#: and octave i's are their powers (i >= 1: exponent > 1), smaller still.
OCTAVE_MOMENTS = 1024


def octave_phases(table: Any, c: float, n_octaves: int, streams: int = 0,
                  kind: str = "convolved") -> NDArray[np.float64]:
    """The octaves' phase functions [sr^-1] (n_octaves, n_wl, m) on the ascending cosines of ``table``'s
    :meth:`~skyscatter.atmosphere.phase_table.PhaseTable.numba_arrays` (``m`` of them): octave 0 the droplets'
    tabulated phase itself (single scattering), octave ``i >= 1`` a phase of asymmetry ``g_i = c^i g*``
    ([Wrenninge2013]: ``g*`` the droplets' asymmetry, that of the delta-M truncated phase when ``streams`` > 0,
    :func:`delta_m_octaves`).

    ``kind`` "henyey-greenstein": [Wrenninge2013]'s Henyey-Greenstein lobe of asymmetry ``g_i``. "convolved": the
    droplets' phase convolved with itself ``n_i = 1 + i ln(c) / ln(g*)`` times, so that its asymmetry is the same
    ``g_i``: the directions of light scattered ``n`` times from one incident direction (each scattering independent
    of the path) have the Legendre moments ``chi_l^n`` (the addition theorem of the spherical harmonics,
    [GoudsmitSaunderson1940] Eq. 5), here with a real exponent. A Henyey-Greenstein phase (moments ``g^l``) is
    its own family under it (``g^(n l)``: the octaves of [Wrenninge2013] with ``c = g^(n_1 - 1)``); the droplets'
    phase is not: it keeps its narrow core (``chi_10 = 0.48`` against ``g^10 = 0.24``), so that the light
    scattered a few times stays nearer the sun than in the lobe of the same asymmetry (docs/clouds.md). The
    series (:data:`OCTAVE_MOMENTS` terms) is tabulated by
    :meth:`~skyscatter.atmosphere.phase_table.PhaseTable.from_legendre_moments` (negative ripples set to 0,
    renormalised).

    ``table`` the droplets' :class:`~skyscatter.atmosphere.phase_table.PhaseTable`; ``c`` [-] in [0, 1] (0: the
    octaves ``i >= 1`` isotropic); ``n_octaves`` [-] >= 1; ``streams`` [-]: the delta-M truncation's ``N`` (0:
    none)."""
    from ..atmosphere.phase_table import PhaseTable

    if kind not in ("convolved", "henyey-greenstein"):
        raise InvalidParameterError(f"octave phase must be 'convolved' or 'henyey-greenstein'; got {kind!r}")
    if not 0.0 <= c <= 1.0:
        raise InvalidParameterError(f"the octaves' eccentricity factor c must be in [0, 1]; got {c!r}")
    arr = table.numba_arrays()
    mu = arr.mu
    nwl = arr.values.shape[0]
    out = np.empty((n_octaves, nwl, mu.size))
    out[0] = arr.values
    if n_octaves == 1:
        return out
    chi = table.legendre_moments(OCTAVE_MOMENTS)
    if streams > 0:
        f = chi[:, streams][:, None]
        chi = np.where(np.arange(chi.shape[1])[None, :] < streams, (chi - f) / (1.0 - f), 0.0)
    g = chi[:, 1]
    if kind == "henyey-greenstein" or c == 0.0:
        for i in range(1, n_octaves):
            gi = (g * c**i)[:, None]
            q = 1.0 + gi**2 - 2.0 * gi * mu[None, :]
            out[i] = (1.0 - gi**2) / (4.0 * math.pi * q * np.sqrt(q))
        return out
    n = 1.0 + np.arange(1, n_octaves)[:, None] * (math.log(c) / np.log(g))[None, :]  # (n_octaves - 1, n_wl)
    moments = np.sign(chi)[None] * np.abs(chi)[None] ** n[:, :, None]
    # every octave and wavelength one row of a single series (one Legendre table for all); the row labels stand in
    # for wavelengths, which the series does not use
    rows = moments.reshape(-1, chi.shape[1])
    series = PhaseTable.from_legendre_moments(rows, np.arange(1.0, rows.shape[0] + 1.0), table.angles,
                                              clip_negative=True)
    out[1:] = series.numba_arrays().values.reshape(n_octaves - 1, nwl, mu.size)
    return out


def delta_m_octaves(k: NDArray[np.float64], albedo: NDArray[np.float64], moments: NDArray[np.float64],
                    streams: int) -> NDArray[np.float64]:
    """The march with the droplets' forward peak truncated, delta-M style ([Wiscombe1977] Eqs. 5-7 and 13, the
    split the precomputed tables' orders use, :meth:`skyscatter.precomputed.compute.Medium.delta_m_scaled`), (3,
    n_wl): the phase ``P = (1 - f) p* + f delta(1 - nu) / (2 pi)``, the peak's light going on in its own direction
    (counted as unscattered).

    Row 0: the extinction relative to 550 nm the march sees, ``k (1 - omega f)`` (the scaled optical depth ``tau* =
    (1 - omega f) tau``), along the view ray and to the sun; row 1: octave 0's factor ``1 / (1 - omega f)``, so that
    single scattering keeps the full tabulated phase (peak included) on the scaled beam, per unit of the physical
    optical depth: the TMS single-scattering correction of [NakajimaTanaka1988] (Eqs. 14-15), which puts the
    peak's light back about the sun; row 2: the octaves' asymmetry, the truncated phase's ``g* = (chi_1 - f) / (1 -
    f)`` (moments ``chi*_l = (chi_l - f) / (1 - f)``). The sky's and the ground's light (isotropic) keep their
    sources: the scaled albedo ``omega* = (1 - f) omega / (1 - omega f)`` is 1 within 1e-4 for water droplets in
    the visible.

    ``k`` (n_wl,) the extinction relative to 550 nm [-]; ``albedo`` (n_wl,) the single-scattering albedo [-];
    ``moments`` (n_wl, >= streams + 1) the phase function's Legendre moments ``chi_l`` [-] (``chi_1 = g``);
    ``streams`` ``N`` [-]: the forward fraction ``f = chi_N``; 0 gives ``f = 0`` (``k`` and ``g`` unchanged)."""
    k = np.asarray(k, dtype=float)
    chi = np.asarray(moments, dtype=float)
    if streams < 0 or (streams > 0 and chi.shape[-1] <= streams):
        raise InvalidParameterError(f"delta-M: need the moments 0..{streams}; got {chi.shape[-1]}")
    f = chi[:, streams] if streams > 0 else np.zeros(k.size)
    if np.any(f >= 1.0) or np.any(f < 0.0):
        raise InvalidParameterError(f"delta-M: the forward fraction must be in [0, 1); got {f}")
    scale = 1.0 - np.asarray(albedo, dtype=float) * f
    return np.ascontiguousarray(np.stack([k * scale, 1.0 / scale, (chi[:, 1] - f) / (1.0 - f)]))


#: Octave i weighted by (1 - exp(-tau_column))^i (module docstring).
THIN_AWARE = True
#: The octaves' light near a thick cloud's base shaped as the diffusion's (:func:`.broken_cloud_kernels.march_rays`;
#: since 2026-12-04, docs/clouds.md "The cloud base's limb darkening"): without it a nearly closed deck's base was
#: equally bright at every elevation, 1.2-1.3x the Monte Carlo's below 40 deg and 0.8-0.9x above.
BASE_PROFILE = True
#: Procedural fields: horizontal size [m], voxels (x, y, z) and noise feature size [m].
PROCEDURAL_SIZE = 16_000.0
PROCEDURAL_RESOLUTION = (128, 128, 32)
PROCEDURAL_FEATURE = 4_000.0
#: Sun cosines of the air's transmittance and irradiance tables read by the march.
_MU_NODES = np.linspace(-0.3, 1.0, 131)
#: Every how many of :data:`_MU_NODES` the sky's hemisphere integral on the clouds is taken (0.05 apart in the
#: sun's cosine; :func:`_sky_irradiance_levels` interpolates its ratio to the irradiance table between them).
_MU_NODE_STRIDE = 5
#: Rays per chunk of the march and its lookups (bounds the working arrays to about 100 MB).
CHUNK = 1 << 17
#: The march's step as a fraction of a voxel along the axis the ray crosses fastest.
STEP_FRACTION = 0.5
#: Block edge [voxels] of the empty-space skipping.
_BLOCK = 4
#: Light shafts (:meth:`BrokenCloudSky._shafts`): on (with the ground-cloud coupling and the clouds' light on the
#: air; docs/clouds.md has the accuracy with and without them); the first step [m], its growth with distance [-] and
#: the altitude nodes of the air's coefficients below the field's top.
_SHAFTS = True
#: The ground-cloud coupling (:attr:`BrokenCloudSky._ground_up`): its domain means of the diffuse light on
#: ``COUPLING_POINTS`` x ``COUPLING_POINTS`` ground points, ``COUPLING_DIRECTIONS`` (zeniths, azimuths) each.
COUPLING_POINTS = 4
COUPLING_DIRECTIONS = (8, 16)
SHAFT_STEP = 250.0
SHAFT_GROWTH = 0.02
SHAFT_NODES = 65
#: The shafts' nodes of the air's spectral integrand (:func:`.broken_cloud_kernels.shaft_loss`): at most this many
#: steps and this optical length of the air [-] (along the ray, or the altitude change's towards the sun) between
#: two (a ray's loss within 0.2 % of every step a node, tests/test_broken_cloud_shaft_nodes.py; docs/clouds.md).
SHAFT_GROUP = (16, 0.1)


def _sky_irradiance_levels(tab: Any, radii: NDArray[np.float64], mu: NDArray[np.float64]) -> NDArray[np.float64]:
    """The clear sky's downward irradiance [W m^-2 nm^-1] on a horizontal surface at ``radii`` [m] (the field's
    levels, (nz,)) under suns of cosines ``mu`` (:data:`_MU_NODES`), (nz, n_mu, n_wl): the tables' sky radiance
    integrated over the hemisphere ([Bruneton2008] Eq. 16;
    :meth:`~skyscatter.precomputed.evaluation.TableLookups.sky_irradiance_integral`), not the irradiance table
    (Eq. 15), whose rows are 4 km apart (linear in the altitude) and interpolate across an aerosol's scale height.

    The integral is taken on the radiance tables' own radius rows around the levels (linear in ``rho``, dense
    near the ground) and on every :data:`_MU_NODE_STRIDE`-th sun cosine; between the rows it is interpolated
    linearly in ``rho``, as the radiance tables themselves are, and along ``mu`` its ratio to the irradiance
    table's read at the same level is (the table holds the shape in the sun's cosine on all the nodes)."""
    bottom, top = tab.parameters.bottom_radius, tab.parameters.top_radius
    n_r = int(tab.sizes.scattering_r)
    big_h = math.sqrt(top * top - bottom * bottom)
    x = np.sqrt(np.maximum(radii**2 - bottom**2, 0.0)) / big_h * (n_r - 1)
    rows = np.arange(int(math.floor(x.min())), min(int(math.ceil(x.max())), n_r - 1) + 1)
    r_rows = np.sqrt((big_h * rows / (n_r - 1)) ** 2 + bottom**2)
    coarse = np.unique(np.append(np.arange(0, mu.size, _MU_NODE_STRIDE), mu.size - 1))
    up = np.array([0.0, 0.0, 1.0])

    def suns(m: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.stack([np.sqrt(1.0 - m**2), np.zeros_like(m), m], axis=-1)[None, :, :]

    def points(r: NDArray[np.float64]) -> NDArray[np.float64]:
        p = np.zeros((r.size, 1, 3))
        p[:, 0, 2] = r
        return p

    e_rows = tab.sky_irradiance_integral(points(r_rows), suns(mu[coarse]))  # (n_rows, n_coarse, n_wl)
    if rows.size > 1:
        k = np.clip(np.searchsorted(rows, x, side="right") - 1, 0, rows.size - 2)
        w = np.clip(x - rows[k], 0.0, 1.0)[:, None, None]
        e_levels = (1.0 - w) * e_rows[k] + w * e_rows[k + 1]
    else:
        e_levels = np.broadcast_to(e_rows[0], (radii.size, *e_rows.shape[1:]))
    _, table = tab.table_irradiance(points(radii), up, suns(mu))  # (nz, n_mu, n_wl)
    ratio_c = np.divide(e_levels, table[:, coarse], out=np.ones_like(e_levels), where=table[:, coarse] > 0.0)
    ratio = np.empty_like(table)
    for i in range(radii.size):
        for wl in range(table.shape[2]):
            ratio[i, :, wl] = np.interp(mu, mu[coarse], ratio_c[i, :, wl])
    return np.ascontiguousarray(table * ratio)


class BrokenCloudSky(SunSkyMixin, SkyModel):
    """The clear sky of the precomputed tables with a 3D cloud field in it (module docstring: the ray march).

    Parameters
    ----------
    sun_zenith, sun_azimuth : float
        Sun position at the observer [rad]; zenith in [0, pi/2] (the clouds are lit by the sun).
    cloud_cover : float
        Procedural field: fraction of the columns that hold cloud, in [0, 1] (default 0.5).
    cloud_seed : int
        Procedural field: seed of its noise (default 0).
    cloud_optical_depth : float
        Procedural field: mean vertical optical depth at 550 nm of its cloudy columns, in (0, 100] (default 10).
    cloud_base, cloud_top : float
        Procedural field: cloud base and highest tops [m], ``0 <= base < top <= 20 km`` (default 1000, 2500 m).
    cloud_effective_radius : float
        The droplets' effective radius [m] (Mie optics, effective variance 0.1), 1 to 50 um (default 10 um).
    cloud_field : str, optional
        A field file (NetCDF ``.nc`` or Zarr ``.zarr``, :meth:`~skyscatter.atmosphere.clouds.CloudField.load`)
        instead of the procedural one; its own droplet optics if it has them, else those of
        ``cloud_effective_radius``.
    clouds : CloudField, optional
        A field object instead (Python only).
    altitude : float
        Observer altitude above the ground [m], 0 to 1e8 (below, inside or above the field).
    ground_albedo : float, optional
        Ground albedo [-] (default: the atmosphere's).
    atmosphere : AtmosphereParameters, optional
        The clear air (default: the Earth defaults); its tables come from the cache.
    interpolation : {"linear", "voxel"}
        The march reads the field's densities (and its shadow volume) trilinearly between voxel centres (default:
        smooth cloud edges) or constant per voxel (the field's definition, as the Monte Carlo traces it).
    """

    model_name = "broken-cloud"
    renders_ground = True

    def __init__(self, sun_zenith: float, sun_azimuth: float = 0.0, *, cloud_cover: float = 0.5,
                 cloud_seed: int = 0, cloud_optical_depth: float = 10.0, cloud_base: float = 1000.0,
                 cloud_top: float = 2500.0, cloud_effective_radius: float = 10e-6, cloud_field: str | None = None,
                 clouds: Any = None, altitude: float = 0.0, ground_albedo: float | None = None,
                 atmosphere: AtmosphereParameters | None = None, interpolation: str = "linear") -> None:
        from ..atmosphere.clouds import CloudField, CloudLayer

        zen, azi = check_sun_angles(sun_zenith, sun_azimuth, allow_below_horizon=False)
        spec = registry.get(self.model_name)
        cover = spec.parameter("cloud_cover").check(cloud_cover)
        seed = spec.parameter("cloud_seed").check(cloud_seed)
        tau = spec.parameter("cloud_optical_depth").check(cloud_optical_depth)
        base = spec.parameter("cloud_base").check(cloud_base)
        top = spec.parameter("cloud_top").check(cloud_top)
        radius = spec.parameter("cloud_effective_radius").check(cloud_effective_radius)
        alt = spec.parameter("altitude").check(altitude)
        if ground_albedo is not None:
            ground_albedo = spec.parameter("ground_albedo").check(ground_albedo)
        if not top > base:
            raise InvalidParameterError(f"cloud_top ({top:g} m) must be above cloud_base ({base:g} m)")
        if clouds is not None and cloud_field is not None:
            raise InvalidParameterError("give the cloud field as clouds= or cloud_field= (a file), not both")
        drops = CloudLayer(0.0, 1.0, 1.0, effective_radius=radius)  # the droplets' optics only
        if clouds is not None:
            if not isinstance(clouds, CloudField):
                raise InvalidParameterError(f"clouds must be a CloudField; got {type(clouds).__name__}")
            field = clouds
        elif cloud_field is not None:
            field = _load_field(cloud_field, drops)
        else:
            field = CloudField.procedural(cover=cover, base=base, top=top, particles=drops, optical_depth=tau,
                                          size=PROCEDURAL_SIZE, resolution=PROCEDURAL_RESOLUTION,
                                          feature_size=PROCEDURAL_FEATURE, seed=seed)
        air = AtmosphereParameters() if atmosphere is None else atmosphere
        if not isinstance(air, AtmosphereParameters):
            raise InvalidParameterError(f"atmosphere must be AtmosphereParameters; got {type(air).__name__}")
        if ground_albedo is not None:
            air = air.replace(ground_albedo=ground_albedo)
        if field.top >= air.thickness:
            raise InvalidParameterError(f"the cloud field's top ({field.top:g} m) must be below the atmosphere's top "
                                        f"({air.thickness:g} m)")
        from .bruneton import BrunetonSky

        #: The clear sky of the same air (its tables light the clouds and lie behind them).
        self.clear = BrunetonSky(zen, azi, altitude=alt, atmosphere=air)
        self.field = field
        self.sun_zenith = zen
        self.sun_azimuth = azi
        self.altitude = alt
        self.sun_angular_radius = self.clear.sun_angular_radius
        #: ``(a, b, c, d, e)`` of the multiple scattering (:data:`FITTED_OCTAVES`; replaceable for fits).
        self.octaves = FITTED_OCTAVES
        if interpolation not in ("linear", "voxel"):
            raise InvalidParameterError(f"interpolation must be 'linear' or 'voxel'; got {interpolation!r}")
        #: "linear": densities interpolated between voxel centres (smooth edges, the default); "voxel": constant
        #: per voxel (the field's definition and the Monte Carlo's).
        self.interpolation = interpolation
        self._remember(cloud_cover=cover, cloud_seed=seed, cloud_optical_depth=tau, cloud_base=base, cloud_top=top,
                       cloud_effective_radius=radius, cloud_field=cloud_field, clouds=clouds, altitude=alt,
                       ground_albedo=ground_albedo, atmosphere=atmosphere, interpolation=interpolation)

    def __repr__(self) -> str:
        return (f"BrokenCloudSky(sun_zenith={self.sun_zenith:.6g}, sun_azimuth={self.sun_azimuth:.6g}, "
                f"field={self.field!r}, altitude={self.altitude:g})")

    # ------------------------------------------------------------------ what is computed once per sky

    @property
    def _tables(self):
        return self.clear.precomputed

    @cached_property
    def _sun_planet(self) -> NDArray[np.float64]:
        return np.ascontiguousarray(self.sun_direction, dtype=float)

    @cached_property
    def _exact(self):
        """The field packed for exact (regular) tracking (every voxel its own block)."""
        from ..montecarlo.tracking import pack_grid

        f = self.field
        return pack_grid(f.extinction, f.size, f.origin, f.base, f.top, f.periodic,
                         self._tables.parameters.bottom_radius, exact=True)

    def _relative_extinction(self, wavelengths: NDArray[np.float64]) -> NDArray[np.float64]:
        """The droplets' extinction at ``wavelengths`` relative to 550 nm."""
        from ..atmosphere.clouds import REFERENCE_WAVELENGTH

        p = self.field.particles
        return np.asarray(p.extinction_at(wavelengths), dtype=float) / float(p.extinction_at([REFERENCE_WAVELENGTH])[0])

    def optical_depth_to_sun(self, points: ArrayLike) -> NDArray[np.float64]:
        """The field's optical depth at 550 nm from ``points`` (..., 3) [m, planet-centred frame: the observer at
        ``(0, 0, bottom_radius + altitude)``] to the sun (exact through the voxels; 50 where it is larger)."""
        from ..precomputed.parallel import parallel_for
        from .broken_cloud_kernels import ground_shadow

        pts = np.asarray(points, dtype=float)
        shape = pts.shape[:-1]
        flat = np.ascontiguousarray(pts.reshape(-1, 3))
        out = np.zeros(flat.shape[0])
        e = self._exact
        parallel_for(ground_shadow, flat.shape[0], flat, e.vf, e.vi, e.rho, e.bmax, e.bmin, e.xe, e.ye, e.re,
                     self._sun_planet, out, grain=256)
        return out.reshape(shape)

    @cached_property
    def _volumes(self) -> dict[str, Any]:
        """The shadow volume, the vertical optical depths, the occupancy blocks and the geometry (module
        docstring)."""
        from ..precomputed.parallel import parallel_for
        from .broken_cloud_kernels import shadow_volume

        f = self.field
        e = self._exact
        rho = e.rho
        nx, ny, nz = rho.shape
        dx, dy, dz = f.voxel_size
        bottom = self._tables.parameters.bottom_radius
        gf = np.array([f.origin[0], f.origin[1], dx, dy, dz, f.size[0], f.size[1], bottom + f.base, bottom + f.top,
                       bottom, 1.0 if f.periodic else 0.0])
        tau_sun = np.zeros((nx, ny, nz))
        parallel_for(shadow_volume, rho.size, gf, e.vf, e.vi, rho, e.bmax, e.bmin, e.xe, e.ye, e.re,
                     self._sun_planet, tau_sun, grain=1024)
        layer = rho * dz
        above = np.cumsum(layer[:, :, ::-1], axis=2)[:, :, ::-1] - 0.5 * layer
        below = np.cumsum(layer, axis=2) - 0.5 * layer
        b = _BLOCK
        nbx, nby, nbz = -(-nx // b), -(-ny // b), -(-nz // b)
        pad = np.zeros((nbx * b, nby * b, nbz * b))
        # a voxel is occupied when it or a neighbour holds cloud (the trilinear density reaches half a voxel out)
        from scipy.ndimage import maximum_filter

        grown = maximum_filter(rho, size=3, mode="wrap" if f.periodic else "nearest")
        pad[:nx, :ny, :nz] = grown
        blocks = (pad.reshape(nbx, b, nby, b, nbz, b).max(axis=(1, 3, 5)) > 0).astype(np.uint8)
        # per voxel: whether its block holds cloud (one load in the march instead of three integer divisions)
        occupied = np.ascontiguousarray(np.repeat(np.repeat(np.repeat(blocks, b, 0), b, 1), b, 2)[:nx, :ny, :nz])
        # the march's volume: density and the three optical depths side by side, with one ghost voxel on each
        # horizontal side (wrapped or the edge repeated: the interpolation then needs no modulo), single precision
        # the vertical optical depths are stored times the density, so that the march's trilinear read weights
        # them by the cloud present (divided by the interpolated density there): a point at a cloud's side wall
        # then has its own column's depth, not one mixed with the clear columns' zeros (vertical streaks at
        # grazing views, docs/clouds.md)
        packed = np.stack([rho, tau_sun, rho * above, rho * below], axis=-1)
        packed = np.pad(packed, ((1, 1), (1, 1), (0, 0), (0, 0)), mode="wrap" if f.periodic else "edge")
        vol = np.ascontiguousarray(packed, dtype=np.float32)
        # the ground's mean shadow (the sun's share of the light the ground sends up to the cloud bases)
        xs, ys, _ = f.coordinates()
        gx, gy = np.meshgrid(xs, ys, indexing="ij")
        gz = np.sqrt(np.maximum(bottom**2 - gx**2 - gy**2, 0.0))
        tau_ground = self.optical_depth_to_sun(np.stack([gx, gy, gz], axis=-1))
        return {"gf": gf, "tau_sun": tau_sun, "vol": vol, "occupied": occupied, "tau_ground": tau_ground,
                "step": STEP_FRACTION}

    @cached_property
    def _light(self) -> dict[str, Any]:
        """The droplets' optics and the clear air's light at the table wavelengths (module docstring)."""
        tab = self._tables
        wl = np.asarray(tab.wavelengths, dtype=float)
        f = self.field
        p = f.particles
        k = self._relative_extinction(wl)
        albedo = np.asarray(p.single_scattering_albedo_at(wl), dtype=float)
        table = p.phase_table(wl)
        arr = table.numba_arrays()
        g = np.asarray(table.asymmetry, dtype=float)
        trunc = delta_m_octaves(k, albedo, table.legendre_moments(max(TRUNCATION_STREAMS, 1) + 1), TRUNCATION_STREAMS)
        bottom = tab.parameters.bottom_radius
        _, _, zc = f.coordinates()
        r = bottom + zc
        mu = _MU_NODES
        t_atm = np.asarray(tab.transmittance(r[:, None], mu[None, :]), dtype=float)
        # rays towards a sun below the point's horizon meet the ground: no sunlight
        horizon = -np.sqrt(np.maximum(1.0 - (bottom / r) ** 2, 0.0))
        t_atm[mu[None, :] < horizon[:, None]] = 0.0
        e_down = _sky_irradiance_levels(tab, r, mu)
        ground = np.array([0.0, 0.0, bottom])
        e_sun_g, e_sky_g = tab.ground_irradiance(ground, np.array([0.0, 0.0, 1.0]), self._sun_planet)
        shadow = np.exp(-np.multiply.outer(self._volumes["tau_ground"].ravel(), k)).mean(axis=0)
        albedo_g = np.asarray(tab.parameters.ground_albedo_at(wl), dtype=float)
        # the ground's upward light before the clouds' own diffuse light on it is added (:attr:`_ground_up`)
        e_up = albedo_g * (e_sun_g * shadow + e_sky_g)
        # the march's source tables: the albedo times the sun's transmittance, times the diffuse light / (2 pi)
        src_sun = np.ascontiguousarray(albedo * t_atm)
        src_amb = np.ascontiguousarray(albedo * np.asarray(e_down, dtype=float) / (2.0 * math.pi))
        amb_up = np.ascontiguousarray(albedo * np.asarray(e_up, dtype=float).reshape(-1) / (2.0 * math.pi))
        return {"wl": wl, "k": k, "albedo": albedo, "ph_mu": np.ascontiguousarray(arr.mu), "src_sun": src_sun,
                "src_amb": src_amb, "amb_up": amb_up,
                "ph_val": np.ascontiguousarray(arr.values), "g": g, "k_march": np.ascontiguousarray(trunc[0]),
                "trunc": np.ascontiguousarray(trunc[1:]),
                "solar": np.asarray(tab.parameters.solar_irradiance_at(wl), dtype=float),
                "t_atm": np.ascontiguousarray(t_atm), "e_down": np.ascontiguousarray(e_down),
                "e_up": np.ascontiguousarray(np.asarray(e_up, dtype=float).reshape(-1)), "ground_albedo": albedo_g,
                "e_direct_mean": np.asarray(e_sun_g, dtype=float).reshape(-1) * shadow,
                "e_sun_ground": np.asarray(e_sun_g, dtype=float).reshape(-1),
                "e_sky_ground": np.asarray(e_sky_g, dtype=float).reshape(-1)}

    @property
    def _ground_up(self) -> dict[str, Any]:
        """:meth:`_ground_coupling` for the current :attr:`octaves` (computed once per octaves: fits change them)."""
        key = tuple(self.octaves)
        cache = self.__dict__.setdefault("_coupling_cache", {})
        if key not in cache:
            cache.clear()
            cache[key] = self._ground_coupling()
        return cache[key]

    def _ground_coupling(self) -> dict[str, Any]:
        """The field's couplings with the ground below and the air above, at the table wavelengths: the ground's
        upward irradiance ``E_up`` under the field and the air's extra downward irradiance ``D`` at the field's
        top [W m^-2 nm^-1], solved together with the model's own light, and the march's source terms of them.

        *Ground* (since 2026-12-02): the ground (albedo ``rho_g``, Lambertian) sends up ``E_up = rho_g (E_dir +
        E_dif)``, the domain means of the direct sun through the field and of the diffuse light; under cloud
        ``E_dif`` is mostly the clouds' light and grows with ``E_up`` (the bases send part of it back down). The
        march adds ``E_up`` as an isotropic source ``omega E_up / (2 pi)`` scaled by the column's reflectance
        (:func:`.broken_cloud_kernels.march_rays`). Until 2026-12-02 the ground sent up the clear sky's diffuse
        light instead (2-6x too little under cover 0.9).

        *Air above* (the cloud-top-air coupling): the clear tables' sky at the field already holds the light the
        air sends back of the clear ground's upward light; the field changes the upward irradiance at its top by
        ``dU`` (the clouds reflect far more than the ground they hide), and the air above sends ``D = s dU`` of it
        back down ([Liou2002] Sec. 6.2, the adding method: a reflector under a layer of spherical albedo ``s`` gets
        the geometric series of the bounces, here solved with ``dU``'s own growth with ``D``). ``s``: the clear
        air above the field's top lit from below by isotropic light (:func:`.cloudy.air_spherical_albedo`,
        DISORT). ``D`` is isotropic radiance ``D / pi`` coming down at the top: in the march's sky source
        (:meth:`_ambient`) and through the gaps (:meth:`_composite`). Rayleigh's backscatter makes it bluish:
        the model's diffuse light was 3-5 % redder than the Monte Carlo's without it (docs/clouds.md).

        Solved on the domain means (``COUPLING_POINTS`` x ``COUPLING_POINTS`` points, ``COUPLING_DIRECTIONS``
        directions): the diffuse light on the ground ``f`` and the upward change at the top ``u`` are affine in
        ``(E_up, D)`` (sources of the march and of the gaps), so three evaluations of each (``(0, 0)``, ``(E_1,
        0)``, ``(0, D_1)``) give their slopes, and per wavelength the two equations ``E_up = rho_g (E_dir + f)``,
        ``D = s u`` are a 2 x 2 linear system."""
        li = self._light
        tab = self._tables
        rho = li["ground_albedo"]
        zero = np.zeros_like(li["amb_up"])
        if not np.any(self.field.extinction > 0.0):
            return {"e_up": li["e_up"], "amb_up": li["amb_up"], "air_light": zero, "top_down": zero,
                    "src_amb": li["src_amb"]}
        from .cloudy import air_spherical_albedo

        f = self.field
        m = COUPLING_POINTS
        u = (np.arange(m) + 0.5) / m
        grid = np.stack(np.meshgrid(f.origin[0] + u * f.size[0], f.origin[1] + u * f.size[1], indexing="ij"),
                        axis=-1).reshape(-1, 2)
        bottom = tab.parameters.bottom_radius
        ground = np.stack([grid[:, 0], grid[:, 1], np.sqrt(bottom**2 - (grid**2).sum(axis=1))], axis=-1)
        # just above the top (the eyes of the upward light; the march starts at the eye)
        tops = ground * ((bottom + f.top + 1.0) / bottom)
        s_air = air_spherical_albedo(tab.parameters, tab.wavelengths, f.top)
        unit = np.asarray(tab.parameters.solar_irradiance_at(tab.wavelengths), dtype=float) * math.pi / 10.0
        nz, na = COUPLING_DIRECTIONS

        def means(e_up: NDArray[np.float64], top_down: NDArray[np.float64]):
            amb = np.ascontiguousarray(li["albedo"] * e_up / (2.0 * math.pi))
            fd = self._ground_diffuse(grid, nz, na, amb_up=amb, top_down=top_down).mean(axis=0)
            uu = self._flux_change(tops, -1.0, nz, na, amb, top_down).mean(axis=0)
            return fd, uu

        f0, u0 = means(zero, zero)
        f1, u1 = means(unit, zero)
        f2, u2 = means(zero, unit)
        fe, ue = (f1 - f0) / unit, (u1 - u0) / unit  # slopes in E_up
        fdd, udd = (f2 - f0) / unit, (u2 - u0) / unit  # slopes in D
        # E_up (1 - rho fe) - rho fdd D = rho (E_dir + f0);  -s ue E_up + (1 - s udd) D = s u0
        a11, a12, b1 = 1.0 - rho * fe, -rho * fdd, rho * (li["e_direct_mean"] + f0)
        a21, a22, b2 = -s_air * ue, 1.0 - s_air * udd, s_air * u0
        det = a11 * a22 - a12 * a21
        e_up = (b1 * a22 - a12 * b2) / det
        # D < 0 where the field reflects less than the clear ground it hides (a bright ground): the tables' sky
        # holds more of the ground's light sent back than there is
        top_down = (a11 * b2 - a21 * b1) / det
        diffuse = f0 + fe * e_up + fdd * top_down
        # the clouds' change to the mean radiance over the sphere below the field's top (the air's extra light,
        # :meth:`_shafts`): down, the diffuse light at the ground less the clear sky's; up, the ground's light less
        # the clear ground's (each hemisphere isotropic: L = E / pi, the sphere's mean their average)
        down = diffuse - li["e_sky_ground"]
        up = e_up - rho * (li["e_sun_ground"] + li["e_sky_ground"])
        air_light = np.ascontiguousarray(np.maximum((down + up) / (2.0 * math.pi), 0.0))
        top_down = np.ascontiguousarray(top_down)
        return {"e_up": e_up, "amb_up": np.ascontiguousarray(li["albedo"] * e_up / (2.0 * math.pi)),
                "reflectance": np.clip(fe, 0.0, 1.0), "air_light": air_light, "top_down": top_down,
                "spherical_albedo": s_air, "upward_change": u0 + ue * e_up + udd * top_down,
                "src_amb": self._ambient(top_down)}

    # ------------------------------------------------------------------ the march

    def _ambient(self, top_down: NDArray[np.float64] | None) -> NDArray[np.float64]:
        """The march's source of the sky's light (n_layers, n_mu, n_wl): the clear tables' (:attr:`_light`) plus
        the albedo times ``top_down`` / (2 pi), the air's extra downward irradiance at the field's top
        [W m^-2 nm^-1] (None: :attr:`_ground_up`'s), isotropic like the tables' (the air within the field, a
        few per cent of an optical depth, neither dims nor adds to it)."""
        li = self._light
        if top_down is None:
            return self._ground_up["src_amb"]
        if not np.any(top_down != 0.0):
            return li["src_amb"]
        # D < 0 (a bright ground) takes back at most the sky light there is
        extra = li["albedo"] * top_down / (2.0 * math.pi)
        return np.ascontiguousarray(np.maximum(li["src_amb"] + extra[None, None, :], 0.0))

    def march(self, directions: ArrayLike, octaves: tuple[float, ...] | None = None,
              lod: float = 0.002, interpolation: str | None = None, origin: ArrayLike | None = None,
              amb_up: NDArray[np.float64] | None = None, top_down: NDArray[np.float64] | None = None):
        """The ray march alone for unit ``directions`` (n, 3): the cloud's radiance at the eye through the cloud
        (n, n_table_wavelengths) [W m^-2 sr^-1 nm^-1], the cloud's transmittance (n, n_wl), the mean depth of the
        cloud's light (n,) [m] and whether each ray met cloud (n,). ``octaves``: ``(a, b, c, d, e)`` instead of
        :attr:`octaves`; ``lod``: the step's growth with distance [-]; ``interpolation``: "linear" or "voxel"
        instead of :attr:`interpolation`; ``origin``: the eye (3,) [m, planet-centred] instead of the observer's;
        ``amb_up``: the march's source of the ground's upward light (n_wl,) instead of :attr:`_ground_up`'s;
        ``top_down``: the air's extra downward irradiance at the field's top (n_wl,) [W m^-2 nm^-1] instead of
        :attr:`_ground_up`'s (the light the air above sends back of the clouds' upward light)."""
        from ..precomputed.parallel import parallel_for
        from .broken_cloud_kernels import march_rays

        d = np.ascontiguousarray(np.asarray(directions, dtype=float).reshape(-1, 3))
        v = self._volumes
        li = self._light
        a, b, c, dd, e = self.octaves if octaves is None else octaves
        n = d.shape[0]
        nwl = li["k"].size
        rad = np.zeros((n, nwl))
        tr = np.ones((n, nwl))
        depth = np.zeros(n)
        hit = np.zeros(n, dtype=np.bool_)
        # the sun's cosine at the observer: over a field of tens of kilometres the planet turns it by < 1e-3 rad
        mp = np.array([a, b, c, dd, v["step"], lod, 0.0, *entry_factors(math.cos(self.sun_zenith), e),
                       1.0 if BASE_PROFILE else 0.0])
        origin = np.ascontiguousarray(self.clear.position if origin is None else origin, dtype=float)
        mu = _MU_NODES
        parallel_for(march_rays, n, origin, d, self._sun_planet, v["gf"], v["vol"], v["occupied"], _BLOCK,
                     li["k_march"], li["ph_mu"], self._octave_phases(c), li["g"], li["solar"], float(mu[0]),
                     float(mu[1] - mu[0]), li["src_sun"], self._ambient(top_down),
                     self._ground_up["amb_up"] if amb_up is None else amb_up, mp,
                     OCTAVES,
                     (interpolation or self.interpolation) == "linear", THIN_AWARE, rad, tr, depth, hit, grain=256)
        return rad, tr, depth, hit

    def _octave_phases(self, c: float) -> NDArray[np.float64]:
        """:func:`octave_phases` of the droplets for the eccentricity factor ``c`` [-] with :data:`OCTAVE_PHASE`,
        octave 0 times its delta-M factor (:func:`delta_m_octaves`; 1 without the truncation), (OCTAVES, n_wl, m):
        computed once per ``c`` (fits change it)."""
        key = (float(c), OCTAVE_PHASE, TRUNCATION_STREAMS)
        cache = self.__dict__.setdefault("_octave_cache", {})
        if key not in cache:
            cache.clear()
            li = self._light
            table = self.field.particles.phase_table(li["wl"])
            ph = octave_phases(table, float(c), OCTAVES, TRUNCATION_STREAMS, OCTAVE_PHASE)
            ph[0] *= li["trunc"][0][:, None]
            cache[key] = np.ascontiguousarray(ph)
        return cache[key]

    def _air_to_top(self, eye: NDArray[np.float64], d: NDArray[np.float64], r_top: float,
                    n_nodes: int = 2049) -> NDArray[np.float64]:
        """The air's transmittance (n, n_wl) from ``eye`` (3,) [m], below the field's top, along the directions
        ``d`` (n, 3) that do not meet the ground to the sphere of radius ``r_top`` [m].

        Seen from one eye the path, and so the transmittance, depends only on the cosine ``mu`` of a direction
        with the eye's vertical (the atmosphere is spherically symmetric): it is looked up
        (:meth:`aerial_perspective`, [Bruneton2008] Eq. 16) at ``n_nodes`` cosines spread with a square law
        towards the lowest (where the path to the top lengthens fastest) and interpolated linearly in its
        logarithm, rather than once per ray (a map's whole upper half): 2.2 CPU-s less per 2048 x 1024 map, the
        map within 6.2e-7 relative of the per-ray lookup (docs/clouds.md, Speed)."""
        r_eye = float(np.sqrt(eye @ eye))
        mu = d @ (eye / r_eye)
        lo, hi = float(mu.min()), float(mu.max())
        s = np.linspace(0.0, 1.0, n_nodes)
        nodes = lo + (hi - lo) * s * s
        # node directions in the plane of the eye's vertical (the azimuth does not matter)
        up = eye / r_eye
        side = np.cross(up, [1.0, 0.0, 0.0] if abs(up[0]) < 0.9 else [0.0, 1.0, 0.0])
        side /= np.linalg.norm(side)
        dn = nodes[:, None] * up[None, :] + np.sqrt(np.maximum(1.0 - nodes * nodes, 0.0))[:, None] * side[None, :]
        b = dn @ eye
        t_top = -b + np.sqrt(np.maximum(b * b - (eye @ eye - r_top * r_top), 0.0))
        t_nodes = self._air_transmittance(eye, eye + t_top[:, None] * dn)
        if hi <= lo:
            return np.repeat(t_nodes[:1], mu.size, axis=0)
        # the node below each cosine: invert the square law, then step back where rounding put it one too far
        k = np.clip(np.floor(np.sqrt(np.clip((mu - lo) / (hi - lo), 0.0, 1.0)) * (n_nodes - 1)).astype(np.int64),
                    0, n_nodes - 2)
        k -= (nodes[k] > mu) & (k > 0)
        w = np.clip((mu - nodes[k]) / np.maximum(nodes[k + 1] - nodes[k], 1e-300), 0.0, 1.0)[:, None]
        log_t = np.log(np.maximum(t_nodes, 1e-300))  # nearly linear in the path length: interpolated in log
        return np.exp(log_t[k] * (1.0 - w) + log_t[k + 1] * w)

    def _air_transmittance(self, eye: NDArray[np.float64], points: NDArray[np.float64]) -> NDArray[np.float64]:
        """The clear air's transmittance (n, n_table_wavelengths) [-] from ``eye`` (3,) to ``points`` (n, 3) [m,
        planet-centred]: the transmittance of :meth:`~skyscatter.precomputed.evaluation.TableLookups.
        aerial_perspective` ([Bruneton2008] Eq. 16) without its inscattered light, bit for bit. The whole ray is
        given as shadowed (Eq. 17's shadow length beyond any ray's length), so the lookup skips the inscatter
        integral, which the march never uses: it was most of the lookups' cost (the transmittance is two reads of
        a 2D table, the inscatter two of the 4D scattering tables)."""
        pts = np.asarray(points, dtype=float).reshape(-1, 3)
        t, _ = self._tables.aerial_perspective(eye, pts, self._sun_planet, shadow_length=np.full(pts.shape[0], 1e30))
        return t

    def _composite(self, d: NDArray[np.float64], hit_only: bool = False, eye: NDArray[np.float64] | None = None,
                   amb_up: NDArray[np.float64] | None = None, top_down: NDArray[np.float64] | None = None):
        """Table-wavelength radiance of the rays ``d`` (n, 3) that meet cloud or ground shadow, and the mask of
        the rays that differ from the clear sky; seen from ``eye`` (3,) [m] (default: the observer); ``amb_up``
        and ``top_down`` as in :meth:`march` (both given while the coupling is solved)."""
        tab = self._tables
        eye = self.clear.position if eye is None else eye
        top_down = self._ground_up["top_down"] if top_down is None else top_down
        rad, tr, depth, hit = self.march(d, origin=eye, amb_up=amb_up, top_down=top_down)
        sun = self._sun_planet
        # views that meet the ground (before leaving the atmosphere): the clouds' shadows there
        bottom = tab.parameters.bottom_radius
        b = d @ eye
        disc = b * b - (eye @ eye - bottom * bottom)
        t_ground = np.where(disc >= 0.0, -b - np.sqrt(np.maximum(disc, 0.0)), -1.0)
        ground = t_ground > 0.0
        # the air's extra light from above the field's top (``top_down``, isotropic, radiance top_down / pi), seen
        # from below the top along rays that leave through it (over the field's box when it is open), dimmed by the
        # cloud on the way and the air up to the top
        sky_up = None
        r_top = bottom + self.field.top
        if np.any(top_down != 0.0) and float(eye @ eye) < r_top * r_top:
            t_top = -b + np.sqrt(np.maximum(b * b - (eye @ eye - r_top * r_top), 0.0))
            # not the rays that meet the planet: from an eye on the ground (t_ground = 0, so not in ``ground``)
            # the lower half's way "to the top" ran through the planet, and its light (up to 0.27 of the return's,
            # 1.2 % of the ground's luminance) was added to the ground seen from there
            up_rows = np.flatnonzero(~((disc >= 0.0) & (b < 0.0)))
            if not self.field.periodic and up_rows.size:
                f = self.field
                exit_pts = eye + t_top[up_rows, None] * d[up_rows]
                over = ((exit_pts[:, 0] >= f.origin[0]) & (exit_pts[:, 0] < f.origin[0] + f.size[0])
                        & (exit_pts[:, 1] >= f.origin[1]) & (exit_pts[:, 1] < f.origin[1] + f.size[1]))
                up_rows = up_rows[over]
            if up_rows.size:
                t_air = self._air_to_top(eye, d[up_rows], r_top)
                sky_up = (up_rows, t_air * tr[up_rows] * (top_down / math.pi)[None, :])
        changed = hit.copy()
        if sky_up is not None:
            changed[sky_up[0]] = True
        out = np.zeros((d.shape[0], tab.wavelengths.size))
        # the shafts and the clouds' light scattered by the air (not while the ground-cloud coupling is solved: that
        # light is the coupling's result)
        air = None  # the air's light below the field's top: gain - loss (n, n_wl)
        if _SHAFTS:
            limits = (np.where(hit, depth, np.inf), np.where(ground, t_ground, np.inf))
            if amb_up is None:
                loss, gain = self._shafts(d, eye, *limits, cloud_light=True)
            else:
                loss, gain = self._shafts(d, eye, *limits), 0.0
            air = gain - loss
        shafted = np.zeros(d.shape[0], dtype=bool) if air is None else np.any(air != 0.0, axis=1)
        changed |= shafted
        # the ground points in the field's shadow, found first: the rest of the ground a ray meets is the clear
        # sky's own unless something else changed the ray (its lookup here would be thrown away: the clear sky's
        # is taken for the unchanged rays)
        shade = None
        g_rows = np.flatnonzero(ground)
        if g_rows.size:
            gpts = eye + t_ground[g_rows, None] * d[g_rows]
            gpts *= (bottom / np.linalg.norm(gpts, axis=-1))[:, None]
            tau = self._ground_optical_depth(gpts)
            shadowed = tau > 0.0
            if np.any(shadowed):
                shade = (g_rows[shadowed], gpts[shadowed], tau[shadowed])
                changed[shade[0]] = True
        idx = np.flatnonzero(hit | changed)
        if idx.size == 0:
            return out, changed
        dd = d[idx]
        value = tab.sky_radiance(eye, dd, sun)  # a new array: updated in place below
        if air is not None:
            value += air[idx]
        if sky_up is not None:  # its rows are among idx (both sorted): added in place, no full-size copy
            value[np.searchsorted(idx, sky_up[0])] += sky_up[1]
        h = hit[idx]
        if np.any(h):
            ih = idx[h]  # the rays' own rows (indexing twice, rad[idx][h], copied every ray's row first)
            pts = eye + depth[ih, None] * d[ih]
            t_air = self._air_transmittance(eye, pts)
            behind = tab.sky_radiance(pts, d[ih], sun)
            value[h] += t_air * (rad[ih] - (1.0 - tr[ih]) * behind)
        if shade is not None:
            s_rows, gpts, tau = shade
            lit = 1.0 - np.exp(-np.multiply.outer(tau, self._light["k"]))
            e_sun, _ = tab.ground_irradiance(gpts, gpts / bottom, sun)
            t_air = self._air_transmittance(eye, gpts)
            value[np.searchsorted(idx, s_rows)] -= (t_air * tr[s_rows] * self._light["ground_albedo"] / math.pi
                                                    * e_sun * lit)
        out[idx] = np.maximum(value, 0.0)
        return out, changed

    @cached_property
    def _shaft_air(self) -> dict[str, Any]:
        """The clear air's single-scattering coefficients and sunlight below the field's top for
        :meth:`shafts`: altitude nodes ``SHAFT_NODES`` from the ground to the top, at the table wavelengths."""
        tab = self._tables
        air = tab.parameters
        wl = np.asarray(tab.wavelengths, dtype=float)
        h = np.linspace(0.0, self.field.top, SHAFT_NODES)
        beta_r, beta_m = air.scattering_coefficients(h, wl)
        beta_e = air.extinction_coefficient(h, wl)
        bottom = air.bottom_radius
        r = bottom + h
        mu = _MU_NODES
        t_sun = np.asarray(tab.transmittance(r[:, None], mu[None, :]), dtype=float)
        horizon = -np.sqrt(np.maximum(1.0 - (bottom / r) ** 2, 0.0))
        t_sun[mu[None, :] < horizon[:, None]] = 0.0
        src = t_sun * np.asarray(air.solar_irradiance_at(wl), dtype=float)
        # the scalar altitude profiles of the shafts' nodes (the sums over wavelength); the nodes need the
        # coefficients separable, beta(h, l) = rho(h) beta(l) (exponential Rayleigh and one aerosol profile), else
        # every step is a node
        rho_r, rho_m = beta_r.sum(axis=1), beta_m.sum(axis=1)
        separable = all(np.allclose(b, np.outer(p, b.sum(axis=0) / max(p.sum(), 1e-300)), rtol=1e-9, atol=0.0)
                        for b, p in ((beta_r, rho_r), (beta_m, rho_m)))
        group = np.array(SHAFT_GROUP if separable else (1, 0.0), dtype=float)
        phase = air.aerosol_phase_table(wl).numba_arrays()
        return {"rho_r": np.ascontiguousarray(rho_r), "rho_m": np.ascontiguousarray(rho_m), "group": group,
                "ph_mu": np.ascontiguousarray(phase.mu), "ph_val": np.ascontiguousarray(phase.values),
                "h_step": float(h[1] - h[0]), "beta_r": np.ascontiguousarray(beta_r, dtype=float),
                "beta_m": np.ascontiguousarray(beta_m, dtype=float),
                "beta_e": np.ascontiguousarray(beta_e, dtype=float), "src": np.ascontiguousarray(src)}

    def _shafts(self, directions: ArrayLike, eye: ArrayLike | None = None, cloud_depth: ArrayLike | None = None,
               ground_distance: ArrayLike | None = None, cloud_light: bool = False):
        """The air's single-scattered sunlight that the field's shadow removes along unit view ``directions`` (n, 3)
        (light shafts), (n, n_table_wavelengths) [W m^-2 sr^-1 nm^-1], >= 0: the single-scattering integral of the air
        ([Bruneton2008] Eq. 11 with the sun's light L0 of Eq. 9, as its single Rayleigh and Mie tables hold it) times
        ``1 - exp(-tau k)`` (:func:`.broken_cloud_kernels.shaft_loss`) over the view ray's part below the field's top,
        from ``eye`` (3,) [m, planet-centred; default the observer] to the first of the cloud's mean depth
        ``cloud_depth`` (n,) [m], the ground at ``ground_distance`` (n,) [m] (inf: none) and the ray's exit through the
        field's top sphere. Steps of :data:`SHAFT_STEP` m growing as :data:`SHAFT_GROWTH` x the distance. Only the
        single scattering: the shadow's effect on the air's multiple scattering (light that reaches the point after
        scattering elsewhere, most of it from outside the shadow) is kept. ``cloud_light``: also return the clouds'
        light the air scatters towards the eye over the same part of the ray (:attr:`_ground_up`'s change of the mean
        radiance, :func:`.broken_cloud_kernels.shaft_loss`), ``(loss, gain)``."""
        from ..precomputed.parallel import parallel_for
        from .broken_cloud_kernels import shaft_loss

        tab = self._tables
        d = np.ascontiguousarray(np.asarray(directions, dtype=float).reshape(-1, 3))
        n = d.shape[0]
        nwl = tab.wavelengths.size
        eye = np.ascontiguousarray(self.clear.position if eye is None else eye, dtype=float)
        end = np.full(n, np.inf)
        for limit in (cloud_depth, ground_distance):
            if limit is not None:
                end = np.minimum(end, np.asarray(limit, dtype=float).reshape(-1))
        out = np.zeros((n, nwl))
        gain = np.zeros((n, nwl))
        if not np.any(self.field.extinction > 0.0):
            return (out, gain) if cloud_light else out
        bottom = tab.parameters.bottom_radius
        r_top = bottom + self.field.top
        b = d @ eye
        c = float(eye @ eye)
        disc = b * b - (c - r_top * r_top)
        s = np.sqrt(np.maximum(disc, 0.0))
        inside = c < r_top * r_top
        t0 = np.where(inside, 0.0, np.maximum(-b - s, 0.0))
        # the planet: a ray that goes down meets it (from the ground at once: the caller's distance is then <= 0)
        g_disc = b * b - (c - bottom * bottom)
        t_planet = np.where((g_disc >= 0.0) & (b < 0.0), np.maximum(-b - np.sqrt(np.maximum(g_disc, 0.0)), 0.0),
                            np.inf)
        t1 = np.minimum(np.minimum(-b + s, end), t_planet)
        seg = np.where(disc >= 0.0, np.maximum(t1 - t0, 0.0), 0.0)
        seg[~np.isfinite(seg)] = 0.0
        rows = np.flatnonzero(seg > 0.0)
        if rows.size == 0:
            return (out, gain) if cloud_light else out
        sun = self._sun_planet
        dr = np.ascontiguousarray(d[rows])
        nu = np.clip(dr @ sun, -1.0, 1.0)
        air = tab.parameters
        p_r = np.ascontiguousarray(air.rayleigh_phase(nu), dtype=float)
        part = np.ones((rows.size, nwl))
        part_gain = np.zeros((rows.size, nwl))
        far = t0[rows] > 0.0
        if np.any(far):
            part[far] = self._air_transmittance(eye, eye + t0[rows][far, None] * dr[far])
        sa = self._shaft_air
        v = self._volumes
        mu = _MU_NODES
        parallel_for(shaft_loss, rows.size, eye, dr, np.ascontiguousarray(seg[rows]),
                     np.ascontiguousarray(t0[rows]), sun, v["gf"], np.ascontiguousarray(v["tau_ground"]),
                     np.ascontiguousarray(v["tau_sun"]), sa["h_step"], sa["beta_r"], sa["beta_m"], sa["beta_e"],
                     sa["rho_r"], sa["rho_m"], sa["src"], float(mu[0]), float(mu[1] - mu[0]), p_r, sa["ph_mu"],
                     sa["ph_val"], self._light["k"], SHAFT_STEP, SHAFT_GROWTH, sa["group"],
                     self._ground_up["air_light"] if cloud_light else np.zeros(nwl), part, part_gain, grain=64)
        out[rows] = part
        gain[rows] = part_gain
        return (out, gain) if cloud_light else out

    def _ground_optical_depth(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        """The field's optical depth to the sun from ground ``points`` (n, 3): bilinear in the map of the voxel
        columns' centres (periodic fields; exact per point for open ones, whose shadows reach outside the box)."""
        f = self.field
        if not f.periodic:
            return self.optical_depth_to_sun(points)
        tau = self._volumes["tau_ground"]
        nx, ny = tau.shape
        dx, dy, _ = f.voxel_size
        u = (points[:, 0] - f.origin[0]) / dx - 0.5
        v = (points[:, 1] - f.origin[1]) / dy - 0.5
        i0 = np.floor(u).astype(np.int64)
        j0 = np.floor(v).astype(np.int64)
        fu = u - i0
        fv = v - j0
        i0 %= nx
        j0 %= ny
        i1 = (i0 + 1) % nx
        j1 = (j0 + 1) % ny
        return ((tau[i0, j0] * (1 - fu) + tau[i1, j0] * fu) * (1 - fv)
                + (tau[i0, j1] * (1 - fu) + tau[i1, j1] * fu) * fv)

    def _directions(self, directions: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64], tuple[int, ...]]:
        """Unit directions (n, 3) for the march, the caller's directions (n, 3) for the clear sky (so that rays
        without cloud get the clear sky's own bits), and the shape."""
        d = as_directions(directions)
        shape = d.shape[:-1]
        raw = np.asarray(directions, dtype=float).reshape(-1, 3)
        return np.ascontiguousarray(d.reshape(-1, 3), dtype=float), raw, shape

    def _chunks(self, d: NDArray[np.float64], raw: NDArray[np.float64], channels: int, clear,
                convert) -> NDArray[np.float64]:
        """``(n, channels)`` values of the rays ``d`` in chunks of :data:`CHUNK` (bounded memory): the clear sky's
        ``clear(raw)`` where nothing changed, ``convert(table radiance)`` elsewhere."""
        out = np.zeros((d.shape[0], channels))
        for start in range(0, d.shape[0], CHUNK):
            part = d[start:start + CHUNK]
            view = out[start:start + CHUNK]
            tab_rad, changed = self._composite(part)
            if np.any(changed):
                view[changed] = convert(tab_rad[changed])
            if np.any(~changed):
                view[~changed] = clear(raw[start:start + CHUNK][~changed])
        return out

    def table_radiance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] at the table wavelengths, (..., n_table_wavelengths)."""
        d, raw, shape = self._directions(directions)
        out = self._chunks(d, raw, self._tables.wavelengths.size, self.clear.table_radiance, lambda v: v)
        return out.reshape(*shape, -1)

    # ------------------------------------------------------------------ the protocol

    def spectral_radiance(self, directions: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] of sky, clouds and ground (no solar disc), (..., n_wl); rays
        that meet no cloud (nor its shadow) are the clear sky's :meth:`BrunetonSky.spectral_radiance`."""
        wl = DEFAULT_WAVELENGTHS if wavelengths is None else as_wavelengths(wavelengths)
        d, raw, shape = self._directions(directions)
        out = self._chunks(d, raw, wl.size, lambda v: self.clear.spectral_radiance(v, wl),
                           lambda v: self._tables.resample(v, wl))
        return out.reshape(*shape, wl.size)

    def xyz(self, directions: ArrayLike) -> NDArray[np.float64]:
        """CIE 1931 XYZ [cd m^-2] (..., 3); rays that meet no cloud are the clear sky's :meth:`BrunetonSky.xyz`."""
        d, raw, shape = self._directions(directions)
        return self._chunks(d, raw, 3, self.clear.xyz, self._tables.to_xyz).reshape(*shape, 3)

    def luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Luminance [cd m^-2] (...)."""
        return self.xyz(directions)[..., 1]

    def sun_shadow(self, points: ArrayLike, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """The field's transmittance to the sun from ``points`` (n, 3) [m] of a flat scene (x east, y north, z above
        the ground at the observer's foot: a point's altitude is its z and its tangent-plane position its x, y) over
        the transmittance from the eye (which dims :attr:`sun`), at ``wavelengths`` [nm], (n, n_wl): exact through
        the voxels (cloud shadows on terrain; both optical depths are capped at 50, so the ratio stays finite)."""
        pts = np.asarray(points, dtype=float).reshape(-1, 3)
        wl = as_wavelengths(wavelengths)
        bottom = self._tables.parameters.bottom_radius
        z = np.sqrt(np.maximum((bottom + pts[:, 2]) ** 2 - pts[:, 0] ** 2 - pts[:, 1] ** 2, 0.0))
        tau = self.optical_depth_to_sun(np.stack([pts[:, 0], pts[:, 1], z], axis=-1))
        tau_eye = float(self.optical_depth_to_sun(self.clear.position[None, :])[0])
        return np.exp(-np.multiply.outer(tau - tau_eye, self._relative_extinction(wl)))

    def sun_transmittance(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """The field's transmittance from the eye to the sun's centre at ``wavelengths`` [nm] (n,)."""
        wl = as_wavelengths(wavelengths)
        tau = float(self.optical_depth_to_sun(self.clear.position[None, :])[0])
        return np.exp(-tau * self._relative_extinction(wl))

    def sun_spectral_radiance(self, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Mean spectral radiance of the solar disc [W m^-2 sr^-1 nm^-1]: the clear sky's, times the field's
        transmittance towards the sun's centre."""
        wl = DEFAULT_WAVELENGTHS if wavelengths is None else as_wavelengths(wavelengths)
        return self.clear.sun_spectral_radiance(wl) * self.sun_transmittance(wl)

    # ------------------------------------------------------------------ irradiance on the ground

    def ground_irradiance(self, points: ArrayLike | None = None, wavelengths: ArrayLike | None = None, *,
                          zeniths: int = 16, azimuths: int = 32) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Direct and diffuse spectral irradiance [W m^-2 nm^-1] on the horizontal ground at ``points``.

        Parameters
        ----------
        points : array_like, shape (n, 2), optional
            East and north offsets [m] of ground points from the observer's foot point (the field's horizontal
            coordinates); default one point at (0, 0).
        wavelengths : array_like, optional
            [nm] (default 380-780 nm every 10 nm), resampled from the table wavelengths like
            :meth:`spectral_radiance` (``E / E_sun`` linear in wavelength; zero outside the tables).
        zeniths, azimuths : int
            The diffuse part's quadrature: midpoints in ``sin^2`` of the zenith angle (``zeniths`` of them, equal
            projected solid angle) times ``azimuths`` midpoints in azimuth, about each point's own vertical.

        Returns
        -------
        direct, diffuse : ndarray, shape (n, n_wl)
            ``direct``: the tables' direct sun on the ground at the point ([Bruneton2008] Eq. 14's sun term) times
            the field's exact transmittance ``exp(-tau k)`` to the sun's centre (:meth:`optical_depth_to_sun`;
            ``k`` the droplets' extinction at ``wavelengths`` relative to 550 nm);
            ``diffuse``: ``E = int L cos(theta) d omega`` of this model's sky radiance (clouds, the octaves'
            multiple scattering, the clear sky and the air in front and behind) seen from the point, without the
            solar disc: the tables' clear-sky irradiance ([Bruneton2008] Eq. 14's sky term) plus ``pi mean(L -
            L_clear)`` over the quadrature (the clear sky's own peaks, the aureole and the horizon, need no
            quadrature: with 16 x 32 nodes they alone were 0.3-2.3 % off at 440-640 nm, sun 30 deg high).
        """
        from ..validation import whole_number

        nz = whole_number("zeniths", zeniths, 1)
        na = whole_number("azimuths", azimuths, 1)
        pts = np.zeros((1, 2)) if points is None else np.asarray(points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2 or not np.all(np.isfinite(pts)) or np.any(np.abs(pts) > 1e6):
            raise InvalidParameterError("points must be (n, 2) finite (east, north) offsets within 1000 km [m]")
        wl = DEFAULT_WAVELENGTHS if wavelengths is None else as_wavelengths(wavelengths)
        return self._ground_direct(pts, wl), self._tables.resample(self._ground_diffuse(pts, nz, na), wl)

    def _ground_diffuse(self, pts: NDArray[np.float64], nz: int, na: int,
                        amb_up: NDArray[np.float64] | None = None,
                        top_down: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
        """The diffuse part of :meth:`ground_irradiance` at the table wavelengths (n, n_table_wavelengths)
        [W m^-2 nm^-1] on ``nz`` x ``na`` directions; ``amb_up`` and ``top_down`` as in :meth:`march`."""
        tab = self._tables
        bottom = tab.parameters.bottom_radius
        ground = np.stack([pts[:, 0], pts[:, 1], np.sqrt(bottom**2 - pts[:, 0] ** 2 - pts[:, 1] ** 2)], axis=-1)
        _, e_sky = tab.ground_irradiance(ground, ground / bottom, self._sun_planet)
        return e_sky + self._flux_change(ground, 1.0, nz, na, amb_up, top_down)

    def _flux_change(self, eyes: NDArray[np.float64], side: float, nz: int, na: int,
                     amb_up: NDArray[np.float64] | None, top_down: NDArray[np.float64] | None) -> NDArray[np.float64]:
        """The field's change of the irradiance [W m^-2 nm^-1] at the table wavelengths (n, n_wl) on horizontal
        planes at ``eyes`` (n, 3) [m, planet-centred], from the hemisphere above them (``side`` 1: downward light)
        or below them (-1: upward light): ``pi mean(L - L_clear)`` over ``nz`` x ``na`` directions of equal
        projected solid angle about each eye's vertical (the clear sky's own peaks, the aureole and the horizon,
        need no quadrature: they cancel in the difference); ``amb_up`` and ``top_down`` as in :meth:`march`."""
        tab = self._tables
        sun = self._sun_planet
        # equal projected solid angle: s = sin^2(theta) uniform, E = (1/2) int ds dphi L = pi mean(L)
        s = (np.arange(nz) + 0.5) / nz
        phi = (np.arange(na) + 0.5) / na * 2.0 * math.pi
        st, ct = np.sqrt(s)[:, None], np.sqrt(1.0 - s)[:, None]
        local = np.stack([np.broadcast_to(st * np.sin(phi), (nz, na)), np.broadcast_to(st * np.cos(phi), (nz, na)),
                          np.broadcast_to(side * ct, (nz, na))], axis=-1).reshape(-1, 3)  # (east, north, up)
        out = np.zeros((eyes.shape[0], tab.wavelengths.size))
        for i in range(eyes.shape[0]):  # one eye per call (the march takes one origin); directions vectorised
            up = eyes[i] / np.linalg.norm(eyes[i])
            d = np.ascontiguousarray(local @ _rotation_to(up).T)
            rad, changed = self._composite(d, eye=eyes[i], amb_up=amb_up, top_down=top_down)
            change = rad[changed] - tab.sky_radiance(eyes[i], d[changed], sun)
            out[i] = math.pi * change.sum(axis=0) / d.shape[0]
        return out

    def domain_ground_irradiance(self, wavelengths: ArrayLike | None = None, *, points_per_axis: int = 8,
                                 direct_points: int = 4, zeniths: int = 32,
                                 azimuths: int = 64) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Direct and diffuse spectral irradiance [W m^-2 nm^-1] on the ground averaged over the field's domain
        (its horizontal box), each (n_wl,): the direct part over ``direct_points`` x ``direct_points`` cell
        centres under every voxel column (a single point per column aliases with the voxel grid: for the sun
        along the grid's diagonal, 30 deg high, the column centres' mean was 4.5 % above the 4 x 4 points' under
        a cover of 0.9), the diffuse part over a grid of ``points_per_axis`` x ``points_per_axis`` cell centres of
        the domain (:meth:`ground_irradiance`, whose ``zeniths`` and ``azimuths`` these are). The quantity the
        Monte Carlo's forward photons give over a periodic domain
        (:func:`skyscatter.montecarlo.domain.domain_quantities`, a flux level at the ground)."""
        from ..validation import whole_number

        m = whole_number("points_per_axis", points_per_axis, 1)
        q = whole_number("direct_points", direct_points, 1)
        f = self.field
        nx, ny, _ = f.shape
        dx, dy, _ = f.voxel_size
        sub = (np.arange(q) + 0.5) / q
        xs = f.origin[0] + (np.arange(nx)[:, None] + sub[None, :]).ravel() * dx
        ys = f.origin[1] + (np.arange(ny)[:, None] + sub[None, :]).ravel() * dy
        cols = np.stack(np.meshgrid(xs, ys, indexing="ij"), axis=-1).reshape(-1, 2)
        direct = sum(self._ground_direct(c, wavelengths).sum(axis=0)
                     for c in np.array_split(cols, max(1, cols.shape[0] // CHUNK))) / cols.shape[0]
        u = (np.arange(m) + 0.5) / m
        grid = np.stack(np.meshgrid(f.origin[0] + u * f.size[0], f.origin[1] + u * f.size[1], indexing="ij"),
                        axis=-1).reshape(-1, 2)
        _, diffuse = self.ground_irradiance(grid, wavelengths, zeniths=zeniths, azimuths=azimuths)
        return direct, diffuse.mean(axis=0)

    def _ground_direct(self, points: NDArray[np.float64], wavelengths: ArrayLike | None) -> NDArray[np.float64]:
        """The direct part of :meth:`ground_irradiance` alone (n, n_wl) [W m^-2 nm^-1]."""
        wl = DEFAULT_WAVELENGTHS if wavelengths is None else as_wavelengths(wavelengths)
        tab = self._tables
        bottom = tab.parameters.bottom_radius
        ground = np.stack([points[:, 0], points[:, 1],
                           np.sqrt(bottom**2 - points[:, 0] ** 2 - points[:, 1] ** 2)], axis=-1)
        e_sun, _ = tab.ground_irradiance(ground, ground / bottom, self._sun_planet)
        tau = self.optical_depth_to_sun(ground)
        # the field's transmittance at the wavelengths asked for, not resampled from the tables': behind optical
        # depths of 10-50 the droplets' 1 % Mie ripple in extinction is a 5 % ripple in the transmittance
        return tab.resample(e_sun, wl) * np.exp(-np.multiply.outer(tau, self._relative_extinction(wl)))


def _rotation_to(up: NDArray[np.float64]) -> NDArray[np.float64]:
    """The rotation (3, 3) taking the observer's vertical (0, 0, 1) to the unit vector ``up`` by the shortest arc
    (Rodrigues: ``I + [v]x + [v]x^2 / (1 + c)``, ``v = z x up``, ``c = z . up``; ``up`` in the upper half)."""
    v = np.array([-up[1], up[0], 0.0])
    vx = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + vx + vx @ vx / (1.0 + up[2])


def _load_field(path: Any, particles: Any):
    """A field file, with ``particles`` when it holds no optics (one-line errors: FileFormatError,
    InvalidParameterError)."""
    from ..atmosphere.clouds import CloudField
    from ..errors import FileFormatError

    if not isinstance(path, (str, bytes)) and not hasattr(path, "__fspath__"):
        raise InvalidParameterError(f"cloud_field must be a file name; got {path!r}")
    try:
        return CloudField.load(path)
    except FileFormatError as exc:
        if "particles" in str(exc) or "optics" in str(exc):
            return CloudField.load(path, particles=particles)
        raise
