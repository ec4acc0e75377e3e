"""``skyscatter sky``: render a sky model to an HDR image (OpenEXR) and a PNG preview."""

from __future__ import annotations

import argparse
import math
import sys
import time

from ..errors import InvalidParameterError
from .common import (
    HELP_FORMATTER,
    add_image_output_options,
    add_sun_options,
    check_output_paths,
    finite_float,
    float_in,
    output_file,
    png_path,
    positive_int,
    sun_angles_from_args,
)
from .sky_options import add_model_options, build_sky_from_args


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "sky",
        help="render a sky model to EXR + PNG",
        description="Render a sky model to a linear HDR OpenEXR image (linear sRGB, Y = luminance / 683, i.e. "
        "radiance-like units Blender and Mitsuba accept) and a tone-mapped PNG preview. With no options it "
        "writes sky.exr and sky.png: a clear (T = 2.5) mid-morning sky, sun 35 deg high in the south-east.",
        formatter_class=HELP_FORMATTER,
    )
    add_model_options(p, default="preetham")
    add_sun_options(p)
    g = p.add_argument_group("image")
    g.add_argument("--projection", choices=["equirect", "fisheye", "pinhole"], default="equirect",
                   help="equirect: full-sphere lat-long map, north at the centre; fisheye: equidistant upper "
                   "hemisphere, zenith at the centre, north up, east left; pinhole: a camera (see --heading, "
                   "--pitch, --fov)")
    g.add_argument("--layout", choices=["skyscatter", "blender", "mitsuba"], default="skyscatter",
                   help="equirect: which way round to write the map so that the sun lands where skyscatter says "
                   "in a Z-up scene with north = +Y, east = +X. skyscatter: north at the centre column; blender: "
                   "for a World Environment Texture with the default mapping; mitsuba: for an envmap with "
                   "to_world = rotate([1, 0, 0], 90)")
    g.add_argument("--width", type=positive_int, default=1024, metavar="PX", help="image width [px]")
    g.add_argument("--height", type=positive_int, default=None, metavar="PX",
                   help="image height [px] (default: width/2 equirect, width fisheye, 3/4 width pinhole)")
    g.add_argument("--heading", type=finite_float, default=0.0, metavar="DEG",
                   help="pinhole: azimuth of the view centre from north towards east [deg]")
    g.add_argument("--pitch", type=float_in(-89.9, 89.9), default=10.0, metavar="DEG",
                   help="pinhole: elevation of the view centre [deg]")
    g.add_argument("--fov", type=float_in(0.1, 179.0), default=60.0, metavar="DEG",
                   help="pinhole: horizontal field of view [deg]")
    g.add_argument("--no-sun-disc", dest="sun_disc", action="store_false",
                   help="leave the solar disc out of the image")
    g.add_argument("--terrain-albedo", type=float_in(0.0, 1.0), default=None, metavar="RHO",
                   help="albedo of the neutral Lambertian ground drawn below the horizon (default 0.2); not used by "
                   "bruneton, which draws its own ground with its atmosphere's --ground-albedo")
    add_image_output_options(p, default_out="sky.exr")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..render import sky_image, write_exr_and_png

    check_output_paths(args)
    if args.layout != "skyscatter" and args.projection != "equirect":
        raise InvalidParameterError(f"--layout {args.layout} applies to --projection equirect only")
    if args.format == "radiance":
        given = [flag for flag, bad in (("--projection", args.projection != "equirect"),
                                        ("--layout", args.layout != "skyscatter"), ("--no-sun-disc", not args.sun_disc),
                                        ("--height", args.height is not None)) if bad]
        if given:
            raise InvalidParameterError(f"{', '.join(given)}: not with --format radiance (a Radiance sky is an "
                                        "equirect picture of the whole sphere, width x width/2, with the sun as "
                                        "a light source)")
    _terrain_albedo(args)
    # The precomputed atmosphere ignores refraction, so it wants the geometric sun (docs/bruneton.md).
    zenith, azimuth = sun_angles_from_args(args, apparent=args.model != "bruneton")
    model = build_sky_from_args(args, zenith, azimuth)
    bar = _monte_carlo_progress(model, args) if args.model == "montecarlo" else None
    t0 = time.perf_counter()
    if args.format == "radiance":
        from ..render.radiance_sky import write_radiance_sky

        try:
            files = write_radiance_sky(output_file(args), model, width=args.width, ground_albedo=args.terrain_albedo,
                                       png_path=png_path(args), exposure_ev=args.exposure)
        finally:
            if bar is not None:
                bar.close()
        print(f"{model!r}: sun zenith {math.degrees(zenith):.2f} deg, azimuth {math.degrees(azimuth):.2f} deg")
        print(f"wrote {', '.join(map(str, files))} ({args.width} x {args.width // 2} picture, "
              f"{time.perf_counter() - t0:.2f} s); render with: oconv {files[0].name} > sky.oct, in that folder")
        return 0
    try:
        image = sky_image(
            model,
            projection=args.projection,
            width=args.width,
            height=args.height,
            heading=math.radians(args.heading),
            pitch=math.radians(args.pitch),
            fov=math.radians(args.fov),
            sun_disc=args.sun_disc,
            ground_albedo=args.terrain_albedo,
            layout=args.layout,
        )
    finally:
        if bar is not None:
            bar.close()
    elapsed = time.perf_counter() - t0
    out, png = write_exr_and_png(output_file(args), png_path(args), image, exposure_ev=args.exposure, key=0.45)
    print(f"{model!r}: sun zenith {math.degrees(zenith):.2f} deg, azimuth {math.degrees(azimuth):.2f} deg")
    print(f"wrote {out} and {png} ({image.shape[1]} x {image.shape[0]}, rendered in {elapsed:.2f} s)")
    return 0


