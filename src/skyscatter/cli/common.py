"""Argument types and option groups shared by the subcommands (degrees only at this boundary)."""

from __future__ import annotations

import argparse
import contextlib
import datetime as dt
import math
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path

from ..errors import InvalidParameterError
from ..fileio import check_output_path


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """``--help`` with "(default: ...)" only where it says something: not on flags (``--no-glare`` would read
    "(default: True)"), required options, options whose default (None, an empty list) the help text describes,
    or help that already names its default."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if (default is None or default is argparse.SUPPRESS or isinstance(default, bool) or action.required
                or (isinstance(default, (list, tuple)) and not default) or "(default" in text):
            return text
        return super()._get_help_string(action)


#: The formatter of every subcommand's ``--help``.
HELP_FORMATTER = HelpFormatter


@contextlib.contextmanager
def one_line_warnings() -> Iterator[None]:
    """Print warnings raised inside the block as one line each, ``skyscatter: warning: <message>``, on stderr."""

    def show(message, category, filename, lineno, file=None, line=None):
        print(f"skyscatter: warning: {message}", file=sys.stderr if file is None else file)

    with warnings.catch_warnings():
        warnings.showwarning = show
        yield


def positive_int(text: str) -> int:
    """argparse type: a whole number > 0."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number > 0, got {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a whole number > 0, got {value}")
    return value


def output_path(text: str) -> Path:
    """argparse type: a path to write; an empty string is refused (it would mean the current folder)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an output path must name a file; got an empty string")
    return Path(text)


def finite_float(text: str) -> float:
    """argparse type: a finite number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def float_in(low: float, high: float):
    """argparse type factory: a finite number in [low, high]."""

    def parse(text: str) -> float:
        value = finite_float(text)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected a number in [{low:g}, {high:g}], got {value:g}")
        return value

    return parse


