"""On-disk cache of precomputed tables.

Tables live in ``$SKYSCATTER_CACHE_DIR`` or, by default, ``~/.cache/skyscatter/``, one ``.npz`` file per
configuration named after the first 24 hex digits of :func:`.storage.cache_key` (a SHA-256 of the atmosphere
parameters, orders, wavelengths, table sizes, library version and table format). Files are written atomically
and verified when read (format, per-table SHA-256 checksums, stored key): a corrupt, truncated or mismatched
file triggers a :class:`CacheRebuildWarning` and is recomputed, never trusted. Tables loaded once are also
kept in memory for the life of the process; their scattering tables stay memory maps of the file
(:mod:`.storage`), which another process may replace (by renaming) without changing what this one reads.
Processes that need the same missing tables at once (parallel test workers, Dask workers, two commands) build
them once: the builder holds an exclusive lock (``.NAME.lock`` beside the file, :func:`fcntl.flock`, released
when its process ends, even killed) and the others wait for it, then load its file.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..deprecation import renamed_keywords
from ..diskcache import CacheRebuildWarning, cache_dir
from ..errors import FileFormatError, InvalidParameterError, OutputError
from ..fileio import build_lock, ensure_output_folder
from .parameters import AtmosphereParameters
from .sizes import DEFAULT_ORDERS, TableSizes, table_wavelengths
from .storage import cache_key
from .tables import PrecomputedAtmosphere

__all__ = ["CacheRebuildWarning", "TableBuildWarning", "cache_dir", "cache_path", "cached_atmosphere",
           "check_cache_dir", "clear_memory_cache", "load_or_compute", "resolve_atmosphere"]

_MEMORY: dict[str, PrecomputedAtmosphere] = {}


class TableBuildWarning(UserWarning):
    """Emitted when tables must be computed (once per atmosphere): the call then takes tens of seconds."""


def check_cache_dir() -> Path:
    """The cache folder, created if missing; :class:`~skyscatter.errors.OutputError` if it cannot be written.

    The message names the folder, says what is wrong and how to choose another (``SKYSCATTER_CACHE_DIR``).
    """
    return ensure_output_folder(cache_dir(), what="the table cache folder",
                                hint="set SKYSCATTER_CACHE_DIR to a writable folder")


def cache_path(key: str) -> Path:
    """Path of the cache file for a table key."""
    return cache_dir() / f"bruneton-{key[:24]}.npz"


def clear_memory_cache() -> None:
    """Forget tables kept in memory (the files stay)."""
    _MEMORY.clear()


@renamed_keywords(params="atmosphere")
def cached_atmosphere(atmosphere: AtmosphereParameters | None = None, *, orders: int = DEFAULT_ORDERS,
                      tables: str | None = None, wavelengths: ArrayLike | None = None,
                      sizes: TableSizes | Mapping[str, int] | None = None, progress: bool | None = None,
                      keep_in_memory: bool = True) -> PrecomputedAtmosphere:
    """Tables for ``atmosphere`` from memory, from the disk cache, or computed and then cached.

    Same arguments as :meth:`PrecomputedAtmosphere.compute` (default: the 16 wavelengths of the spectral mode;
    ``tables="rgb"`` for the 3-wavelength mode; the wavelengths are part of the cache key, so tables cached
    under other defaults are not reused). If the cache folder cannot be written the tables are still returned
    (with a warning). ``keep_in_memory=False`` does not keep the tables in the process's memory cache (a
    caller that holds many tables, such as :class:`~skyscatter.precomputed.family.TableFamily`, bounds its own
    memory).
    """
    return load_or_compute(atmosphere, orders=orders, tables=tables, wavelengths=wavelengths, sizes=sizes,
                           progress=progress, keep_in_memory=keep_in_memory)[0]


@renamed_keywords(params="atmosphere")
def load_or_compute(atmosphere: AtmosphereParameters | None = None, *, orders: int = DEFAULT_ORDERS,
                    tables: str | None = None, wavelengths: ArrayLike | None = None,
                    sizes: TableSizes | Mapping[str, int] | None = None, progress: bool | None = None,
                    force: bool = False, require_saved: bool = False,
                    keep_in_memory: bool = True) -> tuple[PrecomputedAtmosphere, bool]:
    """Like :func:`cached_atmosphere`, also saying whether the tables were computed: ``(tables, computed)``.

    With ``force`` the tables are recomputed even if cached; the cache file is replaced only once the new
    tables are written (atomically), so an interrupted run keeps the old, valid file. With ``require_saved``
    (the caller asked for the cache file itself, as ``skyscatter precompute`` does) an unusable cache folder
    is an :class:`~skyscatter.errors.OutputError`, raised before any computation, instead of a warning.
    """
    params = AtmosphereParameters() if atmosphere is None else atmosphere
    wl = table_wavelengths(wavelengths, tables)
    sz = TableSizes.coerce(sizes)
    key = cache_key(params, orders, wl, sz)
    hit = None if force else _MEMORY.get(key)
    if hit is not None:
        return hit, False
    path = cache_path(key)
    if require_saved:
        check_cache_dir()
    atm, seen = (None, None) if force else _load(path, key)
    computed = atm is None
    if computed:
        with build_lock(path):  # one process builds; the others wait here, then load its file
            if not force and _identity(path) not in (None, seen):  # written by another process while we waited
                atm, _ = _load(path, key)
            computed = atm is None
            if computed:
                atm = _build_and_save(path, params, orders, wl, sz, progress, require_saved)
    if keep_in_memory:
        _MEMORY[key] = atm
    return atm, computed


def _build_and_save(path: Path, params: AtmosphereParameters, orders: int, wl: NDArray[np.float64],
                    sz: TableSizes, progress: bool | None, require_saved: bool) -> PrecomputedAtmosphere:
    """Compute the tables (:meth:`PrecomputedAtmosphere.compute`) and store them at ``path`` (atomically); an
    unwritable cache is a warning, or an :class:`~skyscatter.errors.OutputError` with ``require_saved``."""
    if progress is None:  # a library call that did not choose: say once why it takes a while
        warnings.warn(f"building the precomputed tables for this atmosphere once ({wl.size} wavelengths, "
                      f"{orders} orders; typically 30-60 s on 2 cores, and about 20 s more the first time, "
                      f"to compile the kernels); they are then cached in {path.parent}",
                      TableBuildWarning, stacklevel=4)
    atm = PrecomputedAtmosphere.compute(params, orders=orders, wavelengths=wl, sizes=sz, progress=progress)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        atm.save(path)
    except (OSError, OutputError) as exc:
        if isinstance(exc, OutputError):  # already names the file and the reason
            what = f"the table cache: {exc}"
        else:
            what = f"the table cache {path}: {exc.strerror or exc}"
        if require_saved:
            raise OutputError(f"could not write {what}") from None
        warnings.warn(f"could not write {what}; the tables are used without being cached", RuntimeWarning,
                      stacklevel=4)
    return atm


def _identity(path: Path) -> tuple[int, int] | None:
    """(inode, modification time in ns) of the file at ``path``, or None if there is none: a file another
    process renamed into place has another identity."""
    try:
        st = path.stat()
    except OSError:
        return None
    return st.st_ino, st.st_mtime_ns


def _load(path: Path, key: str) -> tuple[PrecomputedAtmosphere | None, tuple[int, int] | None]:
    """The tables cached at ``path`` (None if missing, or damaged: with a :class:`CacheRebuildWarning`) and the
    identity (:func:`_identity`) of the file read."""
    seen = _identity(path)
    if seen is None:
        return None, None
    try:
        return PrecomputedAtmosphere.load(path, expected_key=key), seen
    except (FileFormatError, OSError) as exc:
        warnings.warn(f"rebuilding cached atmosphere tables: {exc}", CacheRebuildWarning, stacklevel=4)
        return None, seen


@renamed_keywords(wavelengths="tables")
def resolve_atmosphere(atmosphere: PrecomputedAtmosphere | AtmosphereParameters | None, *,
                       tables: str | None = None) -> PrecomputedAtmosphere:
    """Tables for an argument that may be tables, an atmosphere or None (the Earth defaults).

    Tables are returned as they are; an atmosphere (or None) gets its tables from :func:`cached_atmosphere`,
    with ``tables`` ``"spectral"`` (the default) or ``"rgb"``.

    Raises
    ------
    InvalidParameterError
        Anything else, or ``tables`` given with tables (which have their wavelengths).
    """
    if tables not in (None, "spectral", "rgb"):
        raise InvalidParameterError(f"tables must be 'spectral' or 'rgb'; got {tables!r}")
    if isinstance(atmosphere, PrecomputedAtmosphere):
        if tables is not None:
            raise InvalidParameterError("tables goes with an atmosphere, not with precomputed tables (they have "
                                        "their own wavelengths)")
        return atmosphere
    if atmosphere is None or isinstance(atmosphere, AtmosphereParameters):
        return cached_atmosphere(atmosphere, tables=tables)
    raise InvalidParameterError(
        f"atmosphere must be a PrecomputedAtmosphere, AtmosphereParameters or None; got {type(atmosphere).__name__}"
    )
