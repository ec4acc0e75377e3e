"""Annual sky matrices: hourly Perez (1993) or ASRC-CIE sky luminance over Tregenza/Reinhart patches from an EPW.

The job Radiance's ``gendaymtx`` does, vectorised over hours:

1. read the EPW file (:func:`skyscatter.epw.read_epw`): site, time zone, hourly direct normal and diffuse
   horizontal irradiance and dew point;
2. the sun for every hour at the middle of the hour the EPW values average over (file hour - 30 min, local
   standard time), NREL SPA through :func:`skyscatter.sun.position.sun_position_unix` (apparent zenith, the site
   elevation as altitude);
3. the Perez sky of every hour with :func:`skyscatter.sky.perez.perez_parameters` (clearness and brightness from
   the irradiances, Perez 1990 luminous efficacies with the hour's dew point, all the guards of
   :mod:`skyscatter.sky.perez`); with ``model="asrc-cie"`` the same sky condition weights the four CIE-type
   skies of :mod:`skyscatter.sky.asrc_cie` instead; the sky is scaled so that it integrates to the hour's
   diffuse horizontal illuminance (Gauss-Legendre rule of :func:`skyscatter.photometry.plane_quadrature`,
   48 x 96 nodes);
4. every patch gets the sky's mean luminance over ``samples x samples`` equal-area cells (``samples=1``: the
   patch centre, as gendaymtx does).

Hours without diffuse light (D_h = 0) give a row of zeros. Hours with diffuse light but the sun below the
horizon at mid-hour (sunrise or sunset inside the hour) are modelled with the sun on the horizon at its
azimuth, as gendaymtx does. With ``include_sun`` the direct normal illuminance of the sun (Perez 1990 direct
efficacy) is spread over the 4 patches nearest to the sun, weighted by proximity, as gendaymtx does
(:func:`add_sun_to_patches`, which states the rule and its source).

The result is a :class:`SkyMatrix`: ``luminance`` [cd m^-2] of shape (hours, patches), with the sun angles, the
Perez parameters and the patch geometry, savable as ``.npz`` and ``.csv``.
"""

from __future__ import annotations

import datetime as dt
import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from . import __version__
from .conventions import direction_from_angles
from .epw import EPWData, EPWLocation, read_epw
from .errors import FileFormatError, InvalidParameterError
from .fileio import atomic_path, atomic_paths
from .patches import PatchScheme, patch_scheme
from .radiance import write_radiance_matrix
from .sky.perez_family import gradation, indicatrix
from .spectral import RADIANCE_EFFICACY
from .validation import whole_number

__all__ = ["MODELS", "NORMALISATION_NODES", "SUN_PATCHES", "SkyMatrix", "add_sun_to_patches",
           "asrc_cie_patch_luminance", "perez_patch_luminance", "skymatrix"]

#: Sky models :func:`skymatrix` builds from an hour's direct normal and diffuse horizontal irradiance.
MODELS = ("perez", "asrc-cie")

#: Gauss-Legendre nodes (zenith, azimuth) of the per-hour normalisation integral.
NORMALISATION_NODES = (48, 96)


#: Values (skies x directions) per vectorised step of :func:`perez_patch_luminance`: its temporaries stay in the
#: CPU caches (measured: 4-8x slower per value once they reach a few MB).
CHUNK_VALUES = 65536


def _perez_chunk(coeffs, sun, scale, dirs_t, q_rows, rows, row_cos, qweights, n_sub, out, work) -> None:
    """One block of skies: normalise each Perez sky to D_v with the quadrature, then average over the samples.

    The Perez function (Perez et al. 1993, Eq. 1) ``max(0, (1 + a exp(b / max(cos theta, 0.01)))(1 + c
    exp(d gamma) + e cos^2 gamma))`` (the one horizon rule of :mod:`skyscatter.sky.perez_family`) is the product of
    the shared kernel's gradation G, tabulated per sky over the distinct zenith angles of the directions
    (``row_cos``; ``rows`` gives each direction's entry), and its indicatrix I per direction: one exponential
    per direction instead of two. ``dirs_t`` (3, n) holds the quadrature nodes (weights ``qweights``), then
    ``n_sub`` samples per patch; every sky of the block has ``scale`` (D_v) > 0. ``work``: a scratch array of at
    least (n_skies, n).

    When the nodes are rows of equal zenith angle (``q_rows``: the entry of each row, ``qweights`` of shape
    (rows, nodes per row)) and G > 0 on every row, ``max(0, G I) = G max(0, I)`` and the normalisation is
    ``sum_r G_r sum_j w_rj max(0, I_rj)``: no per-node gather of G (the same sum, in another order).
    """
    n_sky = coeffs.shape[0]
    a, b, c, d, e = (coeffs[:, k : k + 1] for k in range(5))
    grad = gradation(row_cos, a, b)  # (n_skies, n_rows)
    cos_g = sun @ dirs_t
    np.clip(cos_g, -1.0, 1.0, out=cos_g)
    gamma = np.arccos(cos_g)
    f = indicatrix(1.0, gamma, cos_g, 1.0, c, d, e, out=gamma, work=work[:n_sky])  # in place: no temporaries
    n_q = qweights.size
    g_q = grad[:, q_rows] if q_rows is not None else None
    if g_q is not None and np.all(g_q > 0.0):
        fq = np.reshape(f[:, :n_q], (n_sky, *qweights.shape), copy=False)  # a view
        np.maximum(fq, 0.0, out=fq)
        total = np.einsum("hr,hr->h", g_q, np.einsum("hrj,rj->hr", fq, qweights))
        fs = f[:, n_q:]
        fs *= np.take(grad, rows[n_q:], axis=1)
        np.maximum(fs, 0.0, out=fs)
    else:
        f *= np.take(grad, rows, axis=1)
        np.maximum(f, 0.0, out=f)
        total = f[:, :n_q] @ qweights.reshape(-1)
    _normalise(total, scale, f[:, n_q:].reshape(n_sky, -1, n_sub), out)


