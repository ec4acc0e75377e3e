"""Engine-ready textures of the precomputed atmosphere: the spectral tables folded into colour, packed as RGBA.

The 4D inscattering tables hold spectra (16 wavelengths by default), more channels than a GPU texture holds (4).
As in Bruneton's 2017 rewrite [Bruneton2017] the spectral precomputation is folded into colour after the fact:
the radiance a lookup returns is a sum of table values times phase factors that do not depend on wavelength
([Bruneton2008] Sec. 4, "Angular precision": ``L = S_R P_R + S_M P_M + S_multiple``), and the conversion to colour
is a matrix ``M`` (3 x n_wavelengths: the CIE 1931 observer integral of :func:`.precomputed.conversion.xyz_matrix`,
then XYZ to linear sRGB, times the HDR scale ``1 / 683``), so ``M L = (M S_R) P_R + (M S_M) P_M + M S_multiple``:
folding each table with ``M`` gives *exactly* the colour of the spectral lookup, at any sun elevation (the colour of
a twilight sky is an integral over the spectrum, which 3 wavelengths cannot give, docs/bruneton.md).

Products of spectra do not fold exactly. The transmittance is folded as the transmittance *of sunlight*,
``T_c = (M (E_sun T))_c / (M E_sun)_c``, which makes the sun's disc and the sunlight on the ground exact; the light
of the ground seen through the air (``T_view albedo (E_sun T_sun + E_sky)``) is then a product of three folded
factors. Measured on the default tables against the spectral product: 0.05 % RMS, worst 0.5 % from 10 km, worst
7.6 % from orbit with the sun 4 deg below the horizon, where the ground is lit by reddened twilight
(docs/realtime.md). The transmittance between two points is a ratio, ``T(x, y) = T(x) / T(y)`` ([Bruneton2008]
Sec. 4), which the ratio of two folded transmittances gets wrong where ``T(y)`` is small in a channel (long grazing
paths: up to 150 % off, or negative); there the ratio of the band-averaged optical depths is used,
``exp(-(tau_c(x) - tau_c(y)))``, ``tau_c = sum w_c(lambda) tau(lambda)`` with ``w_c`` the positive part of the colour
row times the solar spectrum, normalised: a ratio taken exactly in the log domain, off by the spread of ``tau``
across the band (rule :data:`SEGMENT_RULE`).

Files (all little-endian, C order, RGBA interleaved per texel, row 0 first = texture coordinate 0):

* ``transmittance`` 2D, width n_mu x height n_r: RGB sunlight transmittance to the top, A the same for luminance.
* ``optical_depth`` 2D, same layout: RGB the optical depth to the top averaged over each channel's band, A over the
  luminance's; for the transmittance between two points where a ratio of sunlight transmittances is ill-conditioned.
* ``irradiance`` 2D, width n_mu_s x height n_r: RGB sky irradiance on a horizontal surface [HDR scale], A 0
  (manifest version 10; versions 6-9 held the illuminance of the table's spectrum, unread since version 9). The
  library reads it
  linearly along mu_s except in the cells that start below the horizon, where the twilight irradiance falls faster
  the lower the sun: there each channel of the cell's two texel columns has its own weight, log_quadratic_weight
  (three-point Lagrange in the logarithm, manifest version 7) of that channel in the three nearest columns (each
  linear in r; manifest version 9, as :func:`skyscatter.precomputed.sampling.irradiance_read` reads each wavelength;
  ``irradiance_uvs``, ``irradiance_lerp`` and ``log_quadratic_weight`` of the mappings).
* ``rayleigh``, ``mie``, ``multiple`` 3D, width n_nu * n_mu_s (x = i_nu * n_mu_s + i_mu_s), height n_mu, depth n_r:
  the library's lookup tables (:attr:`skyscatter.precomputed.PrecomputedAtmosphere.lookup_tables`): the stored
  tables refined along the sun zenith (manifest version 11), their first C cells (those below the horizon and the
  one across it: :func:`skyscatter.precomputed.geometry.twilight_cells`, 8 of the default 32, -12 to +0.78 deg; 7
  until 2026-12-05, the cells wholly below the horizon; none where fewer than two texels lie below it) split into
  ``MU_S_SPLIT`` (3) sub-cells whose texels hold the single scattering computed at their suns
  (:func:`skyscatter.precomputed.compute.stored_single_scattering`) and the four-point Lagrange rule in the logarithm
  of the stored texels for the multiple scattering (fewer than four: the fall-backs of
  :func:`skyscatter.precomputed.lookup.refine_sun_zenith`), so n_mu_s = the stored count + 2 C (48 of the default
  32). The refinement is per wavelength and not linear, so it is done before the fold: the texture
  unit's linear read of a folded texel column is then the fold of the library's linear read of the refined
  spectra. The mu_s position of a read is the stored axis' p, times 3 in the split cells (p < C), else p + 2 C
  (``scattering_mu_s_index`` of the mappings, :func:`skyscatter.precomputed.geometry.refined_mu_s_cell`).
  RGB single Rayleigh and single Mie scattering without their phase functions, multiple scattering with it and
  divided by the lobe ``multiple_lobe(nu)`` of the mappings at each texel's own nu (manifest version 10, table
  format 19: :func:`skyscatter.precomputed.sampling.multiple_lobe`; ``inscattered_radiance`` multiplies by it at
  the lookup's nu, so the interpolation between nu slices follows the aerosol's forward lobe); A the
  table's own value at its middle wavelength (index n_wavelengths // 2, the manifest's
  ``azimuth_weight_wavelength_nm``; spectral, W m^-2 nm^-1 or W m^-2 sr^-1 nm^-1, not on the HDR scale). The
  library's lookups (table format 12) interpolate between the two nu slices of a lookup with the weight
  :func:`skyscatter.precomputed.geometry.log_lerp_weight` of that wavelength's values in the two slices, each
  interpolated linearly in (mu_s, mu, r) (:func:`skyscatter.precomputed.sampling.nu_weight`), and apply it to every
  wavelength: the texture unit's trilinear read of A gives those two values, so a shader computes the same weight
  and applies it to RGB (``log_lerp_weight`` and ``azimuth_lerp`` of the mappings). The multiple scattering since
  manifest version 12 through four nu slices (:func:`skyscatter.precomputed.sampling.lookup4_cell_azimuth`: the
  four-point Lagrange rule where the four A lie within ``AZIMUTH_RATIO_FOUR_POINT`` of each other, the weight above
  beyond ``AZIMUTH_RATIO_LOG_LINEAR``, blended between; ``scattering_uvw4`` and ``azimuth_read`` of the mappings).
  Except for the single scattering
  where the point is in the Earth's shadow (manifest version 3): there the library interpolates the two slices
  linearly, each times the density of its constituent where the query's ray leaves the shadow over that where the
  slice's ray leaves it, at most ``SHADOW_RATIO_MAX`` (:func:`skyscatter.precomputed.sampling.shadow_nu_weights`;
  ``single_scattering_lerp``, ``shadow_factors`` of the mappings, with the density profiles ``RAYLEIGH_DENSITY``,
  ``MIE_DENSITY`` of the constants). The luminance (Y) that A held in manifest version 1 is the RGB's dot product
  with ``hdr_scale.luminance_from_rgb``.

in ``.rgba32f`` (float32), ``.rgba16f`` (IEEE half) and ``.exr`` (OpenEXR, float32 R, G, B, A; a 3D texture's
depth slices stacked vertically) form, with ``skyscatter_realtime.json``: the version, sizes, constants, units, the
HDR scale, and every mapping as code (Python source evaluated by the tests against the library's own lookups, the
GLSL of :data:`GLSL_LIBRARY`).

Reference: [Bruneton2008], [Bruneton2017].
"""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError, OutputError
from ..fileio import atomic_paths
from ..spectral import HDR_SCALE, xyz_to_linear_srgb

