"""Radiance's matrix files: what ``rmtxop``, ``dctimestep`` and ``rcollate`` read, what ``gendaymtx`` writes.

A matrix file ([RadianceSource2025], the header written by ``gendaymtx`` and read by ``rmtxop``/``dctimestep``)
is a text header

::

    #?RADIANCE
    <free lines: the command that made it, ...>
    NROWS=<rows>
    NCOLS=<columns>
    NCOMP=<components per entry, 3 for RGB>
    [BYTEORDER=LittleEndian]          (binary data only)
    FORMAT=ascii | float | double
    <empty line>

followed by the entries row after row, column after column, component after component: ``rows x columns x
components`` numbers (ASCII separated by white space, or little-endian IEEE floats). A sky matrix is patches x time
steps x RGB, with the ground patch first (:meth:`skyscatter.sky_matrix.SkyMatrix.save_radiance`): the layout
:func:`write_radiance_matrix` takes, for any (rows, columns, components) array (spectral matrices too).

Colours are Radiance RGB radiances [W sr^-1 m^-2] with 179 lm/W (:func:`skyscatter.spectral.xyz_to_radiance_rgb`).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import FileFormatError, InvalidParameterError
from .fileio import atomic_path

__all__ = ["ENCODINGS", "read_radiance_matrix", "write_radiance_matrix"]

#: Encodings of the data: ``FORMAT=`` value -> numpy dtype (None: text).
ENCODINGS = {"ascii": None, "float": np.dtype("<f4"), "double": np.dtype("<f8")}
#: Rows of values written per step in ASCII (bounds the working memory).
_ASCII_CHUNK = 4096


def write_radiance_matrix(path: str | os.PathLike[str], values: ArrayLike, *, header: list[str] | tuple[str, ...] = (),
                          encoding: str = "float", atomic: bool = True, allow_nan: bool = False) -> Path:
    """Write ``values`` (rows, columns, components) as a Radiance matrix file, atomically; returns the path.

    Parameters
    ----------
    path : path
        The file (any name; Radiance's tools use ``.mtx``, ``.smx`` for sky matrices).
    values : array_like, shape (rows, columns, components)
        The entries; a sky matrix is patches x time steps x RGB (ground patch first). Finite numbers only.
    header : sequence of str
        Extra header lines (each one line, no ``NROWS=``-style keys of this function's own).
    encoding : {"float", "double", "ascii"}
        Little-endian 32- or 64-bit floats (compact and fast; every Radiance tool reads them) or text
        (``%.6g``, what ``gendaymtx`` writes by default; about 10 times larger and slower).
    atomic : bool
        Write through a temporary file renamed into place (default). False writes ``path`` directly: for a
        temporary of a group already written atomically (:func:`skyscatter.fileio.atomic_paths`).
    allow_nan : bool
        Let NaN through (a spectral sky matrix marks the hours it could not retrieve with NaN, so that nothing
        downstream mistakes them for a sky); infinities are still refused.

    Raises
    ------
    InvalidParameterError
        A bad array, header line or encoding.
    OutputError
        The file cannot be written (nothing is left behind).
    """
    if encoding not in ENCODINGS:
        raise InvalidParameterError(f"encoding must be one of {', '.join(ENCODINGS)}; got {encoding!r}")
    a = np.asarray(values, dtype=float)
    if a.ndim != 3 or min(a.shape) < 1:
        raise InvalidParameterError(f"a Radiance matrix is (rows, columns, components) with each >= 1; got {a.shape}")
    if not np.all(np.isfinite(a) | (allow_nan & np.isnan(a))):
        raise InvalidParameterError("a Radiance matrix must hold finite numbers; got NaN or infinite values")
    lines = ["#?RADIANCE"]
    for line in header:
        text = str(line)
        if "\n" in text or not text.strip() or text.split("=", 1)[0] in ("NROWS", "NCOLS", "NCOMP", "FORMAT",
                                                                       "BYTEORDER"):
            raise InvalidParameterError(f"header lines must be single, non-empty lines without the matrix keys; "
                                        f"got {text!r}")
        lines.append(text)
    rows, cols, comps = a.shape
    lines += [f"NROWS={rows}", f"NCOLS={cols}", f"NCOMP={comps}"]
    dtype = ENCODINGS[encoding]
    if dtype is not None:
        lines.append("BYTEORDER=LittleEndian")
    lines.append(f"FORMAT={encoding}")
    head = ("\n".join(lines) + "\n\n").encode("ascii")
    target = Path(path)
    if not atomic:
        _write(target, head, a, dtype)
        return target
    with atomic_path(target) as tmp:
        _write(tmp, head, a, dtype)
    return target


def _write(path: Path, head: bytes, a: NDArray[np.float64], dtype) -> None:
    with open(path, "wb") as fh:
        fh.write(head)
        if dtype is not None:
            fh.write(memoryview(np.ascontiguousarray(a, dtype=dtype)).cast("B"))
            return
        rows, cols, comps = a.shape
        flat = a.reshape(rows * cols, comps)
        fmt = " ".join(["%.6g"] * comps)
        for start in range(0, flat.shape[0], _ASCII_CHUNK):
            block = flat[start:start + _ASCII_CHUNK]
            fh.write(("\n".join(fmt % tuple(r) for r in block.tolist()) + "\n").encode("ascii"))


def read_radiance_matrix(path: str | os.PathLike[str]) -> tuple[NDArray[np.float64], dict[str, str]]:
    """Read a Radiance matrix file (ASCII, float or double, either byte order): (values (rows, columns,
    components), header as ``KEY -> value`` for its ``KEY=value`` lines).

    Raises
    ------
    FileFormatError
        Not a Radiance matrix, or its data do not match its header.
    """
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot read: {exc.strerror or exc}") from None
    end = raw.find(b"\n\n")
    if not raw.startswith(b"#?RADIANCE") or end < 0:
        raise FileFormatError(f"{p}: not a Radiance matrix (no '#?RADIANCE' header ending in an empty line)")
    keys: dict[str, str] = {}
    for line in raw[:end].decode("latin-1").splitlines()[1:]:
        if "=" in line:
            k, v = line.split("=", 1)
            keys[k.strip()] = v.strip()
    try:
        rows, cols, comps = (int(keys[k]) for k in ("NROWS", "NCOLS", "NCOMP"))
    except (KeyError, ValueError):
        raise FileFormatError(f"{p}: the header lacks NROWS, NCOLS or NCOMP") from None
    fmt = keys.get("FORMAT", "ascii")
    body = raw[end + 2:]
    n = rows * cols * comps
    if fmt == "ascii":
        values = np.array(body.split(), dtype=float)
    elif fmt in ("float", "double"):
        order = "<" if keys.get("BYTEORDER", "LittleEndian" if sys.byteorder == "little" else "BigEndian"
                                ).startswith("Little") else ">"
        dtype = np.dtype(f"{order}{'f4' if fmt == 'float' else 'f8'}")
        if len(body) != n * dtype.itemsize:
            raise FileFormatError(f"{p}: {len(body)} data bytes; the header's {rows} x {cols} x {comps} {fmt} "
                                  f"entries need {n * dtype.itemsize}")
        values = np.frombuffer(body, dtype=dtype).astype(float)
    else:
        raise FileFormatError(f"{p}: FORMAT={fmt}; this reader knows ascii, float and double")
    if values.size != n:
        raise FileFormatError(f"{p}: {values.size} numbers; the header's {rows} x {cols} x {comps} need {n}")
    return values.reshape(rows, cols, comps), keys