def _normalise(total, scale, samples, out) -> None:
    """``out`` = the patch means of ``samples`` (skies, patches, cells) scaled so each sky integrates to
    ``scale`` (D_v) by its quadrature ``total``; a sky without positive luminance anywhere is uniform."""
    uniform = total <= 0.0  # no positive luminance anywhere: uniform sky (as PerezSky and gendaymtx)
    with np.errstate(divide="ignore", invalid="ignore"):
        norm = np.where(uniform, 0.0, scale / np.where(uniform, 1.0, total))
    n_sub = samples.shape[-1]
    acc = samples[..., 0] if n_sub == 1 else samples.sum(axis=-1)
    np.multiply(norm[:, None], acc, out=out)
    if n_sub > 1:
        out /= n_sub
    out[uniform] = (scale[uniform] / np.pi)[:, None]


def _perez_positive(coeffs) -> NDArray[np.bool_]:
    """Skies whose indicatrix ``1 + c exp(d gamma) + e cos^2 gamma`` is positive for every gamma in [0, pi]
    (a lower bound: ``1 + min(c, c exp(d pi)) + min(e, 0)``, with a margin far above rounding)."""
    c, d, e = coeffs[:, 2], coeffs[:, 3], coeffs[:, 4]
    return 1.0 + np.minimum(c, c * np.exp(d * np.pi)) + np.minimum(e, 0.0) > 1e-6


def _perez_totals(coeffs, sun, g_q, nodes_t, qweights, moments, scratch) -> NDArray[np.float64]:
    """The quadrature of skies whose indicatrix is positive everywhere (:func:`_perez_positive`) and whose
    gradation is positive on every row of the horizontal rule (``g_q``, skies x rows): ``sum_r G_r (sum_j w_rj +
    e s^T M_r s + c sum_j w_rj exp(d gamma_rj))``.

    It is :func:`_perez_chunk`'s ``sum_r G_r sum_j w_rj max(0, I_rj)`` with the max dropped (I > 0) and the sum
    taken term by term: with ``cos gamma = s . n`` (s the sun, n the node), ``sum_j w_rj cos^2 gamma_rj = s^T M_r
    s``, ``M_r = sum_j w_rj n n^T`` (``moments``: the rows' weight sums and M_r), so only ``exp(d gamma)`` is
    evaluated per node: equal to rounding (measured: patch luminance within 9e-16 relative over a year).
    ``nodes_t`` (3, rows x nodes per row); ``scratch``: a flat float64 array of at least skies x nodes.
    """
    n_sky = coeffs.shape[0]
    w_sum, w_nn = moments
    cos_q = np.matmul(sun, nodes_t, out=scratch[: n_sky * nodes_t.shape[1]].reshape(n_sky, -1))
    np.clip(cos_q, -1.0, 1.0, out=cos_q)
    np.arccos(cos_q, out=cos_q)
    cos_q *= coeffs[:, 3:4]
    np.exp(cos_q, out=cos_q)
    peak = np.einsum("hrj,rj->hr", cos_q.reshape(n_sky, *qweights.shape), qweights)
    peak *= coeffs[:, 2:3]
    quad = np.einsum("hi,rij,hj->hr", sun, w_nn, sun)
    quad *= coeffs[:, 4:5]
    quad += w_sum
    quad += peak
    return np.einsum("hr,hr->h", g_q, quad)


def _hour_directions(scheme: PatchScheme, samples: int):
    """The directions every hour's sky is evaluated at: the 48 x 96 normalisation nodes, then ``samples^2``
    equal-area cells per patch (the centres for 1). Returns (dirs (n, 3), dirs.T contiguous, node weights,
    cells per patch)."""
    from .photometry import plane_quadrature

    qd, qw = plane_quadrature(0.0, 0.0, nodes=NORMALISATION_NODES)
    sdirs = scheme.centre_directions if samples == 1 else scheme.sample_directions(samples)
    sdirs = np.asarray(sdirs, dtype=np.float64).reshape(-1, 3)
    dirs = np.concatenate([np.asarray(qd, dtype=np.float64).reshape(-1, 3), sdirs])
    n_sub = sdirs.shape[0] // scheme.n_patches
    return dirs, np.ascontiguousarray(dirs.T), np.asarray(qw, dtype=np.float64).reshape(-1), n_sub


