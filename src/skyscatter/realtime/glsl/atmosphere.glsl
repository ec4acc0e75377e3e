// skyscatter real-time atmosphere: GLSL ES 3.00 functions reading the textures of `skyscatter export-luts`
// (manifest skyscatter_realtime.json, format "skyscatter-realtime-luts" version 12).
//
// Reference: E. Bruneton, F. Neyret, Precomputed Atmospheric Scattering, EGSR 2008 [Bruneton2008], equation numbers
// below are the paper's; the distance-based texture mappings and the horizon blend follow Bruneton's 2017 rewrite
// [Bruneton2017]; skyscatter's own mappings (the angular halves of mu and mu_s, the azimuth axis for nu) are those
// of skyscatter.precomputed.geometry, written here from the manifest's Python code.
//
// Before this file, declare (the manifest's "glsl_constants" string does it):
//   const float BOTTOM_RADIUS, TOP_RADIUS            [m]  planet radius and top of the atmosphere
//   const float MU_S_MIN                                   cosine of the largest sun zenith angle in the tables
//   const float SUN_ANGULAR_RADIUS                    [rad]
//   const float SUN_SOLID_ANGLE                       [sr]   2 pi (1 - cos SUN_ANGULAR_RADIUS)
//   const float MIE_G; const int MIE_PHASE_KIND              asymmetry; 0 Cornette-Shanks, 1 Henyey-Greenstein
//   const float MULTIPLE_LOBE, MULTIPLE_LOBE_G               weight and asymmetry of MultipleLobe
//   const vec3 SOLAR_IRRADIANCE                              sun at the top of the atmosphere, linear sRGB, HDR scale
//   const vec3 GROUND_ALBEDO                                 Lambertian ground, linear sRGB (sunlight-weighted)
//   const int TRANSMITTANCE_N_R, TRANSMITTANCE_N_MU, IRRADIANCE_N_R, IRRADIANCE_N_MU_S,
//             SCATTERING_N_R, SCATTERING_N_MU, SCATTERING_N_MU_S, SCATTERING_N_NU   texel counts
//   const int SCATTERING_MU_S_CELLS, MU_S_SPLIT     the first SCATTERING_MU_S_CELLS cells of the stored sun-zenith
//             axis (those below and across the horizon) split into MU_S_SPLIT sub-cells each in the scattering
//             textures, whose SCATTERING_N_MU_S counts the refined axis (ScatteringMuSIndex)
//   const float LOG_LERP_FLOOR                               floor of the smaller value's ratio in LogLerpWeight
//   const float SHADOW_RATIO_MAX                             largest shadow factor in ShadowFactors
//   const float AZIMUTH_RATIO_FOUR_POINT, AZIMUTH_RATIO_LOG_LINEAR   bounds of the four-point read in AzimuthRead
//   const int DENSITY_MAX_LAYERS; const int RAYLEIGH_DENSITY_LAYERS, MIE_DENSITY_LAYERS   layers of the profiles
//   const float RAYLEIGH_DENSITY[5 * DENSITY_MAX_LAYERS], MIE_DENSITY[...]   relative density profiles of air and
//             aerosol, per layer (width [m], exp_term, exp_scale [1/m], linear_term [1/m], constant_term)
// Units: lengths in metres, positions planet-centred (the planet's centre at the origin), directions unit vectors.
// Colour: linear sRGB (IEC 61966-2-1 primaries, D65) with Y = luminance [cd m^-2] / 683 (skyscatter's HDR scale):
// radiance-like values in W m^-2 sr^-1 weighted by the photopic curve; irradiance in W m^-2 likewise.
// Textures: bind with LINEAR filtering and CLAMP_TO_EDGE on every axis (RGBA32F needs OES_texture_float_linear;
// RGBA16F filters everywhere).

uniform highp sampler2D transmittance_texture;   // RGB: sunlight-weighted transmittance to the top; A: luminance's
uniform highp sampler2D optical_depth_texture;   // RGB: optical depth to the top averaged over each channel; A: Y's
uniform highp sampler2D irradiance_texture;      // RGB: sky irradiance on a horizontal surface; A: 0
// The scattering textures' A: each table's spectral value at its middle wavelength (not folded), for the azimuth
// weight (LogLerpWeight).
uniform highp sampler3D rayleigh_texture;        // RGB: single Rayleigh scattering S_R[L0] without phase; A: see above
uniform highp sampler3D mie_texture;             // RGB: single Mie scattering S_M[L0] without phase; A: see above
uniform highp sampler3D multiple_texture;        // RGB: multiple scattering S[L*] (orders >= 2, phase included) divided by MultipleLobe; A: idem

const float PI = 3.14159265358979;
//: sun zenith cosines this close below MU_S_MIN count as at the limit (as skyscatter.precomputed.geometry)
const float MU_S_LIMIT_TOLERANCE = 1e-6;
//: half-width in mu of the band around the horizon blended in GetSkyRadianceToPoint ([Bruneton2017])
const float HORIZON_EPSILON = 0.004;

// BEGIN MAPPINGS -------------------------------------------------------------------------------------------------
// Texel i of an axis of n texels holds the value at index position p = i (the first and last texels hold the ends
// of each range); a texture coordinate is (p + 0.5) / n. Differences of squares are written as products,
// (a - b)(a + b), so that float32 keeps them near the ground and the horizon.

float SafeSqrt(float a) { return sqrt(max(a, 0.0)); }

// Arc cosine [rad] to 2.2e-8 rad ([Abramowitz1964] Eq. 4.4.46, acos(-x) = pi - acos(x)), the rule of the Python
// lookups: a GPU's acos may be less accurate than float32 allows (on SwiftShader this one cut the difference of
// ground views with the Python renderer by 2-6x).
float Acos(float x) {
  float a = min(abs(x), 1.0);
  float p = ((((((-0.0012624911 * a + 0.0066700901) * a - 0.0170881256) * a + 0.0308918810) * a - 0.0501743046) * a
              + 0.0889789874) * a - 0.2145988016) * a + 1.5707963050;
  float v = sqrt(1.0 - a) * p;
  return x >= 0.0 ? v : PI - v;
}
float TexCoord(float p, int n) { return (p + 0.5) / float(n); }

// Distance [m] from radius r along direction cosine mu to the top of the atmosphere ([Bruneton2008] Sec. 4: the
// root of t^2 + 2 r mu t + r^2 - R_t^2 = 0), without cancellation.
float DistanceToTop(float r, float mu) {
  float disc = (TOP_RADIUS - r) * (TOP_RADIUS + r) + r * r * mu * mu;
  float s = SafeSqrt(disc);
  if (mu > 0.0) return max((TOP_RADIUS - r) * (TOP_RADIUS + r) / (r * mu + s), 0.0);
  return max(-r * mu + s, 0.0);
}

