"""Package namespaces that import their public names on first use (PEP 562 module ``__getattr__``).

``import skyscatter``, ``skyscatter.sun`` and ``skyscatter.atmosphere`` stay quick, and importing one submodule
(the sun's position, the air mass) does not import its siblings (the spectral sunlight, the medium): a quick command
line (docs/architecture.md, "Start-up").
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable, Mapping
from typing import Any

__all__ = ["lazy_namespace"]


def lazy_namespace(namespace: dict[str, Any], names: Mapping[str, str], submodules: Iterable[str] = ()
                   ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for a package whose ``globals()`` is ``namespace``.

    ``names`` maps each public name to the module that defines it, relative to the package
    (``{"sun_position": "sun.position"}`` in ``skyscatter``); a name is imported on first access and then kept
    in the namespace. ``submodules`` are returned (imported) as attributes.
    """
    package = namespace["__name__"]
    subs = frozenset(submodules)

    def __getattr__(name: str) -> Any:  # noqa: N807 - the module hook's name
        if name in names:
            value = getattr(importlib.import_module(f"{package}.{names[name]}"), name)
            namespace[name] = value
            return value
        if name in subs:
            return importlib.import_module(f"{package}.{name}")
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:  # noqa: N807
        return sorted({*namespace.get("__all__", ()), *names, *subs})

    return __getattr__, __dir__
