"""``skyscatter skymatrix``: hourly Perez (or ASRC-CIE) sky luminance over sky patches from an EPW weather file."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from .common import HELP_FORMATTER, float_in, output_path, positive_int


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "skymatrix",
        help="annual sky matrix (hours x patches) from an EPW weather file, like Radiance gendaymtx",
        description="Read an hourly EnergyPlus weather file (.epw), place the sun at the middle of every hour "
        "(NREL SPA), build the sky of every hour (--model: the Perez 1993 all-weather sky, or the ASRC-CIE sky) "
        "from its direct normal and diffuse horizontal irradiance (Perez 1990 sky clearness, brightness and "
        "luminous efficacies with the hour's dew point) and write the mean "
        "luminance [cd m^-2] of every sky patch: an hours x patches matrix in a .npz file (and optionally a "
        "CSV), or (--format radiance) a Radiance matrix file that rmtxop and dctimestep read, laid out as "
        "gendaymtx writes it. Patches: Tregenza (145) or Reinhart MF 2 (577) / MF 4 (2305), ordered from the "
        "horizon band up, each band starting at north and going east, zenith last (Radiance's order without its "
        "ground patch). "
        "Weather records are checked: a direct normal irradiance above the extraterrestrial value or a diffuse "
        "horizontal above the global is refused with the line; light while the sun stays below the horizon is "
        "left dark with a warning (--night-irradiance); a time zone more than 3 h from the longitude's is warned "
        "about. Example: skyscatter skymatrix weather.epw --patches reinhart2 --out matrix.npz --csv matrix.csv",
        formatter_class=HELP_FORMATTER,
    )
    from ..patches import SCHEMES
    from ..sky import registry

    # Sky models an hour of weather data defines: those taking direct normal and diffuse horizontal irradiance.
    needed = {"direct_normal_irradiance", "diffuse_horizontal_irradiance"}
    weather_models = [s.name for s in registry.models() if needed <= {q.name for q in s.parameters}]
    p.add_argument("epw", type=Path, help="hourly EnergyPlus weather file (.epw)")
    p.add_argument("--model", choices=weather_models, default="perez",
                   help="sky model of every hour, from its direct normal and diffuse horizontal irradiance: "
                   + "; ".join(f"{m}: {registry.get(m).summary}" for m in weather_models))
    p.add_argument("--patches", choices=list(SCHEMES), default="reinhart2",
                   help="patch scheme: tregenza = reinhart1 (145 patches), reinhart2 (577), reinhart4 (2305)")
    p.add_argument("--format", choices=["npz", "radiance"], default="npz",
                   help="npz: luminance [cd m^-2] (hours x patches, float32), times, sun angles [rad], Perez "
                   "epsilon/delta, diffuse and sun illuminance [lx], patch zenith/azimuth [rad] and solid angle [sr]; "
                   "radiance: a Radiance matrix (#?RADIANCE header, FORMAT=float), patches x hours x RGB with the "
                   "ground patch first, RGB radiance [W sr^-1 m^-2] at Radiance's 179 lm/W, the sky in gendaymtx's "
                   "default colour (0.960 1.004 1.118), the sun white")
    p.add_argument("--out", type=output_path, default=None, metavar="PATH",
                   help="output file (default: skymatrix.npz, or skymatrix.mtx with --format radiance)")
    p.add_argument("--ground-albedo", type=float_in(0.0, 1.0), default=None, metavar="RHO",
                   help="--format radiance: reflectance of the ground patch, whose radiance is RHO x the global "
                   "horizontal illuminance / pi, 0 to 1 (gendaymtx's -g; default 0.2)")
    p.add_argument("--night-irradiance", choices=["dark", "error"], default="dark",
                   help="records with light while the sun stays below the horizon for their whole interval (more "
                   "than 1 deg for direct, 6 deg for diffuse light; a time shift or the wrong place): dark = left "
                   "dark with one warning counting them; error = refuse the file at the first")
    p.add_argument("--csv", type=output_path, default=None, metavar="PATH",
                   help="also write a CSV: a time column (ISO 8601, mid-hour) and one luminance column per patch")
    p.add_argument("--include-sun", action="store_true",
                   help="add the direct sun, spread over the 4 nearest patches weighted by proximity as gendaymtx does")
    p.add_argument("--samples", type=positive_int, default=3, metavar="N",
                   help="average each patch over N x N equal-area cells (1: patch centre only, as gendaymtx)")
    p.add_argument("--timestep", choices=["records", "hourly"], default="records",
                   help="sub-hourly files (N records per hour declared in the DATA PERIODS header): records = one "
                   "row per record, the sun at the middle of each record's interval (as gendaymtx, one row per "
                   "input time step); hourly = average each hour's records first, one row per hour")
    p.add_argument("--no-progress", dest="progress", action="store_false",
                   help="hide the progress bar (shown only when stderr is a terminal)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import sys

    import numpy as np

    from ..errors import InvalidParameterError
    from ..fileio import check_output_path
    from ..sky_matrix import skymatrix

    if args.out is None:
        args.out = Path("skymatrix.mtx" if args.format == "radiance" else "skymatrix.npz")
    if args.format == "npz" and args.out.suffix.lower() != ".npz":
        raise InvalidParameterError(f"--out must end in .npz; got {args.out} (a Radiance matrix: --format radiance)")
    if args.format == "radiance" and args.out.suffix.lower() == ".npz":
        raise InvalidParameterError(f"--out {args.out}: a Radiance matrix is not an .npz file (use e.g. .mtx)")
    if args.format == "npz" and args.ground_albedo is not None:
        raise InvalidParameterError("--ground-albedo applies to --format radiance only")
    check_output_path(args.out, option="--out")
    if args.csv is not None:
        check_output_path(args.csv, option="--csv")
        if args.csv.resolve() == args.out.resolve():
            raise InvalidParameterError("--out and --csv must be different files")
    if args.samples > 16:
        raise InvalidParameterError(f"--samples must be at most 16; got {args.samples}")
    t0 = time.perf_counter()
    matrix = skymatrix(args.epw, scheme=args.patches, include_sun=args.include_sun, samples=args.samples,
                       progress=args.progress and sys.stderr.isatty(), timestep=args.timestep, model=args.model,
                       night_irradiance=args.night_irradiance)
    elapsed = time.perf_counter() - t0
    written = [str(t) for t in matrix.save(args.out, args.csv, format=args.format,
                                           ground_reflectance=0.2 if args.ground_albedo is None
                                           else args.ground_albedo)]
    hours, patches = matrix.shape
    lit = int(np.count_nonzero(matrix.diffuse_illuminance > 0))
    loc = matrix.location
    print(f"{args.epw}: {loc.city}, {loc.country} ({loc.latitude_deg:.3f}, {loc.longitude_deg:.3f} deg, "
          f"UTC{loc.timezone_hours:+g} h); {hours} hours, {lit} with daylight")
    print(f"{patches} patches ({matrix.scheme.name}), {matrix.model} sky, sun "
          f"{'included' if matrix.include_sun else 'excluded'}; computed in {elapsed:.2f} s")
    print("wrote " + " and ".join(written))
    return 0
