"""``skyscatter illuminance``: horizontal, vertical and tilted illuminance [lx] under a sky model."""

from __future__ import annotations

import argparse
import json
import math

from ..errors import InvalidParameterError
from .common import (
    HELP_FORMATTER,
    add_sun_options,
    finite_float,
    sun_angles_from_args,
)
from .sky_options import add_model_options, build_sky_from_args


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
    from ..sky import registry

    # every registered model but the Monte Carlo reference (the quadrature needs thousands of directions)
    add_model_options(p, [s.name for s in registry.models() if s.cost != "expensive"], default="cie-overcast")
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


def run(args: argparse.Namespace) -> int:
    from ..photometry import (
        horizontal_illuminance,
        sun_normal_illuminance,
        sun_plane_illuminance,
        tilted_illuminance,
    )

    zenith, azimuth = sun_angles_from_args(args)
    model = build_sky_from_args(args, zenith, azimuth)
    if args.include_sun and model.sun is None:
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
