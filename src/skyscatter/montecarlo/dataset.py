"""Batch reference runs written to Zarr (the ``skyscatter reference`` command).

A reference job is the grid sun elevations x aerosol amounts x ground albedos, each cell one
:func:`~skyscatter.montecarlo.sky_radiance` call over the same directions and wavelengths. The result is an
xarray Dataset in a Zarr store:

=================  ===============================================  =================================
variable           dims                                             unit
=================  ===============================================  =================================
radiance           sun_elevation, aerosol, albedo, direction, wl    W m^-2 sr^-1 nm^-1
stderr             same                                             W m^-2 sr^-1 nm^-1
solar_disc         sun_elevation, aerosol, albedo, wavelength       W m^-2 sr^-1 nm^-1
done               sun_elevation, aerosol, albedo                   bool (cell written)
direction_xyz      direction, xyz                                   unit ENU vector
=================  ===============================================  =================================

Each cell is one Zarr chunk of every variable. A cell is written first and only then marked ``done``, so an
interrupted run loses nothing written and a re-run skips the cells already done. The store's attributes hold the
job description (atmosphere with its aerosol phase function, axes, directions, samples, seed, version) and its
SHA-256; a store that holds
a different job is refused rather than overwritten.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import __version__
from ..atmosphere import AtmosphereParameters
from ..atmosphere.turbidity import ANGSTROM_ALPHA, angstrom_beta, angstrom_beta_from_optical_depth
from ..errors import InvalidParameterError, OutputError
from .driver import (
    DEFAULT_GROUP_SIZE,
    batch_layout,
    check_directions,
    check_wavelengths,
    plan_tasks,
    sky_radiance,
    solar_disc_radiance,
    wavelength_groups,
)

__all__ = ["ReferenceJob", "equal_area_directions", "reference"]

AEROSOL_KINDS = ("turbidity", "aerosol_optical_depth")


def equal_area_directions(n: int) -> NDArray[np.float64]:
    """``n`` directions spread evenly over the upper hemisphere (spherical Fibonacci lattice, equal area per point;
    [Gonzalez2010]), unit ENU vectors (n, 3)."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InvalidParameterError(f"number of directions must be an integer >= 1; got {n!r}")
    i = np.arange(n) + 0.5
    z = 1.0 - i / n  # uniform in cos(zenith) on (0, 1]: equal area on the hemisphere
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.sin(phi), s * np.cos(phi), z], axis=-1)