// Distance [m] to the first hit of the planet (meaningful when RayHitsGround).
float DistanceToBottom(float r, float mu) {
  float disc = r * r * mu * mu - (r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS);
  float q = -r * mu + SafeSqrt(disc);
  return q <= 0.0 ? 0.0 : max((r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS) / q, 0.0);
}

bool RayHitsGround(float r, float mu) {
  return mu < 0.0 && r * r * mu * mu - (r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS) >= 0.0;
}

// Transmittance texture: x_mu = (d - d_min) / (d_max - d_min), d the distance to the top, d_min = R_t - r,
// d_max = rho + H; x_r = rho / H, rho = sqrt(r^2 - R_g^2), H = sqrt(R_t^2 - R_g^2). Width: mu, height: r.
vec2 TransmittanceUv(float r, float mu) {
  float H = sqrt((TOP_RADIUS - BOTTOM_RADIUS) * (TOP_RADIUS + BOTTOM_RADIUS));
  float rho = SafeSqrt((r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS));
  float d = DistanceToTop(r, mu);
  float d_min = TOP_RADIUS - r;
  float d_max = rho + H;
  float x_mu = d_max > d_min ? (d - d_min) / (d_max - d_min) : 0.0;
  return vec2(TexCoord(clamp(x_mu, 0.0, 1.0) * float(TRANSMITTANCE_N_MU - 1), TRANSMITTANCE_N_MU),
              TexCoord(clamp(rho / H, 0.0, 1.0) * float(TRANSMITTANCE_N_R - 1), TRANSMITTANCE_N_R));
}

// Irradiance texture: x_mu_s = (1 + mu_s) / 2 (width), x_r = (r - R_g) / (R_t - R_g) (height).
vec2 IrradianceUv(float r, float mu_s) {
  float x_r = clamp((r - BOTTOM_RADIUS) / (TOP_RADIUS - BOTTOM_RADIUS), 0.0, 1.0);
  float x_mu_s = clamp(0.5 * (mu_s + 1.0), 0.0, 1.0);
  return vec2(TexCoord(x_mu_s * float(IRRADIANCE_N_MU_S - 1), IRRADIANCE_N_MU_S),
              TexCoord(x_r * float(IRRADIANCE_N_R - 1), IRRADIANCE_N_R));
}

// The mu_s texel columns of the irradiance texture for a read at mu_s: (u0, v, t, below), three consecutive columns
// at u0, u0 + 1 / IRRADIANCE_N_MU_S and u0 + 2 / IRRADIANCE_N_MU_S (each read linear in r; the third may lie past the
// texture's last column, where its weight is 0), t the position in [-1, 1] relative to the middle one (the read's
// cell is the first two for t < 0, else the last two), below 1.0 if the cell starts below the horizon (its first
// column at mu_s < 0), else 0.0. Below the horizon the three are the nearest texels (the cell and the texel next to
// its nearer end), elsewhere the cell's two and the next (irradiance_uvs of the Python mappings).
vec4 IrradianceUvs(float r, float mu_s) {
  float x_r = clamp((r - BOTTOM_RADIUS) / (TOP_RADIUS - BOTTOM_RADIUS), 0.0, 1.0);
  float p = clamp(0.5 * (mu_s + 1.0), 0.0, 1.0) * float(IRRADIANCE_N_MU_S - 1);
  float j = min(floor(p), float(IRRADIANCE_N_MU_S - 2));
  bool below = 2.0 * j < float(IRRADIANCE_N_MU_S - 1);
  float j0 = below ? clamp(p - j < 0.5 ? j - 1.0 : j, 0.0, float(IRRADIANCE_N_MU_S - 3)) : j;
  return vec4(TexCoord(j0, IRRADIANCE_N_MU_S), TexCoord(x_r * float(IRRADIANCE_N_R - 1), IRRADIANCE_N_R),
              p - (j0 + 1.0), below ? 1.0 : 0.0);
}

// Index position of r on the depth axis of the scattering textures: the rows sit at rho_i = H i / (n - 1)
// (x_r = rho / H, [Bruneton2008] Sec. 4), and within the cell between rows i and i + 1, if row i lies below 200 m
// (the cell touching the ground and the next), the position is linear in r (the altitude), not in rho (measured
// better there against the integral); r - r_i as (rho^2 - rho_i^2) / (r + r_i): no cancellation of two radii in float
// (skyscatter.precomputed.geometry.scattering_r_index).
float ScatteringRIndex(float r, float rho, float H) {
  float n = float(SCATTERING_N_R - 1);
  float i = min(floor(clamp(rho / H, 0.0, 1.0) * n), n - 1.0);
  float rho0 = H * i / n;
  float rho1 = H * (i + 1.0) / n;
  float r0 = sqrt(rho0 * rho0 + BOTTOM_RADIUS * BOTTOM_RADIUS);
  if (rho0 * rho0 >= 200.0 * (r0 + BOTTOM_RADIUS)) return clamp(rho / H, 0.0, 1.0) * n;
  float r1 = sqrt(rho1 * rho1 + BOTTOM_RADIUS * BOTTOM_RADIUS);
  // a cell reaching above 300 m (tables with few rows): linear in rho
  if (rho1 * rho1 >= 300.0 * (r1 + BOTTOM_RADIUS)) return clamp(rho / H, 0.0, 1.0) * n;
  float w = (rho - rho0) * (rho + rho0) * (r1 + r0) / ((rho1 - rho0) * (rho1 + rho0) * (max(r, BOTTOM_RADIUS) + r0));
  return i + clamp(w, 0.0, 1.0);
}

// Index position on the mu axis of a ray that misses the ground from radius r (rho = sqrt(r^2 - R_g^2)): the mean
// of (d - d_min) / (d_max - d_min) (d to the top, d_min = R_t - r, d_max = rho + H) and theta / theta_h (zenith angle
// over the horizon's, theta_h = Acos(-rho / r)), on n/2 .. n - 1 (zenith to horizon).
float ScatteringSkyMuIndex(float r, float rho, float H, float mu) {
  float half_n = float(SCATTERING_N_MU / 2);
  float d = DistanceToTop(r, mu);
  float d_min = TOP_RADIUS - r;
  float d_max = rho + H;
  float x_d = d_max > d_min ? (d - d_min) / (d_max - d_min) : 0.0;
  float x_a = Acos(clamp(mu, -1.0, 1.0)) / Acos(clamp(-rho / r, -1.0, 1.0));
  return half_n + 0.5 * (clamp(x_d, 0.0, 1.0) + clamp(x_a, 0.0, 1.0)) * (half_n - 1.0);
}

