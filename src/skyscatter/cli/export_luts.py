"""``skyscatter export-luts``: write the precomputed tables as raw float32 textures plus a JSON description."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .common import HELP_FORMATTER


def register(subparsers: argparse._SubParsersAction) -> None:
    from .precompute import add_atmosphere_options

    p = subparsers.add_parser(
        "export-luts",
        help="export the Bruneton tables as raw float32 textures + JSON for real-time engines",
        description=(
            "Write, into --out-dir: transmittance.raw (2D, mu x r), irradiance.raw (2D, mu_s x r), "
            "single_rayleigh_scattering.raw, single_mie_scattering.raw, multiple_scattering.raw and "
            "scattering.raw (the 4D tables packed into 3D textures with the nu slices side by side along x, as in "
            "Bruneton & Neyret 2008 Sec. 6; scattering.raw is the paper's packed C* = S_R + S_multiple / P_R), "
            "scattering_rgba.raw for 3 wavelengths, and atmosphere.json (sizes, coordinate mappings, constants, "
            "XYZ conversion), written last. Little-endian float32, channels in decreasing wavelength. Each file is "
            "written atomically, the folder as a whole is not: an interrupted export can leave new textures next "
            "to an older atmosphere.json, so re-run it. Tables come from --from FILE.npz, else from the cache "
            "(computed if missing) for the atmosphere options below."
        ),
        formatter_class=HELP_FORMATTER,
    )
    p.add_argument("--out-dir", type=Path, required=True, default=argparse.SUPPRESS, metavar="DIR",
                   help="output folder (created if missing)")
    p.add_argument("--from", dest="source", type=Path, default=None, metavar="FILE.npz",
                   help="tables saved by 'skyscatter precompute --out' (the atmosphere options are then ignored)")
    add_atmosphere_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..fileio import ensure_output_folder
    from ..precomputed import PrecomputedAtmosphere
    from ..precomputed.cache import cached_atmosphere
    from .common import one_line_warnings
    from .precompute import atmosphere_from_args

    # The output folder first: refuse it before a table build that can take a minute.
    ensure_output_folder(args.out_dir, what="--out-dir")
    if args.source is not None:
        atm = PrecomputedAtmosphere.load(args.source)
    else:
        params, sizes = atmosphere_from_args(args)
        with one_line_warnings():
            atm = cached_atmosphere(params, orders=args.orders, wavelengths=args.wavelengths, sizes=sizes,
                                    progress=not args.no_progress and sys.stderr.isatty())
    description = atm.export(args.out_dir)
    for f in sorted(args.out_dir.glob("*.raw")):
        print(f"wrote {f} ({f.stat().st_size / 1e6:.1f} MB)")
    print(f"wrote {description}")
    return 0
