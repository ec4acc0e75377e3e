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
checksum           sun_elevation, aerosol, albedo                   uint64 (BLAKE2b of the cell's data)
direction_xyz      direction, xyz                                   unit ENU vector
=================  ===============================================  =================================

Each cell is one Zarr chunk of every variable. A cell is written with its checksum first and only then marked
``done``, so an interrupted run loses nothing written and a re-run skips the cells already done; on resuming,
every done cell's data is checked against its checksum and recomputed if it was damaged. The store's attributes
hold the job description (atmosphere with its aerosol phase function, axes, directions, samples, seed, the window
of scattering orders when it is not every order, version)
and its SHA-256; a store that holds a different job, or lacks a variable, is refused rather than overwritten.

Every argument is checked before the store is touched. A new store is written as a hidden temporary folder
beside its target and renamed into place, so it appears complete (all cells pending) or not at all; a process
writing a store holds a lock file beside it (``.NAME.skyscatter-lock`` with its pid), so that a second process on
the same store (two runs started together on a new store, or a resume while a run goes on) stops with a one-line
error and leaves nothing behind. A lock or temporary store left by a process that no longer runs is taken over /
removed.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import math
import os
import re
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import __version__
from ..atmosphere import AtmosphereParameters
from ..errors import InvalidParameterError, MissingDependencyError, OutputError
from ..fileio import ensure_output_folder
from ..validation import whole_number
from .driver import (
    DEFAULT_GROUP_SIZE,
    batch_layout,
    check_directions,
    check_orders,
    check_scheduler,
    check_wavelengths,
    count_tasks,
    prepare_medium,
    sky_radiance,
    solar_disc_radiance,
    wavelength_groups,
)
from .kernels import MAX_ORDER

__all__ = ["ReferenceJob", "equal_area_directions", "reference"]

AEROSOL_KINDS = ("turbidity", "aerosol_optical_depth")
#: Largest number of paths per direction a job may ask for (planned and reduced lazily: no memory up front).
MAX_SAMPLES = 10**15
#: Largest number of view directions of a job (a cell of radiance is one chunk: directions x wavelengths).
MAX_DIRECTIONS = 1_000_000
#: The variables of a store and their dimensions (checked when a store is opened).
STORE_VARIABLES = {
    "radiance": ("sun_elevation", "aerosol", "albedo", "direction", "wavelength"),
    "stderr": ("sun_elevation", "aerosol", "albedo", "direction", "wavelength"),
    "solar_disc": ("sun_elevation", "aerosol", "albedo", "wavelength"),
    "done": ("sun_elevation", "aerosol", "albedo"),
    "checksum": ("sun_elevation", "aerosol", "albedo"),
    "direction_xyz": ("direction", "xyz"),
}
#: Suffix of the lock file beside a store (``.NAME<suffix>``) while a process writes it.
LOCK_SUFFIX = ".skyscatter-lock"


def equal_area_directions(n: int) -> NDArray[np.float64]:
    """``n`` directions spread evenly over the upper hemisphere (spherical Fibonacci lattice, equal area per point;
    [Gonzalez2010]), unit ENU vectors (n, 3)."""
    n = whole_number("number of directions", n, 1)
    i = np.arange(n) + 0.5
    z = 1.0 - i / n  # uniform in cos(zenith) on (0, 1]: equal area on the hemisphere
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.sin(phi), s * np.cos(phi), z], axis=-1)