// Scattering textures, (v, w) = (mu, r) coordinates. r: rows at x_r = rho / H; between them ScatteringRIndex for rays
// that miss the ground, linear in rho for rays that meet it (their mu coordinate fixes a length to the ground nearly
// linear in rho). mu is split at the horizon ([Bruneton2008]
// Fig. 4): rays that meet the ground fill index positions 0 .. n/2 - 1 (grazing to straight down) with
// 1 - (d - d_min) / (d_max - d_min), d the distance to the ground, d_min = r - R_g, d_max = rho; the other rays fill
// n/2 .. n - 1 (ScatteringSkyMuIndex). Linear filtering never mixes the halves: their positions stay within
// [0, n/2 - 1] and [n/2, n - 1]. Within the cell touching the ground a ray that misses the ground is read from each
// row at its own mu coordinate instead (ScatteringGroundCell).
vec2 ScatteringMuRCoords(float r, float mu, bool hits_ground) {
  float H = sqrt((TOP_RADIUS - BOTTOM_RADIUS) * (TOP_RADIUS + BOTTOM_RADIUS));
  float rho = SafeSqrt((r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS));
  float half_n = float(SCATTERING_N_MU / 2);
  float p_mu;
  if (hits_ground) {
    float d = DistanceToBottom(r, mu);
    float d_min = r - BOTTOM_RADIUS;
    float x = rho > d_min ? (d - d_min) / (rho - d_min) : 0.0;
    p_mu = (1.0 - clamp(x, 0.0, 1.0)) * (half_n - 1.0);
  } else {
    p_mu = ScatteringSkyMuIndex(r, rho, H, mu);
  }
  return vec2(TexCoord(p_mu, SCATTERING_N_MU),
              TexCoord(hits_ground ? clamp(rho / H, 0.0, 1.0) * float(SCATTERING_N_R - 1)
                                   : ScatteringRIndex(r, rho, H), SCATTERING_N_R));
}

// The cell of rows touching the ground (below the first row above it, 62.7 m of the default 32 rows), for a ray that
// misses the ground: (v0, v1, w, 1.0), v0 and v1 the mu coordinates at which rows 0 and 1 hold the ray's direction
// (ScatteringSkyMuIndex with each row's own radius), w the altitude weight of row 1 (ScatteringRIndex); the two rows
// read there and mixed with w (ScatteringTexture), as skyscatter's lookups since table format 16 (skyscatter.
// precomputed.geometry.scattering_r_mu_rows: the shared coordinate reads the two rows in two directions, as the
// horizon's zenith angle moves from 90 deg at the ground to 90.25 deg at 62.7 m). vec4(0.0) elsewhere.
vec4 ScatteringGroundCell(float r, float mu, bool hits_ground) {
  if (hits_ground) return vec4(0.0);
  float H = sqrt((TOP_RADIUS - BOTTOM_RADIUS) * (TOP_RADIUS + BOTTOM_RADIUS));
  float rho = SafeSqrt((r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS));
  float p_r = ScatteringRIndex(r, rho, H);
  float rho1 = H / float(SCATTERING_N_R - 1);
  float r1 = sqrt(rho1 * rho1 + BOTTOM_RADIUS * BOTTOM_RADIUS);
  // above the cell, or a cell reaching above 300 m (tables with few rows): one shared coordinate
  if (p_r >= 1.0 || rho1 * rho1 >= 300.0 * (r1 + BOTTOM_RADIUS)) return vec4(0.0);
  return vec4(TexCoord(ScatteringSkyMuIndex(BOTTOM_RADIUS, 0.0, H, mu), SCATTERING_N_MU),
              TexCoord(ScatteringSkyMuIndex(r1, rho1, H, mu), SCATTERING_N_MU), p_r, 1.0);
}

// a(mu_s) = (d - d_min) / (d_max - d_min), d the distance from the ground to the top along mu_s, d_min = R_t - R_g,
// d_max = H.
float MuSDistanceUnit(float mu_s) {
  float H = sqrt((TOP_RADIUS - BOTTOM_RADIUS) * (TOP_RADIUS + BOTTOM_RADIUS));
  return (DistanceToTop(BOTTOM_RADIUS, mu_s) - (TOP_RADIUS - BOTTOM_RADIUS)) / (H - (TOP_RADIUS - BOTTOM_RADIUS));
}

// Index position of mu_s on the refined sun-zenith axis of the scattering textures (0 at MU_S_MIN,
// SCATTERING_N_MU_S - 1 at the zenith). On the stored axis (SCATTERING_N_MU_S - (MU_S_SPLIT - 1)
// SCATTERING_MU_S_CELLS texels) it is p, the mean of max(1 - a / A, 0) / (1 + a) ([Bruneton2017], A = a(MU_S_MIN))
// and 1 - theta_s / theta_max (theta_max = Acos(MU_S_MIN)); the first SCATTERING_MU_S_CELLS cells are split into
// MU_S_SPLIT sub-cells (the cells below and across the horizon; sub-texels of the single scattering computed at
// their suns, of the multiple scattering from the four-point Lagrange rule in the logarithm, [Abramowitz1964]
// Eq. 25.2.13, of the stored texels: the twilight sky falls by 2-5 times across one stored cell), so the position is MU_S_SPLIT p there and p + (MU_S_SPLIT - 1)
// SCATTERING_MU_S_CELLS above (continuous at the split's end; skyscatter.precomputed.geometry.refined_mu_s_cell).
float ScatteringMuSIndex(float mu_s) {
  float a = MuSDistanceUnit(mu_s);
  float big_a = MuSDistanceUnit(MU_S_MIN);
  float x_d = clamp(max(1.0 - a / big_a, 0.0) / (1.0 + a), 0.0, 1.0);
  float x_a = clamp(1.0 - Acos(clamp(mu_s, -1.0, 1.0)) / Acos(MU_S_MIN), 0.0, 1.0);
  float cells = float(SCATTERING_MU_S_CELLS);
  float p = 0.5 * (x_d + x_a) * float(SCATTERING_N_MU_S - (MU_S_SPLIT - 1) * SCATTERING_MU_S_CELLS - 1);
  return p < cells ? float(MU_S_SPLIT) * p : p + float(MU_S_SPLIT - 1) * cells;
}

// Index position of nu: x_nu = 1 - phi / pi, phi the azimuth between view and sun,
// cos phi = (nu - mu mu_s) / sqrt((1 - mu^2)(1 - mu_s^2)).
float ScatteringNuIndex(float mu, float mu_s, float nu) {
  float s = SafeSqrt((1.0 - mu * mu) * (1.0 - mu_s * mu_s));
  if (s < 1e-9) return 0.5 * float(SCATTERING_N_NU - 1);
  float cphi = clamp((nu - mu * mu_s) / s, -1.0, 1.0);
  return (1.0 - Acos(cphi) / PI) * float(SCATTERING_N_NU - 1);
}

