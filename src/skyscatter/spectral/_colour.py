"""The CIE tables skyscatter ships, and the one place that imports colour-science.

The tables the spectral pipeline reads at run time (CIE 1931 2-degree colour-matching functions, CIE daylight
basis S0, S1, S2) are package data (``skyscatter/data/cie*.csv``), generated from colour-science by
``tools/generate_cie_tables.py`` and checked equal to colour-science's in the tests: importing colour-science
takes seconds (it imports matplotlib), which the command line should not pay. colour-science itself is imported
only where a caller asks for it (:func:`colour_module`), without its warning that matplotlib is missing.
"""

from __future__ import annotations

import importlib
import warnings
from functools import cache
from importlib import resources
from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from ..errors import FileFormatError


@cache
def cie_table(name: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(wavelengths [nm], values (n, k)) of the shipped CIE table ``skyscatter/data/<name>.csv``.

    Lines starting with ``#`` cite the source; the first other line names the columns.
    """
    try:
        with resources.files("skyscatter.data").joinpath(f"{name}.csv").open("r", encoding="utf-8") as fh:
            data = np.loadtxt(fh, delimiter=",", comments="#", skiprows=3, ndmin=2)
    except (FileNotFoundError, ModuleNotFoundError, ValueError) as exc:
        raise FileFormatError(f"data table {name}.csv of the skyscatter package is missing or damaged: {exc}") from exc
    data.setflags(write=False)
    return data[:, 0], data[:, 1:]


def colour_module(name: str = "colour") -> ModuleType:
    """Import ``name`` (colour or one of its submodules) with colour's optional-dependency warnings silenced."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*Matplotlib.*related API features are not available.*")
        return importlib.import_module(name)
