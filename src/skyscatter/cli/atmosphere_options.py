"""The atmosphere's options of every command that builds an atmosphere, generated from one list.

The flags, units, ranges and help texts come from :data:`skyscatter.atmosphere.options.ATMOSPHERE_OPTIONS`; the
values are applied by :meth:`AtmosphereParameters.from_options <skyscatter.atmosphere.AtmosphereParameters
.from_options>`. ``sky`` and ``illuminance`` get the same options through the Bruneton model's registry spec, which
lists the same parameters. Deprecated spellings of options (kept for one release) print one warning line.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterable
from typing import Any

from ..atmosphere.options import ATMOSPHERE_OPTIONS, atmosphere_option
from ..errors import InvalidParameterError
from .sky_options import add_option

__all__ = ["DeprecatedOption", "add_atmosphere_options", "add_deprecated_option", "atmosphere_from_args",
           "atmosphere_values"]

#: The names of every atmosphere option.
NAMES = tuple(p.name for p in ATMOSPHERE_OPTIONS)


class DeprecatedOption(argparse.Action):
    """An old spelling of an option: stores into the new option's ``dest`` and prints one warning line."""

    def __init__(self, option_strings: list[str], dest: str, *, new: str, **kwargs: Any) -> None:
        self.new = new
        super().__init__(option_strings, dest, **kwargs)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any,
                 option_string: str | None = None) -> None:
        print(f"skyscatter: warning: {option_string} is deprecated and will be removed in the next release; use "
              f"{self.new}", file=sys.stderr)
        setattr(namespace, self.dest, values)


def add_deprecated_option(group: Any, old: str, new: str, dest: str, **kwargs: Any) -> None:
    """A hidden option ``old`` that stores into ``dest`` (the option ``new``'s) with a deprecation line."""
    group.add_argument(old, dest=dest, action=DeprecatedOption, new=new, help=argparse.SUPPRESS, **kwargs)


def add_atmosphere_options(group: Any, names: Iterable[str] = NAMES) -> None:
    """Add the options ``names`` of :data:`ATMOSPHERE_OPTIONS` to ``group`` (a parser or an argument group)."""
    names = tuple(names)
    for name in names:
        add_option(group, [("atmosphere", atmosphere_option(name))], label=False)
    group.set_defaults(_atmosphere_options=tuple(names))


def atmosphere_values(args: argparse.Namespace, names: Iterable[str] = NAMES) -> dict[str, Any]:
    """The atmosphere options given on the command line (checked against their ranges), by keyword name."""
    out: dict[str, Any] = {}
    for name in names:
        value = getattr(args, name, None)
        if value is not None:
            p = atmosphere_option(name)
            try:
                out[name] = p.check(value)
            except InvalidParameterError as exc:
                raise InvalidParameterError(f"{p.cli_flag} {value}: {str(exc).split(' ', 1)[-1]}") from None
    return out


def atmosphere_from_args(args: argparse.Namespace, **changes: Any):
    """The :class:`~skyscatter.atmosphere.AtmosphereParameters` the options describe, with ``changes`` (fields of
    the medium the command sets itself, such as ``max_sun_zenith``)."""
    from ..atmosphere import AtmosphereParameters

    params = AtmosphereParameters.from_options(**atmosphere_values(args, getattr(args, "_atmosphere_options", NAMES)))
    return params.replace(**changes) if changes else params