@dataclass(frozen=True)
class ReferenceJob:
    """A validated reference job (angles in radians, wavelengths in nm)."""

    atmosphere: AtmosphereParameters
    sun_elevations: NDArray[np.float64]
    aerosol_kind: str
    aerosol: NDArray[np.float64]
    albedos: NDArray[np.float64]
    wavelengths: NDArray[np.float64]
    directions: NDArray[np.float64]
    samples: int
    seed: int
    altitude: float
    group_size: int

    def cell_atmosphere(self, k: int, m: int) -> AtmosphereParameters:
        """Medium of aerosol index ``k`` and albedo index ``m``."""
        a = float(self.aerosol[k])
        if self.aerosol_kind == "turbidity":
            # Preetham et al. 1999, Appendix A.1 (as AtmosphereParameters.from_turbidity)
            changes = dict(mie_angstrom_alpha=ANGSTROM_ALPHA, mie_angstrom_beta=float(angstrom_beta(a)))
        else:
            # vertical aerosol optical depth at 550 nm with the base Angstrom exponent
            changes = dict(mie_angstrom_beta=angstrom_beta_from_optical_depth(a, self.atmosphere.mie_angstrom_alpha))
        return self.atmosphere.replace(ground_albedo=float(self.albedos[m]), **changes)

    def description(self) -> dict[str, Any]:
        """JSON-able description; equal descriptions mean equal results."""
        return {
            "atmosphere": self.atmosphere.to_dict(),
            "sun_elevation_rad": self.sun_elevations.tolist(),
            "aerosol_kind": self.aerosol_kind,
            "aerosol": self.aerosol.tolist(),
            "albedo": self.albedos.tolist(),
            "wavelength_nm": self.wavelengths.tolist(),
            "directions_sha256": hashlib.sha256(np.ascontiguousarray(self.directions).tobytes()).hexdigest(),
            "samples": self.samples,
            "seed": self.seed,
            "altitude_m": self.altitude,
            "group_size": self.group_size,
            "method": "skyscatter.montecarlo (docs/montecarlo.md)",
        }

    def job_id(self) -> str:
        text = json.dumps(self.description(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()

    def tasks_per_cell(self) -> int:
        bs, nb = batch_layout(self.samples)
        return len(plan_tasks(self.directions.shape[0], len(wavelength_groups(self.wavelengths.size,
                                                                               self.group_size)), nb, bs))


def _axis(name: str, values: ArrayLike, lo: float, hi: float, unit: str) -> NDArray[np.float64]:
    v = np.atleast_1d(np.asarray(values, dtype=float))
    if v.ndim != 1 or v.size == 0:
        raise InvalidParameterError(f"{name} must be a non-empty list of numbers [{unit}]")
    if not np.all(np.isfinite(v)) or np.any(v < lo) or np.any(v > hi):
        raise InvalidParameterError(f"{name} must lie in [{lo:g}, {hi:g}] {unit}; got {v.tolist()}")
    if np.unique(v).size != v.size:
        raise InvalidParameterError(f"{name} contains repeated values: {v.tolist()}")
    return v


def make_job(*, sun_elevations: ArrayLike, albedos: ArrayLike, wavelengths: ArrayLike, directions: ArrayLike,
             turbidities: ArrayLike | None = None, aerosol_optical_depths: ArrayLike | None = None,
             atmosphere: AtmosphereParameters | None = None, samples: int = 4096, seed: int = 0,
             altitude: float = 0.0, group_size: int = DEFAULT_GROUP_SIZE) -> ReferenceJob:
    """Validate the inputs of a reference job (see :func:`reference`)."""
    atm = AtmosphereParameters() if atmosphere is None else atmosphere
    if (turbidities is None) == (aerosol_optical_depths is None):
        raise InvalidParameterError("give exactly one of turbidities or aerosol optical depths")
    if turbidities is not None:
        kind, aer = "turbidity", _axis("turbidities", turbidities, 1.0, 20.0, "")
    else:
        kind, aer = "aerosol_optical_depth", _axis("aerosol optical depths", aerosol_optical_depths, 0.0, 10.0, "")
    wl = check_wavelengths(wavelengths)
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 1:
        raise InvalidParameterError(f"samples must be an integer >= 1; got {samples!r}")
    job = ReferenceJob(atm, _axis("sun elevations", sun_elevations, -math.pi / 2, math.pi / 2, "rad"), kind, aer,
                       _axis("albedos", albedos, 0.0, 1.0, ""), wl, check_directions(directions), int(samples),
                       int(seed), float(altitude), int(group_size))
    # validate every cell's medium and the spectra once, before anything is written
    for k in range(aer.size):
        job.cell_atmosphere(k, 0).check_wavelengths(wl)
    return job


def _open_or_create(store: Path, job: ReferenceJob):
    import xarray as xr

    jid = job.job_id()
    if store.exists():
        try:
            ds = xr.open_zarr(store, consolidated=False)
        except Exception as exc:  # noqa: BLE001 - any unreadable store is refused the same way
            raise OutputError(f"{store} exists and is not a skyscatter reference store ({exc}); choose another "
                              "path") from None
        other = ds.attrs.get("job_sha256")
        if other != jid:
            raise OutputError(f"{store} holds a different reference job (job_sha256 {str(other)[:12]}..., this job "
                              f"{jid[:12]}...); it is not overwritten; choose another path")
        return ds
    n_s, n_a, n_m = job.sun_elevations.size, job.aerosol.size, job.albedos.size
    n_d, n_w = job.directions.shape[0], job.wavelengths.size
    zen = np.degrees(np.arccos(np.clip(job.directions[:, 2], -1, 1)))
    azi = np.degrees(np.mod(np.arctan2(job.directions[:, 0], job.directions[:, 1]), 2 * np.pi))
    coords = {
        "sun_elevation": ("sun_elevation", np.degrees(job.sun_elevations), {"units": "deg"}),
        "aerosol": ("aerosol", job.aerosol, {"long_name": job.aerosol_kind}),
        "albedo": ("albedo", job.albedos, {"units": "1"}),
        "wavelength": ("wavelength", job.wavelengths, {"units": "nm"}),
        "direction": ("direction", np.arange(n_d)),
        "view_zenith": ("direction", zen, {"units": "deg"}),
        "view_azimuth": ("direction", azi, {"units": "deg", "long_name": "from north towards east"}),
    }
    unit = "W m-2 sr-1 nm-1"
    ds = xr.Dataset(
        {
            "radiance": (("sun_elevation", "aerosol", "albedo", "direction", "wavelength"),
                         np.full((n_s, n_a, n_m, n_d, n_w), np.nan),
                         {"units": unit, "long_name": "sky spectral radiance without the solar disc"}),
            "stderr": (("sun_elevation", "aerosol", "albedo", "direction", "wavelength"),
                       np.full((n_s, n_a, n_m, n_d, n_w), np.nan),
                       {"units": unit, "long_name": "Monte Carlo standard error of radiance"}),
            "solar_disc": (("sun_elevation", "aerosol", "albedo", "wavelength"), np.full((n_s, n_a, n_m, n_w), np.nan),
                           {"units": unit, "long_name": "transmitted solar disc radiance (disc mean)"}),
            "done": (("sun_elevation", "aerosol", "albedo"), np.zeros((n_s, n_a, n_m), dtype=bool)),
            "direction_xyz": (("direction", "xyz"), job.directions, {"long_name": "unit view vector, ENU"}),
        },
        coords={k: v for k, v in coords.items()},
        attrs={
            "title": "skyscatter Monte Carlo sky radiance reference",
            "skyscatter_version": __version__,
            "job_sha256": jid,
            "job": json.dumps(job.description(), sort_keys=True),
            "samples": job.samples,
            "seed": job.seed,
            "mie_phase_function": job.atmosphere.mie_phase_function,
            "altitude_m": job.altitude,
            "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "conventions": "ENU frame (x east, y north, z up); azimuth from north towards east",
        },
    )
    encoding = {
        "radiance": {"chunks": (1, 1, 1, n_d, n_w)},
        "stderr": {"chunks": (1, 1, 1, n_d, n_w)},
        "solar_disc": {"chunks": (1, 1, 1, n_w)},
        "done": {"chunks": (1, 1, 1)},
    }
    tmp = store.with_name(store.name + f".tmp-{os.getpid()}")
    ds.to_zarr(tmp, mode="w-", encoding=encoding, consolidated=False)
    os.replace(tmp, store)  # the store appears complete (all cells pending) or not at all
    return xr.open_zarr(store, consolidated=False)


def reference(store: str | os.PathLike[str], *, sun_elevations: ArrayLike, albedos: ArrayLike,
              wavelengths: ArrayLike, directions: ArrayLike, turbidities: ArrayLike | None = None,
              aerosol_optical_depths: ArrayLike | None = None, atmosphere: AtmosphereParameters | None = None,
              samples: int = 4096, seed: int = 0, altitude: float = 0.0, group_size: int = DEFAULT_GROUP_SIZE,
              scheduler: Any = None,
              progress: Callable[[int, int], None] | None = None):
    """Compute (or resume) a reference grid and write it to the Zarr ``store``; return the xarray Dataset.

    Parameters
    ----------
    store : path
        Zarr directory; created if absent, resumed if it holds the same job, refused if it holds another.
    sun_elevations : array_like
        Sun elevations [rad] in [-pi/2, pi/2] (negative: twilight and night).
    albedos : array_like
        Ground albedos in [0, 1].
    wavelengths : array_like
        [nm].
    directions : array_like (N, 3)
        View directions (ENU); e.g. :func:`equal_area_directions`.
    turbidities, aerosol_optical_depths : array_like
        Exactly one: Linke-style turbidity (Preetham 1999 Angstrom beta, alpha 1.3) or vertical aerosol optical
        depth at 550 nm (with the base atmosphere's Angstrom alpha).
    atmosphere : AtmosphereParameters, optional
        Base medium (Earth defaults); aerosol and albedo are replaced per cell. Its ``mie_phase_function`` and
        ``mie_phase_g`` give the aerosol phase function of every cell.
    samples, seed, altitude, group_size, scheduler
        As :func:`~skyscatter.montecarlo.sky_radiance`.
    progress : callable(done, total), optional
        Task progress over the cells still to compute.
    """
    job = make_job(sun_elevations=sun_elevations, albedos=albedos, wavelengths=wavelengths, directions=directions,
                   turbidities=turbidities, aerosol_optical_depths=aerosol_optical_depths, atmosphere=atmosphere,
                   samples=samples, seed=seed, altitude=altitude, group_size=group_size)
    path = Path(store)
    ds = _open_or_create(path, job)
    done = ds["done"].values.copy()
    pending = [(i, k, m) for i in range(done.shape[0]) for k in range(done.shape[1]) for m in range(done.shape[2])
               if not done[i, k, m]]
    per_cell = job.tasks_per_cell()
    total = per_cell * len(pending)
    for c, (i, k, m) in enumerate(pending):
        atm = job.cell_atmosphere(k, m)
        zen = math.pi / 2 - float(job.sun_elevations[i])

        def cell_progress(d: int, t: int, c: int = c) -> None:
            if progress is not None:
                progress(c * per_cell + d, total)

        res = sky_radiance(atm, job.directions, job.wavelengths, sun_zenith=zen, altitude=job.altitude,
                           samples=job.samples, seed=job.seed, scheduler=scheduler, group_size=job.group_size,
                           progress=cell_progress)
        disc = solar_disc_radiance(atm, job.wavelengths, sun_zenith=zen, altitude=job.altitude)
        _write_cell(path, ds, (i, k, m), res.radiance, res.stderr, disc)
    import xarray as xr

    return xr.open_zarr(path, consolidated=False)


def _write_cell(path: Path, template, ijk: tuple[int, int, int], radiance, stderr, disc) -> None:
    import xarray as xr

    i, k, m = ijk
    region = {"sun_elevation": slice(i, i + 1), "aerosol": slice(k, k + 1), "albedo": slice(m, m + 1)}
    dims5 = ("sun_elevation", "aerosol", "albedo", "direction", "wavelength")
    data = xr.Dataset({
        "radiance": (dims5, radiance[None, None, None]),
        "stderr": (dims5, stderr[None, None, None]),
        "solar_disc": (("sun_elevation", "aerosol", "albedo", "wavelength"), disc[None, None, None]),
    })
    data.to_zarr(path, region={**region, "direction": slice(None), "wavelength": slice(None)}, consolidated=False)
    # mark the cell only once its data is on disk
    flag = xr.Dataset({"done": (("sun_elevation", "aerosol", "albedo"), np.ones((1, 1, 1), dtype=bool))})
    flag.to_zarr(path, region=region, consolidated=False)
