"""Storing the tables: their identity (the cache key), the ``.npz`` file format, writing and verified reading.

A table file is an ``.npz`` archive with one array per name of :data:`TABLE_NAMES` and ``metadata``, a JSON text:
format name and :data:`FORMAT_VERSION`, library version, the key of :func:`cache_key`, the atmosphere
(:meth:`.AtmosphereParameters.to_dict`), orders, wavelengths [nm], sizes, a SHA-256 checksum per table and the
timings of the computation. :func:`read_tables` checks all of it before the tables are used.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ..errors import FileFormatError, InvalidParameterError
from ..fileio import atomic_path
from .parameters import AtmosphereParameters
from .sizes import TableSizes

if TYPE_CHECKING:
    from .tables import PrecomputedAtmosphere

__all__ = ["FILE_FORMAT", "FORMAT_VERSION", "TABLE_NAMES", "cache_key", "checksum", "read_tables", "write_tables"]

#: Version of the table layout and algorithm; part of the cache key and checked by :func:`read_tables`.
FORMAT_VERSION = 5
#: The ``format`` entry of a table file's metadata.
FILE_FORMAT = "skyscatter-bruneton-tables"
#: The tables of a precomputed atmosphere, in file order (their content: :mod:`.tables`).
TABLE_NAMES = ("transmittance", "irradiance", "single_rayleigh", "single_mie", "multiple")


def checksum(arr: NDArray[Any]) -> str:
    """SHA-256 (hex) of an array's dtype, shape and bytes."""
    h = hashlib.sha256()
    h.update(f"{arr.dtype.str}{arr.shape}".encode())
    h.update(np.ascontiguousarray(arr).tobytes())
    return h.hexdigest()


def cache_key(atmosphere: AtmosphereParameters, orders: int, wavelengths: NDArray[np.float64],
              sizes: TableSizes) -> str:
    """SHA-256 (hex) of the parameters, orders, wavelengths, sizes, library version and table format."""
    from .. import __version__  # the package's __init__ imports this package's modules: read at call time

    described = atmosphere.to_dict()
    if described.get("mie_phase_function") == "cornette-shanks":
        # the phase function the tables had before the field existed: keep the keys of existing caches
        del described["mie_phase_function"]
    blob = json.dumps(
        {
            "params": described,  # the key of every cache written so far: not renamed
            "orders": int(orders),
            "wavelengths": [float(w) for w in wavelengths],
            "sizes": dataclasses.asdict(sizes),
            "version": __version__,
            "format": FORMAT_VERSION,
        },
        sort_keys=True,
        separators=(",", ":"),
    )
    return hashlib.sha256(blob.encode()).hexdigest()


def _metadata(atm: PrecomputedAtmosphere) -> dict[str, Any]:
    from .. import __version__  # as in cache_key

    return {
        "format": FILE_FORMAT,
        "format_version": FORMAT_VERSION,
        "library_version": __version__,
        "key": atm.cache_key,
        "parameters": atm.parameters.to_dict(),
        "orders": atm.orders,
        "wavelengths": [float(w) for w in atm.wavelengths],
        "sizes": dataclasses.asdict(atm.sizes),
        "checksums": {name: checksum(atm.tables[name]) for name in TABLE_NAMES},
        "timings": atm.timings,
    }


def write_tables(atm: PrecomputedAtmosphere, path: str | os.PathLike[str]) -> Path:
    """Write the tables and their description to an .npz file, atomically; returns the path."""
    target = Path(path)
    meta = json.dumps(_metadata(atm), sort_keys=True)
    with atomic_path(target) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, metadata=np.array(meta), **atm.tables)
    return target


def read_tables(cls: type[PrecomputedAtmosphere], path: str | os.PathLike[str], *,
                expected_key: str | None = None) -> PrecomputedAtmosphere:
    """Tables written by :func:`write_tables`, as a ``cls``, verifying format, shapes and checksums.

    Raises
    ------
    FileFormatError
        If the file is not a skyscatter table file, is damaged, was written by another format version, or
        (with ``expected_key``) holds other parameters.
    """
    p = Path(path)
    try:
        with np.load(p, allow_pickle=False) as data:
            meta = json.loads(str(data["metadata"][()]))
            arrays = {name: np.array(data[name]) for name in TABLE_NAMES}
    except FileNotFoundError:
        raise
    except KeyError as exc:
        raise FileFormatError(f"{p}: not a skyscatter table file (no table {exc})") from None
    except Exception:  # OSError, ValueError (NumPy's pickle advice), zipfile.BadZipFile, JSON errors...
        # NumPy's messages (e.g. "allow_pickle=True") would mislead: say what the file should be instead.
        raise FileFormatError(
            f"{p}: not a readable skyscatter table file (damaged, or not an .npz written by "
            "'skyscatter precompute --out' or PrecomputedAtmosphere.save)"
        ) from None
    if meta.get("format") != FILE_FORMAT:
        raise FileFormatError(f"{p}: not a skyscatter table file")
    if meta.get("format_version") != FORMAT_VERSION:
        raise FileFormatError(
            f"{p}: table format version {meta.get('format_version')} (this library reads {FORMAT_VERSION})"
        )
    for name in TABLE_NAMES:
        if checksum(arrays[name]) != meta["checksums"].get(name):
            raise FileFormatError(f"{p}: checksum mismatch in table {name!r} (file damaged)")
    try:
        atmosphere = AtmosphereParameters.from_dict(meta["parameters"])
        sizes = TableSizes(**meta["sizes"])
        atm = cls(atmosphere, meta["wavelengths"], sizes, meta["orders"], arrays, meta.get("timings"))
    except (KeyError, TypeError, InvalidParameterError) as exc:
        raise FileFormatError(f"{p}: inconsistent table description ({exc})") from None
    if atm.cache_key != meta.get("key"):
        raise FileFormatError(f"{p}: the stored key does not match the stored parameters")
    if expected_key is not None and meta.get("key") != expected_key:
        raise FileFormatError(f"{p}: tables were computed for other parameters, sizes or library version")
    return atm