if TYPE_CHECKING:  # pragma: no cover
    from ..precomputed import PrecomputedAtmosphere

__all__ = ["FORMATS", "MANIFEST_FORMAT", "MANIFEST_NAME", "MANIFEST_VERSION", "PYTHON_MAPPINGS", "TEXTURE_NAMES",
           "engine_textures", "export_realtime", "fold_matrix", "glsl_constants", "glsl_library", "glsl_mappings"]

MANIFEST_NAME = "skyscatter_realtime.json"
MANIFEST_FORMAT = "skyscatter-realtime-luts"
#: Raised whenever a file's layout or meaning changes; readers refuse other versions. 2: the scattering textures'
#: alpha holds each table's middle wavelength (was Y), from which the azimuth weight is computed. 3: the constants
#: hold the Rayleigh and aerosol density profiles, and the single scattering's azimuth weight follows the Earth's
#: shadow (shadow_factors of the mappings). 4: the irradiance texture's alpha holds its middle wavelength (was Y),
#: from which the weight along mu_s below the horizon is computed (irradiance_uvs, irradiance_lerp). 5: within the
#: cell of rows touching the ground the scattering textures' rows are read each at its own mu coordinate and mixed
#: linearly in the altitude (scattering_ground_cell, scattering_texture; skyscatter table format 16). 6: the
#: irradiance texture's alpha holds the illuminance [lx] of its spectrum (the library's weight along mu_s: the same
#: for any set of table wavelengths); the constant SHADOW_RATIO_MAX (shadow_factors). 7: below the horizon the
#: irradiance texture is read quadratically in the logarithm over three mu_s columns (irradiance_uvs returns three
#: columns and the position t, irradiance_lerp takes three reads; log_quadratic_weight). 8: the altitude weight and
#: the rows apart of version 5 only where the cell touching the ground ends below 300 m (skyscatter table format 18).
#: 9: below the horizon each channel of the irradiance texture has its own weight along mu_s (irradiance_lerp; the
#: lookups read each wavelength with its own), the alpha is no longer read. 10: the multiple-scattering texture holds
#: the multiple scattering divided by the lobe MultipleLobe(nu) (constants MULTIPLE_LOBE, MULTIPLE_LOBE_G; multiple_lobe
#: and inscattered_radiance of the mappings; skyscatter table format 19); the irradiance texture's alpha is 0 (was the
#: illuminance, unread since version 9). 11: the scattering textures hold the library's lookup tables refined along
#: the sun zenith (the first SCATTERING_MU_S_CELLS cells split into MU_S_SPLIT sub-cells; SCATTERING_N_MU_S is the
#: refined count; scattering_mu_s_index of the mappings returns the refined position). Which cells are split and
#: what their sub-texels hold (since 2026-12-05 also the cell across the horizon, and the single scattering
#: computed) is the library's, carried by those constants: a version-11 reader reads either export. 12: the
#: multiple-scattering texture is read along the azimuth through four nu slices (scattering_uvw4, azimuth_read of the
#: mappings; constants AZIMUTH_RATIO_FOUR_POINT, AZIMUTH_RATIO_LOG_LINEAR), as the library's lookups since
#: 2026-12-06 (skyscatter.precomputed.sampling.lookup4_cell_azimuth); the textures are unchanged.
MANIFEST_VERSION = 12
#: File formats: suffix and description.
FORMATS = {"rgba32f": "raw little-endian float32 RGBA", "rgba16f": "raw little-endian IEEE 754 half RGBA",
           "exr": "OpenEXR, float32 R, G, B, A (3D textures: depth slices stacked vertically, r slowest)"}
TEXTURE_NAMES = ("transmittance", "optical_depth", "irradiance", "rayleigh", "mie", "multiple")
#: The segment rule (module docstring): where the far end's sunlight transmittance in a channel is below 0.02 the
#: optical depths give the segment's transmittance, above 0.1 the ratio, blended linearly between (a switch at one
#: threshold leaves a seam). Measured on the default tables, 395 segments of 0.5-50 km from 0, 2 and 10 km at
#: -1..20 deg, single thresholds: 0.05 gave absolute error median 0.25 %, 95th percentile 2.5 %, worst 7 % (ratio
#: alone: worst 152 %; optical depths alone: median 2.9 %); 0.02 / 0.1 gave worst 13 % / 7.2 %.
SEGMENT_RULE = ("T(x, y)_c = mix(exp(-max(tau_c(x) - tau_c(y), 0)), clamp(T_c(x) / T_c(y), 0, 1), s), "
                "s = clamp((T_c(y) - 0.02) / 0.08, 0, 1); T: the transmittance texture, tau: the optical_depth "
                "texture (rgb); x the nearer end, both read along the ray towards the top (rays that meet the ground: "
                "both reversed)")
#: Largest finite IEEE half.
HALF_MAX = 65504.0