def almucantar_directions(n_zenith: int, n_azimuth: int) -> NDArray[np.float64]:
    """``n_zenith x n_azimuth`` directions over the upper hemisphere on almucantars (rings of equal zenith angle),
    unit ENU vectors (n_zenith * n_azimuth, 3), ring by ring from the zenith down: ring ``i`` at ``cos(zenith) = 1 -
    (i + 1/2) / n_zenith`` (the centres of equal-area bands, as :func:`equal_area_directions`), azimuths ``(k +
    1/2) 2 pi / n_azimuth`` from north towards east. The Monte Carlo traces the views of one ring as one where the
    medium allows it (``driver.almucantars``), so a sky on this layout costs about half as much under clouds."""
    nz = whole_number("number of almucantars", n_zenith, 1)
    na = whole_number("number of azimuths per almucantar", n_azimuth, 1)
    z = 1.0 - (np.arange(nz) + 0.5) / nz
    phi = (np.arange(na) + 0.5) * (2.0 * math.pi / na)
    zz, pp = np.meshgrid(z, phi, indexing="ij")
    s = np.sqrt(1.0 - zz * zz)
    return np.stack([s * np.sin(pp), s * np.cos(pp), zz], axis=-1).reshape(-1, 3)


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
    orders: tuple[int, int] = (1, MAX_ORDER)

    def cell_atmosphere(self, k: int, m: int) -> AtmosphereParameters:
        """Medium of aerosol index ``k`` and albedo index ``m``."""
        a = float(self.aerosol[k])
        if self.atmosphere.aerosol is not None:  # a particle aerosol (e.g. an OPAC type): its own column scaled
            aerosol = dataclasses.replace(cast(Any, self.atmosphere.aerosol), optical_depth_550=a)
            return self.atmosphere.replace(aerosol=aerosol, ground_albedo=float(self.albedos[m]))
        if self.aerosol_kind == "turbidity":
            options = dict(turbidity=a)
        else:  # vertical aerosol optical depth at 550 nm with the base Angstrom exponent
            options = dict(aerosol_optical_depth=a, angstrom_alpha=self.atmosphere.mie_angstrom_alpha)
        return AtmosphereParameters.from_options(self.atmosphere, ground_albedo=float(self.albedos[m]), **options)

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
        } | ({} if self.orders == (1, MAX_ORDER) else {"orders": list(self.orders)})  # every order: as before

    def job_id(self) -> str:
        text = json.dumps(self.description(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()

    def tasks_per_cell(self) -> int:
        bs, nb = batch_layout(self.samples)
        return count_tasks(self.directions.shape[0], len(wavelength_groups(self.wavelengths.size, self.group_size)),
                           nb, bs)


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
             altitude: float = 0.0, group_size: int = DEFAULT_GROUP_SIZE, orders: Any = None) -> ReferenceJob:
    """Validate the inputs of a reference job (see :func:`reference`)."""
    atm = AtmosphereParameters() if atmosphere is None else atmosphere
    if (turbidities is None) == (aerosol_optical_depths is None):
        raise InvalidParameterError("give exactly one of turbidities or aerosol optical depths")
    if turbidities is not None:
        kind, aer = "turbidity", _axis("turbidities", turbidities, 1.0, 20.0, "")
    else:
        kind, aer = "aerosol_optical_depth", _axis("aerosol optical depths", aerosol_optical_depths, 0.0, 10.0, "")
    if not isinstance(atm, AtmosphereParameters):
        raise InvalidParameterError(f"atmosphere must be AtmosphereParameters; got {type(atm).__name__}")
    if atm.aerosol is not None and (kind != "aerosol_optical_depth"
                                    or not hasattr(atm.aerosol, "optical_depth_550")):
        raise InvalidParameterError("an atmosphere with a particle aerosol (an aerosol type) takes aerosol optical "
                                    "depths at 550 nm, not turbidities" if kind == "turbidity" else
                                    f"the aerosol {type(atm.aerosol).__name__} has no optical depth to set per cell")
    wl = check_wavelengths(wavelengths)
    samples = whole_number("samples (paths per direction)", samples, 1, MAX_SAMPLES)
    seed = whole_number("seed", seed, 0, 2**63 - 1)
    group_size = whole_number("group_size (wavelengths per path)", group_size, 1, 1024)
    try:
        alt = float(altitude)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"altitude must be a number [m]; got {altitude!r}") from None
    if not (math.isfinite(alt) and 0.0 <= alt <= 1e8):
        raise InvalidParameterError(f"altitude must be in [0, 1e8] m; got {altitude!r}")
    dirs = check_directions(directions)
    if dirs.shape[0] > MAX_DIRECTIONS:
        raise InvalidParameterError(f"at most {MAX_DIRECTIONS} directions; got {dirs.shape[0]}")
    window = check_orders(orders)
    job = ReferenceJob(atm, _axis("sun elevations", sun_elevations, -math.pi / 2, math.pi / 2, "rad"), kind, aer,
                       _axis("albedos", albedos, 0.0, 1.0, ""), wl, dirs, samples, seed, alt, group_size, window)
    # validate every cell's medium and the spectra once, before anything is written
    for k in range(aer.size):
        job.cell_atmosphere(k, 0).check_wavelengths(wl)
    if window != (1, MAX_ORDER):  # a window needs a medium without a forward peak split off (every cell alike)
        check_orders(orders, prepare_medium(job.cell_atmosphere(0, 0), wl[:1]))
    return job