def _terrain_albedo(args: argparse.Namespace) -> None:
    """--terrain-albedo (default 0.2); --ground-albedo with a model that has no ground is its old spelling."""
    from ..sky import registry

    takes_ground = any(p.name == "ground_albedo" for p in registry.get(args.model).parameters)
    if not takes_ground and getattr(args, "ground_albedo", None) is not None:
        import sys

        print("skyscatter: warning: --ground-albedo for the ground drawn below the horizon is deprecated and will be "
              "removed in the next release; use --terrain-albedo (--ground-albedo is the atmosphere's ground, of "
              "the models that have one)", file=sys.stderr)
        if args.terrain_albedo is None:
            args.terrain_albedo = args.ground_albedo
        del args.ground_albedo
    if args.terrain_albedo is None:
        args.terrain_albedo = 0.2


def _format_seconds(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def _monte_carlo_progress(model, args: argparse.Namespace):
    """Say how long the Monte Carlo sky will take (from a pilot run) and attach a progress bar to it."""
    from tqdm import tqdm

    from ..runtime import num_threads

    h = args.height if args.height is not None else (
        args.width // 2 if args.projection == "equirect" else args.width if args.projection == "fisheye"
        else max(1, round(args.width * 3 / 4)))
    n = args.width * h
    seconds = model.estimate_seconds(n)
    print(f"skyscatter sky: the Monte Carlo sky traces {model.samples} paths for each of {n} pixels x 6 wavelength "
          f"groups (95 wavelengths): about {_format_seconds(seconds)} on {num_threads()} thread(s), estimated from "
          "a pilot run; Ctrl-C stops it (a smaller --width or --samples is quicker)", file=sys.stderr, flush=True)
    bar = tqdm(total=None, unit="task", desc="skyscatter sky (Monte Carlo)", file=sys.stderr, disable=None)

    def progress(done: int, total: int) -> None:
        if bar.total != total:
            bar.total = total
        bar.n = done
        bar.refresh()

    model.progress = progress
    return bar
