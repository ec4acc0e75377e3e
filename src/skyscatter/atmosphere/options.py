"""The atmosphere from a user's options: the one list of options and the one function that applies them.

:data:`ATMOSPHERE_OPTIONS` declares each option once (name, unit, valid range, command-line flag, help); the
Bruneton sky model's registry spec, every command that builds an atmosphere (``sky``, ``illuminance``, ``demo``,
``precompute``, ``export-luts``, ``fit-hosek-wilkie``) and :func:`atmosphere_from_options` (also
:meth:`AtmosphereParameters.from_options <skyscatter.atmosphere.AtmosphereParameters.from_options>`) read it.

The aerosol is given one of three ways: Linke-style ``turbidity`` ([Preetham1999] A.1: Angstrom alpha 1.3,
beta 0.04608 T - 0.04586), ``aerosol_optical_depth`` at 550 nm with ``angstrom_alpha`` ([Angstrom1929]; alpha
1.3 by default), or an OPAC ``aerosol_type`` ([Hess1998]) with its optical depth at 550 nm. The options change
the Earth defaults, or the atmosphere given as ``base``, or the air read from ``atmosphere_file``.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

from ..errors import InvalidParameterError
from ..validation import Parameter

if TYPE_CHECKING:
    from .medium import AtmosphereParameters

__all__ = ["ATMOSPHERE_OPTIONS", "atmosphere_from_options", "atmosphere_option"]


def _aerosol_types() -> tuple[str, ...]:
    from .aerosol_types import AEROSOL_TYPES  # deferred: the OPAC tables are read only when an option needs them

    return tuple(AEROSOL_TYPES)


#: The options that describe an atmosphere (keyword name = :func:`atmosphere_from_options` argument).
ATMOSPHERE_OPTIONS: tuple[Parameter, ...] = (
    Parameter("turbidity", "1", None, "aerosols from turbidity (Preetham 1999 A.1: Angstrom alpha 1.3, beta "
              "0.04608 T - 0.04586; default: the Earth defaults' light aerosol, optical depth 0.0053)",
              low=1.0, high=20.0),
    Parameter("aerosol_optical_depth", "1", None, "vertical aerosol optical depth at 550 nm (instead of "
              "--turbidity)", low=0.0, high=10.0, flag="--aod"),
    Parameter("angstrom_alpha", "1", None, "Angstrom exponent of the aerosol optical depth (with --aod; default "
              "1.3)", low=-1.0, high=4.0),
    Parameter("ground_albedo", "1", None, "albedo of the atmosphere's ground (Lambertian, the same at every "
              "wavelength; default 0.1)", low=0.0, high=1.0),
    Parameter("ozone_column", "DU", None, "total ozone column (default 300)", low=0.0, high=1000.0, flag="--ozone"),
    Parameter("mie_phase_g", "1", None, "asymmetry g of the aerosol phase function (Cornette-Shanks; default 0.8)",
              low=-0.99, high=0.99, flag="--mie-g"),
    Parameter("aerosol_type", "", None, "OPAC aerosol type with Mie optics (Hess et al. 1998; with --aod its "
              "optical depth at 550 nm, else the type's own)", kind="choice", choices=(), flag="--aerosol"),
    Parameter("atmosphere_file", "", None, "the air from a JSON file [.json] (written by 'skyscatter "
              "fit-atmosphere' or AtmosphereParameters.save_json); the other options change it", kind="path",
              flag="--atmosphere"),
)


def _with_choices(p: Parameter) -> Parameter:
    if p.name == "aerosol_type":
        return dataclasses.replace(p, choices=_aerosol_types())
    return p


def atmosphere_option(name: str) -> Parameter:
    """The :class:`~skyscatter.validation.Parameter` of one atmosphere option (choices filled in)."""
    for p in ATMOSPHERE_OPTIONS:
        if p.name == name:
            return _with_choices(p)
    raise InvalidParameterError(f"no atmosphere option {name!r}; the options are: "
                                + ", ".join(p.name for p in ATMOSPHERE_OPTIONS))


def atmosphere_from_options(base: AtmosphereParameters | None = None, *, turbidity: float | None = None,
                            aerosol_optical_depth: float | None = None, angstrom_alpha: float | None = None,
                            ground_albedo: float | None = None, ozone_column: float | None = None,
                            mie_phase_g: float | None = None, aerosol_type: str | None = None,
                            atmosphere_file: str | None = None) -> AtmosphereParameters:
    """The atmosphere the options describe: ``base`` (default: the Earth defaults), or the air of
    ``atmosphere_file``, with each option given (not None) changed.

    Every value is checked against :data:`ATMOSPHERE_OPTIONS`. ``turbidity`` and ``aerosol_optical_depth``
    exclude each other; ``angstrom_alpha`` goes with ``aerosol_optical_depth``; ``aerosol_type`` takes
    ``aerosol_optical_depth`` only. An aerosol from the options replaces the base's aerosol (its Angstrom fields
    and any particle component in ``aerosol``); the other fields of the base are kept.
    """
    # deferred: the option list alone (a command's --help, the registry) needs neither the medium nor the formulas
    from .medium import AtmosphereParameters
    from .turbidity import ANGSTROM_ALPHA, angstrom_beta, angstrom_beta_from_optical_depth

    given = {k: v for k, v in (("turbidity", turbidity), ("aerosol_optical_depth", aerosol_optical_depth),
                               ("angstrom_alpha", angstrom_alpha), ("ground_albedo", ground_albedo),
                               ("ozone_column", ozone_column), ("mie_phase_g", mie_phase_g),
                               ("aerosol_type", aerosol_type), ("atmosphere_file", atmosphere_file)) if v is not None}
    values: dict[str, Any] = {k: atmosphere_option(k).check(v) for k, v in given.items()}
    if base is not None and not isinstance(base, AtmosphereParameters):
        raise InvalidParameterError(f"the atmosphere must be AtmosphereParameters or None; got {type(base).__name__}")
    if "atmosphere_file" in values:
        if base is not None:
            raise InvalidParameterError("give either an atmosphere or atmosphere_file, not both")
        base = AtmosphereParameters.load_json(values["atmosphere_file"])
    base = AtmosphereParameters() if base is None else base
    if "turbidity" in values and "aerosol_optical_depth" in values:
        raise InvalidParameterError("give either turbidity or aerosol_optical_depth, not both")
    changes: dict[str, Any] = {k: values[k] for k in ("ground_albedo", "ozone_column", "mie_phase_g") if k in values}
    if "aerosol_type" in values:
        if "turbidity" in values or "angstrom_alpha" in values:
            raise InvalidParameterError("an aerosol type takes --aod (its optical depth at 550 nm), not turbidity "
                                        "or angstrom_alpha")
        from .aerosol_types import OpacAerosol  # deferred: Mie optics of the OPAC components

        changes["aerosol"] = OpacAerosol.preset(values["aerosol_type"], values.get("aerosol_optical_depth"),
                                                column_height=base.thickness)
        return base.replace(**changes)
    if "angstrom_alpha" in values and "aerosol_optical_depth" not in values:
        raise InvalidParameterError("angstrom_alpha goes with aerosol_optical_depth")
    if "turbidity" in values or "aerosol_optical_depth" in values:
        if "turbidity" in values:
            alpha, beta = ANGSTROM_ALPHA, float(angstrom_beta(values["turbidity"]))
        else:
            alpha = values.get("angstrom_alpha", ANGSTROM_ALPHA)
            beta = angstrom_beta_from_optical_depth(values["aerosol_optical_depth"], alpha)
        # the Angstrom aerosol of the options replaces a component aerosol of the base
        changes.update(mie_angstrom_alpha=alpha, mie_angstrom_beta=beta, aerosol=None)
    return base.replace(**changes) if changes else base
