"""``skyscatter export-luts``: write the precomputed tables as raw float32 textures plus a JSON description."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..fileio import ensure_output_folder
from .common import HELP_FORMATTER


def _folder(text: str) -> Path:
    """argparse type: a folder path; an empty string is refused (it would mean the current folder)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an output folder must be named; got an empty string (use '.' for the "
                                         "current folder)")
    return Path(text)


def register(subparsers: argparse._SubParsersAction) -> None:
    from .precompute import add_table_options

    p = subparsers.add_parser(
        "export-luts",
        help="export the Bruneton tables as raw float32 textures + JSON for real-time engines",
        description=(
            "Write, into --out-dir: transmittance.raw (2D, mu x r), irradiance.raw (2D, mu_s x r), "
            "single_rayleigh_scattering.raw, single_mie_scattering.raw, multiple_scattering.raw and "
            "scattering.raw (the 4D tables packed into 3D textures with the nu slices side by side along x, as in "
            "Bruneton & Neyret 2008 Sec. 6; scattering.raw is the paper's packed C* = S_R + S_multiple / P_R), "
            "scattering_rgba.raw for 3 wavelengths, and atmosphere.json (sizes, coordinate mappings, constants, "
            "XYZ conversion). Little-endian float32, channels in decreasing wavelength. The files are written "
            "together: all appear, or (a failed or interrupted export, a full disk) none changes. Textures of an "
            "earlier export that this one does not write (scattering_rgba.raw of 3-channel tables) are left alone "
            "and reported; atmosphere.json lists the ones that belong to it. Tables come from --from FILE.npz, else "
            "from the cache (computed if missing) for the atmosphere options below."
        ),
        formatter_class=HELP_FORMATTER,
    )
    p.add_argument("--out-dir", type=_folder, required=True, default=argparse.SUPPRESS, metavar="DIR",
                   help="output folder (created if missing); about 270 MB for the default 16-wavelength tables")
    p.add_argument("--from", dest="source", type=Path, default=None, metavar="FILE.npz",
                   help="tables saved by 'skyscatter precompute --out' (the atmosphere options are then ignored)")
    add_table_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..precomputed import PrecomputedAtmosphere
    from ..precomputed.cache import cached_atmosphere
    from .common import one_line_warnings
    from .precompute import tables_from_args

    # The output folder first: refuse it before a table build that can take a minute.
    ensure_output_folder(args.out_dir, what="--out-dir")
    if args.source is not None:
        atm = PrecomputedAtmosphere.load(args.source)
    else:
        params, sizes, table_options = tables_from_args(args)
        with one_line_warnings():
            atm = cached_atmosphere(params, sizes=sizes, progress=not args.no_progress and sys.stderr.isatty(),
                                    **table_options)
    description = atm.export(args.out_dir)
    import json

    textures = json.loads(description.read_text(encoding="utf-8"))["textures"]
    written = {entry["file"] for entry in textures.values()}
    for entry in textures.values():
        print(f"wrote {args.out_dir / entry['file']} ({entry['bytes'] / 1e6:.1f} MB)")
    print(f"wrote {description}")
    from ..precomputed.export import TEXTURES

    stale = [n for n in (f"{t}.raw" for t in TEXTURES) if n not in written and (args.out_dir / n).exists()]
    if stale:
        print(f"skyscatter export-luts: note: {', '.join(stale)} in {args.out_dir} {'is' if len(stale) == 1 else 'are'}"
              " from an earlier export and not part of this one", file=sys.stderr)
    return 0