def _xarray():
    try:
        import xarray as xr
        import zarr  # noqa: F401 - the store format
    except ImportError as exc:  # a dependency of skyscatter; only a broken install lacks it
        raise MissingDependencyError(f"a reference store needs the package {exc.name!r} (a dependency of "
                                     "skyscatter: pip install xarray zarr dask)") from None
    return xr


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True  # exists, owned by someone else
    return True


def lock_path(store: Path) -> Path:
    """The lock file of a store: ``.NAME.skyscatter-lock`` beside it (outside the Zarr hierarchy)."""
    return (store.parent if str(store.parent) else Path(".")) / f".{store.name}{LOCK_SUFFIX}"


def _lock_holder(store: Path) -> int | None:
    """The pid in the store's lock file if that process still runs, else None."""
    try:
        text = lock_path(store).read_text(encoding="ascii").strip()
        pid = int(text.split()[0])
    except (OSError, ValueError, IndexError):
        return None
    return pid if _pid_alive(pid) else None


def _acquire(store: Path) -> None:
    """Take the store's lock (:func:`lock_path`, holding our pid); a lock left by a process that no longer runs is
    taken over. Another live writer: OutputError.

    The lock appears with its pid already in it: the pid is written to a private file that is then hard-linked to
    the lock's name (``link`` fails if the name exists, like an exclusive create). An exclusive create followed by
    a write left a moment when the lock existed empty, and a second process starting at the same time read that as
    a stale lock, took it over and raced the first to create the store (seen in CI)."""
    lock = lock_path(store)
    mine = lock.with_name(f"{lock.name}.{os.getpid()}.{os.urandom(6).hex()}")
    try:
        mine.write_text(f"{os.getpid()}\n", encoding="ascii")
    except OSError as exc:  # a full disk or a read-only folder: nothing is left behind
        with contextlib.suppress(OSError):
            mine.unlink()
        raise OutputError(f"cannot write {store}: {exc.strerror or exc}") from None
    try:
        for _ in range(3):
            try:
                os.link(mine, lock)
            except FileExistsError:
                holder = _lock_holder(store)
                if holder is not None:
                    raise OutputError(f"{store} is being written by another skyscatter process (pid {holder}); wait "
                                      "for it to finish (re-running then resumes) or choose another path") from None
                with contextlib.suppress(OSError):
                    lock.unlink()  # stale: its process is gone
                continue
            except OSError as exc:
                raise OutputError(f"cannot write {store}: {exc.strerror or exc}") from None
            return
        raise OutputError(f"{store}: could not take its lock {lock}")  # pragma: no cover - a live race on the lock
    finally:
        with contextlib.suppress(OSError):
            mine.unlink()


def _release(store: Path) -> None:
    if _lock_holder(store) == os.getpid():
        with contextlib.suppress(OSError):
            lock_path(store).unlink()


_TEMP_STORE = re.compile(r"^\.(?P<name>.+)\.(?P<pid>\d+)\.[0-9a-f]{12}\.tmp$")


