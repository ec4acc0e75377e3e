"""Spectral sky matrices from weather records: per hour, patch and wavelength band, the sky of the retrieved air.

:func:`spectral_sky_matrix` takes a weather record, retrieves the atmosphere of every hour
(:func:`skyscatter.fit.weather.retrieve_hourly_atmosphere`) and computes, through the retrieval's family of
precomputed tables, the mean spectral radiance of every sky patch (Tregenza or Reinhart MF 1-4,
:mod:`skyscatter.patches`) in every wavelength band, and the sun's direct normal spectral irradiance separately.
The result is an :class:`xarray.Dataset` (dimensions ``time``, ``patch``, ``wavelength``; units and provenance
in the attributes) that :func:`save_dataset` writes to NetCDF or Zarr and :func:`write_radiance_matrix` to
Radiance's matrix format for ``rmtxop`` / ``dctimestep``; :func:`plane_irradiance` gives the spectral irradiance
on any tilted plane from it. :func:`spectral_sky_matrix_sites` runs many records as Dask tasks into one Zarr
store with a ``site`` dimension, resumably.

**Bands.** ``bands=20`` (default): 20 bands of 20 nm over 380-780 nm (centres 390-770 nm), like Radiance's
gensdaymtx; ``bands=41``: 41 bands of 10 nm centred on 380, 390, ..., 780 nm; or a list of band centres [nm]
(edges half-way between them). A band value is the band mean of the spectral radiance
``E0(lambda) r(lambda)``: the reduced radiance ``r = L / E0`` of the tables interpolated linearly in wavelength
between the table wavelengths (:data:`~skyscatter.precomputed.family.FAMILY_WAVELENGTHS`) times the 1 nm ASTM
G173 sun, so the sun's Fraunhofer structure is carried into every band. Water vapour and O2 absorption (not in
the medium) multiply sun and sky per band with the sun's gas path (Bird & Riordan 1986, as in
:mod:`skyscatter.fit.weather`); the variable ``sky_radiance_no_gas`` is not stored (set ``gases=False``).
Radiances are scaled by the day's Sun-Earth distance (Spencer 1971).

**Patches.** Each patch's radiance is the mean over ``samples x samples`` equal-area cells
(:meth:`~skyscatter.patches.PatchScheme.sample_directions`); the observer sits on the tables' ground. A clear
sky's patches are then scaled, per table wavelength, so that their horizontal irradiance ``sum_p L_p cos(theta_p)
Omega_p`` equals the tables' radiance integrated over the hemisphere
(:meth:`~skyscatter.precomputed.evaluation.TableLookups.horizontal_sky_irradiance`), the one description of the
diffuse horizontal irradiance that the retrieval closes DHI on; the factor before scaling is reported
(``sky_quadrature``). The hemisphere integral, not the tables' irradiance texture (Bruneton & Neyret 2008, Eq. 14),
because it is the closer to DISORT: coarse tables, AOD 0.2-0.5, sun zenith 10-60 deg, 450 and 550 nm, closer in 62
of 64 cases, mean |difference| 1.30 % against 3.47 % (docs/sky_matrices.md).

**Hours.** Every record of the file is a time step (``time`` the middle of the hour, UTC). Night hours are 0;
clear hours come from the family's tables; cloudy (overcast) hours from the cloud table of the retrieval
(:class:`~skyscatter.fit.weather.CloudTable`: the radiance of the fast cloudy sky at the hour's cloud optical
depth and sun, :func:`_cloud_patches`); broken hours are the blend ``(1 - f) clear + f overcast`` of
:func:`~skyscatter.fit.weather.fit_broken_sky` (an approximation); broken hours brighter than any blend get its stated
enhanced-diffuse rule (the closest blend's sun, its overcast sky term scaled to the record's DHI); low-sun hours the
stated fallback of the retrieval. Hours without a retrieved sky (cloudy not retrieved, invalid records; ``status``,
see :data:`~skyscatter.fit.weather.HOUR_STATUS`) are NaN, so that nothing downstream mistakes them for a sky; the
``status`` and ``reason`` variables say why. ``dhi_matrix`` is the broadband diffuse horizontal irradiance of the
matrix itself (patch radiances at the table wavelengths integrated over the patches' solid angles and carried to
broadband as in the retrieval): ``dhi_matrix / dhi - 1`` is the closure of the matrix, the retrieval's wherever it
converged.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..conventions import direction_from_angles
from ..errors import InvalidParameterError, OutputError
from ..fileio import atomic_path, check_output_path
from ..patches import PatchScheme, patch_scheme
from ..radiance import write_radiance_matrix as _write_matrix
from ..validation import whole_number
from .weather import (
    BROKEN,
    CLEAR,
    CLEAR_OPEN,
    CLOUDY,
    ENHANCED,
    HOUR_STATUS,
    LOW_SUN,
    BroadbandClearSky,
    HourlyAtmosphere,
    RetrievalOptions,
    retrieve_hourly_atmosphere,
)

__all__ = [
    "band_edges",
    "ground_radiance",
    "plane_irradiance",
    "radiance_rgb",
    "save_dataset",
    "spectral_sky_matrix",
    "spectral_sky_matrix_sites",
    "write_radiance_matrix",
]

#: Hours per compiled call of the clear sky's patch pass (bounds the radiances held at once).
HOUR_CHUNK = 64

#: Radiance's spectral partition header of a 380-780 nm matrix (gensdaymtx's ``WAVELENGTH_SPLITS``).
RADIANCE_WAVELENGTH_SPLITS = (780, 588, 480, 380)


def _references() -> str:
    from ..references import cite

    return cite("Bruneton2008", "BirdRiordan1986")


def band_edges(bands: int | Sequence[float] = 20) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(centres, edges)`` [nm] of the output bands: ``20`` (20 nm bands over 380-780 nm), ``41`` (10 nm bands
    centred on 380-780 nm) or increasing band centres (edges half-way between, the outer ones mirrored)."""
    if isinstance(bands, (int, np.integer)) and not isinstance(bands, bool):
        if bands == 20:
            edges = np.arange(380.0, 781.0, 20.0)
        elif bands == 41:
            edges = np.arange(375.0, 786.0, 10.0)
        else:
            raise InvalidParameterError(f"bands must be 20, 41 or a list of band centres [nm]; got {bands}")
        return 0.5 * (edges[1:] + edges[:-1]), edges
    c = np.asarray(bands, dtype=float)
    if c.ndim != 1 or c.size < 2 or not np.all(np.isfinite(c)) or np.any(np.diff(c) <= 0):
        raise InvalidParameterError("band centres must be at least two increasing wavelengths [nm]")
    mid = 0.5 * (c[1:] + c[:-1])
    edges = np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])
    return c, edges


