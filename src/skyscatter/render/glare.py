"""Scattering in the eye: glare (bloom) as a convolution with the point-spread function of Spencer et al. 1995.

[Spencer1995] Sec. 4-5: the eye's point-spread function is a weighted sum of four radial components of the angle theta
[deg] from the source,

* ``f0(theta) = 2.61e6 exp(-(theta / 0.02)^2)``            (the core: the eye's optics),
* ``f1(theta) = 20.91 / (theta + 0.02)^3``                   (near scattering, the ciliary corona),
* ``f2(theta) = 72.37 / (theta + 0.02)^2``                   (bloom, scattering in cornea, lens and retina),
* ``f3(theta, lambda) = 436.9 (568 / lambda) exp(-19.75 (theta - 3 lambda / 568)^2)``
  (the lenticular halo, a ring near 3 deg that depends on the wavelength lambda [nm]),

combined as ``P_photopic = 0.384 f0 + 0.478 f1 + 0.138 f2`` (daylight adaptation, small pupil; the paper's
photopic PSF) and ``P_scotopic = 0.282 f0 + 0.478 f1 + 0.207 f2 + 0.033 f3`` (dark adaptation). The values
are densities per square degree. The lecture notes (seed 004) motivate the image-space treatment: the angle
between source and receiving pixel is about proportional to the image-space distance, so glare is a
convolution.

Discretisation choices (documented here because they decide the energy balance):

* Angles are measured in the image plane with the angular size of the centre pixel (exact for small
  fields of view, an approximation towards the corners of a wide pinhole image).
* Each kernel pixel holds the PSF integrated over the pixel's square: ``f0`` exactly (a separable Gaussian,
  with ``erf``), the other components by midpoint sub-sampling that is finer near the centre (64 x 64 per
  pixel within 4 px, 8 x 8 within 16 px, 2 x 2 within 64 px, 1 beyond), except the disc inscribed in the
  centre pixel, which is integrated in closed form (the peak of ``f1`` is narrower than a sub-sample).
* ``f2`` has no finite integral over the plane (its mass grows like ``log theta``), so the PSF is truncated at
  ``max_angle`` and normalised to unit mass over that disc with the closed-form radial integrals of
  :func:`spencer_psf_mass`. :func:`apply_glare` uses a (2H - 1) x (2W - 1) kernel; the PSF fills the whole
  rectangle (every source reaches every pixel; truncating at the inscribed disc instead, about 34 deg for a
  60-deg-wide 16:9 image, drew a visible circle around the sun), and the sampling accuracy is checked on the
  inscribed disc against the closed form. The discrete kernel then sums to 1 to within the sub-sampling
  error, which :func:`glare_kernel` reports (tests require < 1e-3); it is finally rescaled to sum to exactly
  1, so the convolution conserves the image's energy apart from light the PSF sends beyond the image border.

Reference: [Spencer1995].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import fft as sfft
from scipy.special import erf

from ..errors import InvalidParameterError

__all__ = [
    "SPENCER_WEIGHTS",
    "GlareKernel",
    "apply_glare",
    "convolve_fft",
    "glare_kernel",
    "spencer_psf",
    "spencer_psf_mass",
]

#: Weights of (f0, f1, f2, f3) in Spencer et al. 1995's photopic and scotopic point-spread functions.
SPENCER_WEIGHTS = {
    "photopic": (0.384, 0.478, 0.138, 0.0),
    "scotopic": (0.282, 0.478, 0.207, 0.033),
}
#: Wavelengths [nm] used for the lenticular halo f3 of the R, G, B channels (dominant wavelengths of the sRGB
#: primaries, rounded).
RGB_WAVELENGTHS = (612.0, 549.0, 464.0)

_A = 0.02  # [deg] the offset/width shared by f0, f1, f2
_F0, _F1, _F2, _F3 = 2.61e6, 20.91, 72.37, 436.9
_K3 = 19.75  # [deg^-2]


def _check_adaptation(adaptation: str) -> tuple[float, float, float, float]:
    try:
        return SPENCER_WEIGHTS[adaptation]
    except KeyError:
        raise InvalidParameterError(
            f"adaptation must be one of {sorted(SPENCER_WEIGHTS)}; got {adaptation!r}"
        ) from None


def _components(theta: NDArray[np.float64], wavelength: float) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    f0 = _F0 * np.exp(-((theta / _A) ** 2))
    f1 = _F1 / (theta + _A) ** 3
    f2 = _F2 / (theta + _A) ** 2
    f3 = _F3 * (568.0 / wavelength) * np.exp(-_K3 * (theta - 3.0 * wavelength / 568.0) ** 2)
    return f0, f1, f2, f3


def spencer_psf(theta_deg: ArrayLike, *, adaptation: str = "photopic", wavelength: float = 568.0) -> NDArray:
    """Spencer et al. 1995 point-spread function [per deg^2] at angle ``theta_deg`` [deg] from a point source.

    Parameters
    ----------
    theta_deg : array_like
        Angle from the source [deg], >= 0.
    adaptation : {"photopic", "scotopic"}
        Which weighting of the components to use (see the module docstring).
    wavelength : float
        Wavelength [nm] for the lenticular halo ``f3`` (only used by the scotopic PSF).
    """
    w = _check_adaptation(adaptation)
    theta = np.asarray(theta_deg, dtype=float)
    return sum(wi * fi for wi, fi in zip(w, _components(theta, float(wavelength)), strict=True))


def _radial_masses(radius: float, wavelength: float) -> NDArray[np.float64]:
    """Closed-form ``int_0^R 2 pi theta f_i(theta) dtheta`` [dimensionless] for the four components."""
    r, a = float(radius), _A
    m0 = _F0 * math.pi * a * a * (1.0 - math.exp(-((r / a) ** 2)))
    m1 = 2 * math.pi * _F1 * (1.0 / (2 * a) - 1.0 / (r + a) + a / (2 * (r + a) ** 2))
    m2 = 2 * math.pi * _F2 * (math.log((r + a) / a) + a / (r + a) - 1.0)
    c = _F3 * 568.0 / wavelength
    t0 = 3.0 * wavelength / 568.0
    sk = math.sqrt(_K3)

    def anti(t: float) -> float:
        gauss = -math.exp(-_K3 * (t - t0) ** 2) / (2 * _K3)
        return gauss + t0 * math.sqrt(math.pi) / (2 * sk) * math.erf(sk * (t - t0))

    m3 = 2 * math.pi * c * (anti(r) - anti(0.0))
    return np.array([m0, m1, m2, m3])


def spencer_psf_mass(max_angle_deg: float, *, adaptation: str = "photopic", wavelength: float = 568.0) -> float:
    """Integral of :func:`spencer_psf` over the disc ``theta <= max_angle_deg`` [deg] (closed form)."""
    w = np.asarray(_check_adaptation(adaptation))
    if not (np.isfinite(max_angle_deg) and max_angle_deg > 0):
        raise InvalidParameterError(f"max_angle must be a positive angle; got {max_angle_deg!r}")
    return float(w @ _radial_masses(max_angle_deg, float(wavelength)))


@dataclass(frozen=True)
class GlareKernel:
    """A discrete, normalised glare kernel.

    Attributes
    ----------
    values : ndarray, shape (2 ky + 1, 2 kx + 1)
        Kernel (sums to 1), centred.
    pixel_angle : float
        Angular size of one pixel [rad].
    max_angle : float
        Truncation angle of the PSF [rad].
    discretisation_error : float
        ``|sum(raw kernel) / closed-form mass - 1|`` before the final rescaling.
    """

    values: NDArray[np.float64]
    pixel_angle: float
    max_angle: float
    discretisation_error: float


def glare_kernel(pixel_angle: float, half_size: tuple[int, int], *, adaptation: str = "photopic",
                 wavelength: float = 568.0, max_angle: float | None = None,
                 fill_corners: bool = False) -> GlareKernel:
    """Sample the Spencer et al. 1995 PSF on a pixel grid.

    Parameters
    ----------
    pixel_angle : float
        Angle [rad] subtended by one pixel (e.g. :meth:`PinholeCamera.pixel_angle`).
    half_size : (int, int)
        Kernel half-height and half-width ``(ky, kx)`` [px]; the kernel is ``(2 ky + 1, 2 kx + 1)``.
    adaptation : {"photopic", "scotopic"}
    wavelength : float
        Wavelength [nm] of the lenticular halo (scotopic only).
    max_angle : float, optional
        Truncation angle [rad], at most the radius of the disc inscribed in the kernel (the default), so
        that the truncated PSF lies wholly inside the kernel.
    fill_corners : bool
        Also sample the PSF outside that disc, up to the kernel's rectangular edge, so a source lights every
        pixel of an image of the kernel's half size and the truncation leaves no visible circle around a
        bright source. The reported sampling error is still measured on the disc (closed form).
    """
    if not (np.isfinite(pixel_angle) and 0 < pixel_angle < math.pi):
        raise InvalidParameterError(f"pixel_angle must be in (0, pi) rad; got {pixel_angle!r}")
    ky, kx = (int(v) for v in half_size)
    if ky < 0 or kx < 0:
        raise InvalidParameterError(f"kernel half size must be >= 0 pixels; got {half_size!r}")
    w = np.asarray(_check_adaptation(adaptation))
    px_deg = math.degrees(pixel_angle)
    inscribed = (min(ky, kx) + 0.5) * pixel_angle
    if max_angle is None:
        max_angle = inscribed
    if not (np.isfinite(max_angle) and 0 < max_angle <= inscribed * (1 + 1e-12)):
        raise InvalidParameterError(
            f"max_angle must be a positive angle [rad] no larger than the kernel's inscribed radius "
            f"{inscribed:.6g} rad; got {max_angle!r}"
        )
    r_max = math.degrees(max_angle)
    wavelength = float(wavelength)

    # f0: exact pixel integrals of the separable Gaussian (its width is far below 1 px at usual sizes).
    def gauss_1d(n: int) -> NDArray[np.float64]:
        edges = (np.arange(-n, n + 2) - 0.5) * px_deg
        return np.diff(erf(edges / _A)) * (math.sqrt(math.pi) * _A / 2)

    kernel = w[0] * _F0 * np.outer(gauss_1d(ky), gauss_1d(kx))
    # The Gaussian beyond r_max is below 1e-300; no truncation needed.

    # The radial part is symmetric about both axes: sample one quadrant (including the axes) and mirror it.
    yy, xx = np.meshgrid(np.arange(ky + 1), np.arange(kx + 1), indexing="ij")
    rr = np.hypot(yy, xx)
    quad = np.zeros(rr.shape)
    corners = np.zeros(rr.shape)
    for lo, hi, nsub in ((0.0, 4.0, 64), (4.0, 16.0, 8), (16.0, 64.0, 2), (64.0, np.inf, 1)):
        sel = (rr >= lo) & (rr < hi)
        if not sel.any():
            continue
        offs = (np.arange(nsub) + 0.5) / nsub - 0.5
        sy, sx = np.meshgrid(offs, offs, indexing="ij")
        cy = yy[sel][:, None] + sy.ravel()[None, :]
        cx = xx[sel][:, None] + sx.ravel()[None, :]
        r_px = np.hypot(cy, cx)
        theta = r_px * px_deg
        inv = 1.0 / (theta + _A)
        val = (w[1] * _F1 * inv + w[2] * _F2) * inv * inv  # w1 f1 + w2 f2
        if w[3]:
            val += w[3] * _F3 * (568.0 / wavelength) * np.exp(-_K3 * (theta - 3.0 * wavelength / 568.0) ** 2)
        keep = theta <= r_max
        outside = ~keep
        if lo == 0.0:
            # The peak of f1 (width 0.02 deg) is narrower than the sub-samples of a coarse pixel: integrate the
            # disc inscribed in the centre pixel in closed form and sub-sample only its corners.
            keep &= r_px >= 0.5
        quad[sel] = np.where(keep, val, 0.0).mean(axis=1) * px_deg * px_deg
        if fill_corners:
            corners[sel] = np.where(outside, val, 0.0).mean(axis=1) * px_deg * px_deg
    core = _radial_masses(min(0.5 * px_deg, r_max), wavelength)
    quad[0, 0] += float(w[1:] @ core[1:])
    kernel = kernel + _mirror(quad)
    mass = float(w @ _radial_masses(r_max, wavelength))
    disc_sum = float(kernel.sum())
    if fill_corners:
        kernel = kernel + _mirror(corners)
    return GlareKernel(kernel / float(kernel.sum()), float(pixel_angle), float(max_angle),
                       abs(disc_sum / mass - 1.0))


def _mirror(quadrant: NDArray[np.float64]) -> NDArray[np.float64]:
    """Full kernel from its quadrant with rows/columns >= 0 (symmetric about both axes)."""
    full = np.concatenate([quadrant[:0:-1], quadrant], axis=0)
    return np.concatenate([full[:, :0:-1], full], axis=1)


def _padded_shape(h: int, w: int, kh: int, kw: int) -> tuple[int, int]:
    return (sfft.next_fast_len(h + kh - 1, real=True), sfft.next_fast_len(w + kw - 1, real=True))


def convolve_fft(image: ArrayLike, kernel: ArrayLike, *, mode: str = "same",
                 kernel_spectrum: NDArray[np.complex128] | None = None) -> NDArray[np.float64]:
    """Linear (zero-padded) 2-D convolution of ``image`` (H, W) or (H, W, C) with a centred odd-sized kernel.

    ``mode="same"`` returns the (H, W[, C]) window aligned with the input; ``mode="full"`` returns everything
    the kernel spreads light into, (H + kh - 1, W + kw - 1[, C]), whose sum equals ``sum(image) * sum(kernel)``.
    ``kernel_spectrum`` may pass the kernel's real FFT on the padded grid, computed once for several images.
    """
    img = np.asarray(image, dtype=np.float64)
    k = np.asarray(kernel, dtype=np.float64)
    if img.ndim not in (2, 3) or k.ndim != 2 or k.shape[0] % 2 == 0 or k.shape[1] % 2 == 0:
        raise InvalidParameterError(
            f"convolve_fft needs an (H, W) or (H, W, C) image and an odd-sized 2-D kernel; "
            f"got {img.shape} and {k.shape}"
        )
    if mode not in ("same", "full"):
        raise InvalidParameterError(f"mode must be 'same' or 'full'; got {mode!r}")
    h, w = img.shape[:2]
    kh, kw = k.shape
    fh, fw = h + kh - 1, w + kw - 1
    sh, sw = _padded_shape(h, w, kh, kw)
    kf = sfft.rfft2(k, s=(sh, sw), workers=-1) if kernel_spectrum is None else kernel_spectrum
    chans = img[..., None] if img.ndim == 2 else img
    out = np.empty((fh, fw, chans.shape[-1]))
    for c in range(chans.shape[-1]):
        f = sfft.rfft2(chans[..., c], s=(sh, sw), workers=-1)
        f *= kf
        out[..., c] = sfft.irfft2(f, s=(sh, sw), workers=-1)[:fh, :fw]
    if mode == "same":
        out = out[kh // 2: kh // 2 + h, kw // 2: kw // 2 + w]
    return out[..., 0] if img.ndim == 2 else out


# The last kernel spectra used by apply_glare (a demo renders several panels of one size); about 70 MB each at
# 1280 x 720, so only two are kept.
_SPECTRA: dict[tuple, tuple[NDArray, NDArray]] = {}


def _kernel_and_spectrum(pixel_angle: float, shape: tuple[int, int], adaptation: str, wavelength: float,
                         max_angle: float | None) -> tuple[NDArray, NDArray]:
    h, w = shape
    key = (round(pixel_angle, 15), h, w, adaptation, wavelength, max_angle)
    if key not in _SPECTRA:
        k = glare_kernel(pixel_angle, (h - 1, w - 1), adaptation=adaptation, wavelength=wavelength,
                         max_angle=max_angle, fill_corners=max_angle is None).values
        spec = sfft.rfft2(k, s=_padded_shape(h, w, *k.shape), workers=-1)
        while len(_SPECTRA) >= 2:
            _SPECTRA.pop(next(iter(_SPECTRA)))
        _SPECTRA[key] = (k, spec)
    return _SPECTRA[key]


def apply_glare(rgb: ArrayLike, pixel_angle: float, *, adaptation: str = "photopic",
                max_angle: float | None = None) -> NDArray[np.float64]:
    """Add the eye's glare to a linear HDR image (apply before tone mapping).

    Parameters
    ----------
    rgb : array_like, shape (H, W, 3)
        Linear scene-referred image (any absolute scale; the operation is linear).
    pixel_angle : float
        Angle [rad] subtended by one pixel at the image centre.
    adaptation : {"photopic", "scotopic"}
        Photopic for daylight scenes (the default); scotopic adds the wavelength-dependent lenticular halo.
    max_angle : float, optional
        Truncation of the PSF [rad], at most ``min(H, W) - 0.5`` pixels (the disc inscribed in the
        (2H - 1) x (2W - 1) kernel). By default the PSF fills the whole kernel rectangle instead, so every source
        reaches every pixel of the image and no truncation circle shows around the sun.

    Returns
    -------
    ndarray, shape (H, W, 3)
        The convolved image; where the PSF sends light beyond the border it is lost, as in the eye.
    """
    img = np.asarray(rgb, dtype=np.float64)
    if img.ndim != 3 or img.shape[-1] != 3:
        raise InvalidParameterError(f"apply_glare needs an (H, W, 3) image; got shape {img.shape}")
    if not np.all(np.isfinite(img)):
        raise InvalidParameterError("apply_glare: the image contains NaN or infinite values")
    weights = _check_adaptation(adaptation)
    shape = img.shape[:2]
    if weights[3] == 0.0:
        k, spec = _kernel_and_spectrum(pixel_angle, shape, adaptation, 568.0, max_angle)
        return convolve_fft(img, k, kernel_spectrum=spec)
    out = np.empty_like(img)
    for c, wl in enumerate(RGB_WAVELENGTHS):
        k, spec = _kernel_and_spectrum(pixel_angle, shape, adaptation, wl, max_angle)
        out[..., c] = convolve_fft(img[..., c], k, kernel_spectrum=spec)
    return out
