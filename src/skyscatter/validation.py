"""Input rules stated once: a parameter's type and valid range (:class:`Parameter`), and whole numbers.

Every range a user can meet is declared once, as a :class:`Parameter` (the sky models' in
:mod:`skyscatter.sky.registry`, the atmosphere's options in :mod:`skyscatter.atmosphere.options`); the classes,
the registry and the command line all check values with :meth:`Parameter.check`, and help texts print
:meth:`Parameter.range_text`. :func:`whole_number` is the one check of a count (an int, not a bool).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .conventions import check_daylight_limit
from .errors import InvalidParameterError

__all__ = ["Parameter", "whole_number"]


def whole_number(name: str, value: Any, low: int | None = None, high: float | None = None, *,
                 integral_floats: bool = False) -> int:
    """``value`` as an int in [low, high]; :class:`InvalidParameterError` naming ``name`` otherwise.

    A bool is refused (``True`` is an int to Python, never a count to a user). Python and numpy integers are
    accepted; floats only with ``integral_floats`` and only when whole (``2.0``).
    """
    ok = not isinstance(value, bool)
    if ok and isinstance(value, (int, np.integer)):
        number = int(value)
    elif ok and integral_floats and isinstance(value, (float, np.floating)) and math.isfinite(value) \
            and float(value).is_integer():
        number = int(value)
    else:
        ok = False
    if ok:
        ok = (low is None or number >= low) and (high is None or number <= high)
    if not ok:
        if low is not None and high is not None:
            bounds = f" in [{low}, {high:.6g}]"
        elif low is not None:
            bounds = f" >= {low}"
        elif high is not None:
            bounds = f" <= {high:.6g}"
        else:
            bounds = ""
        raise InvalidParameterError(f"{name} must be a whole number{bounds}; got {value!r}")
    return number


@dataclass(frozen=True)
class Parameter:
    """One input of the library: a keyword argument of a sky model or of the atmosphere, with its valid range.

    Attributes
    ----------
    name : str
        Keyword name in the Python API.
    unit : str
        SI unit, ``"1"`` for dimensionless numbers, ``""`` for non-numeric values.
    default : Any
        Value used when the parameter is not given (None: optional, the model decides).
    help : str
        One line for documentation and ``--help``.
    kind : {"float", "int", "bool", "choice", "path", "atmosphere", "object"}
        Value type (``"path"``: a file name). ``"atmosphere"`` is an
        :class:`~skyscatter.atmosphere.AtmosphereParameters` or precomputed
        tables (serialised through the parameters' ``to_dict``); ``"object"`` a skyscatter object with
        ``to_dict`` / ``from_dict`` (such as a fitted dataset).
    low, high : float or None
        Inclusive valid range of numeric values (None: unbounded on that side).
    choices : tuple
        Allowed values of a ``"choice"`` parameter.
    flag : str or None
        Command-line flag; default ``--name-with-dashes``. ``cli=False`` keeps the parameter out of the CLI.
    low_open : bool
        True when ``low`` itself is excluded (the value must be greater than ``low``).
    why : str
        Where the range comes from (a physical limit, the publication's validity), quoted in error messages.
    """

    name: str
    unit: str
    default: Any = None
    help: str = ""
    kind: str = "float"
    low: float | None = None
    high: float | None = None
    choices: tuple = ()
    flag: str | None = None
    cli: bool = True
    low_open: bool = False
    why: str = ""

    @property
    def cli_flag(self) -> str:
        return self.flag or "--" + self.name.replace("_", "-")

    def range_text(self, *, with_unit: bool = True) -> str:
        """Human-readable valid range with unit, e.g. ``"1.65 to 11"`` or ``">= 0 lx"``."""
        unit = "" if self.unit in ("1", "") or not with_unit else f" {self.unit}"
        if self.kind == "choice":
            return "one of " + ", ".join(map(str, self.choices))
        if self.low is not None and self.high is not None:
            return f"{'above ' if self.low_open else ''}{self.low:g} to {self.high:g}{unit}"
        if self.low is not None:
            return f"{'>' if self.low_open else '>='} {self.low:g}{unit}"
        if self.high is not None:
            return f"<= {self.high:g}{unit}"
        return f"any finite value{unit}" if self.kind in ("float", "int") else ""

    def check(self, value: Any, model: str = "", *, ranges: bool = True) -> Any:
        """Validate one value (type, finiteness and, with ``ranges``, the range); return it converted.

        ``model`` prefixes the messages (``"preetham: turbidity ..."``). The sky-model classes and
        :meth:`AtmosphereParameters.from_options <skyscatter.atmosphere.AtmosphereParameters.from_options>` check
        their inputs with the same rule; the command line checks the ranges here first so that it can refuse a
        value before any work, and the conformance suite checks that spec and class agree.
        """
        if value is None:
            return None
        where = f"{model}: {self.name}" if model else self.name
        if self.kind in ("float", "int"):
            what = "a whole number" if self.kind == "int" else f"a number [{self.unit}]"
            if isinstance(value, (bool, np.bool_, str)):
                raise InvalidParameterError(f"{where} must be {what}; got {value!r}")
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise InvalidParameterError(f"{where} must be {what}; got {value!r}") from None
            if not math.isfinite(number):
                raise InvalidParameterError(f"{where} must be finite; got {value!r}")
            if self.kind == "int":
                if number != int(number):
                    raise InvalidParameterError(f"{where} must be a whole number; got {value!r}")
                number = int(number)
            below = self.low is not None and (number <= self.low if self.low_open else number < self.low)
            outside = below or (self.high is not None and number > self.high)
            if ranges and outside:
                if self.high is not None and number > self.high:
                    check_daylight_limit(self.name, number, self.unit)  # the physical limit, named with its source
                reason = f" ({self.why})" if self.why else ""
                unit = "" if self.unit in ("1", "") else f" {self.unit}"
                raise InvalidParameterError(f"{where} {number:g}{unit} is outside {self.range_text()}{reason}")
            return number
        if self.kind == "bool":
            if not isinstance(value, bool):
                raise InvalidParameterError(f"{where} must be True or False; got {value!r}")
            return value
        if self.kind == "choice":
            if value not in self.choices:
                raise InvalidParameterError(f"{where} must be {self.range_text()}; got {value!r}")
            return value
        if self.kind == "path":
            if not isinstance(value, str) or not value:
                raise InvalidParameterError(f"{where} must be a file name; got {value!r}")
            return value
        return value