#: The texture-coordinate mappings as Python (standard library only), the same functions as the GLSL library's
#: mapping section; ``exec`` it with the manifest's constants (``BOTTOM_RADIUS`` ... ``MIE_DENSITY``) defined.
PYTHON_MAPPINGS = '''
import math

def safe_sqrt(a):
    return math.sqrt(max(a, 0.0))

def tex_coord(p, n):
    """Index position p in [0, n - 1] to a texture coordinate: texel i is centred at (i + 0.5) / n."""
    return (p + 0.5) / n

def clamp(x, lo, hi):
    return min(max(x, lo), hi)

def distance_to_top(r, mu):
    disc = (TOP_RADIUS - r) * (TOP_RADIUS + r) + r * r * mu * mu
    s = safe_sqrt(disc)
    if mu > 0.0:
        return max((TOP_RADIUS - r) * (TOP_RADIUS + r) / (r * mu + s), 0.0)
    return max(-r * mu + s, 0.0)

def distance_to_bottom(r, mu):
    disc = r * r * mu * mu - (r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS)
    q = -r * mu + safe_sqrt(disc)
    return 0.0 if q <= 0.0 else max((r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS) / q, 0.0)

def ray_hits_ground(r, mu):
    return mu < 0.0 and r * r * mu * mu - (r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS) >= 0.0

def transmittance_uv(r, mu):
    """(u, v) in the transmittance texture (width mu, height r) of the ray (r [m], mu) to the top."""
    big_h = math.sqrt((TOP_RADIUS - BOTTOM_RADIUS) * (TOP_RADIUS + BOTTOM_RADIUS))
    rho = safe_sqrt((r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS))
    d = distance_to_top(r, mu)
    d_min, d_max = TOP_RADIUS - r, rho + big_h
    x_mu = (d - d_min) / (d_max - d_min) if d_max > d_min else 0.0
    return (tex_coord(clamp(x_mu, 0.0, 1.0) * (TRANSMITTANCE_N_MU - 1), TRANSMITTANCE_N_MU),
            tex_coord(clamp(rho / big_h, 0.0, 1.0) * (TRANSMITTANCE_N_R - 1), TRANSMITTANCE_N_R))

def irradiance_uv(r, mu_s):
    """(u, v) in the irradiance texture (width mu_s, height r)."""
    x_r = clamp((r - BOTTOM_RADIUS) / (TOP_RADIUS - BOTTOM_RADIUS), 0.0, 1.0)
    x_mu_s = clamp(0.5 * (mu_s + 1.0), 0.0, 1.0)
    return (tex_coord(x_mu_s * (IRRADIANCE_N_MU_S - 1), IRRADIANCE_N_MU_S),
            tex_coord(x_r * (IRRADIANCE_N_R - 1), IRRADIANCE_N_R))

def irradiance_uvs(r, mu_s):
    """The texture coordinates (u, v) of three consecutive mu_s texel columns of the irradiance texture for a read at
    mu_s (each read linear in r; the third may lie past the last column, where its weight is 0), the position t in
    [-1, 1] relative to the middle one (the read's cell is the first two for t < 0, else the last two) and whether
    the cell starts below the horizon (its first column at mu_s < 0; then the three are the nearest texels, the cell
    and the texel next to its nearer end): a lookup is irradiance_lerp(texture(uv0), texture(uv1), texture(uv2), t,
    below)."""
    x_r = clamp((r - BOTTOM_RADIUS) / (TOP_RADIUS - BOTTOM_RADIUS), 0.0, 1.0)
    p = clamp(0.5 * (mu_s + 1.0), 0.0, 1.0) * (IRRADIANCE_N_MU_S - 1)
    j = min(math.floor(p), IRRADIANCE_N_MU_S - 2)
    below = 2 * j < IRRADIANCE_N_MU_S - 1
    j0 = min(max(j - 1 if p - j < 0.5 else j, 0), IRRADIANCE_N_MU_S - 3) if below else j
    v = tex_coord(x_r * (IRRADIANCE_N_R - 1), IRRADIANCE_N_R)
    return (tex_coord(j0, IRRADIANCE_N_MU_S), v), (tex_coord(j0 + 1, IRRADIANCE_N_MU_S), v), \
        (tex_coord(j0 + 2, IRRADIANCE_N_MU_S), v), p - (j0 + 1), below

def log_quadratic_weight(y0, y1, y2, t):
    """Weight of the upper end of the cell around t (y0, y1 for t < 0, else y1, y2) for lo + weight (hi - lo) that
    follows ln y quadratic through three values at consecutive texels (t in [-1, 1] relative to the middle one): the
    three-point Lagrange formula in the logarithm, kept between the cell's two values; log_lerp_weight of the cell
    where a value is not positive, the fraction of the cell where its two values are equal."""
    lo, hi, w = (y0, y1, t + 1.0) if t < 0.0 else (y1, y2, t)
    if not (y0 > 0.0 and y1 > 0.0 and y2 > 0.0):
        return log_lerp_weight(lo, hi, w)
    y = math.exp(0.5 * t * (t - 1.0) * math.log(y0) + (1.0 - t * t) * math.log(y1)
                 + 0.5 * t * (t + 1.0) * math.log(y2))
    return w if hi == lo else clamp((y - lo) / (hi - lo), 0.0, 1.0)

def irradiance_lerp(e0, e1, e2, t, below):
    """RGB of the irradiance texture from the reads e0, e1, e2 (RGBA) of its three mu_s columns at t: where the cell
    starts below the horizon each channel of the cell's two columns with its own weight, log_quadratic_weight of that
    channel's three values (the twilight blue and red fall at other rates), else linear in the cell."""
    a, b = (e0, e1) if t < 0.0 else (e1, e2)
    if not below:
        k = t + 1.0 if t < 0.0 else t
        return [x + k * (y - x) for x, y in zip(a[:3], b[:3])]
    return [x + log_quadratic_weight(e0[c], e1[c], e2[c], t) * (y - x) for c, (x, y) in enumerate(zip(a[:3], b[:3]))]

def scattering_r_index(r, rho, big_h):
    """Index position of r on the depth axis of the 3D scattering textures: the rows sit at rho_i = H i / (n - 1)
    (x_r = rho / H), and within the cell between rows i and i + 1, if row i lies below 200 m (the cell touching the
    ground and the next), the position is linear in r (the altitude), not in rho; r - r_i is formed as
    (rho^2 - rho_i^2) / (r + r_i), without cancellation."""
    n = SCATTERING_N_R - 1
    x = clamp(rho / big_h, 0.0, 1.0) * n
    i = min(math.floor(x), n - 1)
    rho0, rho1 = big_h * i / n, big_h * (i + 1) / n
    r0 = math.sqrt(rho0 * rho0 + BOTTOM_RADIUS * BOTTOM_RADIUS)
    if rho0 * rho0 >= 200.0 * (r0 + BOTTOM_RADIUS):
        return x  # the cells from 200 m up: linear in rho (measured better there)
    r1 = math.sqrt(rho1 * rho1 + BOTTOM_RADIUS * BOTTOM_RADIUS)
    if rho1 * rho1 >= 300.0 * (r1 + BOTTOM_RADIUS):
        return x  # a cell reaching above 300 m (tables with few rows): linear in rho
    w = (rho * rho - rho0 * rho0) * (r1 + r0) / ((rho1 * rho1 - rho0 * rho0) * (max(r, BOTTOM_RADIUS) + r0))
    return i + clamp(w, 0.0, 1.0)

def scattering_sky_mu_index(r, rho, big_h, mu):
    """Index position on the mu axis (n/2 .. n - 1, zenith to horizon) of a ray from r [m] (rho = sqrt(r^2 - R_g^2))
    that misses the ground: the mean of (d - d_min) / (d_max - d_min) (d to the top, d_min = R_t - r,
    d_max = rho + H) and theta / theta_h (zenith angle over the horizon's)."""
    half = SCATTERING_N_MU // 2
    d = distance_to_top(r, mu)
    d_min, d_max = TOP_RADIUS - r, rho + big_h
    x_d = (d - d_min) / (d_max - d_min) if d_max > d_min else 0.0
    x_a = math.acos(clamp(mu, -1.0, 1.0)) / math.acos(clamp(-rho / r, -1.0, 1.0))
    return half + 0.5 * (clamp(x_d, 0.0, 1.0) + clamp(x_a, 0.0, 1.0)) * (half - 1)

def scattering_mu_r_coords(r, mu, hits_ground):
    """(v, w) in the 3D scattering textures: the mu coordinate (height) and the r coordinate (depth:
    scattering_r_index for rays that miss the ground, rho / H for rays that meet it). Within the cell touching the
    ground a ray that misses the ground is read from each row at its own mu coordinate (scattering_ground_cell)."""
    big_h = math.sqrt((TOP_RADIUS - BOTTOM_RADIUS) * (TOP_RADIUS + BOTTOM_RADIUS))
    rho = safe_sqrt((r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS))
    half = SCATTERING_N_MU // 2
    if hits_ground:
        d = distance_to_bottom(r, mu)
        d_min = r - BOTTOM_RADIUS
        x = (d - d_min) / (rho - d_min) if rho > d_min else 0.0
        p_mu = (1.0 - clamp(x, 0.0, 1.0)) * (half - 1)
    else:
        p_mu = scattering_sky_mu_index(r, rho, big_h, mu)
    # rays that meet the ground: linear in rho (their mu coordinate fixes a length to the ground nearly linear in rho)
    p_r = clamp(rho / big_h, 0.0, 1.0) * (SCATTERING_N_R - 1) if hits_ground else scattering_r_index(r, rho, big_h)
    return tex_coord(p_mu, SCATTERING_N_MU), tex_coord(p_r, SCATTERING_N_R)

def scattering_ground_cell(r, mu, hits_ground):
    """Within the cell of rows touching the ground (below the first row above it), for a ray that misses the ground:
    (v0, v1, w), the mu coordinates at which rows 0 and 1 hold the ray's direction (scattering_sky_mu_index with
    each row's own radius) and the altitude weight of row 1 (scattering_r_index); None elsewhere. A lookup reads
    the two rows there and mixes them with w (scattering_texture)."""
    if hits_ground:
        return None
    big_h = math.sqrt((TOP_RADIUS - BOTTOM_RADIUS) * (TOP_RADIUS + BOTTOM_RADIUS))
    rho = safe_sqrt((r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS))
    p_r = scattering_r_index(r, rho, big_h)
    rho1 = big_h / (SCATTERING_N_R - 1)
    r1 = math.sqrt(rho1 * rho1 + BOTTOM_RADIUS * BOTTOM_RADIUS)
    if p_r >= 1.0 or rho1 * rho1 >= 300.0 * (r1 + BOTTOM_RADIUS):
        return None  # above the cell, or a cell reaching above 300 m (few rows): one shared coordinate
    return (tex_coord(scattering_sky_mu_index(BOTTOM_RADIUS, 0.0, big_h, mu), SCATTERING_N_MU),
            tex_coord(scattering_sky_mu_index(r1, rho1, big_h, mu), SCATTERING_N_MU), p_r)

def scattering_texture(sample, uvw, cell):
    """A scattering texture's RGBA at uvw (of scattering_uvw) read with sample(uvw) (the GPU's trilinear read), or,
    within the cell touching the ground (cell of scattering_ground_cell, not None), its rows 0 and 1 each at their
    own v, mixed with the altitude weight."""
    if cell is None:
        return list(sample(uvw))
    a = sample((uvw[0], cell[0], tex_coord(0.0, SCATTERING_N_R)))
    b = sample((uvw[0], cell[1], tex_coord(1.0, SCATTERING_N_R)))
    return [x + cell[2] * (y - x) for x, y in zip(a, b)]

def mu_s_distance_unit(mu_s):
    big_h = math.sqrt((TOP_RADIUS - BOTTOM_RADIUS) * (TOP_RADIUS + BOTTOM_RADIUS))
    d_min = TOP_RADIUS - BOTTOM_RADIUS
    return (distance_to_top(BOTTOM_RADIUS, mu_s) - d_min) / (big_h - d_min)

def scattering_mu_s_index(mu_s):
    """Index position of mu_s along an nu slice of the refined axis (0 at MU_S_MIN, SCATTERING_N_MU_S - 1 at the
    zenith): p, the position on the stored axis of SCATTERING_N_MU_S - (MU_S_SPLIT - 1) SCATTERING_MU_S_CELLS
    texels, is MU_S_SPLIT p in the first SCATTERING_MU_S_CELLS cells (split into MU_S_SPLIT sub-cells each) and
    p + (MU_S_SPLIT - 1) SCATTERING_MU_S_CELLS above them (the same at p = SCATTERING_MU_S_CELLS)."""
    a = mu_s_distance_unit(mu_s)
    big_a = mu_s_distance_unit(MU_S_MIN)
    x_d = clamp(max(1.0 - a / big_a, 0.0) / (1.0 + a), 0.0, 1.0)
    x_a = clamp(1.0 - math.acos(clamp(mu_s, -1.0, 1.0)) / math.acos(MU_S_MIN), 0.0, 1.0)
    cells = SCATTERING_MU_S_CELLS
    p = 0.5 * (x_d + x_a) * (SCATTERING_N_MU_S - (MU_S_SPLIT - 1) * cells - 1)
    return MU_S_SPLIT * p if p < cells else p + (MU_S_SPLIT - 1) * cells

def scattering_nu_index(mu, mu_s, nu):
    """Index position of nu (x_nu = 1 - phi / pi, phi the view-sun azimuth)."""
    s = safe_sqrt((1.0 - mu * mu) * (1.0 - mu_s * mu_s))
    if s < 1e-9:
        return 0.5 * (SCATTERING_N_NU - 1)
    cphi = clamp((nu - mu * mu_s) / s, -1.0, 1.0)
    return (1.0 - math.acos(cphi) / math.pi) * (SCATTERING_N_NU - 1)

def scattering_uvw(r, mu, mu_s, nu, hits_ground):
    """The two texture coordinates (u, v, w) of the nu slices around nu and the fraction w of the cell between
    them: a single-scattering lookup is single_scattering_lerp(texture(uvw0), texture(uvw1), ...), each read
    trilinear, or within the cell touching the ground with scattering_texture(texture, uvw,
    scattering_ground_cell(r, mu, hits_ground)); the multiple scattering reads four slices (scattering_uvw4)."""
    v, w = scattering_mu_r_coords(r, mu, hits_ground)
    p_s = scattering_mu_s_index(max(mu_s, MU_S_MIN))
    p_n = clamp(scattering_nu_index(mu, mu_s, nu), 0.0, SCATTERING_N_NU - 1)
    i_n = min(math.floor(p_n), SCATTERING_N_NU - 2)
    n_x = SCATTERING_N_NU * SCATTERING_N_MU_S
    u0 = (i_n * SCATTERING_N_MU_S + p_s + 0.5) / n_x
    return (u0, v, w), (u0 + SCATTERING_N_MU_S / n_x, v, w), p_n - i_n

def log_lerp_weight(a, b, w):
    """Weight of the second of two values a, b (>= 0) at the fraction w of the cell for a + weight (b - a) that
    follows a log-linear (exponential) variation: w a' / (w a' + (1 - w) sqrt(a' b')), a' and b' the values with
    the smaller raised to at least LOG_LERP_FLOOR times the larger; w where both are zero."""
    m = max(a, b)
    lo = LOG_LERP_FLOOR * m
    a2 = max(a, lo)
    b2 = max(b, lo)
    wa = w * a2
    d = wa + (1.0 - w) * math.sqrt(a2 * b2)
    return wa / d if d > 0.0 else w

def azimuth_lerp(s0, s1, w):
    """RGB of a scattering texture between the reads s0, s1 (RGBA) of its two nu slices: the weight is
    log_lerp_weight of their alpha (the table's middle wavelength), applied to every channel."""
    k = log_lerp_weight(s0[3], s1[3], w)
    return [a + k * (b - a) for a, b in zip(s0[:3], s1[:3])]

def scattering_uvw4(r, mu, mu_s, nu, hits_ground):
    """The multiple scattering's read along the azimuth: the texture coordinates of four nu slices (the cell's two,
    those of scattering_uvw, and one on each side; the axis runs over the view-sun azimuth from pi to 0 and the sky
    is symmetric about both ends, so the slice before the first is the second and the one after the last the one
    before it), the fraction w of the cell and the four-point Lagrange weights at w (-w (w - 1) (w - 2) / 6,
    (w + 1) (w - 1) (w - 2) / 2, -(w + 1) w (w - 2) / 2, (w + 1) w (w - 1) / 6), for azimuth_read."""
    uvw0, uvw1, w = scattering_uvw(r, mu, mu_s, nu, hits_ground)
    p_n = clamp(scattering_nu_index(mu, mu_s, nu), 0.0, SCATTERING_N_NU - 1)
    i_n = min(math.floor(p_n), SCATTERING_N_NU - 2)
    j0 = i_n - 1 if i_n > 0 else 1
    j3 = i_n + 2 if i_n + 2 <= SCATTERING_N_NU - 1 else 2 * (SCATTERING_N_NU - 1) - (i_n + 2)
    du = 1.0 / SCATTERING_N_NU  # one nu slice along x
    uvws = [(uvw0[0] + (j0 - i_n) * du, uvw0[1], uvw0[2]), uvw0, uvw1, (uvw0[0] + (j3 - i_n) * du, uvw0[1], uvw0[2])]
    lagrange = (-w * (w - 1.0) * (w - 2.0) / 6.0, 0.5 * (w + 1.0) * (w - 1.0) * (w - 2.0),
                -0.5 * (w + 1.0) * w * (w - 2.0), (w + 1.0) * w * (w - 1.0) / 6.0)
    return uvws, w, lagrange

def azimuth_read(s, w, lagrange):
    """RGB of the multiple-scattering texture from the reads s[0] .. s[3] (RGBA) of its four nu slices
    (scattering_uvw4): the four-point weights where the four alphas (the table's middle wavelength) lie within a
    factor AZIMUTH_RATIO_FOUR_POINT of each other, the log-linear read of the middle two (log_lerp_weight of their
    alphas) beyond AZIMUTH_RATIO_LOG_LINEAR or where an alpha is not positive, blended linearly in the ratio in
    between; one set of weights for every channel."""
    a = [x[3] for x in s]
    lo = min(a)
    hi = max(a)
    beta = 0.0
    if lo > 0.0:
        beta = clamp((AZIMUTH_RATIO_LOG_LINEAR - hi / lo) / (AZIMUTH_RATIO_LOG_LINEAR - AZIMUTH_RATIO_FOUR_POINT),
                     0.0, 1.0)
    g = log_lerp_weight(a[1], a[2], w)
    k = (beta * lagrange[0], beta * lagrange[1] + (1.0 - beta) * (1.0 - g), beta * lagrange[2] + (1.0 - beta) * g,
         beta * lagrange[3])
    return [sum(k[e] * s[e][c] for e in range(4)) for c in range(3)]

def shadow_lerp(s0, s1, w, f):
    """RGB of a single-scattering texture between the reads s0, s1 (RGBA) of its two nu slices where the point is
    in the Earth's shadow (in_earth_shadow): linear, each slice times its shadow factor f[0], f[1]
    (shadow_factors)."""
    return [(1.0 - w) * f[0] * a + w * f[1] * b for a, b in zip(s0[:3], s1[:3])]

def single_scattering_lerp(s0, s1, r, mu, mu_s, nu, w, constituent):
    """A single-scattering lookup ("rayleigh" or "mie") between its two nu slices: shadow_lerp where the point is in
    the Earth's shadow, else azimuth_lerp (the multiple scattering: azimuth_read of four slices)."""
    if in_earth_shadow(r, max(mu_s, MU_S_MIN)):
        return shadow_lerp(s0, s1, w, shadow_factors(r, mu, mu_s, nu, constituent))
    return azimuth_lerp(s0, s1, w)

def shadow_cylinder_c(r, mu_s):
    """r^2 (1 - mu_s^2) - R_g^2 [m^2], negative inside the Earth's shadow cylinder (written without cancellation)."""
    s = safe_sqrt((1.0 - mu_s) * (1.0 + mu_s))
    return ((r - BOTTOM_RADIUS) - r * mu_s * mu_s / (1.0 + s)) * (r * s + BOTTOM_RADIUS)

def in_earth_shadow(r, mu_s):
    """True if the point (r [m], sun zenith cosine mu_s) is in the Earth's geometric shadow."""
    return mu_s < 0.0 and shadow_cylinder_c(r, mu_s) < 0.0

def shadow_exit_altitude(r, mu, mu_s, nu):
    """Altitude [m] where the ray (r, mu; view-sun cosine nu) leaves the Earth's shadow (the start's if it is lit; at
    most TOP_RADIUS - BOTTOM_RADIUS): the larger root of (1 - nu^2) t^2 + 2 r (mu - mu_s nu) t + r^2 (1 - mu_s^2)
    - R_g^2 = 0, or the plane y.s = 0 at t = -r mu_s / nu if nearer."""
    c = shadow_cylinder_c(r, mu_s)
    if mu_s >= 0.0 or c >= 0.0:
        return clamp(r - BOTTOM_RADIUS, 0.0, TOP_RADIUS - BOTTOM_RADIUS)
    a = (1.0 - nu) * (1.0 + nu)
    b = r * (mu - mu_s * nu)
    q = safe_sqrt(b * b - a * c)
    t = math.inf
    if b > 0.0:
        t = -c / (b + q)
    elif a > 1e-12:
        t = (q - b) / a
    if nu > 0.0:
        t = min(t, -r * mu_s / nu)
    if t == math.inf:
        return TOP_RADIUS - BOTTOM_RADIUS
    e2 = t * t + 2.0 * r * mu * t + (r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS)
    h = e2 / (safe_sqrt(t * t + 2.0 * r * mu * t + r * r) + BOTTOM_RADIUS)
    return clamp(h, 0.0, TOP_RADIUS - BOTTOM_RADIUS)

def density_at(profile, layers, h):
    """Relative density of a profile (flat rows of width [m], exp_term, exp_scale [1/m], linear_term [1/m],
    constant_term) at altitude h [m]: the first layer whose top is above h, the last above all; at least 0."""
    start = 0.0
    for k in range(layers):
        w, e, sc, lin, const = profile[5 * k:5 * k + 5]
        if k == layers - 1 or h < start + w:
            return max(e * math.exp(sc * h) + lin * h + const, 0.0)
        start += w
    return 0.0

def scattering_nu_param(i_n, mu, mu_s):
    """nu of texel index i_n for view and sun zenith cosines mu, mu_s."""
    s = safe_sqrt((1.0 - mu * mu) * (1.0 - mu_s * mu_s))
    return clamp(mu * mu_s + s * math.cos(math.pi * (1.0 - i_n / (SCATTERING_N_NU - 1))), -1.0, 1.0)

def shadow_factors(r, mu, mu_s, nu, constituent):
    """Shadow factors (a, b) of the two nu slices of a lookup (those of scattering_uvw) for the single scattering of
    constituent "rayleigh" or "mie": (1, 1) where the point is lit, else the constituent's density where the query's
    ray leaves the Earth's shadow over that where each slice's ray leaves it, each at most SHADOW_RATIO_MAX (mu_s at
    least MU_S_MIN, as in scattering_uvw). A ray that starts in the shadow scatters sunlight only beyond its exit,
    nearly in proportion to the density there."""
    mu_s = max(mu_s, MU_S_MIN)
    if not in_earth_shadow(r, mu_s):
        return (1.0, 1.0)
    p_n = clamp(scattering_nu_index(mu, mu_s, nu), 0.0, SCATTERING_N_NU - 1)
    i_n = min(math.floor(p_n), SCATTERING_N_NU - 2)
    profile, layers = ((RAYLEIGH_DENSITY, RAYLEIGH_DENSITY_LAYERS) if constituent == "rayleigh"
                       else (MIE_DENSITY, MIE_DENSITY_LAYERS))
    fq = density_at(profile, layers, shadow_exit_altitude(r, mu, mu_s, nu))
    f0 = density_at(profile, layers, shadow_exit_altitude(r, mu, mu_s, scattering_nu_param(i_n, mu, mu_s)))
    f1 = density_at(profile, layers, shadow_exit_altitude(r, mu, mu_s, scattering_nu_param(i_n + 1, mu, mu_s)))
    return (fq / f0 if f0 * SHADOW_RATIO_MAX > fq else SHADOW_RATIO_MAX,
            fq / f1 if f1 * SHADOW_RATIO_MAX > fq else SHADOW_RATIO_MAX)

def segment_transmittance(t_x, t_y, tau_x, tau_y):
    """Transmittance between x and y per channel from the two texture reads at each end (x nearer, both towards the
    top): the ratio of sunlight transmittances where it is well conditioned, else the optical depths'."""
    out = []
    for a, b, ta, tb in zip(t_x, t_y, tau_x, tau_y):
        from_depth = math.exp(-max(ta - tb, 0.0))
        s = min(max((b - 0.02) / 0.08, 0.0), 1.0)  # linear blend for b in 0.02..0.1: no seam
        out.append(from_depth + s * (min(max(a / b, 0.0), 1.0) - from_depth) if s > 0.0 else from_depth)
    return out

def rayleigh_phase(nu):
    return 3.0 / (16.0 * math.pi) * (1.0 + nu * nu)

def mie_phase(nu):
    g = MIE_G
    den = max(1.0 + g * g - 2.0 * g * nu, 1e-12)
    if MIE_PHASE_KIND == 1:
        return (1.0 - g * g) / (4.0 * math.pi * den * math.sqrt(den))
    return 3.0 * (1.0 - g * g) * (1.0 + nu * nu) / (8.0 * math.pi * (2.0 + g * g) * den * math.sqrt(den))

def multiple_lobe(nu):
    """The lobe by which the multiple-scattering texture is divided: 1 - a + a (1 - g^2) / (1 + g^2 - 2 g nu)^1.5,
    a = MULTIPLE_LOBE, g = MULTIPLE_LOBE_G."""
    g = MULTIPLE_LOBE_G
    d = 1.0 + g * g - 2.0 * g * nu
    return 1.0 - MULTIPLE_LOBE + MULTIPLE_LOBE * (1.0 - g * g) / (d * math.sqrt(d))

def inscattered_radiance(rayleigh, mie, multiple, nu):
    """Radiance [HDR scale] from the three scattering lookups: S_R P_R + S_M P_M + S_multiple F(nu)."""
    f = multiple_lobe(nu)
    return [a * rayleigh_phase(nu) + b * mie_phase(nu) + c * f for a, b, c in zip(rayleigh, mie, multiple)]
'''


