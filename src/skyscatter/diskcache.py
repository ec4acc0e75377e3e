"""The disk cache's folder and its small verified entries: arrays stored under a key, checked when read.

The cache folder (:func:`cache_dir`) holds the precomputed tables (:mod:`skyscatter.precomputed.cache`, with
their own file format) and small entries written by :func:`cached_arrays`: the cloud table of the weather fit,
the droplets' Mie optics. An entry is an ``.npz`` archive (uncompressed) with ``metadata``, a JSON text (the
entry's kind and key text, and a SHA-256 checksum per array, :func:`array_checksum`, over its dtype, shape and
bytes), and its arrays. It is written atomically (:func:`skyscatter.fileio.atomic_path`: a temporary file
renamed over the target, so a reader sees the old file or the new one, never a part) and verified when read: a
file that cannot be read, has another key or an array that does not match its checksum is refused with a
:class:`CacheRebuildWarning` and built again. Processes that need the same missing entry at once build it once:
the builder holds the entry's exclusive lock (:func:`skyscatter.fileio.build_lock`, released when its process
ends, however it ends), the others wait for it and then read its file.
"""

from __future__ import annotations

import hashlib
import json
import os
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .fileio import atomic_path, build_lock

__all__ = ["CacheRebuildWarning", "array_checksum", "cache_dir", "cache_entry_path", "cached_arrays",
           "read_entry", "write_entry"]


class CacheRebuildWarning(UserWarning):
    """A cached file was unreadable, damaged or for other parameters and is being recomputed."""


def cache_dir() -> Path:
    """The cache folder: ``$SKYSCATTER_CACHE_DIR`` if set, else ``~/.cache/skyscatter``."""
    env = os.environ.get("SKYSCATTER_CACHE_DIR")
    return Path(env).expanduser() if env else Path.home() / ".cache" / "skyscatter"


def array_checksum(arr: NDArray[Any]) -> str:
    """SHA-256 (hex) of an array's dtype, shape and bytes."""
    h = hashlib.sha256()
    h.update(f"{arr.dtype.str}{arr.shape}".encode())
    h.update(np.ascontiguousarray(arr).tobytes())
    return h.hexdigest()


def cache_entry_path(kind: str, key: str) -> Path:
    """The file of an entry: ``<kind>-<first 24 hex digits of the key text's SHA-256>.npz`` in :func:`cache_dir`."""
    return cache_dir() / f"{kind}-{hashlib.sha256(key.encode()).hexdigest()[:24]}.npz"


def read_entry(path: Path, kind: str, key: str) -> dict[str, NDArray[Any]] | None:
    """The arrays of the entry at ``path`` stored under ``kind`` and ``key``, verified; None if there is no file
    or it holds another key (a hash collision of the file name), and None with a :class:`CacheRebuildWarning` if
    it is damaged (unreadable, truncated, an array that does not match its checksum)."""
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["metadata"]))
            if meta.get("kind") != kind or meta.get("key") != key:
                return None
            sums = meta["checksums"]
            arrays = {name: np.array(z[name]) for name in sums}
    except Exception as exc:  # noqa: BLE001 - any failure to read a cache file means: build it again
        warnings.warn(f"rebuilding the cached {kind} in {path}: unreadable ({type(exc).__name__}: {exc})",
                      CacheRebuildWarning, stacklevel=3)
        return None
    bad = [name for name, arr in arrays.items() if array_checksum(arr) != sums[name]]
    if bad:
        warnings.warn(f"rebuilding the cached {kind} in {path}: {', '.join(bad)} do not match their checksums "
                      "(damaged)", CacheRebuildWarning, stacklevel=3)
        return None
    return arrays


def write_entry(path: Path, kind: str, key: str, arrays: Mapping[str, NDArray[Any]]) -> None:
    """Store ``arrays`` under ``kind`` and ``key`` at ``path``, atomically, with their checksums (module
    docstring). Raises what writing raises (``OSError``, :class:`~skyscatter.errors.OutputError`)."""
    meta = {"kind": kind, "key": key,
            "checksums": {name: array_checksum(np.asarray(arr)) for name, arr in arrays.items()}}
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        stored: dict[str, Any] = {"metadata": np.array(json.dumps(meta, sort_keys=True)), **arrays}
        np.savez(fh, **stored)


def cached_arrays(kind: str, key: str, build: Callable[[], Mapping[str, NDArray[Any]]]
                  ) -> dict[str, NDArray[Any]]:
    """The arrays of the entry ``kind`` / ``key`` from the disk cache, else ``build()`` and stored (module
    docstring: verified when read, written atomically, built once by processes that need it at once). An
    unwritable cache folder costs a warning and a rebuild in the next process, never the result."""
    path = cache_entry_path(kind, key)
    found = read_entry(path, kind, key)
    if found is not None:
        return found
    with build_lock(path):
        found = read_entry(path, kind, key)  # built by another process while this one waited
        if found is not None:
            return found
        arrays = {name: np.asarray(arr) for name, arr in build().items()}
        try:
            write_entry(path, kind, key, arrays)
        except Exception as exc:  # noqa: BLE001 - the cache is an optimisation: failing to store is a warning
            warnings.warn(f"the {kind} could not be cached in {path.parent} ({exc}); it is rebuilt in every "
                          "process", RuntimeWarning, stacklevel=2)
    return arrays