def _remove_stale_temporary_stores(store: Path) -> None:
    """Remove temporary stores (``.NAME.PID.TOKEN.tmp``) and private lock files (``.NAME<lock suffix>.PID.TOKEN``)
    beside ``store`` left by processes that no longer run."""
    folder = store.parent
    private_lock = re.compile(rf"^\.{re.escape(store.name)}{re.escape(LOCK_SUFFIX)}\.(?P<pid>\d+)\.[0-9a-f]{{12}}$")
    with contextlib.suppress(OSError):
        for entry in os.scandir(folder):
            m = _TEMP_STORE.match(entry.name)
            if m and m["name"] == store.name and not _pid_alive(int(m["pid"])) and entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path, ignore_errors=True)
            m = private_lock.match(entry.name)
            if m and not _pid_alive(int(m["pid"])):
                with contextlib.suppress(OSError):
                    os.unlink(entry.path)


def check_store_path(store: str | os.PathLike[str]) -> Path:
    """Refuse a store path that cannot be created or resumed, before any work: empty, an existing file, a missing
    or read-only folder."""
    text = os.fspath(store)
    if not str(text).strip():
        raise OutputError("the store path is empty; name a folder such as ref.zarr")
    path = Path(store)
    if path.exists() and not path.is_dir():
        raise OutputError(f"{path}: exists and is not a folder (a Zarr store is a folder); choose another path")
    if not path.exists():
        parent = path.parent if str(path.parent) else Path(".")
        if not parent.is_dir():
            raise OutputError(f"cannot create {path}: folder {parent} does not exist")
        ensure_output_folder(parent, what="store folder")
    elif not os.access(path, os.W_OK | os.X_OK):
        raise OutputError(f"{path}: the store is not writable")
    return path