def glsl_library() -> str:
    """The GLSL ES 3.00 library (``skyscatter/realtime/glsl/atmosphere.glsl``) as text."""
    return resources.files(__package__).joinpath("glsl/atmosphere.glsl").read_text(encoding="utf-8")


def glsl_mappings() -> str:
    """The mapping section of :func:`glsl_library` (between its BEGIN and END MAPPINGS lines)."""
    text = glsl_library()
    start = text.index("// BEGIN MAPPINGS")
    end = text.index("\n", text.index("// END MAPPINGS"))
    return text[start:end + 1]


def fold_matrix(atm: PrecomputedAtmosphere) -> NDArray[np.float64]:
    """Matrix (3, n_wavelengths) from spectral radiance at the table wavelengths [W m^-2 sr^-1 nm^-1] to linear sRGB
    in skyscatter's HDR scale (Y = luminance / 683): the CIE 1931 integral of the tables' colour rule
    (:func:`skyscatter.precomputed.conversion.xyz_matrix`; for tables of fewer than 15 wavelengths its quadratic or
    piecewise-linear rule without the negative-lobe guard, which is not linear) then XYZ to linear sRGB."""
    return np.asarray(xyz_to_linear_srgb(atm.xyz_matrix.T).T * HDR_SCALE, dtype=np.float64)


