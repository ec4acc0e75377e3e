"""CIE 1931 colorimetry of spectra and the linear sRGB conversion.

The colour-matching functions are the CIE 1931 2-degree standard observer (CIE 018:2019; 1 nm, 360-830 nm,
shipped as ``skyscatter/data/cie1931_2deg_cmfs.csv``, generated from colour-science's table), linearly
interpolated to the caller's wavelengths and zero outside that range.
Photometric quantities use K_m = 683 lm/W, so ``Y`` of a spectral radiance [W m^-2 sr^-1 nm^-1] is a
luminance [cd m^-2] and of a spectral irradiance an illuminance [lx].
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from .grid import as_wavelengths

__all__ = [
    "HDR_SCALE",
    "LUMINOUS_EFFICACY",
    "cie_cmfs",
    "RADIANCE_EFFICACY",
    "RADIANCE_LUMINANCE_WEIGHTS",
    "RADIANCE_PRIMARIES",
    "gamut_map_rgb",
    "gamut_map_srgb",
    "integration_weights",
    "linear_srgb_to_xyz",
    "radiance_rgb_to_xyz",
    "spectrum_to_luminance",
    "spectrum_to_xyz",
    "xyY_to_xyz",
    "xyz_to_chromaticity",
    "xyz_to_linear_srgb",
    "xyz_to_radiance_rgb",
]

#: Maximum luminous efficacy of radiation K_m [lm/W] (CIE 1931 photopic).
LUMINOUS_EFFICACY = 683.0
#: Absolute scale of HDR images: linear sRGB whose Y equals luminance [cd m^-2] / 683, i.e. radiance-like
#: units [W m^-2 sr^-1] weighted by the photopic curve. Renderers read the values as their own radiance; their
#: skies use other scales (Mitsuba's sunsky and Blender's Hosek-Wilkie sky are about 107 times dimmer): the
#: factors are in docs/conventions.md, "The HDR scale against renderers and cameras".
HDR_SCALE = 1.0 / LUMINOUS_EFFICACY

# IEC 61966-2-1 sRGB primaries with D65 white (the matrix colour-science also uses for 'sRGB').
_XYZ_TO_SRGB = np.array(
    [
        [3.2406, -1.5372, -0.4986],
        [-0.9689, 1.8758, 0.0415],
        [0.0557, -0.2040, 1.0570],
    ]
)
_SRGB_TO_XYZ = np.linalg.inv(_XYZ_TO_SRGB)

#: Radiance's luminous efficacy of its white [lm/W] (``WHTEFFICACY``, [RadianceSource2025] color.h): a Radiance RGB
#: radiance [W sr^-1 m^-2] has luminance ``179 (0.265 R + 0.670 G + 0.065 B)`` [cd m^-2].
RADIANCE_EFFICACY = 179.0
#: Radiance's standard primaries and white, x, y of R, G, B and W ([RadianceSource2025] color.h, ``CIE_x_r`` ...
#: ``CIE_y_w``): an equal-energy white.
RADIANCE_PRIMARIES = (0.640, 0.330, 0.290, 0.600, 0.150, 0.060, 1.0 / 3.0, 1.0 / 3.0)
#: Radiance's luminance weights of R, G, B (``CIE_rf``, ``CIE_gf``, ``CIE_bf``), the Y row of its primaries' matrix
#: rounded to 3 digits (exact: 0.26511, 0.67011, 0.06479).
RADIANCE_LUMINANCE_WEIGHTS = (0.265, 0.670, 0.065)


def _rgb_to_xyz_matrix(primaries: tuple[float, ...]) -> NDArray[np.float64]:
    """RGB -> XYZ for primaries (xr, yr, xg, yg, xb, yb, xw, yw), white (1, 1, 1) -> Y = 1 ([WyszeckiStiles1982]
    3.7)."""
    xr, yr, xg, yg, xb, yb, xw, yw = primaries
    p = np.array([[xr / yr, xg / yg, xb / yb], [1.0, 1.0, 1.0],
                  [(1 - xr - yr) / yr, (1 - xg - yg) / yg, (1 - xb - yb) / yb]])
    white = np.array([xw / yw, 1.0, (1 - xw - yw) / yw])
    return p * np.linalg.solve(p, white)


_RADIANCE_TO_XYZ = _rgb_to_xyz_matrix(RADIANCE_PRIMARIES)
_XYZ_TO_RADIANCE = np.linalg.inv(_RADIANCE_TO_XYZ)


def xyz_to_radiance_rgb(xyz: ArrayLike) -> NDArray[np.float64]:
    """CIE XYZ [cd m^-2] -> Radiance RGB radiance [W sr^-1 m^-2]: Radiance's primaries and equal-energy white,
    divided by its 179 lm/W (so Radiance's ``179 (0.265 R + 0.670 G + 0.065 B)`` gives the luminance back, to
    0.05 % from the rounding of its weights). Out-of-gamut colours have negative components
    (:func:`gamut_map_rgb`)."""
    return np.asarray(xyz, dtype=float) @ _XYZ_TO_RADIANCE.T / RADIANCE_EFFICACY


def radiance_rgb_to_xyz(rgb: ArrayLike) -> NDArray[np.float64]:
    """Radiance RGB radiance [W sr^-1 m^-2] -> CIE XYZ [cd m^-2] (the inverse of :func:`xyz_to_radiance_rgb`)."""
    return np.asarray(rgb, dtype=float) @ _RADIANCE_TO_XYZ.T * RADIANCE_EFFICACY


def _cmfs_table() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    from ._colour import cie_table

    return cie_table("cie1931_2deg_cmfs")


def cie_cmfs(wavelengths: ArrayLike) -> NDArray[np.float64]:
    """CIE 1931 2-degree colour-matching functions xbar, ybar, zbar at ``wavelengths`` [nm].

    Returns an array of shape (n_wavelengths, 3); zero outside 360-830 nm.
    """
    wl = as_wavelengths(wavelengths)
    table_wl, table = _cmfs_table()
    return np.stack([np.interp(wl, table_wl, table[:, i], left=0.0, right=0.0) for i in range(3)], axis=-1)


def integration_weights(wavelengths: ArrayLike) -> NDArray[np.float64]:
    """Trapezoidal quadrature weights [nm] for a strictly increasing wavelength grid [nm]."""
    wl = as_wavelengths(wavelengths)
    if wl.size < 2 or np.any(np.diff(wl) <= 0):
        raise InvalidParameterError(
            "integrating over wavelength needs at least 2 strictly increasing wavelengths [nm]"
        )
    w = np.empty_like(wl)
    d = np.diff(wl)
    w[0] = d[0] / 2
    w[-1] = d[-1] / 2
    w[1:-1] = (d[:-1] + d[1:]) / 2
    return w


def spectrum_to_xyz(spectrum: ArrayLike, wavelengths: ArrayLike) -> NDArray[np.float64]:
    """CIE XYZ of spectra (trailing wavelength axis), ``X = 683 * integral(S xbar d lambda)``.

    Parameters
    ----------
    spectrum : array_like, shape (..., n_wavelengths)
        Spectral radiance [W m^-2 sr^-1 nm^-1] (giving XYZ in cd m^-2) or spectral irradiance
        [W m^-2 nm^-1] (giving lx).
    wavelengths : array_like, shape (n_wavelengths,)
        Strictly increasing wavelengths [nm].

    Returns
    -------
    ndarray, shape (..., 3)
    """
    wl = as_wavelengths(wavelengths)
    s = np.asarray(spectrum)
    if s.shape[-1:] != wl.shape:
        raise InvalidParameterError(
            f"spectrum's last axis ({s.shape[-1:] if s.ndim else '()'}) must match the {wl.size} wavelengths"
        )
    m = cie_cmfs(wl) * integration_weights(wl)[:, None] * LUMINOUS_EFFICACY
    return s @ m


def spectrum_to_luminance(spectrum: ArrayLike, wavelengths: ArrayLike) -> NDArray[np.float64]:
    """Luminance [cd m^-2] (or illuminance [lx]) ``683 * integral(S ybar d lambda)`` of spectra (..., n)."""
    return spectrum_to_xyz(spectrum, wavelengths)[..., 1]


def xyz_to_chromaticity(xyz: ArrayLike) -> NDArray[np.float64]:
    """CIE 1931 chromaticity (x, y) of XYZ (..., 3); black (X + Y + Z = 0) maps to the D65 white point."""
    xyz = np.asarray(xyz, dtype=float)
    s = np.sum(xyz, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        xy = xyz[..., :2] / s
    return np.where(s > 0, xy, np.array([0.31271, 0.32902]))


def xyY_to_xyz(x: ArrayLike, y: ArrayLike, Y: ArrayLike) -> NDArray[np.float64]:  # noqa: N802, N803
    """CIE XYZ (..., 3) from chromaticity (x, y) and luminance Y [any photometric unit]."""
    x, y, Y = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (x, y, Y)))  # noqa: N806
    with np.errstate(invalid="ignore", divide="ignore"):
        X = np.where(y > 0, x * Y / y, 0.0)  # noqa: N806
        Z = np.where(y > 0, (1.0 - x - y) * Y / y, 0.0)  # noqa: N806
    return np.stack([X, Y, Z], axis=-1)


def xyz_to_linear_srgb(xyz: ArrayLike) -> NDArray[np.floating]:
    """Linear sRGB (IEC 61966-2-1 primaries, D65) of XYZ (..., 3); no scaling, no clipping.

    float32 input stays float32.
    """
    xyz = np.asarray(xyz)
    dtype = xyz.dtype if xyz.dtype == np.float32 else np.float64
    return (xyz @ _XYZ_TO_SRGB.T).astype(dtype, copy=False)


def linear_srgb_to_xyz(rgb: ArrayLike) -> NDArray[np.floating]:
    """CIE XYZ of linear sRGB values (..., 3), the inverse of :func:`xyz_to_linear_srgb`."""
    rgb = np.asarray(rgb)
    dtype = rgb.dtype if rgb.dtype == np.float32 else np.float64
    return (rgb @ _SRGB_TO_XYZ.T).astype(dtype, copy=False)


#: Luminance row of the sRGB -> XYZ matrix: Y of linear sRGB (R, G, B).
_SRGB_LUMINANCE = _SRGB_TO_XYZ[1]


def gamut_map_srgb(rgb: ArrayLike) -> NDArray[np.floating]:
    """Bring linear sRGB colours outside the sRGB gamut inside it, keeping their luminance (..., 3).

    A colour with a negative component (a spectrum more saturated than the sRGB primaries, such as the deep
    red of the solar disc at sunset) is desaturated towards the D65 grey of the same luminance,
    ``c' = g + t (c - g)`` with ``g = Y / Y_white`` (``Y`` its luminance by the IEC 61966-2-1 matrix, ``Y_white``
    that of (1, 1, 1)) and the largest ``t`` in [0, 1] that makes every component >= 0. In-gamut colours
    are returned unchanged; a colour with ``Y <= 0`` (not a physical light) becomes black. Luminance and
    dominant hue are kept; only saturation that sRGB cannot show is lost. float32 input stays float32.
    """
    return gamut_map_rgb(rgb, _SRGB_LUMINANCE)


def gamut_map_rgb(rgb: ArrayLike, luminance_weights: ArrayLike) -> NDArray[np.floating]:
    """:func:`gamut_map_srgb` for any RGB space whose luminance is ``rgb @ luminance_weights`` (e.g.
    :data:`RADIANCE_LUMINANCE_WEIGHTS`): out-of-gamut colours desaturated towards the grey of the same
    luminance."""
    c = np.asarray(rgb)
    dtype = c.dtype if c.dtype == np.float32 else np.float64
    if c.dtype not in (np.float32, np.float64):
        c = c.astype(np.float64)
    if c.shape[-1:] != (3,):
        raise InvalidParameterError(f"linear RGB colours need a last axis of 3; got shape {c.shape}")
    weights = np.asarray(luminance_weights, dtype=float)
    # the test and the mapping on the out-of-gamut colours only, in float64 (a whole image is not converted)
    low = np.minimum(np.minimum(c[..., 0], c[..., 1]), c[..., 2])
    bad = low < 0
    if not np.any(bad):
        return c.astype(dtype, copy=False)
    cb = c[bad].astype(np.float64)
    y = cb @ weights
    out = c.astype(dtype, copy=True)
    # the grey (g, g, g) of the same luminance; the white (1, 1, 1) has Y = sum of the weights
    g, lb = y / weights.sum(), low[bad].astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(g > 0, g / (g - lb), 0.0)  # the lowest component g + t (low - g) becomes 0
    t = np.clip(t, 0.0, 1.0)
    mapped = np.maximum(g[:, None] + t[:, None] * (cb - g[:, None]), 0.0)
    mapped[g <= 0] = 0.0
    out[bad] = mapped
    return out
