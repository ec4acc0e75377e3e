"""``skyscatter fit-hosek-wilkie``: fit the Hosek-Wilkie sky form to the precomputed atmosphere, write a dataset."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time

from ..errors import InvalidParameterError
from ..fileio import check_output_path
from .atmosphere_options import add_atmosphere_options, atmosphere_from_args
from .common import HELP_FORMATTER, float_list, output_path, positive_int

#: Most sun elevations a fit samples (the published model has 6 control points; 90 is one per degree).
MAX_ELEVATIONS = 90


def _wavelength_list(text: str) -> list[float]:
    values = float_list("fit wavelengths", "nm")(text)
    if not values or any(not (300.0 <= v <= 1000.0) for v in values) or values != sorted(set(values)):
        raise argparse.ArgumentTypeError(f"expected increasing wavelengths in 300-1000 nm, got {text!r}")
    return values


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "fit-hosek-wilkie",
        help="fit the Hosek-Wilkie sky form to the precomputed atmosphere and write a dataset (.npz)",
        description=(
            "Sample the precomputed multiple-scattering sky (Bruneton & Neyret 2008; tables from the cache, built "
            "the first time, about 15 s) at several sun elevations and fit the Hosek & Wilkie 2012 form (nine "
            "parameters and a radiance scale, quintic Bezier curves in the cube root of the sun elevation) at each "
            "wavelength by least squares. The dataset file is read by HosekWilkieSky(..., dataset="
            "HosekWilkieDataset.load(path)). Example: skyscatter fit-hosek-wilkie --turbidity 3 --out t3.npz"
        ),
        formatter_class=HELP_FORMATTER,
    )
    p.add_argument("--out", type=output_path, required=True, metavar="FILE.npz",
                   help="dataset file to write [.npz]; read it with HosekWilkieDataset.load")
    g = p.add_argument_group("atmosphere", "Earth defaults of the precomputed atmosphere unless changed.")
    add_atmosphere_options(g)
    f = p.add_argument_group("fit")
    f.add_argument("--fit-wavelengths", type=_wavelength_list, default=[440.0, 550.0, 680.0], metavar="LIST",
                   help="wavelengths to fit [nm], increasing, 300 to 1000, a list like 440,550,680 or "
                   "START:STOP:STEP (default: 440,550,680)")
    f.add_argument("--elevations", type=positive_int, default=16, metavar="N",
                   help=f"number of sun elevations sampled, even in (elevation / 90 deg)^(1/3), 6 to {MAX_ELEVATIONS}; "
                   "the fit's time grows with it (about a second per elevation and wavelength)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..fit import fit_hosek_wilkie, fit_sun_elevations
    from ..precomputed.cache import load_or_compute

    if args.out.suffix != ".npz":
        raise InvalidParameterError(f"--out must name an .npz file; got {args.out}")
    check_output_path(args.out, option="--out")
    if not 6 <= args.elevations <= MAX_ELEVATIONS:
        raise InvalidParameterError(f"--elevations must be at least 6 (one per control point) and at most "
                                    f"{MAX_ELEVATIONS}; got {args.elevations}")
    params = atmosphere_from_args(args)
    t0 = time.perf_counter()
    atm, _ = load_or_compute(params, progress=sys.stderr.isatty())
    from ..sky.bruneton import BrunetonSky

    def make(zenith: float, azimuth: float):
        return BrunetonSky(zenith, azimuth, precomputed=atm)

    ds = fit_hosek_wilkie(make, args.fit_wavelengths, sun_elevations=fit_sun_elevations(args.elevations),
                          provenance={"atmosphere": json.loads(params.canonical_json())})
    ds.save(args.out)
    rms = ds.provenance["fit"]["rms_relative_error_at_samples"]
    n_wl = len(args.fit_wavelengths)
    print(f"fitted {n_wl} wavelength{'s' if n_wl > 1 else ''} at {args.elevations} sun elevations in "
          f"{time.perf_counter() - t0:.1f} s")
    for w, row in zip(args.fit_wavelengths, rms, strict=True):
        worst = max(row)
        print(f"  {w:g} nm: RMS relative error at the samples {100 * math.fsum(row) / len(row):.2f} % mean, "
              f"{100 * worst:.2f} % worst")
    print(f"wrote {args.out}")
    return 0