def _band_matrix(edges: NDArray[np.float64], table_wl: NDArray[np.float64], e0_table: NDArray[np.float64],
                 model: BroadbandClearSky) -> tuple[NDArray[np.float64], NDArray[np.float64], list[NDArray]]:
    """``(M, band_e0, masks)``: band mean of ``E0 r`` = ``L_table @ M.T`` (r linear between table wavelengths);
    the band-mean E0; the fine-grid wavelengths of each band."""
    wl, e0 = model.wavelengths, model.e0
    if edges[0] < table_wl[0] - 1e-9 or edges[-1] > table_wl[-1] + 1e-9:
        raise InvalidParameterError(f"bands {edges[0]:g}-{edges[-1]:g} nm reach beyond the tables' wavelengths "
                                    f"{table_wl[0]:g}-{table_wl[-1]:g} nm")
    n_b = edges.size - 1
    m = np.zeros((n_b, table_wl.size))
    band_e0 = np.zeros(n_b)
    masks = []
    for b in range(n_b):
        x = np.unique(np.concatenate([[edges[b], edges[b + 1]], wl[(wl > edges[b]) & (wl < edges[b + 1])]]))
        ex = np.interp(x, wl, e0)
        w = np.zeros_like(x)
        w[:-1] += np.diff(x) / 2
        w[1:] += np.diff(x) / 2
        w /= w.sum()
        j = np.clip(np.searchsorted(table_wl, x, side="right") - 1, 0, table_wl.size - 2)
        t = (x - table_wl[j]) / (table_wl[j + 1] - table_wl[j])
        np.add.at(m[b], j, w * ex * (1 - t) / e0_table[j])
        np.add.at(m[b], j + 1, w * ex * t / e0_table[j + 1])
        band_e0[b] = float(np.sum(w * ex))
        masks.append((wl >= edges[b]) & (wl <= edges[b + 1]))
    return m, band_e0, masks


def _band_means(values: NDArray[np.float64], weights_e0: NDArray[np.float64], masks) -> NDArray[np.float64]:
    """Band means of ``values`` (n, n_fine) with the weights ``weights_e0`` (n_fine,) over each band's fine
    wavelengths (quadrature weights for a mean over wavelength; times E0 for an E0-weighted mean)."""
    out = np.empty((values.shape[0], len(masks)))
    for b, sel in enumerate(masks):
        w = weights_e0[sel]
        out[:, b] = values[:, sel] @ w / w.sum()
    return out


