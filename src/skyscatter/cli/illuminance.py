"""``skyscatter illuminance``: horizontal, vertical and tilted illuminance [lx] under a sky model."""

from __future__ import annotations

import argparse
import json
import math

from .common import (
    HELP_FORMATTER,
    add_sun_options,
    finite_float,
    float_in,
    select_model_options,
    sun_angles_from_args,
)

# Options that belong to each model (a model refuses options meant for another).
_MODEL_OPTIONS = {
    "preetham": {"turbidity"},
    "cie": {"sky_type", "zenith_luminance", "diffuse_illuminance", "sun_illuminance_normal"},
    "cie-overcast": {"zenith_luminance", "diffuse_illuminance"},
    "cie-clear": {"zenith_luminance", "diffuse_illuminance", "sun_illuminance_normal"},
    "perez": {
        "epsilon",
        "delta",
        "diffuse_illuminance",
        "direct_normal_irradiance",
        "diffuse_horizontal_irradiance",
        "day_of_year",
        "dew_point",
    },
}


def _day_of_year(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole day number 1-366, got {text!r}") from None
    if not 1 <= value <= 366:
        raise argparse.ArgumentTypeError(f"expected a day number 1-366, got {value}")
    return value


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "illuminance",
        help="illuminance [lx] on horizontal, vertical and tilted planes under a sky model",
        description="Integrate a sky model's luminance over the sky seen by a plane and print the illuminance "
        "in lux: always the horizontal plane, plus any vertical (--vertical) or tilted (--tilted) planes. "
        "Sky only by default; --include-sun adds the direct sun. Ground-reflected light is not included. "
        "Example: skyscatter illuminance --model cie --sky-type 12 --sun-elevation 40 --vertical 180 90",
        formatter_class=HELP_FORMATTER,
    )
    p.add_argument("--model", choices=list(_MODEL_OPTIONS), default="cie-overcast",
                   help="sky model: cie (CIE 2003 general sky, --sky-type), cie-overcast (Moon & Spencer), "
                   "cie-clear (CIE 1973, Kittler), perez (Perez 1993 all-weather), preetham (Preetham 1999)")
    m = p.add_argument_group("model parameters (each applies to the models named)")
    m.add_argument("--sky-type", type=int, choices=range(1, 16), default=None, metavar="N",
                   help="cie: CIE 2003 standard sky type 1-15 (default 12, the CIE clear sky)")
    m.add_argument("--zenith-luminance", type=finite_float, default=None, metavar="CD_M2",
                   help="cie*: zenith luminance [cd m^-2] (default: scale to 10000 lx diffuse)")
    m.add_argument("--diffuse-illuminance", type=finite_float, default=None, metavar="LX",
                   help="cie*, perez: horizontal diffuse illuminance [lx] to scale the sky to")
    m.add_argument("--sun-illuminance", dest="sun_illuminance_normal", type=float_in(0, 2e5), default=None,
                   metavar="LX", help="cie, cie-clear: direct normal illuminance of the sun [lx] for --include-sun "
                   "(default 0: the CIE distributions describe the sky only)")
    m.add_argument("--turbidity", type=finite_float, default=None, metavar="T",
                   help="preetham: turbidity, 1.65 to 11 (default 2.5)")
    m.add_argument("--epsilon", type=finite_float, default=None, help="perez: sky clearness epsilon, >= 1")
    m.add_argument("--delta", type=finite_float, default=None, help="perez: sky brightness delta, >= 0")
    m.add_argument("--dni", dest="direct_normal_irradiance", type=finite_float, default=None, metavar="W_M2",
                   help="perez: direct normal irradiance [W m^-2] (with --dhi, instead of --epsilon/--delta)")
    m.add_argument("--dhi", dest="diffuse_horizontal_irradiance", type=finite_float, default=None, metavar="W_M2",
                   help="perez: diffuse horizontal irradiance [W m^-2]")
    m.add_argument("--day-of-year", type=_day_of_year, default=None, metavar="DAY",
                   help="perez: day of the year 1-366 for the Sun-Earth distance (default: mean distance)")
    m.add_argument("--dew-point", type=float_in(-90, 60), default=None, metavar="DEG_C",
                   help="perez: surface dew point [deg C] for the luminous efficacies (default 11)")
    add_sun_options(p)
    g = p.add_argument_group("planes")
    g.add_argument("--vertical", type=finite_float, nargs="+", default=[], metavar="AZ_DEG",
                   help="also vertical planes facing these azimuths [deg from north towards east], e.g. 180 90")
    g.add_argument("--tilted", type=finite_float, nargs=2, action="append", default=[], metavar=("TILT_DEG", "AZ_DEG"),
                   help="also a plane tilted TILT_DEG from horizontal (0-180) facing AZ_DEG; repeatable")
    g.add_argument("--include-sun", action="store_true",
                   help="add the direct sun (models with a sun; CIE skies need --sun-illuminance)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.set_defaults(func=run)


def _build(args: argparse.Namespace, zenith: float, azimuth: float):
    opts = select_model_options(args, _MODEL_OPTIONS)
    if args.model == "cie":
        from ..sky.cie import CIEStandardSky

        return CIEStandardSky(opts.pop("sky_type", 12), zenith, azimuth, **opts)
    if args.model == "cie-overcast":
        from ..sky.cie import CIEOvercastSky

        return CIEOvercastSky(**opts)
    if args.model == "cie-clear":
        from ..sky.cie import CIEClearSky

        return CIEClearSky(zenith, azimuth, **opts)
    if args.model == "perez":
        from ..sky.perez import PerezSky

        return PerezSky(zenith, azimuth, **opts)
    from ..sky.preetham import PreethamSky

    return PreethamSky(opts.pop("turbidity", 2.5), zenith, azimuth)


def run(args: argparse.Namespace) -> int:
    from ..errors import InvalidParameterError
    from ..photometry import (
        horizontal_illuminance,
        sun_normal_illuminance,
        sun_plane_illuminance,
        tilted_illuminance,
    )

    zenith, azimuth = sun_angles_from_args(args)
    model = _build(args, zenith, azimuth)
    if args.include_sun and not getattr(model, "has_sun", False):
        raise InvalidParameterError(f"--include-sun: --model {args.model} has no sun")
    planes = [("horizontal", 0.0, 0.0)]
    planes += [(f"vertical facing {a % 360:g} deg", 90.0, a) for a in args.vertical]
    for tilt, az in args.tilted:
        if not 0.0 <= tilt <= 180.0:
            raise InvalidParameterError(f"--tilted: tilt must be within 0-180 deg; got {tilt:g}")
        planes.append((f"tilted {tilt:g} deg facing {az % 360:g} deg", tilt, az))
    rows = []
    for label, tilt, az in planes:
        t, a = math.radians(tilt), math.radians(az)
        if tilt == 0.0:
            diffuse = horizontal_illuminance(model)
        else:
            diffuse = tilted_illuminance(model, t, a)
        row = {"plane": label, "tilt_deg": tilt, "azimuth_deg": az % 360, "sky_lx": diffuse}
        if args.include_sun:
            row["total_lx"] = diffuse + sun_plane_illuminance(model, t, a)
        rows.append(row)
    result = {
        "model": repr(model),
        "sun_zenith_deg": math.degrees(zenith),
        "sun_azimuth_deg": math.degrees(azimuth),
        "planes": rows,
    }
    if args.include_sun:
        result["sun_normal_illuminance_lx"] = sun_normal_illuminance(model)
    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    print(f"{model!r}")
    print(f"sun zenith {math.degrees(zenith):.2f} deg, azimuth {math.degrees(azimuth):.2f} deg")
    if args.include_sun:
        print(f"sun, direct normal: {result['sun_normal_illuminance_lx']:.1f} lx")
    for row in rows:
        text = f"{row['plane']}: sky {row['sky_lx']:.1f} lx"
        if args.include_sun:
            text += f", sky + sun {row['total_lx']:.1f} lx"
        print(text)
    return 0
