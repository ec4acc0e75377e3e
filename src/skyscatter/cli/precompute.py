"""``skyscatter precompute``: build the Bruneton & Neyret (2008) tables, into the cache or an .npz file."""

from __future__ import annotations

import argparse
import re
import sys
import time

from ..errors import InvalidParameterError
from ..fileio import check_output_path
from .atmosphere_options import NAMES as ATMOSPHERE_NAMES
from .atmosphere_options import add_atmosphere_options, add_deprecated_option, atmosphere_from_args
from .common import HELP_FORMATTER, float_in, float_list, one_line_warnings, output_path, positive_int


def _sizes(n: int, name: str):
    def parse(text: str) -> tuple[int, ...]:
        parts = re.split(r"[x,]", text.strip().lower())
        try:
            values = tuple(int(p) for p in parts)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name}: expected {n} whole numbers like 'AxB', got {text!r}") from None
        if len(values) != n or min(values) < 2:
            raise argparse.ArgumentTypeError(f"{name}: expected {n} whole numbers >= 2 separated by 'x', got {text!r}")
        return values

    return parse


def _wavelengths(text: str) -> list[float] | str:
    """A list '680,550,440' or a range 'START:STOP:STEP' [nm] (inclusive); a set's name ('spectral', 'rgb') is the
    deprecated spelling of --tables."""
    t = text.strip()
    if t in ("spectral", "rgb"):
        return t
    values = float_list("wavelengths", "nm")(t)
    bad = [v for v in values if not v > 0]
    if bad:
        raise argparse.ArgumentTypeError(f"wavelengths: {bad[0]:g} nm is not a wavelength; they must be positive "
                                         "[nm] (the tables' solar spectrum covers 280-1100 nm)")
    return values


def add_table_options(p: argparse.ArgumentParser, exclude: tuple[str, ...] = ()) -> None:
    """Options describing the atmosphere (generated from the one list, less ``exclude``) and the tables (shared
    with ``export-luts`` and ``view``)."""
    g = p.add_argument_group("atmosphere", "The Earth defaults of Bruneton & Neyret 2008 (as in Bruneton's 2017 "
                             "implementation) unless changed.")
    add_atmosphere_options(g, [n for n in ATMOSPHERE_NAMES if n not in exclude])
    add_deprecated_option(g, "--albedo", "--ground-albedo", "ground_albedo", type=float_in(0.0, 1.0), metavar="A")
    t = p.add_argument_group("tables")
    t.add_argument("--max-sun-zenith", type=float_in(102.0, 180.0), default=102.0, metavar="DEG",
                   help="largest sun zenith angle tabulated [deg]; the sky is dark beyond it")
    t.add_argument("--orders", type=positive_int, default=None, metavar="N",
                   help="scattering orders computed one by one (default: the library's, 8: "
                        "skyscatter.precomputed.DEFAULT_ORDERS); from 3 on the later orders are added as their "
                        "geometric tail (docs/bruneton.md)")
    t.add_argument("--tables", choices=["spectral", "rgb"], default=None,
                   help="named set of table wavelengths: spectral (the default: 400:700:20, 16 wavelengths, colour "
                        "within delta-xy 0.003 of a 41-wavelength computation) or rgb (680,550,440: faster, wrong "
                        "colour at low sun)")
    t.add_argument("--wavelengths", type=_wavelengths, default=None, metavar="NM",
                   help="the table wavelengths [nm] instead of --tables: a list '680,550,440' or a range "
                        "'380:780:10'; 15 or more give the spectral mode (XYZ by integration with the CIE observer)")
    t.add_argument("--transmittance-size", type=_sizes(2, "transmittance size"), default="256x64", metavar="MUxR",
                   help="transmittance table: view-zenith x radius samples")
    t.add_argument("--irradiance-size", type=_sizes(2, "irradiance size"), default="64x16", metavar="MUSxR",
                   help="irradiance table: sun-zenith x radius samples")
    t.add_argument("--scattering-size", type=_sizes(4, "scattering size"), default="32x128x32x8",
                   metavar="RxMUxMUSxNU",
                   help="4D scattering table: radius x view-zenith (even) x sun-zenith x view-sun angle samples")
    t.add_argument("--no-progress", action="store_true", help="no progress bar")


