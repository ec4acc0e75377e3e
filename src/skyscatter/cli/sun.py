"""``skyscatter sun``: where the sun is for a place and a time (degrees at this boundary only)."""

from __future__ import annotations

import argparse
import json
import math

from .common import HELP_FORMATTER, aware_datetime, finite_float, float_in


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "sun",
        help="sun zenith, azimuth and elevation for a place and time",
        description=(
            "Print the sun's zenith angle, azimuth (from north towards east) and elevation in degrees for a "
            "site and a time. The default method is NREL SPA (Reda & Andreas 2004) with the refraction-corrected "
            "(apparent) zenith; 'preetham1999' is the approximation of Preetham et al. 1999, Appendix A.6."
        ),
        formatter_class=HELP_FORMATTER,
    )
    p.add_argument("--lat", type=float_in(-90, 90), required=True, default=argparse.SUPPRESS, metavar="DEG",
                   help="site latitude, north positive [deg]")
    p.add_argument("--lon", type=float_in(-180, 180), required=True, default=argparse.SUPPRESS, metavar="DEG",
                   help="site longitude, east positive [deg]")
    p.add_argument("--time", type=aware_datetime, required=True, default=argparse.SUPPRESS, metavar="ISO",
                   help="time with a UTC offset, ISO 8601, e.g. 2024-06-21T09:30+02:00 or 2024-06-21T07:30Z")
    p.add_argument("--method", choices=["spa", "preetham1999"], default="spa",
                   help="NREL SPA (Reda & Andreas 2004, skyscatter.sun.spa), or Preetham 1999 A.6 (about 0.3 deg "
                        "mean, 1.2 deg max error)")
    p.add_argument("--altitude", type=finite_float, default=0.0, metavar="M",
                   help="site height above sea level [m] (spa only)")
    p.add_argument("--pressure", type=float_in(1.0, 2.0e5), default=101325.0, metavar="PA",
                   help="mean air pressure at the site [Pa], for refraction (spa only)")
    p.add_argument("--temperature", type=float_in(-100.0, 100.0), default=12.0, metavar="DEGC",
                   help="mean air temperature at the site [deg C], for refraction (spa only)")
    p.add_argument("--geometric", action="store_true",
                   help="report the geometric zenith, without the refraction correction (spa only)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of one line per angle")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..sun.position import sun_position

    pos = sun_position(
        math.radians(args.lat), math.radians(args.lon), args.time, method=args.method,
        altitude=args.altitude, pressure=args.pressure, temperature=args.temperature,
        apparent=not args.geometric,
    )
    zenith, azimuth, elevation = (math.degrees(v) for v in (pos.zenith, pos.azimuth, pos.elevation))
    if args.json:
        print(json.dumps({
            "time": args.time.isoformat(),
            "latitude_deg": args.lat,
            "longitude_deg": args.lon,
            "method": args.method,
            "zenith_deg": zenith,
            "azimuth_deg": azimuth,
            "elevation_deg": elevation,
        }))
    else:
        print(f"zenith    {zenith:10.5f} deg")
        print(f"azimuth   {azimuth:10.5f} deg (from north towards east)")
        print(f"elevation {elevation:10.5f} deg")
    return 0
