"""``skyscatter sky``: render a sky model to an HDR image (OpenEXR) and a PNG preview."""

from __future__ import annotations

import argparse
import math
import time

from .common import (
    HELP_FORMATTER,
    add_image_output_options,
    add_sun_options,
    check_output_paths,
    finite_float,
    float_in,
    png_path,
    positive_int,
    select_model_options,
    sun_angles_from_args,
)

# Options that belong to each model (a model refuses options meant for another).
_MODEL_OPTIONS = {
    "preetham": {"turbidity"},
    "preetham-overcast": {"turbidity"},
    "cie": {"sky_type", "zenith_luminance", "diffuse_illuminance"},
    "cie-overcast": {"zenith_luminance", "diffuse_illuminance"},
    "cie-clear": {"zenith_luminance", "diffuse_illuminance"},
    "perez": {"epsilon", "delta", "diffuse_illuminance", "direct_normal_irradiance", "diffuse_horizontal_irradiance"},
    "bruneton": {"altitude"},
}


def register(subparsers: argparse._SubParsersAction) -> None:
    from ..sky.registry import SKY_MODELS

    p = subparsers.add_parser(
        "sky",
        help="render a sky model to EXR + PNG",
        description="Render a sky model to a linear HDR OpenEXR image (linear sRGB, Y = luminance / 683, i.e. "
        "radiance-like units Blender and Mitsuba accept) and a tone-mapped PNG preview. With no options it "
        "writes sky.exr and sky.png: a clear (T = 2.5) mid-morning sky, sun 35 deg high in the south-east.",
        formatter_class=HELP_FORMATTER,
    )
    p.add_argument("--model", choices=list(SKY_MODELS), default="preetham",
                   help="sky model: " + "; ".join(f"{k}: {v}" for k, v in SKY_MODELS.items()))
    m = p.add_argument_group("model parameters (each applies to the models named)")
    m.add_argument("--turbidity", type=finite_float, default=None, metavar="T",
                   help="preetham: turbidity, 1.65 to 11 (default 2.5, a clear sky); preetham-overcast: "
                   "1.65 to 11, blended into the CIE overcast sky from T = 6 to 10 (default 8)")
    m.add_argument("--sky-type", type=int, choices=range(1, 16), default=None, metavar="N",
                   help="cie: CIE 2003 standard sky type 1-15 (default 12, clear sky with low turbidity)")
    m.add_argument("--zenith-luminance", type=finite_float, default=None, metavar="CD_M2",
                   help="cie*: zenith luminance [cd m^-2] (default: the model's own scale)")
    m.add_argument("--diffuse-illuminance", type=finite_float, default=None, metavar="LX",
                   help="cie*, perez: horizontal diffuse illuminance [lx] to scale the sky to")
    m.add_argument("--epsilon", type=finite_float, default=None, help="perez: sky clearness epsilon [1, inf)")
    m.add_argument("--delta", type=finite_float, default=None, help="perez: sky brightness delta [0, 1)")
    m.add_argument("--dni", dest="direct_normal_irradiance", type=finite_float, default=None, metavar="W_M2",
                   help="perez: direct normal irradiance [W m^-2]")
    m.add_argument("--dhi", dest="diffuse_horizontal_irradiance", type=finite_float, default=None, metavar="W_M2",
                   help="perez: diffuse horizontal irradiance [W m^-2]")
    m.add_argument("--altitude", type=float_in(0.0, 1e8), default=None, metavar="M",
                   help="bruneton: observer altitude above sea level [m], from the ground to orbit (default 0)")
    add_sun_options(p)
    g = p.add_argument_group("image")
    g.add_argument("--projection", choices=["equirect", "fisheye", "pinhole"], default="equirect",
                   help="equirect: full-sphere lat-long map, north at the centre; fisheye: equidistant upper "
                   "hemisphere, zenith at the centre, north up, east left; pinhole: a camera (see --heading, "
                   "--pitch, --fov)")
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
    g.add_argument("--ground-albedo", type=float_in(0.0, 1.0), default=0.2, metavar="RHO",
                   help="albedo of the neutral Lambertian ground drawn below the horizon; not used by bruneton, "
                   "which draws its own ground with its atmosphere's albedo (0.1, the Earth default; other values "
                   "from Python with AtmosphereParameters(ground_albedo=...))")
    add_image_output_options(p, default_out="sky.exr")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..render import sky_image, write_exr_and_png
    from ..sky.registry import build_sky

    check_output_paths(args)
    # The precomputed atmosphere ignores refraction, so it wants the geometric sun (docs/bruneton.md).
    zenith, azimuth = sun_angles_from_args(args, apparent=args.model != "bruneton")
    model = build_sky(args.model, zenith, azimuth, **select_model_options(args, _MODEL_OPTIONS))
    t0 = time.perf_counter()
    image = sky_image(
        model,
        projection=args.projection,
        width=args.width,
        height=args.height,
        heading=math.radians(args.heading),
        pitch=math.radians(args.pitch),
        fov=math.radians(args.fov),
        sun_disc=args.sun_disc,
        ground_albedo=args.ground_albedo,
    )
    elapsed = time.perf_counter() - t0
    out, png = write_exr_and_png(args.out, png_path(args), image, exposure_ev=args.exposure, key=0.45)
    print(f"{model!r}: sun zenith {math.degrees(zenith):.2f} deg, azimuth {math.degrees(azimuth):.2f} deg")
    print(f"wrote {out} and {png} ({image.shape[1]} x {image.shape[0]}, rendered in {elapsed:.2f} s)")
    return 0