def _analytic_phase(atm: PrecomputedAtmosphere):
    """The aerosol's analytic phase function (kind, g), as the lookups use it; refuses a tabulated one."""
    analytic = atm.parameters.aerosol_component.analytic_phase
    if analytic is None:
        raise InvalidParameterError(
            "the real-time textures need an analytic aerosol phase function (cornette-shanks or henyey-greenstein): "
            "a tabulated, wavelength-dependent phase cannot be applied after the tables are folded into colour")
    return analytic


def _sun_weighted(spectra: NDArray[np.float32], weights: NDArray[np.float64], m: NDArray[np.float64]) -> NDArray:
    """``(M (w X))_c / (M w)_c`` for spectra X (..., n) and a weighting spectrum w: X's value for light of w's
    spectrum, per colour channel, and the same for luminance (4 channels)."""
    m4 = np.vstack([m, _y_row(m)])
    num = (spectra.astype(np.float64) * weights) @ m4.T
    return num / (m4 @ weights)


def _y_row(m: NDArray[np.float64]) -> NDArray[np.float64]:
    """Row (n,) giving the HDR-scale luminance Y of a spectrum from the sRGB rows ``m`` (Rec. 709 luminance)."""
    return np.array([0.2126, 0.7152, 0.0722]) @ m


def engine_textures(atm: PrecomputedAtmosphere) -> dict[str, NDArray[np.float32]]:
    """The six RGBA textures of the module docstring as float32 arrays: 2D (height, width, 4), 3D
    (depth, height, width, 4).

    Raises
    ------
    InvalidParameterError
        For tables with a tabulated (wavelength-dependent) aerosol phase function.
    """
    _analytic_phase(atm)
    m = fold_matrix(atm)
    # the tables the library's lookups read: the 4D ones refined along the sun zenith, per wavelength, so that the
    # folded textures read linearly give the fold of the library's read (the refinement is not linear)
    t = atm.lookup_tables
    solar = atm.parameters.solar_irradiance_at(atm.wavelengths)
    n_r, n_mu, n_s, n_n = t["single_rayleigh"].shape[:4]
    tau = -np.log(np.maximum(t["transmittance"].astype(np.float64), 1e-30))  # T = 0 -> optical depth 69
    w = np.maximum(np.vstack([m, _y_row(m)]), 0.0) * solar
    w /= w.sum(axis=1, keepdims=True)
    out = {"transmittance": _sun_weighted(t["transmittance"], solar, m).astype(np.float32),
           "optical_depth": (tau @ w.T).astype(np.float32),
           # A: 0 (the library weighs each channel by its own values)
           "irradiance": np.concatenate([t["irradiance"].astype(np.float64) @ m.T,
                                         np.zeros((*t["irradiance"].shape[:-1], 1))], axis=-1)}
    m4 = np.vstack([m, np.zeros(m.shape[1])]).astype(np.float32)  # R, G, B rows; A is filled below
    for name, key in (("rayleigh", "single_rayleigh"), ("mie", "single_mie"), ("multiple", "multiple")):
        # einsum, not matmul: a (1M, 16) x (16, 4) product is 4x quicker without BLAS's threads
        rgba = np.einsum("ij,kj->ik", t[key].reshape(-1, atm.wavelengths.size), m4)
        # A: the middle wavelength, from which the lookups' azimuth weight is computed (sampling.nu_weight)
        rgba[:, 3] = t[key].reshape(-1, atm.wavelengths.size)[:, atm.wavelengths.size // 2]
        # (r, mu, mu_s, nu, 4) -> (r, mu, nu, mu_s, 4): x = i_nu * n_mu_s + i_mu_s
        out[name] = rgba.reshape(n_r, n_mu, n_s, n_n, 4).transpose(0, 1, 3, 2, 4).reshape(n_r, n_mu, n_n * n_s, 4)
    return {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in out.items()}


def _constants(atm: PrecomputedAtmosphere) -> dict[str, Any]:
    from ..atmosphere.phase import aerosol_phase_kind
    from ..precomputed.compute import density_profiles
    from ..precomputed.geometry import (
        AZIMUTH_RATIO_FOUR_POINT,
        AZIMUTH_RATIO_LOG_LINEAR,
        LOG_LERP_FLOOR,
        MU_S_SPLIT,
        refined_mu_s_count,
        twilight_cells,
    )
    from ..precomputed.sampling import MULTIPLE_LOBE_G, SHADOW_RATIO_MAX, lobe_weight
    from ..sun.disc import solar_disc_solid_angle

    p = atm.parameters
    phase = _analytic_phase(atm)
    m = fold_matrix(atm)
    solar = p.solar_irradiance_at(atm.wavelengths)
    albedo = p.ground_albedo_at(atm.wavelengths)
    n_r, n_mu, n_s, n_n = atm.sizes.scattering_shape
    cells = twilight_cells(p.bottom_radius, p.top_radius, p.mu_s_min, n_s)
    profiles, counts = density_profiles(p)
    n_layers = int(max(counts[0], counts[1]))
    return {
        "BOTTOM_RADIUS": float(p.bottom_radius), "TOP_RADIUS": float(p.top_radius), "MU_S_MIN": float(p.mu_s_min),
        "SUN_ANGULAR_RADIUS": float(p.sun_angular_radius),
        "SUN_SOLID_ANGLE": solar_disc_solid_angle(p.sun_angular_radius),
        "MIE_G": float(phase.g), "MIE_PHASE_KIND": aerosol_phase_kind(phase.kind),
        "MULTIPLE_LOBE": float(lobe_weight(p)), "MULTIPLE_LOBE_G": float(MULTIPLE_LOBE_G),
        "SOLAR_IRRADIANCE": [float(v) for v in m @ solar],
        "GROUND_ALBEDO": [float(v) for v in (m @ (albedo * solar)) / (m @ solar)],
        "TRANSMITTANCE_N_R": atm.sizes.transmittance_r, "TRANSMITTANCE_N_MU": atm.sizes.transmittance_mu,
        "IRRADIANCE_N_R": atm.sizes.irradiance_r, "IRRADIANCE_N_MU_S": atm.sizes.irradiance_mu_s,
        "SCATTERING_N_R": n_r, "SCATTERING_N_MU": n_mu, "SCATTERING_N_MU_S": refined_mu_s_count(n_s, cells),
        "SCATTERING_N_NU": n_n, "SCATTERING_MU_S_CELLS": cells, "MU_S_SPLIT": MU_S_SPLIT,
        "LOG_LERP_FLOOR": float(LOG_LERP_FLOOR), "SHADOW_RATIO_MAX": float(SHADOW_RATIO_MAX),
        "AZIMUTH_RATIO_FOUR_POINT": float(AZIMUTH_RATIO_FOUR_POINT),
        "AZIMUTH_RATIO_LOG_LINEAR": float(AZIMUTH_RATIO_LOG_LINEAR),
        "DENSITY_MAX_LAYERS": n_layers,
        "RAYLEIGH_DENSITY_LAYERS": int(counts[0]), "MIE_DENSITY_LAYERS": int(counts[1]),
        "RAYLEIGH_DENSITY": [float(v) for v in profiles[0, :n_layers].ravel()],
        "MIE_DENSITY": [float(v) for v in profiles[1, :n_layers].ravel()],
    }


def glsl_constants(constants: dict[str, Any]) -> str:
    """GLSL declarations of the constants the library expects (``const float ...;``), from a manifest's
    ``constants``."""
    lines = []
    for name, value in constants.items():
        if name.endswith("_DENSITY"):  # a density profile: 5 floats per layer, padded to DENSITY_MAX_LAYERS
            n = 5 * int(constants["DENSITY_MAX_LAYERS"])
            vals = ", ".join(_glsl_float(v) for v in list(value) + [0.0] * (n - len(value)))
            lines.append(f"const float {name}[{n}] = float[{n}]({vals});")
        elif isinstance(value, list):
            lines.append(f"const vec3 {name} = vec3({', '.join(_glsl_float(v) for v in value)});")
        elif isinstance(value, int):
            lines.append(f"const int {name} = {value};")
        else:
            lines.append(f"const float {name} = {_glsl_float(value)};")
    return "\n".join(lines) + "\n"


def _glsl_float(v: float) -> str:
    text = repr(float(v))
    return text if ("." in text or "e" in text) else text + ".0"


#: What the scattering textures' alpha holds (manifest meaning).
_ALPHA = ("the table's spectral value at azimuth_weight_wavelength_nm (its middle wavelength) [W m^-2 nm^-1; "
          "multiple: W m^-2 sr^-1 nm^-1; not folded, not on the HDR scale], for the weights of the interpolation "
          "along nu, applied to RGB: the single scattering between two nu slices, log_lerp_weight(A0, A1, w) of the "
          "mappings (azimuth_lerp; where the point is in the Earth's shadow shadow_lerp, which does not read A), the "
          "multiple scattering through four (scattering_uvw4, azimuth_read: the four-point rule where the four A lie "
          "within AZIMUTH_RATIO_FOUR_POINT of each other, log_lerp_weight of the middle two beyond "
          "AZIMUTH_RATIO_LOG_LINEAR)")


def _texture_entry(name: str, shape: tuple[int, ...]) -> dict[str, Any]:
    meaning = {
        "transmittance": "RGB: transmittance of sunlight from (r, mu) to the top of the atmosphere, (M (E_sun T)) / "
                         "(M E_sun) per channel [1]; A: the same for luminance",
        "optical_depth": "RGB: optical depth from (r, mu) to the top averaged over each channel's band, sum_l w_c(l) "
                         "tau(l), w_c = max(M_c, 0) E_sun normalised [1]; A: the same for luminance",
        "irradiance": "RGB: sky irradiance on a horizontal surface at (r, mu_s) [W m^-2, HDR scale]; A: 0 "
                      "(irradiance_lerp of the mappings weighs each channel by its own values)",
        "rayleigh": "RGB: single Rayleigh scattering S_R[L0] without its phase function [W m^-2, HDR scale; times "
                    "P_R [sr^-1] gives radiance]; A: " + _ALPHA,
        "mie": "RGB: single Mie scattering S_M[L0] without its phase function [W m^-2, HDR scale]; A: " + _ALPHA,
        "multiple": "RGB: multiple scattering S[L*], orders >= 2, phase included, divided by multiple_lobe(nu) of "
                    "the mappings at the texel's nu [W m^-2 sr^-1, HDR scale; times multiple_lobe(nu) gives "
                    "radiance]; A: " + _ALPHA,
    }[name]
    entry: dict[str, Any] = {"meaning": meaning, "channels": 4}
    if len(shape) == 3:
        entry.update(dimensions=2, width=shape[1], height=shape[0],
                     axes={"x": "mu_s" if name == "irradiance" else "mu", "y": "r"})
    else:
        entry.update(dimensions=3, width=shape[2], height=shape[1], depth=shape[0],
                     axes={"x": "i_nu * SCATTERING_N_MU_S + i_mu_s (i_mu_s on the refined sun-zenith axis: "
                                "scattering_mu_s_index of the mappings)", "y": "mu", "z": "r"})
    return entry


def _write_raw(path: Path, array: NDArray, dtype: str) -> int:
    data = np.ascontiguousarray(array, dtype=dtype)
    with open(path, "wb") as fh:
        fh.write(data.tobytes())  # little-endian by dtype; at most a few hundred MB per texture
    return int(data.nbytes)


def _write_exr(path: Path, array: NDArray[np.float32]) -> None:
    import OpenEXR

    flat = np.ascontiguousarray(array.reshape(-1, array.shape[-2], 4), dtype=np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    try:
        OpenEXR.File(header, {"RGBA": flat}).write(str(path))
    except RuntimeError as exc:
        raise OSError(None, str(exc).replace(str(path), "the file"), str(path)) from exc


def export_realtime(atm: PrecomputedAtmosphere, folder: str | Path, *,
                    formats: tuple[str, ...] = ("rgba32f", "rgba16f")) -> Path:
    """Write the engine-ready textures of ``atm`` in ``formats`` (keys of :data:`FORMATS`) and the manifest into
    ``folder`` (created if missing), all or nothing (:func:`skyscatter.fileio.atomic_paths`). Returns the manifest's
    path.

    Raises
    ------
    InvalidParameterError
        For an unknown format, a tabulated aerosol phase, or (half floats) a value beyond the half range.
    OutputError
        If the folder cannot be created or a file cannot be written.
    """
    import skyscatter

    formats = tuple(dict.fromkeys(formats))
    unknown = [f for f in formats if f not in FORMATS]
    if unknown or not formats:
        raise InvalidParameterError(f"real-time formats must be among {', '.join(FORMATS)}; got {list(formats)}")
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create output folder {folder}: {exc.strerror or exc}") from None
    textures = engine_textures(atm)
    if "rgba16f" in formats:
        worst = max(float(np.abs(a).max()) for a in textures.values())
        if not worst < HALF_MAX:
            raise InvalidParameterError(f"a texture value ({worst:.4g}) exceeds the half-float range ({HALF_MAX}); "
                                        "export rgba32f or exr instead")
    constants = _constants(atm)
    entries = {name: _texture_entry(name, arr.shape) for name, arr in textures.items()}
    names = [(name, fmt) for name in TEXTURE_NAMES for fmt in formats]
    targets = [folder / f"{name}.{fmt}" for name, fmt in names] + [folder / MANIFEST_NAME]
    with atomic_paths(*targets) as temps:
        for (name, fmt), tmp in zip(names, temps[:-1], strict=True):
            arr = textures[name]
            if fmt == "exr":
                _write_exr(tmp, arr)
                size = tmp.stat().st_size
            else:
                size = _write_raw(tmp, arr, "<f4" if fmt == "rgba32f" else "<f2")
            entries[name].setdefault("files", {})[fmt] = {"file": f"{name}.{fmt}", "bytes": size}
        manifest = {
            "format": MANIFEST_FORMAT,
            "version": MANIFEST_VERSION,
            "written_by": f"skyscatter {skyscatter.__version__}",
            "references": ["Bruneton2008", "Bruneton2017"],
            "colour": "linear sRGB (IEC 61966-2-1 primaries, D65 white), no chromatic adaptation",
            "hdr_scale": {"rule": "Y = luminance [cd m^-2] / 683", "luminance_from_rgb": [0.2126, 0.7152, 0.0722],
                          "cd_m2_per_unit_Y": 683.0},
            "units": {"length": "m", "positions": "planet-centred, the planet's centre at the origin",
                      "angles": "rad", "radiance": "W m^-2 sr^-1 (photopically weighted: Y = luminance / 683)",
                      "irradiance": "W m^-2 (photopically weighted: Y = illuminance / 683)"},
            "byte_order": "little",
            "texel_layout": "C order, RGBA interleaved, x fastest, row 0 (y = 0) first; 3D: z slowest",
            "formats": {f: FORMATS[f] for f in formats},
            "constants": constants,
            "textures": entries,
            "filtering": "LINEAR with CLAMP_TO_EDGE on every axis; nu is interpolated by hand: the single "
                         "scattering between two lookups with the log-linear weight of their alpha (azimuth_lerp of "
                         "the mappings), where the point is in the Earth's shadow linearly with the shadow factors "
                         "of its constituent's density (single_scattering_lerp); the multiple scattering through "
                         "four lookups (scattering_uvw4, azimuth_read)",
            "mappings": {"python": PYTHON_MAPPINGS, "glsl": glsl_mappings()},
            "glsl_constants": glsl_constants(constants),
            "segment_transmittance": SEGMENT_RULE,
            "radiance": {"sky": "rayleigh * rayleigh_phase(nu) + mie * mie_phase(nu) + multiple (no solar disc)",
                         "sun_disc": "SOLAR_IRRADIANCE / SUN_SOLID_ANGLE * transmittance_to_sun",
                         "ground": "T_view * GROUND_ALBEDO / pi * (SOLAR_IRRADIANCE * T_sun * cos + E_sky)"},
            "atmosphere_parameters": atm.parameters.to_dict(),
            "orders": atm.orders,
            "table_wavelengths_nm": [float(w) for w in atm.wavelengths],
            "azimuth_weight_wavelength_nm": float(atm.wavelengths[atm.wavelengths.size // 2]),
            "fold_matrix": fold_matrix(atm).tolist(),
            "cache_key": atm.cache_key,
        }
        temps[-1].write_text(json.dumps(manifest, indent=1), encoding="utf-8")
    return targets[-1]