// Weight of the second of two values a, b (>= 0) at the fraction w of the cell, for a + weight (b - a) following a
// log-linear (exponential) variation between them: w a' / (w a' + (1 - w) sqrt(a' b')), a' and b' the values with
// the smaller raised to at least LOG_LERP_FLOOR times the larger; w where both are zero. It meets the geometric
// interpolation a^(1 - w) b^w at both ends and the centre (skyscatter.precomputed.geometry.log_lerp_weight, whose
// docstring gives the derivation and the error; the lookups along the view-sun azimuth, table format 12).
float LogLerpWeight(float a, float b, float w) {
  float lo = LOG_LERP_FLOOR * max(a, b);
  float a2 = max(a, lo);
  float b2 = max(b, lo);
  float wa = w * a2;
  float d = wa + (1.0 - w) * sqrt(a2 * b2);
  return d > 0.0 ? wa / d : w;
}

// RGB of a scattering texture between the reads s0, s1 of its two nu slices: the weight from their alpha (the
// table's middle wavelength, interpolated in mu_s, mu and r by the texture unit as skyscatter's
// sampling.nu_weight does), applied to every channel.
vec3 AzimuthLerp(vec4 s0, vec4 s1, float w) { return mix(s0.rgb, s1.rgb, LogLerpWeight(s0.a, s1.a, w)); }

// RGB of the multiple-scattering texture from the reads s0 .. s3 of four nu slices (the cell's two, s1 and s2, and
// one on each side, mirrored at the axis' ends) at the fraction w of the cell: the four-point Lagrange weights
// [Abramowitz1964] Eq. 25.2.13 where the four alphas (the table's middle wavelength) lie within a factor
// AZIMUTH_RATIO_FOUR_POINT of each other, the log-linear read of s1, s2 (AzimuthLerp) beyond
// AZIMUTH_RATIO_LOG_LINEAR or where an alpha is not positive, blended linearly in the ratio in between
// (skyscatter.precomputed.sampling.lookup4_cell_azimuth, geometry.azimuth_read_weights).
vec3 AzimuthRead(vec4 s0, vec4 s1, vec4 s2, vec4 s3, float w) {
  float lo = min(min(s0.a, s1.a), min(s2.a, s3.a));
  float hi = max(max(s0.a, s1.a), max(s2.a, s3.a));
  float beta = lo > 0.0 ? clamp((AZIMUTH_RATIO_LOG_LINEAR - hi / lo) /
                                (AZIMUTH_RATIO_LOG_LINEAR - AZIMUTH_RATIO_FOUR_POINT), 0.0, 1.0) : 0.0;
  float g = LogLerpWeight(s1.a, s2.a, w);
  float l0 = -w * (w - 1.0) * (w - 2.0) / 6.0;
  float l1 = 0.5 * (w + 1.0) * (w - 1.0) * (w - 2.0);
  float l2 = -0.5 * (w + 1.0) * w * (w - 2.0);
  float l3 = (w + 1.0) * w * (w - 1.0) / 6.0;
  return beta * l0 * s0.rgb + (beta * l1 + (1.0 - beta) * (1.0 - g)) * s1.rgb +
         (beta * l2 + (1.0 - beta) * g) * s2.rgb + beta * l3 * s3.rgb;
}

// Weight of the upper end of the cell around t (y0, y1 for t < 0, else y1, y2) for lo + weight (hi - lo) following
// ln y quadratic through three values at consecutive texels (t in [-1, 1] relative to the middle one): the
// three-point Lagrange formula in the logarithm [Abramowitz1964] Eq. 25.2.11, kept between the cell's two values;
// LogLerpWeight of the cell where a value is not positive, the fraction of the cell where its two values are equal
// (skyscatter.precomputed.geometry.log_quadratic_weight).
float LogQuadraticWeight(float y0, float y1, float y2, float t) {
  float lo = t < 0.0 ? y0 : y1;
  float hi = t < 0.0 ? y1 : y2;
  float w = t < 0.0 ? t + 1.0 : t;
  if (!(y0 > 0.0 && y1 > 0.0 && y2 > 0.0)) return LogLerpWeight(lo, hi, w);
  float y = exp(0.5 * t * (t - 1.0) * log(y0) + (1.0 - t * t) * log(y1) + 0.5 * t * (t + 1.0) * log(y2));
  return hi == lo ? w : clamp((y - lo) / (hi - lo), 0.0, 1.0);
}

// RGB of the irradiance texture from the reads e0, e1, e2 of its three mu_s columns (IrradianceUvs) at t: where the
// cell starts below the horizon each channel of the cell's two columns with its own weight, LogQuadraticWeight of
// that channel's three values (the twilight sky irradiance falls faster the lower the sun, and its blue and red at
// other rates; skyscatter.precomputed.sampling.irradiance_read), else linear in the cell.
vec3 IrradianceLerp(vec4 e0, vec4 e1, vec4 e2, float t, bool below) {
  vec3 a = t < 0.0 ? e0.rgb : e1.rgb;
  vec3 b = t < 0.0 ? e1.rgb : e2.rgb;
  if (!below) return mix(a, b, t < 0.0 ? t + 1.0 : t);
  return mix(a, b, vec3(LogQuadraticWeight(e0.r, e1.r, e2.r, t), LogQuadraticWeight(e0.g, e1.g, e2.g, t),
                        LogQuadraticWeight(e0.b, e1.b, e2.b, t)));
}

// RGB of a single-scattering texture between the reads s0, s1 of its two nu slices where the point is in the Earth's
// shadow: linear, each slice times its shadow factor f.x, f.y (ShadowFactors; skyscatter.precomputed.sampling.
// shadow_nu_weights).
vec3 ShadowLerp(vec4 s0, vec4 s1, float w, vec2 f) { return (1.0 - w) * f.x * s0.rgb + w * f.y * s1.rgb; }

// True if the point at radius r with sun zenith cosine mu_s is in the Earth's geometric shadow (the half cylinder of
// radius R_g behind the planet: mu_s < 0 and r^2 (1 - mu_s^2) < R_g^2; skyscatter.precomputed.geometry.
// in_earth_shadow). r sin(theta_s) - R_g is written (r - R_g) - r mu_s^2 / (1 + sin(theta_s)) (no cancellation).
float ShadowCylinderC(float r, float mu_s) {
  float s = SafeSqrt((1.0 - mu_s) * (1.0 + mu_s));
  float rs = r * s;
  return ((r - BOTTOM_RADIUS) - r * mu_s * mu_s / (1.0 + s)) * (rs + BOTTOM_RADIUS);
}
bool InEarthShadow(float r, float mu_s) { return mu_s < 0.0 && ShadowCylinderC(r, mu_s) < 0.0; }

