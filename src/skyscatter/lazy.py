"""The one lazy-import mechanism: namespaces that import their public names on first use (PEP 562).

``import skyscatter``, ``skyscatter.sun``, ``skyscatter.atmosphere``, ``skyscatter.sky`` and ``skyscatter.render``
stay quick, and importing one submodule (the sun's position, the air mass) does not import its siblings (the
spectral sunlight, the medium): a quick command line (docs/architecture.md, "Start-up"). The numba versions of the
phase functions are built on first use the same way.

Every namespace that uses it also imports the same names under ``if TYPE_CHECKING:``, so that type checkers see
the real classes and signatures (``skyscatter.PreethamSky("2.5", ...)`` is flagged) while nothing is imported at
run time; ``tests/test_imports.py`` checks that the two lists agree.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable, Mapping
from typing import Any

__all__ = ["lazy_namespace"]


def lazy_namespace(namespace: dict[str, Any], names: Mapping[str, str], submodules: Iterable[str] = ()
                   ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for the module whose ``globals()`` is ``namespace``.

    ``names`` maps each public name to the module that defines it, relative to the module's package
    (``{"sun_position": "sun.position"}`` in ``skyscatter``; a leading dot goes one package up: ``{"BrunetonSky":
    ".sky.bruneton"}`` for the alias in ``skyscatter.precomputed``); a name is imported on first access and then
    kept in the namespace. ``submodules`` (of a package) are returned, imported, as attributes.
    """
    package = namespace.get("__package__") or namespace["__name__"]
    module_name = namespace["__name__"]
    subs = frozenset(submodules)

    def __getattr__(name: str) -> Any:  # noqa: N807 - the module hook's name
        if name in names:
            value = getattr(importlib.import_module("." + names[name], package), name)
            namespace[name] = value
            return value
        if name in subs:
            return importlib.import_module(f"{module_name}.{name}")
        raise AttributeError(f"module {module_name!r} has no attribute {name!r}")

    def __dir__() -> list[str]:  # noqa: N807
        return sorted({*namespace.get("__all__", ()), *names, *subs})

    return __getattr__, __dir__
