"""Sky-model options shared by the commands that build a sky (``sky``, ``illuminance``)."""

from __future__ import annotations

import argparse

from .common import finite_float, float_in, select_model_options

#: Options each model takes (a model refuses options meant for another).
MODEL_OPTIONS: dict[str, set[str]] = {
    "preetham": {"turbidity"},
    "preetham-overcast": {"turbidity"},
    "cie": {"sky_type", "zenith_luminance", "diffuse_illuminance", "sun_illuminance_normal"},
    "cie-overcast": {"zenith_luminance", "diffuse_illuminance"},
    "cie-clear": {"zenith_luminance", "diffuse_illuminance", "sun_illuminance_normal"},
    "perez": {"epsilon", "delta", "diffuse_illuminance", "direct_normal_irradiance",
              "diffuse_horizontal_irradiance", "day_of_year", "dew_point"},
    "bruneton": {"altitude"},
    "hosek-wilkie": {"turbidity", "albedo"},
}


def _day_of_year(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole day number 1-366, got {text!r}") from None
    if not 1 <= value <= 366:
        raise argparse.ArgumentTypeError(f"expected a day number 1-366, got {value}")
    return value


# dest -> (flag, argparse keywords)
_OPTIONS: dict[str, tuple[str, dict]] = {
    "turbidity": ("--turbidity", dict(type=finite_float, metavar="T",
                  help="preetham: turbidity, 1.65 to 11 (default 2.5, a clear sky); preetham-overcast: 1.65 to 11, "
                  "blended into the CIE overcast sky from T = 6 to 10 (default 8); hosek-wilkie: 1 to 10 "
                  "(default 3)")),
    "albedo": ("--albedo", dict(type=float_in(0.0, 1.0), metavar="RHO",
               help="hosek-wilkie: ground albedo 0 to 1, all wavelengths (default 0.1)")),
    "sky_type": ("--sky-type", dict(type=int, choices=range(1, 16), metavar="N",
                 help="cie: CIE 2003 standard sky type 1-15 (default 12, the CIE clear sky)")),
    "zenith_luminance": ("--zenith-luminance", dict(type=finite_float, metavar="CD_M2",
                         help="cie*: zenith luminance [cd m^-2] (default: scale to 10000 lx diffuse)")),
    "diffuse_illuminance": ("--diffuse-illuminance", dict(type=finite_float, metavar="LX",
                            help="cie*, perez: horizontal diffuse illuminance [lx] to scale the sky to")),
    "sun_illuminance_normal": ("--sun-illuminance", dict(type=float_in(0, 2e5), metavar="LX",
                               help="cie, cie-clear: direct normal illuminance of the sun [lx] (default 0: the CIE "
                               "distributions describe the sky only, so no sun disc or direct light)")),
    "epsilon": ("--epsilon", dict(type=finite_float, help="perez: sky clearness epsilon, >= 1")),
    "delta": ("--delta", dict(type=finite_float, help="perez: sky brightness delta, >= 0")),
    "direct_normal_irradiance": ("--dni", dict(type=finite_float, metavar="W_M2",
                                 help="perez: direct normal irradiance [W m^-2] (with --dhi, instead of "
                                 "--epsilon/--delta)")),
    "diffuse_horizontal_irradiance": ("--dhi", dict(type=finite_float, metavar="W_M2",
                                      help="perez: diffuse horizontal irradiance [W m^-2]")),
    "day_of_year": ("--day-of-year", dict(type=_day_of_year, metavar="DAY",
                    help="perez: day of the year 1-366 for the Sun-Earth distance (default: mean distance)")),
    "dew_point": ("--dew-point", dict(type=float_in(-90, 60), metavar="DEG_C",
                  help="perez: surface dew point [deg C] for the luminous efficacies (default 11)")),
    "altitude": ("--altitude", dict(type=float_in(0.0, 1e8), metavar="M",
                 help="bruneton: observer altitude above sea level [m], from the ground to orbit (default 0)")),
}


def add_model_options(parser: argparse.ArgumentParser, models: list[str], default: str) -> None:
    """``--model`` (one of ``models``) and the options of those models, in one argument group."""
    from ..sky.registry import SKY_MODELS

    parser.add_argument("--model", choices=models, default=default,
                        help="sky model: " + "; ".join(f"{k}: {SKY_MODELS[k]}" for k in models))
    group = parser.add_argument_group("model parameters (each applies to the models named)")
    used = set().union(*(MODEL_OPTIONS[m] for m in models))
    for dest, (flag, kwargs) in _OPTIONS.items():
        if dest in used:
            group.add_argument(flag, dest=dest, default=None, **kwargs)
    parser.set_defaults(_models=models)


def build_sky_from_args(args: argparse.Namespace, sun_zenith: float, sun_azimuth: float):
    """The sky model chosen by ``--model`` with its options, for a sun at (zenith, azimuth) [rad]."""
    from ..sky.registry import build_sky

    table = {m: MODEL_OPTIONS[m] for m in args._models}
    return build_sky(args.model, sun_zenith, sun_azimuth, **select_model_options(args, table))