// Altitude [m] where the ray (r, mu) with view-sun cosine nu leaves the Earth's shadow (the start's if it is lit), at
// most TOP_RADIUS - BOTTOM_RADIUS (skyscatter.precomputed.geometry.shadow_exit_altitude): the larger root of
// (1 - nu^2) t^2 + 2 r (mu - mu_s nu) t + r^2 (1 - mu_s^2) - R_g^2 = 0 (the cylinder), or the plane y.s = 0 at
// t = -r mu_s / nu if nearer; roots and the altitude written without cancellation for float32.
float ShadowExitAltitude(float r, float mu, float mu_s, float nu) {
  float c = ShadowCylinderC(r, mu_s);
  if (mu_s >= 0.0 || c >= 0.0) return clamp(r - BOTTOM_RADIUS, 0.0, TOP_RADIUS - BOTTOM_RADIUS);
  float a = (1.0 - nu) * (1.0 + nu);
  float b = r * (mu - mu_s * nu);
  float q = SafeSqrt(b * b - a * c);
  float t = 1e30;
  if (b > 0.0) t = -c / (b + q);
  else if (a > 1e-12) t = (q - b) / a;
  if (nu > 0.0) t = min(t, -r * mu_s / nu);
  if (t >= 1e30) return TOP_RADIUS - BOTTOM_RADIUS;
  // r_exit - R_g = (t^2 + 2 r mu t + (r - R_g)(r + R_g)) / (r_exit + R_g)
  float e2 = t * t + 2.0 * r * mu * t + (r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS);
  float h = e2 / (SafeSqrt(t * t + 2.0 * r * mu * t + r * r) + BOTTOM_RADIUS);
  return clamp(h, 0.0, TOP_RADIUS - BOTTOM_RADIUS);
}

// Relative density of a profile at altitude h [m]: the first layer whose top is above h (the last layer above all),
// exp_term exp(exp_scale h) + linear_term h + constant_term, at least 0 (skyscatter.precomputed.sampling.density_at).
float DensityAt(float p[5 * DENSITY_MAX_LAYERS], int layers, float h) {
  float start = 0.0;
  for (int k = 0; k < DENSITY_MAX_LAYERS; ++k) {
    if (k == layers - 1 || h < start + p[5 * k]) {
      return max(p[5 * k + 1] * exp(p[5 * k + 2] * h) + p[5 * k + 3] * h + p[5 * k + 4], 0.0);
    }
    start += p[5 * k];
  }
  return 0.0;
}

// Shadow factors (a, b) of the two nu texels of a single-scattering texture (skyscatter.precomputed.sampling.
// shadow_ratios_fast): the density at the query's shadow exit h.x over the density at each texel's exit h.y, h.z, each
// at most SHADOW_RATIO_MAX. A ray that starts in the Earth's shadow scatters sunlight only beyond its exit, nearly in
// proportion to the density there.
vec2 ShadowFactors(vec3 h, float p[5 * DENSITY_MAX_LAYERS], int layers) {
  float fq = DensityAt(p, layers, h.x);
  float f0 = DensityAt(p, layers, h.y);
  float f1 = DensityAt(p, layers, h.z);
  return vec2(f0 * SHADOW_RATIO_MAX > fq ? fq / f0 : SHADOW_RATIO_MAX,
              f1 * SHADOW_RATIO_MAX > fq ? fq / f1 : SHADOW_RATIO_MAX);
}

// nu of texel index i_n for view and sun zenith cosines mu, mu_s: mu mu_s + sqrt((1 - mu^2)(1 - mu_s^2)) cos(phi),
// phi = pi (1 - i_n / (n - 1)) (skyscatter.precomputed.geometry.scattering_nu_param).
float ScatteringNuParam(float i_n, float mu, float mu_s) {
  float s = SafeSqrt((1.0 - mu * mu) * (1.0 - mu_s * mu_s));
  return clamp(mu * mu_s + s * cos(PI * (1.0 - i_n / float(SCATTERING_N_NU - 1))), -1.0, 1.0);
}

// Shadow exit altitudes [m] of the query (x) and of the rays of the nu texels i_n (y) and i_n + 1 (z), with the
// query's r, mu and mu_s (skyscatter.precomputed.sampling.shadow_exit_altitudes).
vec3 ShadowExitAltitudes(float r, float mu, float mu_s, float nu, float i_n) {
  return vec3(ShadowExitAltitude(r, mu, mu_s, nu), ShadowExitAltitude(r, mu, mu_s, ScatteringNuParam(i_n, mu, mu_s)),
              ShadowExitAltitude(r, mu, mu_s, ScatteringNuParam(i_n + 1.0, mu, mu_s)));
}
// END MAPPINGS ---------------------------------------------------------------------------------------------------

// Texture reads. GPUs interpolate with a fixed-point fraction (8 bits is common; SwiftShader too), which where the
// tables change steeply within a texel (the limb of the atmosphere seen from orbit) is visible; define
// SKYSCATTER_EXACT_FILTERING before this file to interpolate in float32 by hand from texelFetch (4 or 8 fetches
// instead of 1). Both follow GL's LINEAR + CLAMP_TO_EDGE rule: texel i centred at (i + 0.5) / n.
#ifdef SKYSCATTER_EXACT_FILTERING
vec4 Texture2D(highp sampler2D t, vec2 uv) {
  ivec2 n = textureSize(t, 0);
  vec2 x = uv * vec2(n) - 0.5;
  vec2 f = floor(x);
  vec2 w = x - f;
  ivec2 i0 = clamp(ivec2(f), ivec2(0), n - 1);
  ivec2 i1 = clamp(ivec2(f) + 1, ivec2(0), n - 1);
  return mix(mix(texelFetch(t, i0, 0), texelFetch(t, ivec2(i1.x, i0.y), 0), w.x),
             mix(texelFetch(t, ivec2(i0.x, i1.y), 0), texelFetch(t, i1, 0), w.x), w.y);
}
vec4 Texture3D(highp sampler3D t, vec3 uvw) {
  ivec3 n = textureSize(t, 0);
  vec3 x = uvw * vec3(n) - 0.5;
  vec3 f = floor(x);
  vec3 w = x - f;
  ivec3 i0 = clamp(ivec3(f), ivec3(0), n - 1);
  ivec3 i1 = clamp(ivec3(f) + 1, ivec3(0), n - 1);
  vec4 a = mix(mix(texelFetch(t, i0, 0), texelFetch(t, ivec3(i1.x, i0.y, i0.z), 0), w.x),
               mix(texelFetch(t, ivec3(i0.x, i1.y, i0.z), 0), texelFetch(t, ivec3(i1.x, i1.y, i0.z), 0), w.x), w.y);
  vec4 b = mix(mix(texelFetch(t, ivec3(i0.x, i0.y, i1.z), 0), texelFetch(t, ivec3(i1.x, i0.y, i1.z), 0), w.x),
               mix(texelFetch(t, ivec3(i0.x, i1.y, i1.z), 0), texelFetch(t, i1, 0), w.x), w.y);
  return mix(a, b, w.z);
}
#else
vec4 Texture2D(highp sampler2D t, vec2 uv) { return texture(t, uv); }
vec4 Texture3D(highp sampler3D t, vec3 uvw) { return texture(t, uvw); }
#endif