def perez_patch_luminance(
    coefficients: NDArray[np.float64],
    model_sun: NDArray[np.float64],
    diffuse_illuminance: NDArray[np.float64],
    scheme: PatchScheme,
    *,
    samples: int = 3,
) -> NDArray[np.float64]:
    """Mean patch luminance [cd m^-2] of many Perez skies at once, shape (n_skies, n_patches).

    Parameters
    ----------
    coefficients : ndarray, shape (n, 5)
        Perez (a, b, c, d, e) per sky (:func:`skyscatter.sky.perez.perez_coefficients`).
    model_sun : ndarray, shape (n, 3)
        Unit vectors to the sun the model uses (after the altitude clamp).
    diffuse_illuminance : ndarray, shape (n,)
        D_v [lx] each sky integrates to; 0 gives a zero row.
    scheme : PatchScheme
    samples : int
        Cells per patch side (1: patch centres).
    """
    dirs, dirs_t, qw, n_sub = _hour_directions(scheme, samples)
    coeffs = np.asarray(coefficients, dtype=np.float64).reshape(-1, 5)
    sun = np.asarray(model_sun, dtype=np.float64).reshape(-1, 3)
    scale = np.asarray(diffuse_illuminance, dtype=np.float64).reshape(-1)
    # distinct zenith cosines of nodes and samples, for the per-sky gradation table
    row_cos, rows = np.unique(dirs[:, 2], return_inverse=True)
    q_rows = None
    nz, na = NORMALISATION_NODES
    if qw.size == nz * na and np.all(rows[: qw.size].reshape(nz, na) == rows[: qw.size : na, None]):
        q_rows, qw = rows[: qw.size : na], qw.reshape(nz, na)  # the horizontal rule: rows of equal zenith angle
        nodes = dirs[: qw.size].reshape(nz, na, 3)
        moments = (qw.sum(axis=1), np.einsum("rj,rji,rjk->rik", qw, nodes, nodes))
    else:
        moments = None
    out = np.zeros((coeffs.shape[0], scheme.n_patches))
    lit = np.flatnonzero(scale > 0.0)
    step = max(1, CHUNK_VALUES // dirs.shape[0])
    work = np.empty((step, dirs.shape[0]))
    if moments is None:
        slow = lit
    else:
        # skies with a positive gradation on every row and a positive indicatrix: the quadrature term by term
        # (_perez_totals) in blocks of nodes, then the samples alone in blocks of samples
        grad_q = gradation(row_cos[q_rows], coeffs[lit, 0:1], coeffs[lit, 1:2])
        quick = np.all(grad_q > 0.0, axis=1) & _perez_positive(coeffs[lit])
        slow = lit[~quick]
        fast, grad_q = lit[quick], grad_q[quick]
        n_q = qw.size
        nodes_t, samples_t = np.ascontiguousarray(dirs_t[:, :n_q]), np.ascontiguousarray(dirs_t[:, n_q:])
        total = np.empty(fast.size)
        q_step = max(1, CHUNK_VALUES // n_q)
        scratch = np.empty(q_step * n_q)
        for start in range(0, fast.size, q_step):
            sel = fast[start : start + q_step]
            total[start : start + sel.size] = _perez_totals(coeffs[sel], sun[sel], grad_q[start : start + q_step],
                                                            nodes_t, qw, moments, scratch)
        s_step = max(1, CHUNK_VALUES // samples_t.shape[1])
        s_rows = rows[n_q:]
        for start in range(0, fast.size, s_step):
            sel = fast[start : start + s_step]
            k = coeffs[sel]
            cos_g = sun[sel] @ samples_t
            np.clip(cos_g, -1.0, 1.0, out=cos_g)
            f = indicatrix(1.0, np.arccos(cos_g), cos_g, 1.0, k[:, 2:3], k[:, 3:4], k[:, 4:5])
            f *= np.take(gradation(row_cos, k[:, 0:1], k[:, 1:2]), s_rows, axis=1)
            np.maximum(f, 0.0, out=f)
            block = np.empty((sel.size, scheme.n_patches))
            _normalise(total[start : start + sel.size], scale[sel], f.reshape(sel.size, -1, n_sub), block)
            out[sel] = block
    for start in range(0, slow.size, step):
        sel = slow[start : start + step]
        block = np.empty((sel.size, scheme.n_patches))
        _perez_chunk(coeffs[sel], sun[sel], scale[sel], dirs_t, q_rows, rows, row_cos, qw, n_sub, block, work)
        out[sel] = block
    return out


def asrc_cie_patch_luminance(
    weights: NDArray[np.float64],
    sun_zenith: NDArray[np.float64],
    sun_directions: NDArray[np.float64],
    diffuse_illuminance: NDArray[np.float64],
    scheme: PatchScheme,
    *,
    samples: int = 3,
) -> NDArray[np.float64]:
    """Mean patch luminance [cd m^-2] of many ASRC-CIE skies at once, shape (n_skies, n_patches).

    Each sky is :func:`skyscatter.sky.asrc_cie.asrc_cie_relative_luminance` scaled so that the 48 x 96 Gauss rule
    gives its D_v (as :func:`perez_patch_luminance`). Skies are taken in groups of the same pair of component
    skies (epsilon <= 1.2, <= 3, above), so each step evaluates two components, not four.

    Parameters
    ----------
    weights : ndarray, shape (n, 4)
        :func:`skyscatter.sky.asrc_cie.asrc_cie_weights` per sky.
    sun_zenith : ndarray, shape (n,)
        Solar zenith angle [rad], at most pi/2.
    sun_directions : ndarray, shape (n, 3)
        Unit vectors to the sun.
    diffuse_illuminance : ndarray, shape (n,)
        D_v [lx]; 0 gives a zero row.
    scheme : PatchScheme
    samples : int
        Cells per patch side (1: patch centres).
    """
    from .sky.asrc_cie import asrc_cie_relative_luminance

    dirs, dirs_t, qw, n_sub = _hour_directions(scheme, samples)
    n_q = qw.size
    w = np.asarray(weights, dtype=np.float64).reshape(-1, 4)
    zen = np.asarray(sun_zenith, dtype=np.float64).reshape(-1)
    sun = np.asarray(sun_directions, dtype=np.float64).reshape(-1, 3)
    scale = np.asarray(diffuse_illuminance, dtype=np.float64).reshape(-1)
    out = np.zeros((w.shape[0], scheme.n_patches))
    # pair of the sky: 0 intermediate/overcast, 1 turbid/intermediate, 2 clear/turbid (weights of the others 0)
    pair = np.where(w[:, 3] > 0, 0, np.where(w[:, 2] > 0, 1, 2))
    step = max(1, CHUNK_VALUES // dirs.shape[0])  # temporaries that stay in the CPU caches (as the Perez kernel)
    for g in range(3):
        hours = np.flatnonzero((scale > 0.0) & (pair == g))
        for start in range(0, hours.size, step):
            sel = hours[start : start + step]
            cos_g = sun[sel] @ dirs_t
            np.clip(cos_g, -1.0, 1.0, out=cos_g)
            rel = asrc_cie_relative_luminance(dirs[:, 2], np.arccos(cos_g), zen[sel, None], w[sel, None, :],
                                              cos_gamma=cos_g)
            norm = scale[sel] / (rel[:, :n_q] @ qw)
            out[sel] = norm[:, None] * rel[:, n_q:].reshape(sel.size, -1, n_sub).mean(axis=-1)
    return out


#: gendaymtx's default sky colour (its ``-c``, [RadianceSource2025] gendaymtx.c), Radiance RGB whose luminance
#: weights give 1.000.
GENDAYMTX_SKY_COLOUR = (0.960, 1.004, 1.118)


@dataclass(eq=False)
class SkyMatrix:
    """Hourly sky luminance over a patch scheme.

    Attributes
    ----------
    luminance : ndarray, shape (n_hours, n_patches)
        Mean patch luminance [cd m^-2] (sky; plus the sun's share if ``include_sun``).
    unix_time : ndarray, shape (n_hours,)
        Middle of each hour (record) as Unix time [s since 1970-01-01T00:00 UTC]; :attr:`times` gives them as a
        pandas ``DatetimeIndex`` in the file's standard time, :meth:`iso_times` as ISO 8601 text.
    utc_offset_hours : float
        The file's standard time minus UTC [h].
    sun_zenith, sun_azimuth : ndarray, shape (n_hours,)
        SPA sun position at mid-hour [rad] (azimuth from north towards east).
    epsilon, delta : ndarray
        Perez sky clearness and brightness used (NaN for hours without diffuse light).
    diffuse_illuminance, sun_illuminance_normal : ndarray
        D_v and the sun's direct normal illuminance [lx] (0 without light).
    scheme : PatchScheme
    location : EPWLocation
    include_sun : bool
    samples : int
    model : str
        The sky model of every hour (one of :data:`MODELS`).
    sun_patches, sun_patch_luminance : ndarray, shape (n_hours, 4), optional
        With ``include_sun``: the patches each hour's sun was spread over (-1: none) and the luminance [cd m^-2]
        it added to each (included in ``luminance``); the Radiance output colours the sun apart from the sky.
    """

    luminance: NDArray[np.float64]
    unix_time: NDArray[np.float64]
    utc_offset_hours: float
    sun_zenith: NDArray[np.float64]
    sun_azimuth: NDArray[np.float64]
    epsilon: NDArray[np.float64]
    delta: NDArray[np.float64]
    diffuse_illuminance: NDArray[np.float64]
    sun_illuminance_normal: NDArray[np.float64]
    scheme: PatchScheme
    location: EPWLocation
    include_sun: bool
    samples: int
    model: str = "perez"
    sun_patches: NDArray[np.int64] | None = None
    sun_patch_luminance: NDArray[np.float64] | None = None

    @property
    def times(self):
        """Middle of each hour (record): tz-aware ``pandas.DatetimeIndex`` in the file's standard time."""
        import pandas as pd

        ns = np.round(self.unix_time * 1e3).astype(np.int64) * 1_000_000  # whole milliseconds, exactly
        tz = dt.timezone(dt.timedelta(hours=self.utc_offset_hours))
        return pd.DatetimeIndex(ns.astype("datetime64[ns]")).tz_localize("UTC").tz_convert(tz)

    def iso_times(self) -> NDArray[np.str_]:
        """Middle of each hour (record) as ISO 8601 text in the file's standard time, e.g.
        ``2023-06-20T00:30:00+01:00`` (to the second: EPW records give whole seconds)."""
        return self.iso_times_of(self.unix_time, self.utc_offset_hours)

    @staticmethod
    def iso_times_of(unix_time: NDArray[np.float64], utc_offset_hours: float) -> NDArray[np.str_]:
        """Unix times [s] as ISO 8601 text at a fixed UTC offset [h] (see :meth:`iso_times`)."""
        offset_s = round(utc_offset_hours * 3600.0)
        local = np.round(unix_time + offset_s).astype(np.int64).astype("datetime64[s]")
        sign = "-" if offset_s < 0 else "+"
        minutes = abs(offset_s) // 60
        return np.char.add(np.datetime_as_string(local, unit="s"), f"{sign}{minutes // 60:02d}:{minutes % 60:02d}")

    @property
    def shape(self) -> tuple[int, int]:
        """(n_hours, n_patches)."""
        return self.luminance.shape  # type: ignore[return-value]

    def horizontal_illuminance(self) -> NDArray[np.float64]:
        """Horizontal illuminance [lx] per hour from the patches: ``sum(L_p Omega_p sin(alt_p))`` (a check)."""
        g = self.scheme
        return self.luminance @ (g.solid_angles * np.sin(g.centre_altitude))

    def save(self, npz_path: str | os.PathLike[str], csv_path: str | os.PathLike[str] | None = None, *,
             format: str = "npz", ground_reflectance: float = 0.2) -> list[Path]:
        """Write the matrix and, if given, the CSV together: both files appear, or neither does.

        ``format`` "npz" (:meth:`save_npz`, the path must end in ``.npz``) or "radiance" (:meth:`save_radiance`
        with ``ground_reflectance``; any name but ``.npz``)."""
        targets = [Path(npz_path)] + ([Path(csv_path)] if csv_path is not None else [])
        if format not in ("npz", "radiance"):
            raise InvalidParameterError(f"format must be 'npz' or 'radiance'; got {format!r}")
        if (targets[0].suffix.lower() == ".npz") != (format == "npz"):
            raise InvalidParameterError(f"{targets[0]}: an npz matrix file must end in .npz, a Radiance one must "
                                        "not (e.g. .mtx or .smx)")
        values = self.radiance_values(ground_reflectance) if format == "radiance" else None
        with atomic_paths(*targets) as temps:
            if values is None:
                self._write_npz(temps[0])
            else:
                write_radiance_matrix(temps[0], values, header=self._radiance_header(ground_reflectance),
                                      atomic=False)
            if csv_path is not None:
                self._write_csv(temps[1])
        return targets

    def radiance_values(self, ground_reflectance: float = 0.2, *,
                        sky_colour: tuple[float, float, float] = GENDAYMTX_SKY_COLOUR,
                        sun_colour: tuple[float, float, float] = (1.0, 1.0, 1.0)) -> NDArray[np.float64]:
        """The matrix as Radiance's ``gendaymtx`` lays it out: (1 + n_patches, n_hours, 3) RGB radiance
        [W sr^-1 m^-2], 179 lm/W.

        Row 0 is the ground, ``ground_reflectance (D_v + E_sun,n max(0, sin(altitude))) / (pi 179)``, grey; then
        the sky patches in this matrix's order (Radiance's own), each ``L_sky / 179`` times ``sky_colour``
        (default gendaymtx's 0.960 1.004 1.118, whose Radiance luminance is 1.000) plus the sun's share
        ``L_sun / 179`` times ``sun_colour`` ([RadianceSource2025] gendaymtx.c ``ComputeSky``, ``AddDirect``).
        Radiance's luminance ``179 (0.265 R + 0.670 G + 0.065 B)`` gives the patch luminance back.
        """
        try:
            rho = float(ground_reflectance)
        except (TypeError, ValueError):
            raise InvalidParameterError(f"ground_reflectance must be a number in [0, 1]; got "
                                        f"{ground_reflectance!r}") from None
        if not 0.0 <= rho <= 1.0:
            raise InvalidParameterError(f"ground_reflectance must be in [0, 1]; got {ground_reflectance!r}")
        sky = self.luminance.copy()
        sun = np.zeros_like(sky)
        if self.sun_patches is not None and self.sun_patch_luminance is not None:
            hours, k = np.nonzero(self.sun_patches >= 0)
            patches = self.sun_patches[hours, k]
            np.add.at(sun, (hours, patches), self.sun_patch_luminance[hours, k])
            sky -= sun
            np.maximum(sky, 0.0, out=sky)  # rounding of the subtraction
        out = np.empty((self.scheme.n_patches + 1, sky.shape[0], 3))
        out[1:] = (sky.T[..., None] * np.asarray(sky_colour, dtype=float)
                   + sun.T[..., None] * np.asarray(sun_colour, dtype=float)) / RADIANCE_EFFICACY
        sin_alt = np.maximum(np.cos(self.sun_zenith), 0.0)
        ground = rho * (self.diffuse_illuminance + self.sun_illuminance_normal * sin_alt) / (np.pi
                                                                                              * RADIANCE_EFFICACY)
        out[0] = ground[:, None]
        return out

    def save_radiance(self, path: str | os.PathLike[str], *, ground_reflectance: float = 0.2,
                      encoding: str = "float") -> Path:
        """Write the matrix as a Radiance matrix file that ``rmtxop`` and ``dctimestep`` read
        (:func:`skyscatter.radiance.write_radiance_matrix`; layout and colours: :meth:`radiance_values`),
        atomically; returns the path. ``encoding`` "float" (default), "double" or "ascii"."""
        return write_radiance_matrix(path, self.radiance_values(ground_reflectance),
                                     header=self._radiance_header(ground_reflectance), encoding=encoding)

    def _radiance_header(self, ground_reflectance: float) -> list[str]:
        loc = self.location
        return [f"skyscatter {__version__} sky matrix: {self.model} sky, {self.scheme.name} ({self.scheme.n_patches} "
                f"patches + ground), {self.shape[0]} time steps from {self.iso_times()[0] if self.shape[0] else '-'}"
                f", sun {'included' if self.include_sun else 'excluded'}, ground reflectance {ground_reflectance:g}",
                f"LATLONG= {loc.latitude_deg:.8f} {loc.longitude_deg:.8f}"]

    def save_npz(self, path: str | os.PathLike[str]) -> Path:
        """Write an ``.npz`` (uncompressed, atomically: fast to write and read; 20 MB for a Reinhart MF 2 year);
        returns the path. Keys are listed in ``docs/standard_skies.md``."""
        target = Path(path)
        with atomic_path(target) as tmp:
            self._write_npz(tmp)
        return target

    def _write_npz(self, tmp: Path) -> None:
        g = self.scheme
        with open(tmp, "wb") as fh:
            np.savez(
                fh,
                luminance=self.luminance.astype(np.float32),
                times=self.iso_times(),
                sun_zenith=self.sun_zenith,
                sun_azimuth=self.sun_azimuth,
                epsilon=self.epsilon,
                delta=self.delta,
                diffuse_illuminance=self.diffuse_illuminance,
                sun_illuminance_normal=self.sun_illuminance_normal,
                patch_zenith=g.centre_zenith,
                patch_azimuth=g.azimuth_centre,
                patch_solid_angle=g.solid_angles,
                scheme=np.array(g.name),
                include_sun=np.array(self.include_sun),
                samples=np.array(self.samples),
                model=np.array(self.model),
                latitude=np.array(self.location.latitude),
                longitude=np.array(self.location.longitude),
                units=np.array("luminance cd m^-2; angles rad; illuminance lx"),
            )

    def save_csv(self, path: str | os.PathLike[str]) -> Path:
        """Write a CSV (atomically): a ``time`` column (ISO 8601, mid-record) and one column per patch [cd m^-2]."""
        target = Path(path)
        with atomic_path(target) as tmp:
            self._write_csv(tmp)
        return target

    def _write_csv(self, tmp: Path) -> None:
        header = "time," + ",".join(f"patch_{i}" for i in range(self.scheme.n_patches))
        stamps = self.iso_times().tolist()
        zero_row = ",".join(["0"] * self.scheme.n_patches)
        with open(tmp, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(header + "\n")
            for stamp, row in zip(stamps, self.luminance, strict=True):
                if not row.any():
                    fh.write(f"{stamp},{zero_row}\n")
                else:
                    fh.write(stamp + "," + ",".join(f"{v:.6g}" for v in row.tolist()) + "\n")


#: Number of patches the sun is spread over (Radiance gendaymtx's NSUNPATCH).
SUN_PATCHES = 4


def add_sun_to_patches(
    luminance: NDArray[np.float64],
    rows: NDArray[np.int64],
    sun_directions: NDArray[np.float64],
    sun_illuminance: NDArray[np.float64],
    scheme: PatchScheme,
    *,
    n_patches: int = SUN_PATCHES,
    chunk: int = 2048,
) -> None:
    """Add the direct sun to the ``n_patches`` sky patches nearest to it, as Radiance's gendaymtx does.

    The rule of gendaymtx (``AddDirect`` in Radiance's ``src/gen/gendaymtx.c``, G. Ward, NREL/Radiance on
    GitHub): take the ``NSUNPATCH = 4`` patches whose centre directions ``p`` have the largest ``p . s`` with the
    sun direction ``s``; weight each by ``w = 1 / (1.002 - p . s)`` (so a sun on a patch centre puts most of its
    light there); add ``E_sun w / (sum(w) Omega_p)`` to the patch luminance. The sun's normal illuminance is
    conserved: ``sum_p dL_p Omega_p = E_sun``. (gendaymtx's weights use the centres of its own patch list; ours
    are the same Tregenza/Reinhart centres without its ground patch.)

    Parameters
    ----------
    luminance : ndarray, shape (n_hours, n_patches)
        Patch luminance [cd m^-2], updated in place.
    rows : ndarray of int
        Rows of ``luminance`` that get a sun.
    sun_directions : ndarray, shape (len(rows), 3)
        Unit vectors to the sun (ENU).
    sun_illuminance : ndarray, shape (len(rows),)
        Direct normal illuminance of the sun [lx].
    scheme : PatchScheme
    n_patches : int
        Patches per sun (gendaymtx: 4).

    Returns
    -------
    patches : ndarray of int, shape (len(rows), n_patches)
        The patches each sun was spread over.
    added : ndarray, shape (len(rows), n_patches)
        The luminance [cd m^-2] added to each.
    """
    centres = scheme.centre_directions.reshape(-1, 3)
    k = int(min(n_patches, centres.shape[0]))
    patches = np.empty((rows.size, k), dtype=np.int64)
    added = np.empty((rows.size, k))
    for start in range(0, rows.size, chunk):
        sl = slice(start, start + chunk)
        dots = sun_directions[sl] @ centres.T
        near = np.argpartition(-dots, k - 1, axis=1)[:, :k]
        d = np.take_along_axis(dots, near, axis=1)
        w = 1.0 / (1.002 - d)
        w /= w.sum(axis=1, keepdims=True)
        add = sun_illuminance[sl, None] * w / scheme.solid_angles[near]
        luminance[rows[sl, None], near] += add
        patches[sl], added[sl] = near, add
    return patches, added


def _check_scheme(scheme: str | PatchScheme) -> PatchScheme:
    return scheme if isinstance(scheme, PatchScheme) else patch_scheme(scheme)


#: Depression of the sun [rad] beyond which a record may carry no direct light (refraction 0.57 deg and the disc's
#: radius 0.27 deg, rounded up) and no diffuse light (the end of civil twilight, where the sky gives ~3 lx).
NIGHT_DIRECT_DEPRESSION = np.radians(1.0)
NIGHT_DIFFUSE_DEPRESSION = np.radians(6.0)


def _light_at_night(epw: EPWData, unix_time: NDArray[np.float64], zenith: NDArray[np.float64]) -> NDArray[np.int64]:
    """Records with light while the sun stays below the horizon for their whole interval (the highest of the
    sun at the start, middle and end of the interval: within a fraction of a degree of the interval's maximum)."""
    from .sun.position import sun_position_unix

    dni, dhi = epw.direct_normal_irradiance, epw.diffuse_horizontal_irradiance
    cand = np.flatnonzero(((dni > 0) | (dhi > 0)) & (zenith > np.pi / 2))
    if cand.size == 0:
        return cand
    loc = epw.location
    half = 1800.0 / epw.records_per_hour
    highest = np.pi / 2 - zenith[cand]
    for shift in (-half, half):
        pos = sun_position_unix(loc.latitude, loc.longitude, unix_time[cand] + shift, altitude=loc.elevation)
        highest = np.maximum(highest, np.pi / 2 - np.asarray(pos.zenith, dtype=float))
    bad = ((dni[cand] > 0) & (highest < -NIGHT_DIRECT_DEPRESSION)) | (
        (dhi[cand] > 0) & (highest < -NIGHT_DIFFUSE_DEPRESSION))
    return cand[bad]


def _report_light_at_night(epw: EPWData, night: NDArray[np.int64], mode: str, unix_time, zenith) -> None:
    i = int(night[0])
    stamp = SkyMatrix.iso_times_of(unix_time[i: i + 1], epw.location.timezone_hours)[0]
    first = (f"line {int(epw.line_numbers[i])} ({stamp}: sun {90.0 - np.degrees(zenith[i]):.1f} deg at mid-record, "
             f"direct normal {epw.direct_normal_irradiance[i]:g}, diffuse horizontal "
             f"{epw.diffuse_horizontal_irradiance[i]:g} W m^-2)")
    why = ("the sun stays below the horizon for the whole record (a time shift, the wrong time zone or place in the "
           "LOCATION line?)")
    if mode == "error":
        raise FileFormatError(f"{epw.path}: {first}: light although {why}")

    from .epw import EPWWarning

    warnings.warn(f"{epw.path}: {night.size} record(s) have light although {why}; they are left dark (first: "
                  f"{first}; night_irradiance='error' / --night-irradiance error refuses such files)", EPWWarning,
                  stacklevel=3)


def _check_irradiance(epw: EPWData) -> None:
    for name, arr in (
        ("direct normal radiation", epw.direct_normal_irradiance),
        ("diffuse horizontal radiation", epw.diffuse_horizontal_irradiance),
    ):
        bad = ~np.isfinite(arr)
        if np.any(bad):
            i = int(np.argmax(bad))
            raise FileFormatError(
                f"{epw.path}: line {int(epw.line_numbers[i])}: {name} is missing (9999); a sky matrix needs "
                "the direct normal and diffuse horizontal radiation of every hour"
            )


def skymatrix(
    epw_path: str | os.PathLike[str] | EPWData,
    *,
    scheme: str | PatchScheme = "reinhart2",
    include_sun: bool = False,
    samples: int = 3,
    chunk_hours: int = 512,
    progress: bool = False,
    timestep: str = "records",
    model: str = "perez",
    night_irradiance: str = "dark",
) -> SkyMatrix:
    """Hourly Perez sky luminance over sky patches for a year of weather (the job of Radiance's gendaymtx).

    Parameters
    ----------
    epw_path : path or EPWData
        An hourly EnergyPlus weather file (or one already read with :func:`skyscatter.epw.read_epw`).
    model : {"perez", "asrc-cie"}
        The sky of every hour: the Perez et al. 1993 all-weather sky (default, as gendaymtx) or the ASRC-CIE sky
        (:class:`skyscatter.sky.asrc_cie.ASRCCIESky`), both from the hour's Perez 1990 sky condition and
        luminous efficacies.
    scheme : str or PatchScheme
        "tregenza" (= "reinhart1", 145 patches), "reinhart2" (577, default) or "reinhart4" (2305).
    include_sun : bool
        Add the direct sun, spread over the 4 nearest patches as gendaymtx does (:func:`add_sun_to_patches`)
        (default False: sky only).
    samples : int
        Equal-area cells per patch side for the patch mean (default 3; 1 samples the patch centre only).
    chunk_hours : int
        Hours computed per vectorised step (memory vs. progress granularity).
    progress : bool
        Show a tqdm progress bar over the hours (advances per chunk).
    timestep : {"records", "hourly"}
        For a sub-hourly file (N records per hour declared in its DATA PERIODS line): "records" (default) gives
        one row per record, the sun at the middle of the record's own interval (as gendaymtx gives one row per
        time step of its input); "hourly" averages the records of each hour first (:meth:`EPWData.hourly`)
        and gives one row per hour. Hourly files give one row per hour either way.
    night_irradiance : {"dark", "error"}
        Records with light although the sun stays below the horizon for their whole interval (direct normal
        irradiance with the sun more than 1 deg below it: refraction and the disc's radius; diffuse with the sun
        more than 6 deg below it: civil twilight), which a time shift or a wrong place in the file produces:
        "dark" (default) leaves them dark with one :class:`~skyscatter.epw.EPWWarning` counting them and naming
        the first; "error" refuses the file at the first one (:class:`~skyscatter.errors.FileFormatError`).

    Returns
    -------
    SkyMatrix

    Raises
    ------
    FileFormatError
        Malformed EPW file (:func:`~skyscatter.epw.read_epw`), missing direct/diffuse radiation in a record, or
        (``night_irradiance="error"``) light at night (the message names the line).
    InvalidParameterError
        Unknown scheme or bad options.
    """
    from .sky.asrc_cie import asrc_cie_weights
    from .sky.perez import MIN_SUN_ZENITH, perez_parameters
    from .sun.position import sun_position_unix

    geom = _check_scheme(scheme)
    whole_number("samples", samples, 1, 16, integral_floats=True)
    whole_number("chunk_hours", chunk_hours, 1, integral_floats=True)
    if timestep not in ("records", "hourly"):
        raise InvalidParameterError(f"timestep must be 'records' or 'hourly'; got {timestep!r}")
    if model not in MODELS:
        raise InvalidParameterError(f"model must be one of {', '.join(MODELS)}; got {model!r}")
    if night_irradiance not in ("dark", "error"):
        raise InvalidParameterError(f"night_irradiance must be 'dark' or 'error'; got {night_irradiance!r}")
    epw = epw_path if isinstance(epw_path, EPWData) else read_epw(epw_path)
    if timestep == "hourly":
        epw = epw.hourly()
    _check_irradiance(epw)
    loc = epw.location
    unix_time = epw.unix_times()  # middle of each record's interval
    pos = sun_position_unix(loc.latitude, loc.longitude, unix_time, altitude=loc.elevation)
    zen = np.asarray(pos.zenith, dtype=float)
    azi = np.asarray(pos.azimuth, dtype=float)
    n = len(epw)
    dni = epw.direct_normal_irradiance
    dhi = epw.diffuse_horizontal_irradiance
    night = _light_at_night(epw, unix_time, zen)
    if night.size:
        _report_light_at_night(epw, night, night_irradiance, unix_time, zen)
        dni, dhi = dni.copy(), dhi.copy()
        dni[night] = 0.0
        dhi[night] = 0.0
    dew = np.where(np.isfinite(epw.dew_point), epw.dew_point, 11.0)
    doy = epw.day_of_year
    lit = dhi > 0.0
    lum = np.zeros((n, geom.n_patches))
    eps = np.full(n, np.nan)
    dlt = np.full(n, np.nan)
    d_v = np.zeros(n)
    e_sun = np.zeros(n)
    idx = np.flatnonzero(lit)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=n, unit="h", desc=f"sky matrix ({geom.name})")
        bar.update(n - idx.size)  # dark hours need no work
    try:
        for start in range(0, idx.size, int(chunk_hours)):
            sel = idx[start : start + int(chunk_hours)]
            p = perez_parameters(
                zen[sel],
                direct_normal_irradiance=dni[sel],
                diffuse_horizontal_irradiance=dhi[sel],
                day_of_year=doy[sel],
                dew_point=dew[sel],
            )
            if model == "perez":
                model_sun = direction_from_angles(p.sun_zenith, azi[sel])
                lum[sel] = perez_patch_luminance(p.coefficients, model_sun, p.diffuse_illuminance, geom,
                                                 samples=samples)
            else:  # the CIE-type skies need no altitude clamp: the true sun, on the horizon at twilight
                z = np.minimum(zen[sel], np.pi / 2)
                lum[sel] = asrc_cie_patch_luminance(asrc_cie_weights(p.epsilon, p.delta), z,
                                                    direction_from_angles(z, azi[sel]), p.diffuse_illuminance,
                                                    geom, samples=samples)
            eps[sel], dlt[sel] = p.epsilon, p.delta
            d_v[sel], e_sun[sel] = p.diffuse_illuminance, p.sun_illuminance_normal
            if bar is not None:
                bar.update(sel.size)
    finally:
        if bar is not None:
            bar.close()
    # direct sun without diffuse light cannot be modelled (epsilon undefined); such records are left dark
    sun_patches = sun_added = None
    if include_sun:
        sunny = np.flatnonzero(e_sun > 0.0)
        sun_patches = np.full((n, SUN_PATCHES), -1, dtype=np.int64)
        sun_added = np.zeros((n, SUN_PATCHES))
        if sunny.size:
            # The sun the sky model uses: altitude at most 87 deg (gendaymtx limits it the same way before adding
            # the sun), a sun below the horizon at mid-record put on the horizon at its azimuth.
            model_zenith = np.clip(zen[sunny], MIN_SUN_ZENITH, np.pi / 2)
            near, added = add_sun_to_patches(lum, sunny, direction_from_angles(model_zenith, azi[sunny]),
                                             e_sun[sunny], geom)
            sun_patches[sunny, : near.shape[1]], sun_added[sunny, : near.shape[1]] = near, added
    return SkyMatrix(
        luminance=lum,
        unix_time=unix_time,
        utc_offset_hours=float(loc.timezone_hours),
        sun_zenith=zen,
        sun_azimuth=azi,
        epsilon=eps,
        delta=dlt,
        diffuse_illuminance=d_v,
        sun_illuminance_normal=e_sun,
        scheme=geom,
        location=loc,
        include_sun=bool(include_sun),
        samples=int(samples),
        model=model,
        sun_patches=sun_patches,
        sun_patch_luminance=sun_added,
    )
