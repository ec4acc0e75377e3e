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

__all__ = ["read_exr", "write_exr", "write_exr_and_png", "write_hdr", "write_png"]


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
    """Write a linear RGB image (H, W, 3) as a float32 OpenEXR file (ZIPS compression: lossless, zlib per
    scanline, compressed on :func:`skyscatter.runtime.num_threads` threads), atomically.

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

    from ..runtime import num_threads

    # ZIPS (zlib per scanline): lossless and read by every OpenEXR reader (Blender, Mitsuba: ZSTD, 3x faster
    # still, is not read by Mitsuba 3.9); one scanline per block spreads over the library's threads, where ZIP's
    # 16-line blocks did not get faster with them. 2048 x 1024 map, float32 RGB, load 9-12 on 2 cores: ZIP 0.58-0.84 s
    # (9.9 MiB), ZIPS 0.31-0.60 s with 2 threads (11.2 MiB), PIZ (Mitsuba's) 1.05-1.4 s (8.0 MiB).
    if OpenEXR.global_thread_count() != num_threads():
        OpenEXR.set_global_thread_count(num_threads())
    header = {"compression": OpenEXR.ZIPS_COMPRESSION, "type": OpenEXR.scanlineimage,
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


def write_hdr(path: str | os.PathLike[str], rgb: ArrayLike, *, comments: tuple[str, ...] | list[str] = ()) -> Path:
    """Write an RGB image (H, W, 3) as a Radiance picture (RGBE, ``.hdr``/``.pic``), atomically; returns the path.

    The values are written as they are (no colour conversion, no exposure): give Radiance RGB radiance
    [W sr^-1 m^-2] (:func:`skyscatter.spectral.xyz_to_radiance_rgb`) for pictures Radiance renders with.
    Non-finite or negative values are refused. Format ([Ward1994]; [RadianceSource2025] color.c): the header
    ``#?RADIANCE``, ``FORMAT=32-bit_rle_rgbe``, an empty line and ``-Y H +X W``; then each scanline run-length
    encoded per component (Radiance's "new" encoding; 8 to 32767 pixels wide, flat pixels otherwise), every
    pixel a shared 8-bit exponent and three 8-bit mantissas (relative precision 1/256).
    """
    target = check_output_path(path)
    a = np.asarray(_check_rgb(rgb), dtype=np.float64)
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise InvalidParameterError("a Radiance picture holds finite values >= 0; gamut map or clip the image first")
    with atomic_path(target) as tmp:
        _save_hdr(tmp, a, comments)
    return target


def _rgbe(a: NDArray[np.float64]) -> NDArray[np.uint8]:
    """(H, W, 3) floats -> (H, W, 4) RGBE bytes, as Radiance's ``setcolr``: mantissas ``floor(c * 255.9999 * m /
    max)`` with ``max = m 2^e`` (m in [0.5, 1)), exponent ``e + 128``; 0 below 1e-32."""
    v = a.max(axis=-1)
    m, e = np.frexp(v)
    lit = v > 1e-32
    scale = np.where(lit, m * 255.9999 / np.where(lit, v, 1.0), 0.0)
    out = np.zeros((*a.shape[:2], 4), dtype=np.uint8)
    out[..., :3] = np.clip(np.floor(a * scale[..., None]), 0, 255).astype(np.uint8)
    out[..., 3] = np.where(lit, e + 128, 0).astype(np.uint8)
    return out


def _save_hdr(path: Path, a: NDArray[np.float64], comments) -> None:
    h, w = a.shape[:2]
    pixels = _rgbe(a)
    lines = ["#?RADIANCE", *(f"# {c}" for c in comments if c), "FORMAT=32-bit_rle_rgbe", "", f"-Y {h} +X {w}"]
    if 8 <= w <= 0x7FFF:
        # each scanline: 2 2 W>>8 W&255, then each component as literal runs of at most 128 bytes (count, bytes)
        n = -(-w // 128)
        padded = np.zeros((h, 4, n * 128), dtype=np.uint8)
        padded[..., :w] = pixels.transpose(0, 2, 1)
        counts = np.full(n, 128, dtype=np.uint8)
        counts[-1] = w - 128 * (n - 1)
        block = np.concatenate([np.broadcast_to(counts[None, None, :, None], (h, 4, n, 1)),
                                padded.reshape(h, 4, n, 128)], axis=-1)
        keep = np.zeros((n, 129), dtype=bool)
        keep[:, 0] = True
        keep[np.arange(129)[None, :] <= counts[:, None].astype(int)] = True
        data = block.reshape(h, 4, n * 129)[..., keep.ravel()].reshape(h, 4 * (w + n))
        start = np.broadcast_to(np.array([2, 2, w >> 8, w & 255], dtype=np.uint8), (h, 4))
        body = np.concatenate([start, data], axis=1)
    else:
        body = pixels
    with open(path, "wb") as fh:
        fh.write(("\n".join(lines) + "\n").encode("ascii"))
        fh.write(memoryview(np.ascontiguousarray(body)).cast("B"))