// A scattering texture at uvw (ScatteringMuRCoords' v, w), or, within the cell touching the ground (cell of
// ScatteringGroundCell), its rows 0 and 1 each at their own v, mixed with the altitude weight: two reads.
vec4 ScatteringTexture(highp sampler3D t, vec3 uvw, vec4 cell) {
  if (cell.w == 0.0) return Texture3D(t, uvw);
  return mix(Texture3D(t, vec3(uvw.x, cell.x, TexCoord(0.0, SCATTERING_N_R))),
             Texture3D(t, vec3(uvw.x, cell.y, TexCoord(1.0, SCATTERING_N_R))), cell.z);
}

// Phase functions [sr^-1]: Rayleigh [Bruneton2008] Eq. 2; Cornette-Shanks Eq. 4; Henyey-Greenstein.
// Sky irradiance on a horizontal surface at radius r [m] with sun zenith cosine mu_s: the irradiance texture's mu_s
// columns for mu_s (IrradianceUvs; the third read only below the horizon), interpolated by IrradianceLerp.
vec3 GetHorizontalSkyIrradiance(float r, float mu_s) {
  vec4 c = IrradianceUvs(r, mu_s);
  float du = 1.0 / float(IRRADIANCE_N_MU_S);
  bool below = c.w > 0.5;
  vec4 e0 = Texture2D(irradiance_texture, c.xy);
  vec4 e1 = Texture2D(irradiance_texture, vec2(c.x + du, c.y));
  if (!below) return mix(e0.rgb, e1.rgb, clamp(c.z + 1.0, 0.0, 1.0));
  vec4 e2 = Texture2D(irradiance_texture, vec2(c.x + 2.0 * du, c.y));
  return IrradianceLerp(e0, e1, e2, c.z, true);
}

float RayleighPhase(float nu) { return 3.0 / (16.0 * PI) * (1.0 + nu * nu); }
float MiePhase(float nu) {
  float g = MIE_G;
  float den = max(1.0 + g * g - 2.0 * g * nu, 1e-12);
  if (MIE_PHASE_KIND == 1) return (1.0 - g * g) / (4.0 * PI * den * sqrt(den));
  return 3.0 * (1.0 - g * g) * (1.0 + nu * nu) / (8.0 * PI * (2.0 + g * g) * den * sqrt(den));
}
// The lobe the multiple-scattering texture is divided by (skyscatter.precomputed.sampling.multiple_lobe): its
// values between the nu slices are read as S / F and multiplied by F at the read's own nu. F = 1 - a + a HG(nu; g)
// ([HenyeyGreenstein1941], times 4 pi), a = MULTIPLE_LOBE, g = MULTIPLE_LOBE_G.
float MultipleLobe(float nu) {
  float g = MULTIPLE_LOBE_G;
  float d = 1.0 + g * g - 2.0 * g * nu;
  return 1.0 - MULTIPLE_LOBE + MULTIPLE_LOBE * (1.0 - g * g) / (d * sqrt(d));
}

// Transmittance T(x, top) along (r, mu) to the top of the atmosphere, ignoring the ground ([Bruneton2008] Eq. 5,
// tabulated). RGB: the transmittance of sunlight, (M (E_sun T)) / (M E_sun) per channel, M the spectrum -> linear
// sRGB matrix: exact for the sun's light, an approximation for other spectra.
vec3 GetTransmittanceToTop(float r, float mu) {
  return Texture2D(transmittance_texture, TransmittanceUv(r, mu)).rgb;
}

// Transmittance between (r, mu) and the point at distance d along the ray: T(x, y) = T(x, v) / T(y, v), or with the
// reversed ray T(y, -v) / T(x, -v) for rays that meet the ground ([Bruneton2008] Sec. 4), capped at 1. The ratio of
// two sunlight transmittances is ill-conditioned where the far one is small in a channel (long grazing paths: a
// reddened beam, whose sRGB blue can even be negative); there the channel's band-averaged optical depths give it,
// exp(-(tau(x) - tau(y))) (the manifest's segment_transmittance rule).
// The two blend linearly for far-end transmittances between 0.02 and 0.1 (no seam where the rule changes).
float SegmentChannel(float a, float b, float tau_a, float tau_b) {
  float from_depth = exp(-max(tau_a - tau_b, 0.0));
  float s = clamp((b - 0.02) / 0.08, 0.0, 1.0);
  return s > 0.0 ? mix(from_depth, clamp(a / b, 0.0, 1.0), s) : from_depth;
}

vec3 GetTransmittance(float r, float mu, float d, bool hits_ground) {
  float r_d = clamp(SafeSqrt(d * d + 2.0 * r * mu * d + r * r), BOTTOM_RADIUS, TOP_RADIUS);
  float mu_d = clamp((r * mu + d) / r_d, -1.0, 1.0);
  vec2 uv_a, uv_b;
  if (hits_ground) {
    uv_a = TransmittanceUv(r_d, -mu_d);
    uv_b = TransmittanceUv(r, -mu);
  } else {
    uv_a = TransmittanceUv(r, mu);
    uv_b = TransmittanceUv(r_d, mu_d);
  }
  vec3 a = Texture2D(transmittance_texture, uv_a).rgb;
  vec3 b = Texture2D(transmittance_texture, uv_b).rgb;
  vec3 ta = Texture2D(optical_depth_texture, uv_a).rgb;
  vec3 tb = Texture2D(optical_depth_texture, uv_b).rgb;
  return vec3(SegmentChannel(a.r, b.r, ta.r, tb.r), SegmentChannel(a.g, b.g, ta.g, tb.g),
              SegmentChannel(a.b, b.b, ta.b, tb.b));
}

// Fraction of the solar disc above the planet's horizon seen from r: a circular segment,
// 1/2 + (h sqrt(1 - h^2) + asin h) / pi, h the disc centre's elevation above the horizon in disc radii.
float SunVisibleFraction(float r, float mu_s) {
  float sin_h = BOTTOM_RADIUS / r;
  float cos_h = -SafeSqrt((r - BOTTOM_RADIUS) * (r + BOTTOM_RADIUS)) / r;
  float h = clamp((mu_s - cos_h) / (max(sin_h, 1e-6) * SUN_ANGULAR_RADIUS), -1.0, 1.0);
  return 0.5 + (h * SafeSqrt(1.0 - h * h) + asin(h)) / PI;
}