def _template(job: ReferenceJob):
    """The empty store of ``job`` (every cell pending) as an xarray Dataset, with its chunk encoding."""
    xr = _xarray()
    jid = job.job_id()
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
    v = STORE_VARIABLES
    ds = xr.Dataset(
        {
            "radiance": (v["radiance"], np.full((n_s, n_a, n_m, n_d, n_w), np.nan),
                         {"units": unit, "long_name": "sky spectral radiance without the solar disc"}),
            "stderr": (v["stderr"], np.full((n_s, n_a, n_m, n_d, n_w), np.nan),
                       {"units": unit, "long_name": "Monte Carlo standard error of radiance"}),
            "solar_disc": (v["solar_disc"], np.full((n_s, n_a, n_m, n_w), np.nan),
                           {"units": unit, "long_name": "transmitted solar disc radiance (disc mean)"}),
            "done": (v["done"], np.zeros((n_s, n_a, n_m), dtype=bool)),
            "checksum": (v["checksum"], np.zeros((n_s, n_a, n_m), dtype=np.uint64),
                         {"long_name": "first 8 bytes of the BLAKE2b digest of the cell's radiance, stderr and "
                                       "solar_disc (float64, C order), checked when a run resumes"}),
            "direction_xyz": (v["direction_xyz"], job.directions, {"long_name": "unit view vector, ENU"}),
        },
        coords=dict(coords.items()),
        attrs={
            "title": "skyscatter Monte Carlo sky radiance reference",
            "skyscatter_version": __version__,
            "job_sha256": jid,
            "job": json.dumps(job.description(), sort_keys=True),
            "samples": job.samples,
            "seed": job.seed,
            "mie_phase_function": (job.atmosphere.mie_phase_function if job.atmosphere.aerosol is None
                                   else "tabulated (the particle aerosol's Mie phase)"),
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
        "checksum": {"chunks": (1, 1, 1)},
    }
    return ds, encoding


def _open_existing(store: Path, job: ReferenceJob):
    """Open a store of ``job`` for resuming; refuse another job's store or one that is not complete."""
    xr = _xarray()
    try:
        ds = xr.open_zarr(store, consolidated=False, chunks=None)
    except Exception as exc:  # noqa: BLE001 - any unreadable store is refused the same way
        raise OutputError(f"{store} exists and is not a skyscatter reference store ({type(exc).__name__}: "
                          f"{str(exc).splitlines()[0] if str(exc) else ''}); choose another path") from None
    other = ds.attrs.get("job_sha256")
    if other != job.job_id():
        raise OutputError(f"{store} holds a different reference job (job_sha256 {str(other)[:12]}..., this job "
                          f"{job.job_id()[:12]}...); it is not overwritten; choose another path")
    for name, dims in STORE_VARIABLES.items():
        if name not in ds.variables or tuple(ds[name].dims) != dims:
            raise OutputError(f"{store} is not a complete skyscatter reference store (variable {name!r} "
                              f"{'missing' if name not in ds.variables else 'has the wrong dimensions'}); it is "
                              "not overwritten; choose another path")
    return ds


def _open_or_create(store: Path, job: ReferenceJob):
    """Lock ``store`` for this process, then open it (same job: resume) or create it atomically (written as a
    hidden temporary folder beside the target and renamed into place). Of two processes starting at once, one
    takes the lock and the other stops with a one-line error, leaving nothing. Returns the Dataset; the caller
    releases the lock (:func:`_release`)."""
    _acquire(store)
    try:
        _remove_stale_temporary_stores(store)
        if store.exists():
            return _open_existing(store, job)
        ds, encoding = _template(job)
        folder = store.parent if str(store.parent) else Path(".")
        tmp = folder / f".{store.name}.{os.getpid()}.{os.urandom(6).hex()}.tmp"
        try:
            ds.to_zarr(tmp, mode="w-", encoding=encoding, consolidated=False)
            os.rename(tmp, store)  # the store appears complete (all cells pending) or not at all
        except OSError as exc:
            shutil.rmtree(tmp, ignore_errors=True)
            raise OutputError(f"cannot create {store}: {exc.strerror or exc}") from None
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        return _xarray().open_zarr(store, consolidated=False, chunks=None)
    except BaseException:
        _release(store)
        raise


def cell_checksum(radiance: NDArray[np.float64], stderr: NDArray[np.float64], disc: NDArray[np.float64]) -> int:
    """Checksum of one cell: the first 8 bytes (big-endian) of the BLAKE2b digest of its three arrays (float64)."""
    h = hashlib.blake2b(digest_size=8)
    for a in (radiance, stderr, disc):
        h.update(np.ascontiguousarray(a, dtype="<f8").tobytes())
    return int.from_bytes(h.digest(), "big")


def _verify_done_cells(ds, store: Path) -> list[tuple[int, int, int]]:
    """Cells marked done whose data no longer match their checksum (or cannot be read): to recompute."""
    done = np.asarray(ds["done"].values, dtype=bool)
    sums = np.asarray(ds["checksum"].values, dtype=np.uint64)
    damaged = []
    for i, k, m in zip(*np.nonzero(done), strict=True):
        try:
            rad = np.asarray(ds["radiance"][i, k, m].values)
            err = np.asarray(ds["stderr"][i, k, m].values)
            disc = np.asarray(ds["solar_disc"][i, k, m].values)
            ok = cell_checksum(rad, err, disc) == int(sums[i, k, m])
        except Exception:  # noqa: BLE001 - an undecodable chunk is a damaged cell
            ok = False
        if not ok:
            damaged.append((int(i), int(k), int(m)))
    return damaged


def reference(store: str | os.PathLike[str], *, sun_elevations: ArrayLike, albedos: ArrayLike,
              wavelengths: ArrayLike, directions: ArrayLike, turbidities: ArrayLike | None = None,
              aerosol_optical_depths: ArrayLike | None = None, atmosphere: AtmosphereParameters | None = None,
              samples: int = 4096, seed: int = 0, altitude: float = 0.0, group_size: int = DEFAULT_GROUP_SIZE,
              scheduler: Any = None,
              progress: Callable[[int, int], None] | None = None, orders: Any = None):
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
        depth at 550 nm (with the base atmosphere's Angstrom alpha; with a particle aerosol, its own spectrum).
    atmosphere : AtmosphereParameters, optional
        Base medium (Earth defaults); aerosol and albedo are replaced per cell. Its ``mie_phase_function`` and
        ``mie_phase_g`` give the aerosol phase function of every cell; a particle aerosol (``atmosphere.aerosol``,
        e.g. :meth:`~skyscatter.atmosphere.AtmosphereParameters.with_aerosol_type`) is kept, Mie phase and
        spectrum, with its optical depth at 550 nm set per cell (aerosol optical depths only).
    samples, seed, altitude, group_size, scheduler, orders
        As :func:`~skyscatter.montecarlo.sky_radiance` (``orders``: the orders of scattering counted, part of the
        job; a store of every order is described as before the option existed).
    progress : callable(done, total), optional
        Task progress over the cells still to compute.
    """
    job = make_job(sun_elevations=sun_elevations, albedos=albedos, wavelengths=wavelengths, directions=directions,
                   turbidities=turbidities, aerosol_optical_depths=aerosol_optical_depths, atmosphere=atmosphere,
                   samples=samples, seed=seed, altitude=altitude, group_size=group_size, orders=orders)
    check_scheduler(scheduler)
    path = check_store_path(store)
    ds = _open_or_create(path, job)
    try:
        done = np.asarray(ds["done"].values, dtype=bool).copy()
        damaged = _verify_done_cells(ds, path)
        if damaged:
            import warnings

            warnings.warn(f"{path}: {len(damaged)} cell(s) marked done do not match their checksum (damaged or "
                          f"partly written: {', '.join(map(str, damaged[:4]))}{', ...' if len(damaged) > 4 else ''}); "
                          "recomputing them", ReferenceStoreWarning, stacklevel=2)
            for ijk in damaged:
                done[ijk] = False
        pending = [(i, k, m) for i in range(done.shape[0]) for k in range(done.shape[1])
                   for m in range(done.shape[2]) if not done[i, k, m]]
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
                               progress=cell_progress, orders=job.orders)
            disc = solar_disc_radiance(atm, job.wavelengths, sun_zenith=zen, altitude=job.altitude)
            try:
                _write_cell(path, (i, k, m), res.radiance, res.stderr, disc)
            except OSError as exc:
                raise OutputError(f"cannot write {path}: {exc.strerror or exc} ({c} cell(s) finished before are "
                                  "kept, this one is not; re-running the same command resumes)") from None
    finally:
        _release(path)
    return _xarray().open_zarr(path, consolidated=False, chunks=None)


class ReferenceStoreWarning(UserWarning):
    """Cells of a reference store failed their checksum when resuming and are computed again."""


def _write_cell(path: Path, ijk: tuple[int, int, int], radiance, stderr, disc) -> None:
    """Write one cell's data with its checksum, then (only then) mark it done."""
    xr = _xarray()
    i, k, m = ijk
    region = {"sun_elevation": slice(i, i + 1), "aerosol": slice(k, k + 1), "albedo": slice(m, m + 1)}
    dims5 = STORE_VARIABLES["radiance"]
    dims3 = STORE_VARIABLES["done"]
    data = xr.Dataset({
        "radiance": (dims5, radiance[None, None, None]),
        "stderr": (dims5, stderr[None, None, None]),
        "solar_disc": (STORE_VARIABLES["solar_disc"], disc[None, None, None]),
        "checksum": (dims3, np.full((1, 1, 1), cell_checksum(radiance, stderr, disc), dtype=np.uint64)),
    })
    data.to_zarr(path, region={**region, "direction": slice(None), "wavelength": slice(None)}, consolidated=False)
    # mark the cell only once its data is on disk
    flag = xr.Dataset({"done": (dims3, np.ones((1, 1, 1), dtype=bool))})
    flag.to_zarr(path, region=region, consolidated=False)
