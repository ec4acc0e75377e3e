"""Tone mapping of linear HDR images (skyscatter's HDR scale) to display sRGB.

The operator is the global photographic operator of Reinhard et al. 2002 ("Photographic Tone Reproduction
for Digital Images", SIGGRAPH 2002), applied to luminance so hue is kept:

1. exposure: ``Y_s = k Y`` with ``k = key / Y_avg`` (Eq. 1-2: key value, 0.18 by default, over the
   log-average luminance ``Y_avg = exp(mean(log(1e-6 + Y)))`` of the non-black pixels), times
   ``2**exposure_ev``; or ``k = 2**exposure_ev`` alone for an absolute exposure (``auto=False``);
2. compression: ``Y_d = Y_s (1 + Y_s / Y_white^2) / (1 + Y_s)`` (Eq. 4) with ``Y_white`` the smallest
   luminance mapped to white (default 8 after exposure, i.e. 3 stops above the key);
3. each channel scaled by ``Y_d / Y``, clipped to [0, 1] and encoded with the sRGB transfer function
   (IEC 61966-2-1).

The curve of step 2 is strictly increasing in ``Y_s``, so the operator is monotonic in luminance.

Reference: [Reinhard2002].
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError

__all__ = ["log_average_luminance", "srgb_encode", "tonemap"]

_LUMA = np.array([0.2126, 0.7152, 0.0722])  # Y of linear sRGB primaries (IEC 61966-2-1)


def log_average_luminance(rgb: ArrayLike) -> float:
    """Log-average luminance of a linear sRGB image (Reinhard et al. 2002, Eq. 1).

    Pixels that are black (outside a fisheye circle, an unlit ground) or non-finite are left out, so they do
    not drag the exposure up.
    """
    y = np.asarray(rgb, dtype=float) @ _LUMA
    y = y[np.isfinite(y) & (y > 0)]
    if y.size == 0:
        return 1.0
    return float(np.exp(np.mean(np.log(1e-6 + np.maximum(y, 0.0)))))


def srgb_encode(linear: ArrayLike) -> NDArray[np.float64]:
    """sRGB transfer function (IEC 61966-2-1:1999, the inverse EOTF) of linear values, clipped to [0, 1].

    ``V = 12.92 L`` for ``L <= 0.0031308``, else ``1.055 L^(1/2.4) - 0.055``.
    """
    lin = np.clip(np.asarray(linear, dtype=float), 0.0, 1.0)
    return np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * np.power(lin, 1.0 / 2.4) - 0.055)


def tonemap(
    rgb: ArrayLike,
    *,
    exposure_ev: float | None = None,
    auto: bool = True,
    white: float = 8.0,
    key: float = 0.18,
) -> NDArray[np.float64]:
    """Map a linear HDR image (H, W, 3) to display-referred, sRGB-encoded values in [0, 1].

    Parameters
    ----------
    rgb : array_like, shape (..., 3)
        Linear sRGB in skyscatter's HDR scale (Y = luminance [cd m^-2] / 683). Negative values count as 0.
    exposure_ev : float, optional
        Exposure compensation [EV stops] added to the automatic exposure (or the absolute exposure with
        ``auto=False``). Default 0.
    auto : bool
        Scale by ``key / log-average luminance`` first (default True).
    white : float
        Exposed luminance mapped to pure white (> 0), default 8.
    key : float
        Key value of the automatic exposure, default 0.18.
    """
    rgb = np.maximum(np.nan_to_num(np.asarray(rgb, dtype=float), nan=0.0, posinf=0.0), 0.0)
    if rgb.shape[-1:] != (3,):
        raise InvalidParameterError(f"tonemap needs an image with 3 channels; got shape {rgb.shape}")
    if not white > 0:
        raise InvalidParameterError(f"white must be > 0; got {white}")
    ev = 0.0 if exposure_ev is None else float(exposure_ev)
    if not (np.isfinite(ev) and abs(ev) <= 60.0):
        raise InvalidParameterError(f"exposure must be within [-60, 60] EV; got {exposure_ev}")
    scale = 2.0**ev
    if auto:
        scale *= key / max(log_average_luminance(rgb), 1e-12)
    y = rgb @ _LUMA
    ys = scale * y
    yd = ys * (1.0 + ys / (white * white)) / (1.0 + ys)
    ratio = np.where(y > 0, yd / np.where(y > 0, y, 1.0), 0.0)
    return srgb_encode(rgb * ratio[..., None])