// Transmittance to the sun times the visible fraction of its disc ([Bruneton2008] Eq. 9's T(x, x_0)).
vec3 GetTransmittanceToSun(float r, float mu_s) {
  float f = SunVisibleFraction(r, mu_s);
  return f <= 0.0 ? vec3(0.0) : GetTransmittanceToTop(r, mu_s) * f;
}

// The three scattering textures at (r, mu, mu_s, nu): trilinear by the texture unit in (mu_s, mu, r) (within the
// cell touching the ground two bilinear reads, one per row: ScatteringTexture) and by hand along nu (the nu slices
// lie side by side along x: x = i_nu * n_mu_s + i_mu_s, [Bruneton2008] Sec. 6), log-linear
// there with each texture's own weight (AzimuthLerp), as skyscatter's lookups since table format 12 (the multiple
// scattering through four slices since manifest version 12: AzimuthRead), except the
// single-scattering textures where the point is in the Earth's shadow: linear with the shadow factors of their
// constituent's density (ShadowLerp, ShadowFactors), as skyscatter's lookups (skyscatter.precomputed.lookup). Returns single
// Rayleigh (no phase); single Mie (no phase) and multiple scattering in the out parameters. Zero below the tables'
// sun limit MU_S_MIN.
vec3 GetScattering(float r, float mu, float mu_s, float nu, bool hits_ground, out vec3 mie, out vec3 multiple) {
  mie = vec3(0.0);
  multiple = vec3(0.0);
  if (mu_s < MU_S_MIN - MU_S_LIMIT_TOLERANCE) return vec3(0.0);
  mu_s = max(mu_s, MU_S_MIN);
  vec2 vw = ScatteringMuRCoords(r, mu, hits_ground);
  float p_s = ScatteringMuSIndex(mu_s);
  float p_n = clamp(ScatteringNuIndex(mu, mu_s, nu), 0.0, float(SCATTERING_N_NU - 1));
  float i_n = min(floor(p_n), float(SCATTERING_N_NU - 2));
  float w_n = p_n - i_n;
  float n_x = float(SCATTERING_N_NU * SCATTERING_N_MU_S);
  vec3 uvw0 = vec3((i_n * float(SCATTERING_N_MU_S) + p_s + 0.5) / n_x, vw.x, vw.y);
  vec3 uvw1 = vec3(uvw0.x + float(SCATTERING_N_MU_S) / n_x, vw.x, vw.y);
  vec4 g = ScatteringGroundCell(r, mu, hits_ground);
  // the multiple scattering through four nu slices, the outer two mirrored at the axis' ends (AzimuthRead)
  float j0 = i_n > 0.0 ? i_n - 1.0 : 1.0;
  float j3 = i_n + 2.0 <= float(SCATTERING_N_NU - 1) ? i_n + 2.0 : 2.0 * float(SCATTERING_N_NU - 1) - i_n - 2.0;
  float du = float(SCATTERING_N_MU_S) / n_x;
  multiple = AzimuthRead(ScatteringTexture(multiple_texture, vec3(uvw0.x + (j0 - i_n) * du, vw.x, vw.y), g),
                         ScatteringTexture(multiple_texture, uvw0, g), ScatteringTexture(multiple_texture, uvw1, g),
                         ScatteringTexture(multiple_texture, vec3(uvw0.x + (j3 - i_n) * du, vw.x, vw.y), g), w_n);
  if (InEarthShadow(r, mu_s)) {
    vec3 h = ShadowExitAltitudes(r, mu, mu_s, nu, i_n);
    mie = ShadowLerp(ScatteringTexture(mie_texture, uvw0, g), ScatteringTexture(mie_texture, uvw1, g), w_n,
                     ShadowFactors(h, MIE_DENSITY, MIE_DENSITY_LAYERS));
    return ShadowLerp(ScatteringTexture(rayleigh_texture, uvw0, g), ScatteringTexture(rayleigh_texture, uvw1, g),
                      w_n, ShadowFactors(h, RAYLEIGH_DENSITY, RAYLEIGH_DENSITY_LAYERS));
  }
  mie = AzimuthLerp(ScatteringTexture(mie_texture, uvw0, g), ScatteringTexture(mie_texture, uvw1, g), w_n);
  return AzimuthLerp(ScatteringTexture(rayleigh_texture, uvw0, g), ScatteringTexture(rayleigh_texture, uvw1, g),
                     w_n);
}

// Inscattered radiance S[L](x, v, s) = S_R[L0] P_R(nu) + S_M[L0] P_M(nu) + S[L*] ([Bruneton2008] Eqs. 7-8 with the
// single scattering kept apart, Sec. 4 "Angular precision").
vec3 GetInscatter(float r, float mu, float mu_s, float nu, bool hits_ground) {
  vec3 mie, multiple;
  vec3 rayleigh = GetScattering(r, mu, mu_s, nu, hits_ground, mie, multiple);
  return rayleigh * RayleighPhase(nu) + mie * MiePhase(nu) + multiple * MultipleLobe(nu);
}

// Moves a camera outside the atmosphere to where its ray enters it; false if the ray misses the atmosphere.
bool EnterAtmosphere(inout vec3 camera, vec3 view_ray, out float entered) {
  entered = 0.0;
  float r = length(camera);
  if (r <= TOP_RADIUS) return true;
  float rmu = dot(camera, view_ray);
  // R_t^2 - p^2, p the distance from the planet's centre to the ray's line: as a product, which float32 keeps for
  // rays that graze the top (rmu^2 - r^2 + R_t^2 loses 6 digits there)
  float p = length(cross(camera, view_ray));
  float disc = (TOP_RADIUS - p) * (TOP_RADIUS + p);
  if (disc < 0.0 || rmu >= 0.0) return false;
  float d = -rmu - sqrt(disc);
  if (d < 0.0) return false;
  camera += d * view_ray;
  entered = d;
  return true;
}

// Sky radiance along view_ray from camera, without the sun's disc and the ground's own light ([Bruneton2008]
// Eq. 16's S[L]|x); transmittance to the end of the ray (the ground or the top) in the out parameter.
vec3 GetSkyRadiance(vec3 camera, vec3 view_ray, vec3 sun_direction, out vec3 transmittance) {
  transmittance = vec3(1.0);
  float entered;
  if (!EnterAtmosphere(camera, view_ray, entered)) return vec3(0.0);
  float r = length(camera);
  float rc = clamp(r, BOTTOM_RADIUS, TOP_RADIUS);
  float mu = clamp(dot(camera, view_ray) / r, -1.0, 1.0);
  float mu_s = clamp(dot(camera, sun_direction) / r, -1.0, 1.0);
  float nu = clamp(dot(view_ray, sun_direction), -1.0, 1.0);
  bool hits = RayHitsGround(rc, mu);
  transmittance = hits ? GetTransmittance(rc, mu, DistanceToBottom(rc, mu), true) : GetTransmittanceToTop(rc, mu);
  return GetInscatter(rc, mu, mu_s, nu, hits);
}

