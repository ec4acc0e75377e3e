"""Published data tables shipped as CSV files in ``skyscatter/data`` (each file's header names its source).

The one loader of the package's data files (Preetham's tables, the CIE sky types, the Perez coefficients, the
ASTM G173 solar spectrum, the Serdyuchenko ozone cross-sections).

Tables are read once with :mod:`importlib.resources` and cached; the returned arrays are read-only so a
caller cannot corrupt the cache.
"""

from __future__ import annotations

import csv
import io
from functools import cache
from importlib import resources

import numpy as np
from numpy.typing import NDArray

from ..errors import FileFormatError

__all__ = ["load_table"]


@cache
def load_table(name: str) -> dict[str, NDArray[np.float64]]:
    """Columns of the data file ``skyscatter/data/<name>.csv`` as read-only float arrays.

    Lines starting with ``#`` are comments (the source citation); the first other line holds the column
    names. Empty cells become NaN (the table gives no value there).

    Raises
    ------
    FileFormatError
        If the file is missing, a row has the wrong number of cells or a cell is not a number.
    """
    try:
        text = resources.files("skyscatter.data").joinpath(f"{name}.csv").read_text(encoding="utf-8")
    except (FileNotFoundError, ModuleNotFoundError) as exc:
        raise FileFormatError(f"data table {name}.csv is missing from the skyscatter package") from exc
    lines = [line for line in text.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    rows = list(csv.reader(io.StringIO("\n".join(lines))))
    if len(rows) < 2:
        raise FileFormatError(f"{name}.csv: expected a header line and at least one data row")
    header, body = rows[0], rows[1:]
    values = np.empty((len(body), len(header)))
    for i, row in enumerate(body):
        if len(row) != len(header):
            raise FileFormatError(
                f"{name}.csv: data row {i + 1} has {len(row)} cells, expected {len(header)}"
            )
        for j, cell in enumerate(row):
            try:
                values[i, j] = float(cell) if cell.strip() else np.nan
            except ValueError:
                raise FileFormatError(
                    f"{name}.csv: data row {i + 1}, column {header[j]!r}: {cell!r} is not a number"
                ) from None
    columns = {}
    for j, column in enumerate(header):
        arr = values[:, j].copy()
        arr.flags.writeable = False
        columns[column.strip()] = arr
    return columns


def tabulated(
    name: str, column: str, *, key: str = "wavelength_nm"
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(key, value) arrays of one column with the rows where the column is empty left out."""
    table = load_table(name)
    mask = ~np.isnan(table[column])
    return table[key][mask], table[column][mask]
