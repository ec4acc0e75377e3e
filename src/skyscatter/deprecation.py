"""Old spellings kept for one release: a keyword renamed, with a :class:`DeprecationWarning` naming the new one.

The names fixed by the glossary (docs/conventions.md, "Glossary") replaced some earlier ones; code written with the
earlier ones keeps working until the next release, and says what to write instead.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable, Mapping
from typing import Any, TypeVar

from .errors import InvalidParameterError

__all__ = ["rename", "renamed_keywords", "warn_renamed"]

F = TypeVar("F", bound=Callable[..., Any])


def warn_renamed(old: str, new: str, where: str, *, stacklevel: int = 3) -> None:
    """Warn that ``old`` (a keyword, an option, a saved key) is now ``new`` in ``where``."""
    warnings.warn(f"{where}: {old} is deprecated and will be removed in the next release; use {new}",
                  DeprecationWarning, stacklevel=stacklevel)


def rename(values: dict[str, Any], renames: Mapping[str, str], where: str, *, stacklevel: int = 4) -> dict[str, Any]:
    """``values`` with each old key of ``renames`` (old -> new) moved to its new key, warning once per old key.

    Giving both spellings is an :class:`InvalidParameterError`.
    """
    out = dict(values)
    for old, new in renames.items():
        if old in out:
            if new in out:
                raise InvalidParameterError(f"{where}: give {new} only ({old} is its deprecated spelling)")
            warn_renamed(old, new, where, stacklevel=stacklevel)
            out[new] = out.pop(old)
    return out


def renamed_keywords(**renames: str) -> Callable[[F], F]:
    """Decorator: accept each ``old=new`` keyword's old spelling, with a DeprecationWarning."""

    def decorate(func: F) -> F:
        where = func.__qualname__.replace(".__init__", "")

        @functools.wraps(func)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            if not renames.keys().isdisjoint(kwargs):
                kwargs = rename(kwargs, renames, where)
            return func(*args, **kwargs)

        return wrapper  # type: ignore[return-value]

    return decorate