def tables_from_args(args: argparse.Namespace):
    """(AtmosphereParameters, TableSizes, table keywords) from the options of :func:`add_table_options`; the
    keywords (``tables`` or ``wavelengths``, ``orders``) go to :func:`~skyscatter.precomputed.cached_atmosphere`."""
    import math

    from ..precomputed import DEFAULT_ORDERS, TableSizes

    params = atmosphere_from_args(args, max_sun_zenith=math.radians(args.max_sun_zenith))
    mu, r = args.transmittance_size
    mus, r_e = args.irradiance_size
    sr, smu, smus, snu = args.scattering_size
    sizes = TableSizes(transmittance_mu=mu, transmittance_r=r, irradiance_mu_s=mus, irradiance_r=r_e,
                       scattering_r=sr, scattering_mu=smu, scattering_mu_s=smus, scattering_nu=snu)
    tables, wavelengths = args.tables, args.wavelengths
    if isinstance(wavelengths, str):  # the spelling before --tables
        print(f"skyscatter: warning: --wavelengths {wavelengths} is deprecated and will be removed in the next "
              f"release; use --tables {wavelengths}", file=sys.stderr)
        if tables is not None:
            raise InvalidParameterError("give --tables only (--wavelengths takes wavelengths [nm])")
        tables, wavelengths = wavelengths, None
    if tables is not None and wavelengths is not None:
        raise InvalidParameterError("give either --tables (a named set) or --wavelengths [nm], not both")
    orders = DEFAULT_ORDERS if args.orders is None else args.orders
    return params, sizes, {"tables": tables, "wavelengths": wavelengths, "orders": orders}


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "precompute",
        help="precompute the Bruneton & Neyret 2008 atmosphere tables (cache or .npz)",
        description=(
            "Run the precomputation of Bruneton & Neyret (2008), Algorithm 4.1: transmittance, irradiance and "
            "4D single + multiple scattering tables, one scattering order after the other, with a progress bar "
            "and the time of each step. Without --out the tables go to the cache ($SKYSCATTER_CACHE_DIR or "
            "~/.cache/skyscatter), where BrunetonSky and 'skyscatter sky --model bruneton' find them."
        ),
        formatter_class=HELP_FORMATTER,
    )
    p.add_argument("--out", type=output_path, default=None, metavar="FILE.npz",
                   help="write the tables to this .npz file instead of the cache")
    p.add_argument("--force", action="store_true", help="recompute even if the cache already holds the tables")
    add_table_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..precomputed import PrecomputedAtmosphere
    from ..precomputed.cache import check_cache_dir, load_or_compute

    params, sizes, table_options = tables_from_args(args)
    if args.out is not None and args.out.suffix != ".npz":
        raise InvalidParameterError(f"--out must name an .npz file; got {args.out}")
    if args.out is not None:
        check_output_path(args.out, option="--out")
    else:
        check_cache_dir()  # the user asked for the cache file: refuse an unusable cache before computing
    progress = not args.no_progress and sys.stderr.isatty()
    t0 = time.perf_counter()
    if args.out is None:
        from ..precomputed.cache import cache_path

        # --force recomputes first and then replaces the file atomically: an interrupted run keeps the old one.
        with one_line_warnings():
            atm, computed = load_or_compute(params, sizes=sizes, progress=progress, force=args.force,
                                            require_saved=True, **table_options)
        target = cache_path(atm.cache_key)
    else:
        atm = PrecomputedAtmosphere.compute(params, sizes=sizes, progress=progress, **table_options)
        target = atm.save(args.out)
        computed = True
    wall = time.perf_counter() - t0
    wl = ", ".join(f"{w:g}" for w in atm.wavelengths)
    print(f"tables: {atm.orders} orders, wavelengths [{wl}] nm, "
          f"{'spectral mode' if atm.spectral_mode else 'few-wavelength mode'}")
    print(f"sizes: transmittance {sizes.transmittance_mu}x{sizes.transmittance_r}, irradiance "
          f"{sizes.irradiance_mu_s}x{sizes.irradiance_r}, scattering {'x'.join(map(str, sizes.scattering_shape))}")
    if computed:
        for name, seconds in atm.timings.items():
            print(f"  {name:<24s} {seconds:8.2f} s")
        print(f"wrote {target} ({wall:.1f} s including compilation and writing)")
    else:
        print(f"already cached: {target} (use --force to recompute)")
    return 0
