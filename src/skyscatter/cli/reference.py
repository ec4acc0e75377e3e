"""``skyscatter reference``: a Monte Carlo sky-radiance reference grid written to Zarr (resumable)."""

from __future__ import annotations

import argparse
import math
import sys
import time

from ..atmosphere.options import atmosphere_option
from ..atmosphere.phase import AEROSOL_PHASE_FUNCTIONS
from ..errors import InvalidParameterError
from .atmosphere_options import add_atmosphere_options, add_deprecated_option, atmosphere_from_args
from .common import HELP_FORMATTER, float_in, float_list, output_path


def _whole_in(low: int, high: int):
    """argparse type: a whole number in [low, high]."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected a whole number from {low} to {high:.6g}, got {value}")
        return value

    return parse


def _orders(text: str) -> tuple[int, int | None] | None:
    """argparse type of --orders: ``all``, ``K`` (that order alone), ``A:B`` or ``A:`` (from A on)."""
    t = text.strip().lower()
    if t == "all":
        return None
    lo, sep, hi = t.partition(":")
    try:
        first = int(lo)
        last = None if sep and not hi.strip() else int(hi) if sep else first
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'all', K, A:B or A: (whole numbers >= 1), got {text!r}") from None
    if first < 1 or (last is not None and last < first):
        raise argparse.ArgumentTypeError(f"expected orders 1 <= A <= B, got {text!r}")
    return first, last


def register(subparsers: argparse._SubParsersAction) -> None:
    from ..montecarlo.dataset import MAX_DIRECTIONS, MAX_SAMPLES

    p = subparsers.add_parser(
        "reference",
        help="Monte Carlo sky radiance reference grid (sun x aerosol x albedo x wavelength x directions) to Zarr",
        description=(
            "Trace the spectral Monte Carlo reference (all orders of scattering in the spherical atmosphere, "
            "the method of Hosek & Wilkie 2012, Sec. 3) for every sun elevation x aerosol amount x ground "
            "albedo, over an equal-area set of sky directions, and write radiance, standard error and the "
            "transmitted solar disc [W m^-2 sr^-1 nm^-1] to a Zarr store (an xarray Dataset with the job as "
            "attributes). Re-running the same command resumes: cells already written (and matching their "
            "checksum) are skipped, damaged ones recomputed. A store holding a different job is refused; a store "
            "another process is writing is refused with its pid. Every option is checked before the store is "
            "created. Cost: about samples x directions x cells x ceil(wavelengths / 16) paths at roughly 10^5 "
            "paths per CPU-second; Ctrl-C or SIGTERM stops within a second, keeping the finished cells. "
            "Example: skyscatter reference ref.zarr --turbidity 2,4 --directions 200"
        ),
        formatter_class=HELP_FORMATTER,
    )
    p.add_argument("output", type=output_path, metavar="STORE.zarr",
                   help="Zarr store (a folder) to create, or to resume if it holds the same job")
    p.add_argument("--sun-elevation", type=float_list("sun elevation", "deg"), default="60,30,10,0,-3,-6",
                   metavar="DEG", help="sun elevations [deg], -90 to 90 (negative: twilight), a list or "
                   "START:STOP:STEP")
    aer = p.add_mutually_exclusive_group()
    aer.add_argument("--turbidity", type=float_list("turbidity", "1-20"), default=None, metavar="T",
                     help=f"turbidities, {atmosphere_option('turbidity').range_text()} (Preetham 1999 A.1 Angstrom "
                     "beta, alpha 1.3), a list; 2.5 when neither --turbidity nor --aod is given")
    aer.add_argument("--aod", type=float_list("aerosol optical depth", "at 550 nm"), default=None, metavar="TAU",
                     help="vertical aerosol optical depths at 550 nm, "
                     f"{atmosphere_option('aerosol_optical_depth').range_text()} (Angstrom alpha 0 of the Earth "
                     "defaults), a list")
    p.add_argument("--ground-albedo", dest="albedo", type=float_list("ground albedo", "0-1"), default="0.1",
                   metavar="A",
                   help=f"albedos of the atmosphere's ground, {atmosphere_option('ground_albedo').range_text()} "
                   "(Lambertian, grey), a list")
    add_deprecated_option(p, "--albedo", "--ground-albedo", "albedo", type=float_list("ground albedo", "0-1"))
    p.add_argument("--wavelengths", type=float_list("wavelengths", "nm"), default="380:780:40", metavar="NM",
                   help="wavelengths [nm], 360 to 830 (the ozone cross-sections), a list or START:STOP:STEP")
    p.add_argument("--directions", type=_whole_in(1, MAX_DIRECTIONS), default=200, metavar="N",
                   help=f"number of equal-area sky directions over the upper hemisphere (spherical Fibonacci), 1 to "
                   f"{MAX_DIRECTIONS}")
    p.add_argument("--almucantars", type=_whole_in(1, MAX_DIRECTIONS), default=None, metavar="K",
                   help=f"lay the --directions on K almucantars (rings of equal zenith angle, centres of equal-area "
                   f"bands) of N/K azimuths each instead of the Fibonacci set, K 1 to {MAX_DIRECTIONS}, N a multiple "
                   "of K. Under a cloud layer the views of a ring share their paths (about half the time); default: "
                   "the Fibonacci set")
    p.add_argument("--samples", type=_whole_in(1, MAX_SAMPLES), default=4096, metavar="N",
                   help=f"paths per direction, 1 to {MAX_SAMPLES:.0e} (rounded up to whole batches of 512; the "
                   "standard error falls as 1/sqrt(N))")
    p.add_argument("--seed", type=_whole_in(0, 2**63 - 1), default=0, metavar="N",
                   help="random seed, 0 to 2^63 - 1 (results depend only on it and the job)")
    p.add_argument("--altitude", type=float_in(0.0, 1e8), default=0.0, metavar="M",
                   help="observer altitude above the ground [m], 0 to 1e8")
    p.add_argument("--orders", type=_orders, default=None, metavar="K|A:B|A:",
                   help="the orders of scattering counted (a ground reflection is one): K that order alone (1: single "
                   "scattering), A:B orders A to B, A: from A on; 'all' (default) every order. Windows 1, 2 and 3: "
                   "of one seed add up to the whole. Not with --cloud-optical-depth")
    p.add_argument("--phase", choices=AEROSOL_PHASE_FUNCTIONS, default=None,
                   help="aerosol phase function (asymmetry g = 0.8; default cornette-shanks); not with --aerosol")
    air = p.add_argument_group("air", "the medium every cell starts from (default: the Earth defaults); --aod sets "
                               "an aerosol type's optical depth per cell (its Mie phase and spectrum kept)")
    add_atmosphere_options(air, ("aerosol_type", "atmosphere_file"))
    cloud = p.add_argument_group("cloud layer", "a horizontally uniform water cloud in every cell (Mie droplets, "
                                 "modified-gamma sizes of effective variance 0.1)")
    cloud.add_argument("--cloud-optical-depth", type=float_in(0.0, 1000.0), default=0.0, metavar="TAU",
                       help="optical depth of the cloud layer at 550 nm, 0 to 1000 (0: no cloud)")
    cloud.add_argument("--cloud-base", type=float_in(0.0, 1e5), default=1000.0, metavar="M",
                       help="altitude of the cloud base [m], 0 to 100000")
    cloud.add_argument("--cloud-top", type=float_in(0.0, 1e5), default=1500.0, metavar="M",
                       help="altitude of the cloud top [m], above the base")
    cloud.add_argument("--cloud-effective-radius", type=float_in(1.0, 50.0), default=10.0, metavar="UM",
                       help="effective radius of the droplets [um], 1 to 50")
    p.add_argument("--scheduler", default=None, metavar="ADDR",
                   help="'synchronous', or a dask.distributed scheduler address (tcp://host:8786; needs the "
                   "montecarlo extra); default: local threads ($SKYSCATTER_NUM_THREADS)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..montecarlo.dataset import almucantar_directions, equal_area_directions, reference

    if args.almucantars is None:
        directions = equal_area_directions(args.directions)
    elif args.directions % args.almucantars:
        raise InvalidParameterError(f"--directions ({args.directions}) must be a multiple of --almucantars "
                                    f"({args.almucantars})")
    else:
        directions = almucantar_directions(args.almucantars, args.directions // args.almucantars)

    bar = None

    def progress(done: int, total: int) -> None:
        nonlocal bar
        if args.no_progress:
            return
        if bar is None:
            from tqdm import tqdm

            bar = tqdm(total=total, unit="task", file=sys.stderr, dynamic_ncols=True,
                       bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} tasks [{elapsed}<{remaining}]")
        bar.n = done
        bar.refresh()

    aerosol_type, air_file = getattr(args, "aerosol_type", None), getattr(args, "atmosphere_file", None)
    if aerosol_type is not None and args.phase is not None:
        raise InvalidParameterError("--phase is the analytic aerosol's; an aerosol type (--aerosol) has its Mie phase")
    if aerosol_type is not None and args.turbidity is not None:
        raise InvalidParameterError("an aerosol type (--aerosol) takes --aod (its optical depths at 550 nm), not "
                                    "--turbidity")
    atmosphere = atmosphere_from_args(args)
    if atmosphere.aerosol is not None:  # a type (or a file's particle aerosol): its own optical depth by default
        turbidity = None
        aod = args.aod if args.aod is not None else [atmosphere.aerosol_component.optical_depth(
            [550.0], atmosphere.thickness)[0]]
    else:
        turbidity = args.turbidity if args.turbidity is not None or args.aod is not None else [2.5]
        aod = args.aod
        if args.phase is not None or air_file is None:
            atmosphere = atmosphere.replace(mie_phase_function=args.phase or "cornette-shanks")
    if args.cloud_optical_depth > 0:
        from ..atmosphere.clouds import CloudLayer

        layer = CloudLayer(args.cloud_base, args.cloud_top, args.cloud_optical_depth,
                           effective_radius=args.cloud_effective_radius * 1e-6)
        atmosphere = atmosphere.replace(particles=(layer,))
    t0 = time.perf_counter()
    try:
        ds = reference(args.output, sun_elevations=[math.radians(e) for e in args.sun_elevation],
                       turbidities=turbidity, aerosol_optical_depths=aod, albedos=args.albedo,
                       wavelengths=args.wavelengths, directions=directions,
                       atmosphere=atmosphere, samples=args.samples,
                       seed=args.seed, altitude=args.altitude, scheduler=args.scheduler, progress=progress,
                       orders=args.orders)
    finally:
        if bar is not None:
            bar.close()
    cells = int(ds["done"].sum())
    print(f"wrote {args.output}: {cells} cells x {ds.sizes['direction']} directions x {ds.sizes['wavelength']} "
          f"wavelengths ({time.perf_counter() - t0:.1f} s)")
    return 0