// Sun and sky irradiance on a surface at point with unit normal ([Bruneton2008] Eq. 14): the sun
// E_sun T(x, sun) max(n.s, 0) (disc fraction included) and the sky's horizontal irradiance times the ambient
// occlusion of a tilted plane, (1 + n.up) / 2.
vec3 GetSunAndSkyIrradiance(vec3 point, vec3 normal, vec3 sun_direction, out vec3 sky_irradiance) {
  float r = length(point);
  vec3 up = point / r;
  float rc = clamp(r, BOTTOM_RADIUS, TOP_RADIUS);
  float mu_s = clamp(dot(up, sun_direction), -1.0, 1.0);
  sky_irradiance = GetHorizontalSkyIrradiance(rc, mu_s) * 0.5 * (1.0 + dot(normal, up));
  return SOLAR_IRRADIANCE * GetTransmittanceToSun(rc, mu_s) * max(dot(normal, sun_direction), 0.0);
}

// Cosine factor of the sun averaged over its disc: 0 below the horizon, (mu + a)^2 / (4 a) across it, mu above.
float SunCosineFactor(float mu) {
  float a = SUN_ANGULAR_RADIUS;
  if (mu < -a) return 0.0;
  if (mu > a) return mu;
  return (mu + a) * (mu + a) / (4.0 * a);
}

// Radiance of the Lambertian ground of the given albedo where view_ray (from camera, inside the atmosphere, radius r,
// cosine mu) meets the planet, lit by sun and sky ([Bruneton2008] Eqs. 10 and 14: albedo / pi (E_sun T cos + E_sky)),
// times the transmittance back to the camera (Eq. 16's T(x, x_s) R[L]).
vec3 GetGroundRadiance(vec3 camera, vec3 view_ray, vec3 sun_direction, vec3 albedo) {
  float entered;
  if (!EnterAtmosphere(camera, view_ray, entered)) return vec3(0.0);
  float r = clamp(length(camera), BOTTOM_RADIUS, TOP_RADIUS);
  float mu = clamp(dot(camera, view_ray) / length(camera), -1.0, 1.0);
  if (!RayHitsGround(r, mu)) return vec3(0.0);
  float d = DistanceToBottom(r, mu);
  vec3 t = GetTransmittance(r, mu, d, true);
  vec3 g = camera + d * view_ray;
  float mu_s_g = clamp(dot(g, sun_direction) / length(g), -1.0, 1.0);
  vec3 e_sky = GetHorizontalSkyIrradiance(BOTTOM_RADIUS, mu_s_g);
  vec3 t_sun = GetTransmittanceToTop(BOTTOM_RADIUS, mu_s_g);
  return t * albedo / PI * (SOLAR_IRRADIANCE * t_sun * SunCosineFactor(mu_s_g) + e_sky);
}

// Radiance of the sun's disc seen from camera (mean over the disc, [Bruneton2008] Eq. 9): E_sun / Omega_sun times
// the transmittance to the sun; zero where the planet hides it.
vec3 GetSolarRadiance(vec3 camera, vec3 sun_direction) {
  float r = length(camera);
  float rmu = dot(camera, sun_direction);
  if (r > TOP_RADIUS && rmu < 0.0 && length(cross(camera, sun_direction)) <= BOTTOM_RADIUS) return vec3(0.0);
  float entered;
  if (!EnterAtmosphere(camera, sun_direction, entered)) return SOLAR_IRRADIANCE / SUN_SOLID_ANGLE;
  r = length(camera);
  float mu_s = clamp(dot(camera, sun_direction) / r, -1.0, 1.0);
  return SOLAR_IRRADIANCE / SUN_SOLID_ANGLE * GetTransmittanceToSun(clamp(r, BOTTOM_RADIUS, TOP_RADIUS), mu_s);
}

vec3 InscatterToPoint(float r, float mu, float mu_s, float nu, float d, bool hits, out vec3 t) {
  vec3 c = GetInscatter(r, mu, mu_s, nu, hits);
  float r_p = clamp(SafeSqrt(d * d + 2.0 * r * mu * d + r * r), BOTTOM_RADIUS, TOP_RADIUS);
  float mu_p = clamp((r * mu + d) / r_p, -1.0, 1.0);
  float mu_s_p = clamp((r * mu_s + d * nu) / r_p, -1.0, 1.0);
  vec3 c2 = GetInscatter(r_p, mu_p, mu_s_p, nu, hits);
  t = GetTransmittance(r, mu, d, hits);
  return max(c - t * c2, vec3(0.0));
}

// Aerial perspective between camera and point ([Bruneton2008] Eq. 16's last terms): an object's radiance L reaches
// the camera as transmittance * L + (returned) inscatter S|x - T(x, p) S|p. Rays within HORIZON_EPSILON of the
// horizon blend the rays just above and below it, where the two halves of the tables disagree ([Bruneton2017]).
vec3 GetSkyRadianceToPoint(vec3 camera, vec3 point, vec3 sun_direction, out vec3 transmittance) {
  transmittance = vec3(1.0);
  vec3 delta = point - camera;
  float dist = length(delta);
  if (dist <= 0.0) return vec3(0.0);
  vec3 v = delta / dist;
  float entered;
  if (!EnterAtmosphere(camera, v, entered)) return vec3(0.0);
  float d = dist - entered;
  if (d <= 0.0) return vec3(0.0);
  float r = length(camera);
  float rc = clamp(r, BOTTOM_RADIUS, TOP_RADIUS);
  float mu = clamp(dot(camera, v) / r, -1.0, 1.0);
  float mu_s = clamp(dot(camera, sun_direction) / r, -1.0, 1.0);
  float nu = clamp(dot(v, sun_direction), -1.0, 1.0);
  bool hits = RayHitsGround(rc, mu);
  float mu_h = -SafeSqrt(1.0 - (BOTTOM_RADIUS / rc) * (BOTTOM_RADIUS / rc));
  vec3 c;
  if (abs(mu - mu_h) < HORIZON_EPSILON) {
    float mu_lo = mu_h - HORIZON_EPSILON;
    float mu_hi = mu_h + HORIZON_EPSILON;
    vec3 t_lo;
    vec3 lo = InscatterToPoint(rc, mu_lo, mu_s, nu, d, true, t_lo);
    vec3 hi = InscatterToPoint(rc, mu_hi, mu_s, nu, d, false, t_lo);
    c = mix(lo, hi, (mu - mu_lo) / (mu_hi - mu_lo));
  } else {
    vec3 t_unused;
    c = InscatterToPoint(rc, mu, mu_s, nu, d, hits, t_unused);
  }
  transmittance = GetTransmittance(rc, mu, d, hits);
  return c;
}
