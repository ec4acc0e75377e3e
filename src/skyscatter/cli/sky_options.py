"""Sky-model options of the commands that build a sky (``sky``, ``illuminance``, ``demo``), made from the registry.

Every ``--model`` choice and every model option comes from the specs in :mod:`skyscatter.sky.registry`: the flag,
unit, default and valid range of each parameter are declared there once. A flag shared by several models (such as
``--turbidity``) is one option whose help lists each model's default; a value is checked against the range of the
model actually chosen, before any work.
"""

from __future__ import annotations

import argparse
from collections.abc import Iterable
from typing import Any

from ..errors import InvalidParameterError
from .common import finite_float


def _parse_int(text: str) -> int:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if not value.is_integer():
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}")
    return int(value)


_PARSERS = {"float": finite_float, "int": _parse_int}


def _metavar(p) -> str:
    """Metavar from the unit (``cd m^-2`` -> ``CD_M2``), or the name for dimensionless parameters."""
    if p.unit in ("1", ""):
        return p.name.upper()
    return p.unit.replace("^-", "").replace("^", "").replace(" ", "_").upper()


def _specs(models: Iterable[str]):
    from ..sky import registry

    return [registry.get(m) for m in models]


def add_model_options(parser, models: list[str] | None = None, default: str | None = "preetham",
                      *, flag: str = "--model", dest: str = "model", shown_default: str | None = None,
                      shared: tuple[str, ...] = (), parameters_of: list[str] | None = None,
                      deprecated: bool = True) -> None:
    """``--model`` (one of ``models``, default: every registered model) and those models' parameters.

    ``parser`` is a parser or an argument group; ``flag`` and ``dest`` name the model option. ``shared`` names
    parameters the command already has as options of its own: no option is added for them, and their value goes
    to the models that take them. ``parameters_of`` limits the parameters added to those of some models (the
    demo gives the precomputed atmosphere's in a group of their own). With ``deprecated``, the old spellings of
    the models' parameters (``ModelSpec.renamed``: ``--albedo``, ``--wavelengths``) are accepted with a warning.
    """
    from ..sky import registry

    names = list(models) if models is not None else registry.names()
    specs = _specs(names)
    parser.add_argument(flag, dest=dest, choices=names, default=default,
                        help=f"sky model (default {shown_default or default}): "
                        + "; ".join(f"{s.name}: {s.summary}" for s in specs))
    # an argument group (the demo's scene options) takes the parameters itself: groups do not nest
    nested = isinstance(parser, argparse.ArgumentParser)
    group = parser.add_argument_group("model parameters (each applies to the models named)") if nested else parser
    by_flag: dict[str, list[tuple[str, Any]]] = {}
    old_flags: dict[str, Any] = {}
    for spec in specs if parameters_of is None else _specs(parameters_of):
        for p in spec.parameters:
            if p.cli and p.name not in shared:
                by_flag.setdefault(p.cli_flag, []).append((spec.name, p))
        for old, new in spec.renamed.items():
            if spec.parameter(new).cli and new not in shared:
                old_flags.setdefault("--" + old.replace("_", "-"), spec.parameter(new))
    for entries in by_flag.values():
        add_option(group, entries)
    if deprecated:
        from .atmosphere_options import add_deprecated_option

        for old_flag, p in old_flags.items():
            kind = {"choices": list(p.choices)} if p.kind == "choice" else {"type": _PARSERS.get(p.kind, str)}
            add_deprecated_option(group, old_flag, p.cli_flag, p.name, default=argparse.SUPPRESS, **kind)
    parser.set_defaults(_models=names, _model_dest=dest, _model_flag=flag, _model_shared=tuple(shared))


def add_option(group, entries: list[tuple[str, Any]], *, label: bool = True) -> None:
    """One option for a parameter shared by the models in ``entries`` ((model name, Parameter) pairs); ``label``
    names the models in the help text."""
    first = entries[0][1]
    cli_flag = first.cli_flag
    texts: dict[str, list[str]] = {}  # one text per distinct description, listing the models it applies to
    for model, p in entries:
        shown = p.default if isinstance(p.default, (int, float)) and not isinstance(p.default, bool) else None
        unit = "" if p.unit in ("1", "") else f" [{p.unit}]"
        allowed = p.range_text(with_unit=False)  # empty for a file name: no dangling colon
        text = f"{p.help}{unit}" + (f": {allowed}" if allowed else "") + (
            f" (default {shown:g})" if shown is not None else "")
        texts.setdefault(text, []).append(model)
    kwargs: dict[str, Any] = dict(dest=first.name, default=argparse.SUPPRESS,
                                  help="; ".join(f"{', '.join(m)}: {t}" if label else t for t, m in texts.items()))
    if first.kind == "choice":
        kwargs["choices"] = list(first.choices)
    else:
        kwargs["type"] = _PARSERS.get(first.kind, str)
        kwargs["metavar"] = _metavar(first)
    group.add_argument(cli_flag, **kwargs)


def add_parameter_options(group, model: str, names: Iterable[str]) -> None:
    """Options for the parameters ``names`` of one ``model`` alone (the demo's precomputed atmosphere)."""
    from ..sky import registry

    spec = registry.get(model)
    for p in spec.parameters:
        if p.name in names:
            add_option(group, [(model, p)])


def parameter_values(args: argparse.Namespace, model: str, names: Iterable[str]) -> dict[str, Any]:
    """The values given for the parameters ``names`` of ``model``, checked against its ranges."""
    from ..sky import registry

    out: dict[str, Any] = {}
    for p in registry.get(model).parameters:
        if p.name in names and getattr(args, p.name, None) is not None:
            value = getattr(args, p.name)
            try:
                out[p.name] = p.check(value, model)
            except InvalidParameterError as exc:
                raise InvalidParameterError(f"{p.cli_flag} {value}: {str(exc).split(': ', 1)[-1]}") from None
    return out


def model_options(args: argparse.Namespace) -> dict[str, Any]:
    """The parameters given for ``args.model``, range-checked; an option of another model is refused."""
    from ..sky import registry

    chosen = getattr(args, args._model_dest)
    spec = registry.get(chosen)
    own = {p.name: p for p in spec.parameters if p.cli}
    given: dict[str, Any] = {}
    for other in _specs(args._models):
        for p in other.parameters:
            if not p.cli or getattr(args, p.name, None) is None:
                continue
            if p.name in args._model_shared:  # the command's own option, passed on where the model takes it
                if p.name in own:
                    given[p.name] = own[p.name].check(getattr(args, p.name), spec.name)
                continue
            if p.name not in own:
                raise InvalidParameterError(f"{p.cli_flag}: does not apply to {args._model_flag} {chosen}")
            value = getattr(args, p.name)
            try:
                given[p.name] = own[p.name].check(value, spec.name)
            except InvalidParameterError as exc:
                raise InvalidParameterError(f"{p.cli_flag} {value}: {str(exc).split(': ', 1)[-1]}") from None
    return given


def build_sky_from_args(args: argparse.Namespace, sun_zenith: float, sun_azimuth: float):
    """The sky model chosen by ``--model`` with its options, for a sun at (zenith, azimuth) [rad]."""
    from ..sky import registry

    return registry.build(getattr(args, args._model_dest), sun_zenith, sun_azimuth, **model_options(args))
