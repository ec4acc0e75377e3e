"""``skyscatter export-luts``: write the precomputed tables as raw float32 textures plus a JSON description, and
the engine-ready RGBA textures of :mod:`skyscatter.realtime` with their manifest."""

from __future__ import annotations

import argparse
import json
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


#: What --formats accepts: the spectral raw export and the real-time ones.
FORMAT_CHOICES = ("raw", "rgba32f", "rgba16f", "exr")
DEFAULT_FORMATS = ("rgba32f", "rgba16f")


def _formats(text: str) -> tuple[str, ...]:
    """argparse type: a comma-separated list of FORMAT_CHOICES."""
    items = tuple(dict.fromkeys(t.strip() for t in text.split(",") if t.strip()))
    bad = [t for t in items if t not in FORMAT_CHOICES]
    if bad or not items:
        raise argparse.ArgumentTypeError(f"formats must be a comma-separated list of {', '.join(FORMAT_CHOICES)}; "
                                         f"got {text!r}")
    return items


def register(subparsers: argparse._SubParsersAction) -> None:
    from .precompute import add_table_options

    p = subparsers.add_parser(
        "export-luts",
        help="export the Bruneton tables as textures for real-time engines (RGBA float32/half/EXR + JSON manifest)",
        description=(
            "Write, into --out-dir, the engine-ready textures (default --formats rgba32f,rgba16f; docs/realtime.md): "
            "transmittance and irradiance (2D), rayleigh, mie and multiple (3D: the 4D tables with the nu slices side "
            "by side along x, Bruneton & Neyret 2008 Sec. 6), the spectral tables folded into linear sRGB with "
            "Y = luminance / 683 as Bruneton's 2017 code does, RGBA little-endian float32 (.rgba32f), half "
            "(.rgba16f) or OpenEXR (.exr), and skyscatter_realtime.json (version, sizes, constants, units, every "
            "texture mapping as Python and GLSL code), which 'skyscatter view --luts DIR' shows and the package's "
            "GLSL library reads. --formats raw writes the spectral tables instead or as well: transmittance.raw "
            "(2D, mu x r), irradiance.raw (2D, mu_s x r), single_rayleigh_scattering.raw, "
            "single_mie_scattering.raw, multiple_scattering.raw and scattering.raw (the paper's packed "
            "C* = S_R + S_multiple / P_R), scattering_rgba.raw for 3 wavelengths, and atmosphere.json; little-endian "
            "float32, channels in decreasing wavelength. The files are written together: all appear, or (a failed "
            "or interrupted export, a full disk) none changes. Raw textures of an earlier export that this one does "
            "not write (scattering_rgba.raw of 3-channel tables) are left alone and reported; atmosphere.json lists "
            "the ones that belong to it. Tables come from --from FILE.npz, else from the cache (computed if "
            "missing) for the atmosphere options below."
        ),
        formatter_class=HELP_FORMATTER,
    )
    p.add_argument("--out-dir", type=_folder, required=True, default=argparse.SUPPRESS, metavar="DIR",
                   help="output folder (created if missing); the default tables take 76 MB as rgba32f + rgba16f, "
                        "270 MB as raw (16 wavelengths)")
    p.add_argument("--from", dest="source", type=Path, default=None, metavar="FILE.npz",
                   help="tables saved by 'skyscatter precompute --out' (the atmosphere options are then ignored)")
    p.add_argument("--formats", type=_formats, default=",".join(DEFAULT_FORMATS), metavar="LIST",
                   help="comma-separated: raw (the spectral tables above), rgba32f, rgba16f (engine-ready RGBA "
                        "float32 / half textures, raw little-endian), exr (the same as OpenEXR float32)")
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
    realtime = tuple(f for f in args.formats if f != "raw")
    if realtime:
        from ..realtime import export_realtime

        manifest = export_realtime(atm, args.out_dir, formats=realtime)
        entries = json.loads(manifest.read_text(encoding="utf-8"))["textures"].values()
        for entry in entries:
            for f in entry["files"].values():
                print(f"wrote {args.out_dir / f['file']} ({f['bytes'] / 1e6:.1f} MB)")
        print(f"wrote {manifest}")
    if "raw" not in args.formats:
        return 0
    description = atm.export(args.out_dir)

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
