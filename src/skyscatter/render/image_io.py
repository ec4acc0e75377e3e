"""Reading and writing images: OpenEXR (linear HDR, float32) and PNG (tone-mapped 8-bit sRGB).

Both writers are atomic (:func:`skyscatter.fileio.atomic_path`): an error or interruption leaves no partial
file, and :func:`write_exr_and_png` writes both files or neither. HDR images hold linear sRGB (D65) with
Y = luminance [cd m^-2] / 683 (``skyscatter.spectral.HDR_SCALE``). Colours outside the sRGB gamut are mapped
into it before writing (:func:`skyscatter.spectral.gamut_map_srgb`: same luminance, desaturated towards
white), so an EXR file never holds a negative value; its header states the sRGB primaries and D65 white
(``chromaticities``). See docs/conventions.md.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import FileFormatError, InvalidParameterError
from ..fileio import atomic_path, atomic_paths, check_output_path
from ..spectral import gamut_map_srgb
from .tonemap import tonemap

__all__ = ["read_exr", "write_exr", "write_exr_and_png", "write_png"]


#: Chromaticities (x, y) of the red, green, blue primaries and white of the files (IEC 61966-2-1 sRGB, D65).
SRGB_CHROMATICITIES = (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290)


def _check_rgb(rgb: ArrayLike) -> NDArray:
    try:
        a = np.asarray(rgb)
    except ValueError as exc:  # ragged nested lists
        raise InvalidParameterError(f"an image must be a numeric array of shape (H, W, 3): {exc}") from None
    if a.dtype.kind not in "biuf":
        raise InvalidParameterError(f"an image must hold numbers; got an array of {a.dtype}")
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] == 0 or a.shape[1] == 0:
        raise InvalidParameterError(f"an image must have shape (H, W, 3) with H, W > 0; got {a.shape}")
    return a


def write_exr(path: str | os.PathLike[str], rgb: ArrayLike) -> Path:
    """Write a linear RGB image (H, W, 3) as a float32 OpenEXR file (ZIP compression), atomically.

    Non-finite values are refused (:class:`~skyscatter.errors.InvalidParameterError`) rather than written;
    colours outside the sRGB gamut are mapped into it (:func:`skyscatter.spectral.gamut_map_srgb`), so the file
    holds no negative value.
    """
    target = check_output_path(_check_suffix(path, ".exr"))
    a = _exr_pixels(rgb)
    with atomic_path(target) as tmp:
        _save_exr(tmp, a)
    return target


def _check_suffix(path: str | os.PathLike[str], suffix: str) -> Path:
    target = Path(path)
    if target.suffix.lower() != suffix:
        raise InvalidParameterError(f"{target}: the file name must end in {suffix}")
    return target


def _exr_pixels(rgb: ArrayLike) -> NDArray[np.float32]:
    a = np.ascontiguousarray(_check_rgb(rgb), dtype=np.float32)
    if not np.all(np.isfinite(a)):
        raise InvalidParameterError("image contains NaN or infinite values; refusing to write it")
    return np.ascontiguousarray(gamut_map_srgb(a), dtype=np.float32)


def _save_exr(path: Path, pixels: NDArray[np.float32]) -> None:
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "chromaticities": SRGB_CHROMATICITIES}
    try:
        OpenEXR.File(header, {"RGB": pixels}).write(str(path))
    except RuntimeError as exc:
        # OpenEXR reports I/O failures (a full disk, a file too large) as RuntimeError('Failed to write ... image
        # file "<path>". No space left on device.'): an OSError for the atomic writer, which names the target.
        text = str(exc)
        reason = text.rsplit('". ', 1)[-1].rstrip(". ") if '". ' in text else text.replace(str(path), "the file")
        raise OSError(None, reason or "the OpenEXR library could not write the file", str(path)) from exc


def _save_png(path: Path, display: NDArray[np.float64]) -> None:
    from PIL import Image

    Image.fromarray(np.round(display * 255.0).astype(np.uint8)).save(path, format="PNG")


def write_exr_and_png(
    exr_path: str | os.PathLike[str],
    png_path: str | os.PathLike[str],
    rgb: ArrayLike,
    *,
    exposure_ev: float | None = None,
    key: float = 0.18,
) -> tuple[Path, Path]:
    """Write an HDR image and its PNG preview together: both files appear, or neither does.

    See :func:`write_exr` and :func:`write_png` for the formats; ``exposure_ev`` and ``key`` go to the tone
    mapper. The two paths must differ and end in ``.exr`` and ``.png``.
    """
    exr = check_output_path(_check_suffix(exr_path, ".exr"))
    png = check_output_path(_check_suffix(png_path, ".png"))
    if exr.resolve() == png.resolve():
        raise InvalidParameterError(f"the HDR and PNG outputs must be different files; both are {exr}")
    pixels = _exr_pixels(rgb)
    display = tonemap(pixels, exposure_ev=exposure_ev, key=key)
    with atomic_paths(exr, png) as (tmp_exr, tmp_png):
        _save_exr(tmp_exr, pixels)
        _save_png(tmp_png, display)
    return exr, png


def read_exr(path: str | os.PathLike[str]) -> NDArray[np.float32]:
    """Read an OpenEXR file's R, G, B channels as a float32 array (H, W, 3)."""
    import OpenEXR

    p = Path(path)
    if not p.is_file():
        raise FileFormatError(f"{p}: no such file")
    try:
        with OpenEXR.File(str(p)) as f:
            channels = f.channels()
            if "RGB" in channels:
                return np.asarray(channels["RGB"].pixels, dtype=np.float32)
            if all(c in channels for c in "RGB"):
                return np.stack([np.asarray(channels[c].pixels, dtype=np.float32) for c in "RGB"], axis=-1)
    except (OSError, RuntimeError) as exc:
        raise FileFormatError(f"{p}: not a readable OpenEXR file ({exc})") from exc
    raise FileFormatError(f"{p}: OpenEXR file has no R, G, B channels (has {sorted(channels)})")


def write_png(
    path: str | os.PathLike[str],
    rgb: ArrayLike,
    *,
    exposure_ev: float | None = None,
    auto_exposure: bool = True,
    key: float = 0.18,
    tonemapped: bool = False,
) -> Path:
    """Write an 8-bit sRGB PNG preview of a linear HDR image (H, W, 3), atomically.

    Parameters
    ----------
    rgb : array_like, shape (H, W, 3)
        Linear HDR image (skyscatter scale), or display values in [0, 1] when ``tonemapped``.
    exposure_ev : float, optional
        Exposure compensation [EV]; see :func:`skyscatter.render.tonemap.tonemap`.
    auto_exposure : bool
        Use the automatic (log-average) exposure of the tone mapper, default True.
    key : float
        Key value of the automatic exposure (0.18 a normal scene; sky-only images look right near 0.4).
    tonemapped : bool
        The input is already display-referred sRGB in [0, 1]; write it as is.
    """
    target = check_output_path(_check_suffix(path, ".png"))
    a = _check_rgb(rgb)
    display = np.clip(np.asarray(a, dtype=float), 0, 1) if tonemapped else tonemap(
        a, exposure_ev=exposure_ev, auto=auto_exposure, key=key
    )
    with atomic_path(target) as tmp:
        _save_png(tmp, display)
    return target