def spectral_sky_matrix(record: Any, *, scheme: str | PatchScheme = "reinhart2", bands: int | Sequence[float] = 20,
                        samples: int = 2, options: RetrievalOptions | None = None, family=None,
                        atmosphere: HourlyAtmosphere | None = None, gases: bool = True,
                        progress: bool = False):
    """Spectral sky matrix of a weather record as an :class:`xarray.Dataset` (module docstring).

    Parameters
    ----------
    record : path or EPWData
        EPW, TMY3 or CSV weather record (:func:`skyscatter.fit.weather.read_weather`).
    scheme : str or PatchScheme
        ``"tregenza"`` / ``"reinhart1"`` (145 patches), ``"reinhart2"`` (577, default), ``"reinhart4"`` (2305); also
        ``"reinhart3"``-style names are refused.
    bands : 20, 41 or sequence of float
        Output bands (:func:`band_edges`).
    samples : int
        Equal-area cells per patch side (1-4, default 2).
    options : RetrievalOptions, optional
        Retrieval settings (default :class:`~skyscatter.fit.weather.RetrievalOptions`).
    family : TableFamily, optional
        Tables (default: the retrieval's default family, built and cached on first use: about 18 table builds).
    atmosphere : HourlyAtmosphere, optional
        A retrieval already done (then ``record``, ``options`` and ``family`` come from it).
    gases : bool
        Apply water vapour and O2 band absorption to sky and sun (default True).
    progress : bool
        tqdm bar over the hours.

    Returns
    -------
    xarray.Dataset
        ``sky_radiance`` (time, patch, wavelength) [W m^-2 sr^-1 nm^-1] (float32), ``sun_irradiance`` (time,
        wavelength) direct normal [W m^-2 nm^-1], the sun position, the retrieved atmosphere, inputs, status and
        closure per hour; coordinates with units; provenance in ``attrs``.
    """
    import xarray as xr

    from .. import __version__

    geom = scheme if isinstance(scheme, PatchScheme) else patch_scheme(scheme)
    whole_number("samples", samples, 1, 4, integral_floats=True)
    centres, edges = band_edges(bands)
    if atmosphere is None:
        atmosphere = retrieve_hourly_atmosphere(record, options, family=family)
    h = atmosphere
    fam = h.family
    o = h.options
    model = BroadbandClearSky(fam.base, o.angstrom_alpha)
    table_wl = fam.wavelengths
    e0t = fam.base.solar_irradiance_at(table_wl)
    bmat, band_e0, masks = _band_matrix(edges, table_wl, e0t, model)
    n, n_p, n_b, n_t = h.status.size, geom.n_patches, centres.size, table_wl.size
    sky = np.zeros((n, n_p, n_b), dtype=np.float32)
    sun = np.zeros((n, n_b))
    dhi_matrix = np.full(n, np.nan)
    peak_fraction, quad, dhi_scale = np.full(n, np.nan), np.full(n, np.nan), np.full(n, np.nan)
    clear_quad = np.full(n, np.nan)
    # clear skies from the family's tables (broken hours: their clear part), overcast skies from the cloud table
    # (broken hours: their cloudy part); hours without a retrieved sky are NaN
    clear_sky = np.isin(h.status, (CLEAR, CLEAR_OPEN, BROKEN, ENHANCED))
    cloud_sky = np.isin(h.status, (CLOUDY, BROKEN, LOW_SUN, ENHANCED)) & (h.cloud_table is not None)
    rows = np.flatnonzero(clear_sky)
    not_sky = ~clear_sky & ~cloud_sky & (h.status != 0)
    sky[not_sky] = np.nan
    sun[not_sky] = np.nan
    # broken hours: (1 - f) clear + f overcast (sky and sun); enhanced-diffuse hours: the same sun, and the sky's
    # overcast term carries its whole diffuse (h.cloud_dhi: DHI - (1 - f) clear_dhi), weight 1
    broken = np.isin(h.status, (BROKEN, ENHANCED))
    enhanced = h.status == ENHANCED
    f_cloud = np.where(broken, h.cloud_fraction, 0.0)
    if rows.size:
        dirs = geom.sample_directions(int(samples))  # (n_p, s^2, 3)
        flat = np.ascontiguousarray(dirs.reshape(-1, 3))
        cos_cells = np.maximum(dirs[..., 2], 0.0).mean(axis=1)  # mean cos over each patch
        omega = geom.solid_angles
        ground = np.array([0.0, 0.0, fam.base.bottom_radius])
        sun_dirs = direction_from_angles(h.sun_zenith, h.sun_azimuth)
        # the Sun-Earth distance scales the tables (mean distance) to the day
        ecc = h.eccentricity
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=rows.size, unit="h", desc=f"spectral sky ({geom.name}, {n_b} bands)")

        def patch_pass(values: NDArray[np.float64], hours: NDArray[np.int64]) -> NDArray[np.float32]:
            """Band radiances (n_p * n_b), the tables' horizontal sky irradiance (the radiance over the hemisphere,
            :meth:`~skyscatter.precomputed.evaluation.TableLookups.horizontal_sky_irradiance`, n_t) and the patches'
            own sum before scaling (n_t) of the ``hours`` (indices of the record), ``values`` their grid
            coordinates. Each node's patch radiances are scaled per table wavelength so that their horizontal
            irradiance equals the hemisphere's: the DHI the retrieval closed (multilinear interpolation commutes)."""

            def evaluate(atm, sub):
                out = np.empty((sub.size, n_p * n_b + 2 * n_t), dtype=np.float32)
                e_hemi = atm.horizontal_sky_irradiance(h.sun_zenith[hours[sub]])
                # all the hours of the cell in one compiled call per chunk (a chunk's radiances: 64 hours x
                # 2308 cells x 23 wavelengths, 27 MB for Reinhart MF 2)
                for c0 in range(0, sub.size, HOUR_CHUNK):
                    c1 = min(c0 + HOUR_CHUNK, sub.size)
                    rad = atm.sky_radiance_suns(ground, flat, sun_dirs[hours[sub[c0:c1]]])
                    cells4 = rad.reshape(c1 - c0, n_p, -1, n_t)
                    rad = cells4[:, :, 0].copy()  # the cells' mean, summed in numpy's order for a mean over them
                    for k in range(1, cells4.shape[2]):
                        rad += cells4[:, :, k]
                    rad /= cells4.shape[2]
                    e_patch = np.einsum("p,hpt->ht", omega * cos_cells, rad)  # the patches' horizontal irradiance
                    scale = np.divide(e_hemi[c0:c1], e_patch, out=np.ones_like(e_patch), where=e_patch > 0)
                    out[c0:c1, : n_p * n_b] = ((rad * scale[:, None, :]) @ bmat.T).reshape(c1 - c0, -1)
                    out[c0:c1, n_p * n_b: n_p * n_b + n_t] = e_hemi[c0:c1]
                    out[c0:c1, n_p * n_b + n_t:] = e_patch
                return out

            return fam.interpolate(values, evaluate, dtype=np.float32,
                                   progress=(lambda k: bar.update(k)) if bar is not None else None)

        def matrix_dhi(e_sky, hours):
            return model.broadband_diffuse(e_sky, h.sun_zenith[hours], h.precipitable_water[hours],
                                           h.pressure[hours], h.ozone[hours], ecc[hours], table_wl)

        values = np.stack([_axis_values(fam, a.name, h) for a in fam.axes], axis=1)[rows]
        try:
            # the hour's air as retrieved (its DHI closed on the same hemisphere integral): one description of
            # the diffuse horizontal irradiance for the retrieval and the matrix
            res = patch_pass(values, rows)
            dhi_matrix[rows] = matrix_dhi(res[:, n_p * n_b: n_p * n_b + n_t].astype(float), rows)
            with np.errstate(divide="ignore", invalid="ignore"):
                clear_quad[rows] = matrix_dhi(res[:, n_p * n_b + n_t:].astype(float), rows) / dhi_matrix[rows] - 1.0
        finally:
            if bar is not None:
                bar.close()
        bandsky = res[:, : n_p * n_b].reshape(rows.size, n_p, n_b)
        gas_b = np.ones((rows.size, n_b))
        if gases:
            tg = model.gas_transmittance(h.sun_zenith[rows], h.precipitable_water[rows], h.pressure[rows])
            gas_b = _band_means(tg, model.e0 * model.weights, masks)
        keep = (1.0 - f_cloud[rows])  # the clear part of broken hours
        bandsky *= (ecc[rows, None] * gas_b * keep[:, None]).astype(np.float32)[:, None, :]
        sky[rows] = bandsky
        dhi_matrix[rows] *= keep
        direct = model.direct_normal_spectral(h.sun_zenith[rows], h.aerosol_optical_depth[rows],
                                              h.precipitable_water[rows], h.pressure[rows], h.ozone[rows],
                                              ecc[rows], weighted=False)
        if not gases:
            direct = direct / model.gas_transmittance(h.sun_zenith[rows], h.precipitable_water[rows],
                                                      h.pressure[rows])
        sun[rows] = _band_means(direct, model.weights, masks) * keep[:, None]  # band mean over wavelength
    crow = np.flatnonzero(cloud_sky)
    if crow.size:
        c_sky, c_sun, c_dhi, c_peak, c_quad, c_scale = _cloud_patches(h, model, geom, int(samples), crow, edges,
                                                                      masks, gases)
        quad[crow], dhi_scale[crow] = c_quad, c_scale
        f = np.where(broken[crow], f_cloud[crow], 1.0)
        f_sky = np.where(enhanced[crow], 1.0, f)
        sky[crow] = np.where(broken[crow, None, None], sky[crow], 0.0) + (c_sky * f_sky[:, None, None]).astype(
            np.float32)
        sun[crow] = np.where(broken[crow, None], sun[crow], 0.0) + c_sun * f[:, None]
        dhi_matrix[crow] = np.where(broken[crow], dhi_matrix[crow], 0.0) + c_dhi * f_sky
        peak_fraction[crow] = c_peak
    times = (np.round(h.unix_time).astype(np.int64)).astype("datetime64[s]").astype("datetime64[ns]")
    loc = h.record.location
    with np.errstate(divide="ignore", invalid="ignore"):
        dhi_closure = np.where(h.dhi > 0, dhi_matrix / h.dhi - 1.0, np.nan)
    flux = "W m-2"
    status_meanings = " ".join(HOUR_STATUS[k].replace(", ", "_").replace(" ", "_") for k in sorted(HOUR_STATUS))
    data = {
        "sky_radiance": (("time", "patch", "wavelength"), sky,
                         {"units": "W m-2 sr-1 nm-1", "long_name": "patch-mean spectral sky radiance (band mean)",
                          "note": "NaN: hour not retrieved (see status, reason); 0 at night; no solar disc"}),
        "sun_irradiance": (("time", "wavelength"), sun,
                           {"units": "W m-2 nm-1", "long_name": "direct normal spectral irradiance of the sun "
                            "(band mean)"}),
        "sun_zenith": ("time", h.sun_zenith, {"units": "rad", "long_name": "true (unrefracted) sun zenith, mid-hour"}),
        "sun_azimuth": ("time", h.sun_azimuth, {"units": "rad", "long_name": "sun azimuth from north towards east"}),
        "status": ("time", h.status.astype(np.int8),
                   {"flag_values": np.array(sorted(HOUR_STATUS), dtype=np.int8), "flag_meanings": status_meanings}),
        "reason": ("time", np.asarray([str(r) for r in h.reason], dtype=str)),
        "aerosol_optical_depth": ("time", h.aerosol_optical_depth, {"units": "1", "long_name":
                                  "retrieved vertical aerosol optical depth at 550 nm"}),
        "aerosol_source": ("time", h.aerosol_source.astype(str)),
        "aerosol_optical_depth_file": ("time", h.aerosol_optical_depth_file,
                                       {"units": "1", "long_name": "the file's aerosol optical depth at 550 nm"}),
        "single_scattering_albedo": ("time", h.single_scattering_albedo, {"units": "1", "long_name":
                                     "aerosol single-scattering albedo (closes DHI in clear hours)"}),
        "aerosol_phase_g": ("time", h.aerosol_phase_g, {"units": "1", "long_name": "aerosol phase parameter g "
                            "(Cornette-Shanks; closes DHI in clear hours below the smallest albedo node)"}),
        "cloud_optical_depth": ("time", h.cloud_optical_depth, {"units": "1"}),
        "cloud_cover": ("time", h.cloud_cover, {"units": "1"}),
        "precipitable_water": ("time", h.precipitable_water, {"units": "cm"}),
        "precipitable_water_source": ("time", h.precipitable_water_source.astype(str)),
        "ozone": ("time", h.ozone, {"units": "DU"}),
        "pressure": ("time", h.pressure, {"units": "Pa"}),
        "ghi": ("time", h.ghi, {"units": flux, "long_name": "record: global horizontal irradiance"}),
        "dni": ("time", h.dni, {"units": flux, "long_name": "record: direct normal irradiance"}),
        "dhi": ("time", h.dhi, {"units": flux, "long_name": "record: diffuse horizontal irradiance"}),
        "dni_model": ("time", h.dni_model, {"units": flux, "long_name": "broadband DNI of the retrieved sky"}),
        "dhi_model": ("time", h.dhi_model, {"units": flux, "long_name": "broadband DHI of the retrieval"}),
        "dhi_matrix": ("time", dhi_matrix, {"units": flux, "long_name": "broadband DHI of the matrix's patches"}),
        "dni_closure": ("time", h.dni_closure, {"units": "1", "long_name": "dni_model / dni - 1"}),
        "dhi_closure": ("time", dhi_closure, {"units": "1", "long_name": "dhi_matrix / dhi - 1"}),
        "cloud_fraction": ("time", h.cloud_fraction, {"units": "1", "long_name": "weight of the overcast sky in "
                           "the hour's sky (1 overcast, the fitted blend weight of broken hours; enhanced-diffuse "
                           "hours: the weight of the cloud's sun, their overcast sky term holding DHI - (1 - f) "
                           "clear DHI)"}),
        "forward_peak_fraction": ("time", peak_fraction, {"units": "1", "long_name": "fraction of the overcast "
                                  "sky's 550 nm diffuse irradiance put in the sun's patch (the droplets' forward "
                                  "peak, not on the cloud table's radiance grid)"}),
        "cloud_quadrature": ("time", quad, {"units": "1", "long_name": "the overcast sky's patches (interpolated "
                             "radiance grid) over DISORT's diffuse without the forward peak, 550 nm, - 1, before "
                             "scaling"}),
        "sky_quadrature": ("time", clear_quad, {"units": "1", "long_name": "the clear sky's patches (mean "
                           "radiances before scaling) over the tables' radiance integrated over the hemisphere, "
                           "broadband diffuse horizontal, - 1; the patches are scaled per table wavelength to the "
                           "hemisphere's, the DHI the retrieval closed (broken hours: their clear part)"}),
        "cloud_dhi_scale": ("time", dhi_scale, {"units": "1", "long_name": "factor that takes the overcast sky's "
                            "DHI to the retrieval's (interpolation in optical depth; low sun: the record's)"}),
    }
    coords = {
        "time": ("time", times, {"long_name": "middle of the hour", "timezone": "UTC"}),
        "patch": ("patch", np.arange(n_p)),
        "patch_zenith": ("patch", geom.centre_zenith, {"units": "rad"}),
        "patch_azimuth": ("patch", geom.azimuth_centre, {"units": "rad", "long_name": "from north towards east"}),
        "patch_solid_angle": ("patch", geom.solid_angles, {"units": "sr"}),
        "wavelength": ("wavelength", centres, {"units": "nm", "long_name": "band centre"}),
        "wavelength_low": ("wavelength", edges[:-1], {"units": "nm"}),
        "wavelength_high": ("wavelength", edges[1:], {"units": "nm"}),
    }
    attrs = {
        "title": "skyscatter spectral sky matrix",
        "skyscatter_version": __version__,
        "source_file": str(h.record.path),
        "latitude_deg": loc.latitude_deg, "longitude_deg": loc.longitude_deg,
        "timezone_hours": loc.timezone_hours, "elevation_m": loc.elevation,
        "scheme": geom.name, "samples": int(samples), "gases": int(bool(gases)),
        "ground_albedo": float(fam.base.ground_albedo_at([550.0])[0]),
        "family": json.dumps(fam.describe(), sort_keys=True),
        "options": json.dumps({k: (v if isinstance(v, (int, float, str, tuple, list)) or v is None else repr(v))
                               for k, v in vars(o).items() if k != "base"}, sort_keys=True, default=list),
        "notes": "; ".join(h.notes),
        "conventions": "ENU frame; azimuth from north towards east; patches in Radiance's order without its "
                       "ground patch; status codes in flag_values/flag_meanings",
        "references": _references(),
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _cloud_patches(h: HourlyAtmosphere, model: BroadbandClearSky, geom: PatchScheme, samples: int,
                   rows: NDArray[np.int64], edges: NDArray[np.float64], masks, gases: bool, chunk: int = 256):
    """The overcast sky of hours ``rows`` from the cloud table: ``(band radiance (n, n_p, n_b) [W m^-2 sr^-1
    nm^-1], sun (n, n_b) [W m^-2 nm^-1], broadband DHI (n,) [W m^-2], forward-peak fraction at 550 nm (n,), ...)``.

    Per hour the table's radiance field at the hour's cloud optical depth and sun (:meth:`~.weather.CloudTable.
    patch_radiance`: linear in ln tau and cos z between the nodes) is averaged over each patch's cells. The field
    holds no forward peak of the droplets (a lobe about 1.5 deg wide, up to a quarter of the diffuse light under
    an optical depth of 1): its flux (:meth:`~.weather.CloudTable.peak_fraction` of DISORT's diffuse irradiance
    at the same optical depth and sun, :meth:`~.weather.CloudTable.diffuse_at`) is put in the patch that holds
    the sun, and the field is scaled per wavelength so that the patches' horizontal irradiance is the rest (the
    patch quadrature of the interpolated grid: ``quadrature`` returned, the relative difference at 550 nm before
    that scaling). The sky is then scaled by one number per hour (``dhi_scale``) so that its broadband DHI is the
    retrieval's ``cloud_dhi`` (the retrieval interpolates the broadband DHI in ln tau by a monotone cubic, this
    one linearly: they differ by a few tenths of a per cent; the low-sun fallback: the record's DHI). The sun:
    the clear direct beam times the cloud's ``exp(-tau s)``; low-sun fallback hours: the clear beam's spectrum
    scaled to the record's DNI.

    Returns ``(sky, sun, dhi, peak, quadrature, dhi_scale)``."""
    table = h.cloud_table
    assert table is not None
    gwl = table.wavelengths
    e0g = table.atmosphere.solar_irradiance_at(gwl)
    # the field is per unit E0 (r = L / E0), grey outside its 380-780 nm: padded with its end values
    lo_wl, hi_wl = min(edges[0], gwl[0]) - 1.0, max(edges[-1], gwl[-1]) + 1.0
    wl_ext = np.concatenate([[lo_wl], gwl, [hi_wl]])
    bmat, _, _ = _band_matrix(edges, wl_ext, np.ones(wl_ext.size), model)
    cells = geom.sample_directions(samples)
    g = geom.solid_angles * np.maximum(cells[..., 2], 0.0).mean(axis=1)  # omega x mean cos per patch
    k550 = int(np.argmin(np.abs(gwl - 550.0)))
    n = rows.size
    n_b = edges.size - 1
    out_sky = np.empty((n, geom.n_patches, n_b), dtype=np.float32)
    out_sun = np.empty((n, n_b))
    out_dhi = np.empty(n)
    out_peak = np.empty(n)
    out_quad = np.empty(n)
    out_dhi_scale = np.empty(n)
    for s0 in range(0, n, chunk):
        sl = slice(s0, min(s0 + chunk, n))
        r_ = rows[sl]
        m = r_.size
        z, az = h.sun_zenith[r_], h.sun_azimuth[r_]
        low = h.status[r_] == LOW_SUN
        tau = np.where(np.isfinite(h.cloud_optical_depth[r_]), h.cloud_optical_depth[r_], 1.0)
        r = table.patch_radiance(z, az, tau, cells)  # (m, n_p, n_wl) [sr^-1]
        e_p = np.einsum("hpw,p->hw", r, g) * e0g  # horizontal irradiance of the patches [W m^-2 nm^-1]
        d = table.diffuse_at(z, tau)
        lobe = table.peak_fraction(z, tau) * d
        # the field's quadrature on the patches: scaled per wavelength to DISORT's diffuse without the peak
        r *= ((d - lobe) / np.where(e_p > 0, e_p, 1.0))[:, None, :]
        p_sun = geom.patch_index(direction_from_angles(np.minimum(z, np.pi / 2 - 1e-6), az))
        r[np.arange(m), p_sun] += lobe / (g[p_sun][:, None] * e0g)
        out_peak[sl] = lobe[:, k550] / d[:, k550]
        out_quad[sl] = e_p[:, k550] / (d - lobe)[:, k550] - 1.0
        dhi_m = model.broadband_diffuse(d, z, h.precipitable_water[r_], h.pressure[r_], h.ozone[r_],
                                        h.eccentricity[r_], gwl)
        scale = h.cloud_dhi[r_] / dhi_m
        out_dhi_scale[sl] = scale
        r *= scale[:, None, None]
        out_dhi[sl] = dhi_m * scale
        r_ext = np.concatenate([r[..., :1], r, r[..., -1:]], axis=2)
        band = r_ext @ bmat.T  # (m, n_p, n_b)
        gas_b = np.ones((m, n_b))
        tg = model.gas_transmittance(z, h.precipitable_water[r_], h.pressure[r_])
        if gases:
            gas_b = _band_means(tg, model.e0 * model.weights, masks)
        out_sky[sl] = band * (h.eccentricity[r_, None] * gas_b)[:, None, :]
        direct = model.direct_normal_spectral(z, h.aerosol_optical_depth[r_], h.precipitable_water[r_],
                                              h.pressure[r_], h.ozone[r_], h.eccentricity[r_], weighted=False)
        clear_dni = (direct * model.weights).sum(axis=1)
        direct = np.where(low[:, None], direct * (h.dni[r_] / np.where(clear_dni > 0, clear_dni, 1.0))[:, None],
                          direct * np.exp(-tau[:, None] * table.slant_optical_depth(z, model.wavelengths)))
        if not gases:
            direct = direct / tg
        out_sun[sl] = _band_means(direct, model.weights, masks)
    return out_sky, out_sun, out_dhi, out_peak, out_quad, out_dhi_scale


def _axis_values(fam, name: str, h: HourlyAtmosphere) -> NDArray[np.float64]:
    if name == "aerosol_optical_depth":
        return np.nan_to_num(h.aerosol_optical_depth, nan=0.0)
    if name == "aerosol_single_scattering_albedo":
        return np.nan_to_num(h.single_scattering_albedo, nan=fam.base.mie_single_scattering_albedo)
    if name == "aerosol_phase_g":
        return np.nan_to_num(h.aerosol_phase_g, nan=fam.base.mie_phase_g)
    if name == "cloud_optical_depth":
        return np.nan_to_num(h.cloud_optical_depth, nan=0.0)
    raise InvalidParameterError(f"no hourly value for the grid axis {name!r}")


# --------------------------------------------------------------------------------------------- outputs


def save_dataset(ds, path: str | os.PathLike[str]) -> Path:
    """Write a spectral sky matrix to NetCDF (``.nc``, via h5netcdf, compressed) or Zarr (``.zarr``), atomically
    (a failed write leaves nothing); returns the path."""
    target = check_output_path(path)
    suffix = target.suffix.lower()
    if suffix == ".nc":
        try:
            import h5netcdf  # noqa: F401
            import h5py  # noqa: F401  (h5netcdf's backend, not installed by h5netcdf itself)
        except ImportError:
            raise OutputError("writing NetCDF needs h5netcdf and h5py, dependencies of skyscatter that are "
                              "missing here (pip install h5netcdf h5py); or write a .zarr store") from None
        # gzip 1 with the byte shuffle: 20 % less CPU than gzip 4 alone and a 17 % smaller file (the made year)
        enc = {v: {"compression": "gzip", "compression_opts": 1, "shuffle": True}
               for v in ("sky_radiance", "sun_irradiance")}
        with atomic_path(target) as tmp:
            try:
                ds.to_netcdf(tmp, engine="h5netcdf", encoding=enc)
            except OSError as exc:
                raise OutputError(f"cannot write {target}: {exc.strerror or exc}") from None
        return target
    if suffix == ".zarr":
        import shutil

        if target.exists():
            raise OutputError(f"{target} exists; choose another path (a Zarr store is not overwritten)")
        tmp = target.with_name(f".{target.name}.tmp-{os.getpid()}")
        try:
            with warnings.catch_warnings():  # fixed-width text (status reasons) has no Zarr v3 spec name yet
                warnings.filterwarnings("ignore", message=".*does not have a Zarr V3 specification")
                ds.to_zarr(tmp, mode="w-", consolidated=False)
            os.replace(tmp, target)
        except OSError as exc:
            shutil.rmtree(tmp, ignore_errors=True)
            raise OutputError(f"cannot write {target}: {exc.strerror or exc}") from None
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        return target
    raise InvalidParameterError(f"{target}: the spectral matrix file must end in .nc (NetCDF) or .zarr (Zarr)")


def ground_radiance(ds) -> NDArray[np.float64]:
    """Radiance [W m^-2 sr^-1 nm^-1] of a Lambertian ground of the dataset's ``ground_albedo`` lit by the sky
    and the sun, shape (time, wavelength): ``rho (E_sky + E_sun cos z) / pi`` (Radiance's ground patch)."""
    sky = np.asarray(ds["sky_radiance"].values, dtype=float)
    omega = ds["patch_solid_angle"].values
    cosp = np.cos(ds["patch_zenith"].values)
    e_sky = np.einsum("tpw,p->tw", sky, omega * cosp)
    e_sun = ds["sun_irradiance"].values * np.maximum(np.cos(ds["sun_zenith"].values), 0.0)[:, None]
    return float(ds.attrs["ground_albedo"]) * (e_sky + e_sun) / np.pi


#: Radiance's standard RGB primaries (CIE xy of R, G, B) and its equal-energy white (``color.h``, ``CIE_x_r`` ...).
RADIANCE_PRIMARIES = ((0.640, 0.330), (0.290, 0.600), (0.150, 0.060))
#: Radiance's luminous efficacy of its RGB radiance units [lm W^-1] (WHTEFFICACY).
RADIANCE_EFFICACY = 179.0


def radiance_rgb_matrix() -> NDArray[np.float64]:
    """3x3 matrix from CIE XYZ to Radiance RGB (its primaries, equal-energy white): ``rgb = M @ xyz``. With it
    ``Y = 0.2651 R + 0.6701 G + 0.0648 B`` (Radiance's luminance formula, 179 lm/W per unit)."""
    xy = np.array(RADIANCE_PRIMARIES)
    prim = np.stack([xy[:, 0] / xy[:, 1], np.ones(3), (1 - xy[:, 0] - xy[:, 1]) / xy[:, 1]])  # columns = R, G, B
    scale = np.linalg.solve(prim, np.ones(3))  # equal-energy white X = Y = Z = 1
    return np.linalg.inv(prim * scale)


def radiance_rgb(ds, values: NDArray[np.float64]) -> NDArray[np.float64]:
    """Band-mean spectral radiance (..., n_bands) [W m^-2 sr^-1 nm^-1] -> Radiance RGB radiance (..., 3)
    [W m^-2 sr^-1 in Radiance's units: 179 lm/W], through the CIE 1931 observer at the band centres times the
    band widths."""
    from ..spectral.colorimetry import cie_cmfs

    centres = ds["wavelength"].values
    width = ds["wavelength_high"].values - ds["wavelength_low"].values
    xyz = 683.0 * np.asarray(values, dtype=float) @ (cie_cmfs(centres) * width[:, None])
    return xyz @ radiance_rgb_matrix().T / RADIANCE_EFFICACY


def write_radiance_matrix(ds, path: str | os.PathLike[str], *, binary: bool = True, rgb: bool = False,
                          command: str = "skyscatter skymatrix --spectral") -> Path:
    """Write the sky matrix in Radiance's matrix format (what ``rmtxop``, ``dctimestep`` and ``rfluxmtx`` read).

    Layout as gensdaymtx writes it: header ``#?RADIANCE``, ``NROWS`` = patches + 1 (the ground patch first,
    then the sky patches in Radiance's order), ``NCOLS`` = hours, ``NCOMP`` = bands, ``WAVELENGTH_SPLITS= 780 588
    480 380`` for the standard 380-780 nm range, ``FORMAT=float`` (little-endian) or ``ascii``;
    each entry's components from the longest wavelength to the shortest (Radiance's spectral order), values the
    band-mean spectral radiance [W m^-2 sr^-1 nm^-1] (written by
    :func:`skyscatter.radiance.write_radiance_matrix`). ``rgb=True`` writes ``NCOMP=3`` Radiance RGB radiance
    instead (:func:`radiance_rgb`, gendaymtx's form), which ``dctimestep`` needs (this Radiance's dctimestep takes 3
    components only; ``rmtxop`` takes the spectral matrix). Hours that are not retrieved are written as NaN (they
    propagate through ``rmtxop``/``dctimestep``: nothing takes them for a sky). Atomic.
    """
    target = check_output_path(path)
    sky = np.asarray(ds["sky_radiance"].values, dtype=np.float32)  # (t, p, w)
    ground = ground_radiance(ds).astype(np.float32)  # (t, w)
    full = np.concatenate([ground[:, None, :], sky], axis=1)
    # Radiance orders spectral components from the long wavelengths to the short; RGB stays R, G, B
    full = radiance_rgb(ds, full).astype(np.float32) if rgb else full[:, :, ::-1]
    rows = np.ascontiguousarray(full.transpose(1, 0, 2))  # (p+1, t, components)
    wl_lo, wl_hi = float(ds["wavelength_low"].values[0]), float(ds["wavelength_high"].values[-1])
    splits = (RADIANCE_WAVELENGTH_SPLITS if (abs(wl_lo - 380) < 6 and abs(wl_hi - 780) < 6)
              else (wl_hi, wl_lo + 2 * (wl_hi - wl_lo) / 3, wl_lo + (wl_hi - wl_lo) / 3, wl_lo))
    header = [command, f"LATLONG= {ds.attrs['latitude_deg']:.8f} {ds.attrs['longitude_deg']:.8f}"]
    if not rgb:
        header.append("WAVELENGTH_SPLITS= " + " ".join(f"{w:g}" for w in splits))
    # NaN marks the hours without a sky (refused by the shared writer, which takes finite numbers)
    return _write_matrix(target, rows, header=header, encoding="float" if binary else "ascii",
                                        allow_nan=True)


def plane_irradiance(ds, tilt: float, azimuth: float, *, samples: int = 4):
    """Spectral irradiance on a tilted plane (the plane-of-array spectrum) from a spectral sky matrix.

    ``E_sky = sum_p L_p Omega_p <max(0, d . n)>_p`` (the mean cosine over ``samples x samples`` cells of each
    patch), ``E_ground = rho E_global,h (1 - cos tilt) / 2`` (an infinite Lambertian ground of the dataset's
    albedo), ``E_direct = E_sun max(0, s . n)``.

    Parameters
    ----------
    ds : xarray.Dataset
        From :func:`spectral_sky_matrix`.
    tilt : float
        Plane tilt from horizontal [rad], in [0, pi].
    azimuth : float
        Azimuth of the plane's normal [rad] from north towards east (pi: facing south).
    samples : int
        Cells per patch side for the mean cosine.

    Returns
    -------
    xarray.Dataset
        ``sky``, ``ground``, ``direct`` and ``global`` (time, wavelength) [W m^-2 nm^-1].
    """
    import xarray as xr

    tilt = float(tilt)
    azimuth = float(azimuth)
    if not (np.isfinite(tilt) and 0.0 <= tilt <= np.pi) or not np.isfinite(azimuth):
        raise InvalidParameterError("tilt must be in [0, pi] rad and azimuth finite [rad]")
    geom = patch_scheme(ds.attrs["scheme"])
    normal = direction_from_angles(tilt, azimuth)
    cells = geom.sample_directions(int(samples))
    mean_cos = np.maximum(cells @ normal, 0.0).mean(axis=1)
    sky_l = np.asarray(ds["sky_radiance"].values, dtype=float)
    e_sky = np.einsum("tpw,p->tw", sky_l, ds["patch_solid_angle"].values * mean_cos)
    sun_dirs = direction_from_angles(np.minimum(ds["sun_zenith"].values, np.pi / 2), ds["sun_azimuth"].values)
    e_sun_n = ds["sun_irradiance"].values
    e_direct = e_sun_n * np.maximum(sun_dirs @ normal, 0.0)[:, None]
    e_direct = np.where(ds["sun_zenith"].values[:, None] < np.pi / 2, e_direct, 0.0)
    ground = ground_radiance(ds) * np.pi  # rho E_global,h
    e_ground = ground * (1.0 - np.cos(tilt)) / 2.0
    dims = ("time", "wavelength")
    unit = {"units": "W m-2 nm-1"}
    return xr.Dataset({"sky": (dims, e_sky, unit), "ground": (dims, e_ground, unit), "direct": (dims, e_direct, unit),
                       "global": (dims, e_sky + e_ground + e_direct, unit)},
                      coords={"time": ds["time"], "wavelength": ds["wavelength"]},
                      attrs={"tilt_rad": tilt, "azimuth_rad": azimuth})


# --------------------------------------------------------------------------------------------- many sites


def _job_description(paths: Sequence[Path], scheme: str, bands, samples: int, options: RetrievalOptions) -> dict:
    def digest(p: Path) -> str:
        return hashlib.sha256(p.read_bytes()).hexdigest()

    return {"sites": [str(p) for p in paths], "sha256": [digest(p) for p in paths], "scheme": scheme,
            "bands": band_edges(bands)[0].tolist(), "samples": int(samples),
            "options": {k: (list(v) if isinstance(v, tuple) else v) for k, v in vars(options).items()
                        if k not in ("base", "sizes")}, "sizes": repr(options.sizes),
            "base": None if options.base is None else options.base.to_dict()}


def _site_arrays(ds) -> dict[str, NDArray]:
    return {"sky_radiance": ds["sky_radiance"].values, "sun_irradiance": ds["sun_irradiance"].values,
            "status": ds["status"].values.astype(np.int8),
            "unix_time": ds["time"].values.astype("datetime64[s]").astype(np.int64).astype(np.float64),
            "sun_zenith": ds["sun_zenith"].values, "sun_azimuth": ds["sun_azimuth"].values,
            "aerosol_optical_depth": ds["aerosol_optical_depth"].values,
            "single_scattering_albedo": ds["single_scattering_albedo"].values,
            "dni_closure": ds["dni_closure"].values, "dhi_closure": ds["dhi_closure"].values}


def _checksum(arrays: dict[str, NDArray]) -> str:
    h = hashlib.sha256()
    for k in sorted(arrays):
        h.update(k.encode())
        h.update(np.ascontiguousarray(arrays[k]).tobytes())
    return h.hexdigest()


def spectral_sky_matrix_sites(records: Sequence[str | os.PathLike[str]], store: str | os.PathLike[str], *,
                              scheme: str = "reinhart2", bands: int | Sequence[float] = 20, samples: int = 2,
                              options: RetrievalOptions | None = None, scheduler: str | None = None,
                              workers: int = 2, progress: bool = False):
    """Spectral sky matrices of many weather records as Dask tasks, into one Zarr store with a ``site`` dimension.

    The store is created (atomically, every site pending) with ``sky_radiance`` (site, hour, patch, wavelength),
    ``sun_irradiance`` (site, hour, wavelength), ``unix_time`` (site, hour) [s], ``status`` and the retrieved
    aerosol per site and hour (records shorter than the longest are padded with NaN), a ``done`` flag and a SHA-256
    ``checksum`` per site. Each task computes one site and writes its region, then its checksum and flag. A rerun
    on the same store (same inputs and settings; anything else is refused) verifies the finished sites'
    checksums, recomputes those that do not match and the unfinished ones, and leaves the store byte-identical
    to an uninterrupted run (the computation is deterministic).

    Parameters
    ----------
    records : sequence of path
        Weather files (EPW, TMY3 or CSV).
    store : path
        Zarr directory (``.zarr``).
    scheduler : None, "threads", "processes", "local" or an address
        None / ``"threads"``: Dask's threaded scheduler with ``workers`` threads (default); ``"local"``: a
        ``distributed.LocalCluster`` of ``workers`` single-threaded worker processes; ``"tcp://host:port"``: an
        existing Dask scheduler.
    workers : int
        Threads or processes (default 2).
    progress : bool
        Dask's progress bar.

    Returns
    -------
    xarray.Dataset (opened lazily from the store)
    """
    import dask
    import xarray as xr

    paths = [Path(p) for p in records]
    if not paths:
        raise InvalidParameterError("give one or more weather records")
    for p in paths:
        if not p.is_file():
            raise InvalidParameterError(f"{p}: no such weather file")
    o = RetrievalOptions() if options is None else options
    store_path = Path(store)
    if store_path.suffix.lower() != ".zarr":
        raise InvalidParameterError(f"{store_path}: the multi-site store must be a .zarr directory")
    whole_number("workers", workers, 1, integral_floats=True)
    geom = patch_scheme(scheme)
    centres, _ = band_edges(bands)
    from .weather import read_weather

    lengths = [len(read_weather(p).hourly()) for p in paths]
    job = _job_description(paths, geom.name, bands, samples, o)
    job_id = hashlib.sha256(json.dumps(job, sort_keys=True).encode()).hexdigest()
    _open_or_create_sites(store_path, job, job_id, len(paths), max(lengths), geom.n_patches, centres)
    ds0 = xr.open_zarr(store_path, consolidated=False)
    done = ds0["done"].values.copy()
    sums = ds0["checksum"].values.copy()
    pending = []
    for s in range(len(paths)):
        if done[s]:
            try:
                intact = _checksum(_read_site(ds0, s, lengths[s])) == str(sums[s])
            except Exception:  # noqa: BLE001 - a chunk that does not even decode is damaged too
                intact = False
            if intact:
                continue
        pending.append(s)
    ds0.close()
    # The family's tables are built on first use inside the tasks (only the nodes the records need); two tasks
    # that need the same missing node at once both build it and one atomic write wins (the cache's rule).

    def run(s: int) -> int:
        ds = spectral_sky_matrix(paths[s], scheme=geom, bands=bands, samples=samples, options=o)
        _write_site(store_path, s, ds, max(lengths))
        return s

    tasks = [dask.delayed(run)(s) for s in pending]
    if tasks:
        _compute(tasks, scheduler, int(workers), progress)
    return xr.open_zarr(store_path, consolidated=False)


def _compute(tasks, scheduler, workers: int, progress: bool) -> None:
    import dask

    if scheduler in (None, "threads", "processes"):
        kw = {"scheduler": scheduler or "threads", "num_workers": workers}
        if progress:
            from dask.diagnostics import ProgressBar

            with ProgressBar():
                dask.compute(*tasks, **kw)
        else:
            dask.compute(*tasks, **kw)
        return
    from distributed import Client, LocalCluster
    from distributed import progress as dprogress

    if scheduler == "local":
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as cl, \
                Client(cl) as client:
            futures = client.compute(tasks)
            if progress:
                dprogress(futures)
            client.gather(futures)
        return
    if not isinstance(scheduler, str) or "://" not in scheduler:
        raise InvalidParameterError(f"scheduler must be 'threads', 'processes', 'local' or an address like "
                                    f"tcp://host:8786; got {scheduler!r}")
    with Client(scheduler) as client:
        futures = client.compute(tasks)
        if progress:
            dprogress(futures)
        client.gather(futures)


def _open_or_create_sites(store: Path, job: dict, job_id: str, n_sites: int, n_hours: int, n_patches: int,
                          centres: NDArray[np.float64]) -> None:
    import xarray as xr

    if store.exists():
        try:
            ds = xr.open_zarr(store, consolidated=False)
        except Exception as exc:  # noqa: BLE001 - any unreadable store is refused the same way
            raise OutputError(f"{store} exists and is not a skyscatter multi-site store ({exc})") from None
        if ds.attrs.get("job_sha256") != job_id:
            raise OutputError(f"{store} holds another multi-site job (other files or settings); it is not "
                              "overwritten; choose another path")
        return
    check_output_path(store)
    dims4 = ("site", "hour", "patch", "wavelength")
    nan4 = np.full((n_sites, n_hours, n_patches, centres.size), np.nan, dtype=np.float32)
    per_hour = {k: (("site", "hour"), np.full((n_sites, n_hours), np.nan))
                for k in ("sun_zenith", "sun_azimuth", "aerosol_optical_depth", "single_scattering_albedo",
                          "dni_closure", "dhi_closure")}
    ds = xr.Dataset(
        {"sky_radiance": (dims4, nan4, {"units": "W m-2 sr-1 nm-1"}),
         "sun_irradiance": (("site", "hour", "wavelength"), np.full((n_sites, n_hours, centres.size), np.nan),
                            {"units": "W m-2 nm-1"}),
         "unix_time": (("site", "hour"), np.full((n_sites, n_hours), np.nan),
                       {"units": "s", "long_name": "middle of the hour, seconds since 1970-01-01T00:00 UTC"}),
         "status": (("site", "hour"), np.full((n_sites, n_hours), -1, dtype=np.int8)),
         **per_hour,
         "done": ("site", np.zeros(n_sites, dtype=bool)),
         "checksum": ("site", np.array([""] * n_sites, dtype="<U64"))},
        coords={"site": np.arange(n_sites), "site_file": ("site", np.array(job["sites"])),
                "wavelength": ("wavelength", centres, {"units": "nm"}), "patch": np.arange(n_patches)},
        attrs={"title": "skyscatter spectral sky matrices of many sites", "job_sha256": job_id,
               "job": json.dumps(job, sort_keys=True)})
    enc = {"sky_radiance": {"chunks": (1, n_hours, n_patches, centres.size)},
           "sun_irradiance": {"chunks": (1, n_hours, centres.size)}, "done": {"chunks": (1,)},
           "checksum": {"chunks": (1,)}, "status": {"chunks": (1, n_hours)}, "unix_time": {"chunks": (1, n_hours)},
           **{k: {"chunks": (1, n_hours)} for k in per_hour}}
    tmp = store.with_name(f".{store.name}.tmp-{os.getpid()}")
    try:
        with warnings.catch_warnings():  # fixed-width text has no Zarr v3 spec name yet
            warnings.filterwarnings("ignore", message=".*does not have a Zarr V3 specification")
            ds.to_zarr(tmp, mode="w-", encoding=enc, consolidated=False)
        os.replace(tmp, store)  # the store appears whole (every site pending) or not at all
    except FileExistsError:
        shutil.rmtree(tmp, ignore_errors=True)
        raise OutputError(f"{store} was created by another run at the same time; run again to resume it") from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _read_site(ds, s: int, n: int) -> dict[str, NDArray]:
    out = {}
    for k in ("sky_radiance", "sun_irradiance", "status", "unix_time", "sun_zenith", "sun_azimuth",
              "aerosol_optical_depth", "single_scattering_albedo", "dni_closure", "dhi_closure"):
        out[k] = ds[k].isel(site=s, hour=slice(0, n)).values
    out["status"] = out["status"].astype(np.int8)
    out["sky_radiance"] = out["sky_radiance"].astype(np.float32)
    return out


def _write_site(store: Path, s: int, ds, n_hours: int) -> None:
    import xarray as xr

    arrays = _site_arrays(ds)
    n = arrays["status"].size
    arrays["sky_radiance"] = arrays["sky_radiance"].astype(np.float32)

    def pad(a, fill):
        if a.shape[0] == n_hours:
            return a
        extra = np.full((n_hours - a.shape[0], *a.shape[1:]), fill, dtype=a.dtype)
        return np.concatenate([a, extra])

    fills = {"status": -1}
    dims = {"sky_radiance": ("site", "hour", "patch", "wavelength"), "sun_irradiance": ("site", "hour", "wavelength")}
    data = {k: (dims.get(k, ("site", "hour")), pad(v, fills.get(k, np.nan))[None]) for k, v in arrays.items()}
    xr.Dataset(data).to_zarr(store, region={"site": slice(s, s + 1), "hour": slice(None), "patch": slice(None),
                                            "wavelength": slice(None)}, consolidated=False)
    # checksum of what was written, then the flag: an interrupted site is recomputed on resume
    flag = xr.Dataset({"checksum": ("site", np.array([_checksum({k: v[:n] for k, v in arrays.items()})],
                                                     dtype="<U64")),
                       "done": ("site", np.ones(1, dtype=bool))})
    flag.to_zarr(store, region={"site": slice(s, s + 1)}, consolidated=False)
