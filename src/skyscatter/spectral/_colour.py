"""One place that imports colour-science.

colour-science is imported lazily (it takes about 2 s) and without its warning that matplotlib is missing:
skyscatter uses none of its plotting, and a plain install should not print that warning on every run.
"""

from __future__ import annotations

import importlib
import warnings
from types import ModuleType


def colour_module(name: str = "colour") -> ModuleType:
    """Import ``name`` (colour or one of its submodules) with colour's optional-dependency warnings silenced."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*Matplotlib.*related API features are not available.*")
        return importlib.import_module(name)