def aware_datetime(text: str) -> dt.datetime:
    """argparse type: an ISO 8601 date-time with a UTC offset, e.g. ``2024-06-21T09:30+02:00`` or ``...Z``."""
    if text.strip().startswith("-"):
        raise argparse.ArgumentTypeError(
            f"time {text!r}: years before 1 are not supported (ISO 8601 dates here run from 0001 to 9999)"
        )
    try:
        value = dt.datetime.fromisoformat(text.replace("Z", "+00:00").replace("z", "+00:00"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"cannot read time {text!r}: use ISO 8601 with a UTC offset, e.g. 2024-06-21T09:30+02:00"
        ) from None
    if value.tzinfo is None or value.utcoffset() is None:
        raise argparse.ArgumentTypeError(
            f"time {text!r} has no UTC offset: add one, e.g. {text}+00:00 or {text}Z"
        )
    return value


def add_sun_options(parser: argparse.ArgumentParser, *, default_elevation: float = 35.0,
                    default_azimuth: float = 120.0) -> None:
    """Add the sun-placement options: explicit angles or a place and time."""
    g = parser.add_argument_group(
        "sun", "Place the sun either by angles or by --lat/--lon/--time (NREL SPA, Reda & Andreas 2004)."
    )
    g.add_argument("--sun-elevation", type=float_in(-90, 90), default=None, metavar="DEG",
                   help=f"sun elevation above the horizon [deg] (default {default_elevation:g} when no --time)")
    g.add_argument("--sun-azimuth", type=float_in(-360, 360), default=None, metavar="DEG",
                   help=f"sun azimuth from north towards east [deg] (default {default_azimuth:g} when no --time)")
    g.add_argument("--lat", type=float_in(-90, 90), default=None, metavar="DEG",
                   help="site latitude, north positive [deg]")
    g.add_argument("--lon", type=float_in(-180, 180), default=None, metavar="DEG",
                   help="site longitude, east positive [deg]")
    g.add_argument("--time", type=aware_datetime, default=None, metavar="ISO",
                   help="local time with UTC offset, ISO 8601, e.g. 2024-06-21T09:30+02:00")
    parser.set_defaults(_default_sun=(default_elevation, default_azimuth))


def sun_angles_from_args(args: argparse.Namespace, *, apparent: bool = True) -> tuple[float, float]:
    """Sun (zenith, azimuth) [rad] from the options of :func:`add_sun_options`.

    With a place and time, ``apparent`` chooses SPA's refraction-corrected position (default) or the geometric
    one, which models that ignore refraction (the precomputed atmosphere) need.
    """
    if args.time is not None or args.lat is not None or args.lon is not None:
        if args.time is None or args.lat is None or args.lon is None:
            raise InvalidParameterError("--lat, --lon and --time must be given together")
        if args.sun_elevation is not None or args.sun_azimuth is not None:
            raise InvalidParameterError("give either --sun-elevation/--sun-azimuth or --lat/--lon/--time, not both")
        from ..sun.position import sun_position

        pos = sun_position(math.radians(args.lat), math.radians(args.lon), args.time, apparent=apparent)
        return float(pos.zenith), float(pos.azimuth)
    elevation, azimuth = args._default_sun
    if args.sun_elevation is not None:
        elevation = args.sun_elevation
    if args.sun_azimuth is not None:
        azimuth = args.sun_azimuth
    return math.radians(90.0 - elevation), math.radians(azimuth % 360.0)


def add_image_output_options(parser: argparse.ArgumentParser, *, default_out: str) -> None:
    """--format (OpenEXR, or a Radiance sky), --out, --png (preview, default beside --out) and --exposure."""
    g = parser.add_argument_group("output")
    g.add_argument("--format", choices=["exr", "radiance"], default="exr",
                   help="exr: an OpenEXR image, float32 linear sRGB, Y = luminance / 683; radiance: a sky Radiance "
                   "renders (rpict, rtrace): --out names a .rad scene with the sun as a light source and the sky "
                   "as a glow mapped from an equirect Radiance picture (.hdr, RGB radiance in W sr^-1 m^-2, 179 "
                   "lm/W) through a function file (.cal), both beside it (run Radiance in that folder); equirect "
                   "only, the image options --projection, --layout and --no-sun-disc do not apply")
    g.add_argument("--out", type=output_path, default=None, metavar="PATH",
                   help=f"the output (default: {default_out}, or {Path(default_out).with_suffix('.rad')} with "
                   "--format radiance)")
    g.add_argument("--png", type=output_path, default=None, metavar="PATH",
                   help="tone-mapped preview PNG (default: the --out path with .png)")
    g.add_argument("--exposure", type=float_in(-30.0, 30.0), default=None, metavar="EV",
                   help="preview exposure compensation [EV stops]; default: automatic (scene key)")
    parser.set_defaults(_default_out=default_out)


def output_file(args: argparse.Namespace) -> Path:
    """--out, or the default of the chosen --format."""
    if args.out is not None:
        return args.out
    default = Path(args._default_out)
    return default.with_suffix(".rad") if getattr(args, "format", "exr") == "radiance" else default


def png_path(args: argparse.Namespace) -> Path:
    """The preview path: --png, or --out with the suffix .png."""
    if args.png is not None:
        return args.png
    out = output_file(args)
    if not out.name:
        from ..errors import OutputError

        raise OutputError(f"--out {str(out)!r}: an output path must name a file")
    return out.with_suffix(".png")


def check_output_paths(args: argparse.Namespace) -> None:
    """Refuse bad --out/--png paths before any work: empty, a folder, wrong suffix, same file, missing or
    read-only folder (:func:`skyscatter.fileio.check_output_path`)."""
    out = output_file(args)
    check_output_path(out, option="--out")
    png = png_path(args)
    if getattr(args, "format", "exr") == "radiance":
        if out.suffix.lower() != ".rad":
            raise InvalidParameterError(f"--out {out}: with --format radiance the output is a Radiance scene "
                                        "description ending in .rad")
        from ..render.radiance_sky import radiance_sky_files

        radiance_sky_files(out, png)
        return
    if out.suffix.lower() != ".exr":
        raise InvalidParameterError(f"--out {out}: the HDR output must be an OpenEXR file ending in .exr")
    check_output_path(png, option="--png")
    if png.suffix.lower() != ".png":
        raise InvalidParameterError(f"--png {png}: the preview must end in .png")
    if out.resolve() == png.resolve():
        raise InvalidParameterError("--out and --png must be different files")


def float_list(name: str, unit: str):
    """argparse type: a comma list ``1,2,3`` or an inclusive range ``START:STOP:STEP`` of finite numbers [unit]."""
    def parse(text: str) -> list[float]:
        t = text.strip()
        try:
            if ":" in t:
                start, stop, step = (float(v) for v in t.split(":"))
                if not step > 0:
                    raise ValueError
                if abs(stop - start) / step > 10_000:
                    raise ValueError
                n = int(math.floor(abs(stop - start) / step + 1e-9)) + 1
                sign = 1.0 if stop >= start else -1.0
                values = [start + sign * i * step for i in range(n)]
            else:
                values = [float(v) for v in t.split(",") if v.strip()]
            if not values or not all(math.isfinite(v) for v in values):
                raise ValueError
            return values
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{name}: expected a list like 1,2,3 or a range START:STOP:STEP [{unit}], got {text!r}"
            ) from None

    return parse
