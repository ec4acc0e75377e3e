"""``skyscatter fit-atmosphere``: retrieve the air from a sky scan, DNI/DHI or optical depths, write it as JSON.

Measurement file (CSV, one measurement per row, '#' lines are comments), columns:

=================  =======================================================================================
``kind``           ``radiance`` [W m^-2 sr^-1 nm^-1], ``luminance`` [cd m^-2], ``dni`` / ``dhi`` (spectral
                   direct normal / diffuse horizontal irradiance [W m^-2 nm^-1]) or ``aod`` (aerosol optical
                   depth [-])
``time``           ISO 8601 time with a UTC offset (needs ``--lat``/``--lon``), one time per file; or leave it
                   empty and give ``sun_elevation_deg`` and ``sun_azimuth_deg`` columns
``azimuth_deg``    view azimuth from north towards east [deg] (radiance and luminance rows)
``elevation_deg``  view elevation above the horizon [deg], in (0, 90] (radiance and luminance rows)
``wavelength_nm``  [nm] (empty for luminance)
``value``          the measured value (> 0; >= 0 for aod)
=================  =======================================================================================
"""

from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

from ..errors import FileFormatError, InvalidParameterError
from ..fileio import check_output_path
from .common import HELP_FORMATTER, float_in

KINDS = ("radiance", "luminance", "dni", "dhi", "aod")
REQUIRED = ("kind", "value")


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "fit-atmosphere",
        help="fit the aerosol and ground albedo to measurements (sky scan, DNI/DHI, optical depths); write JSON",
        description=(
            "Least-squares retrieval of the air over the precomputed sky (Bruneton & Neyret 2008; tables rebuilt "
            "at reduced size for each trial, about 1 s each; the fit reports how many). The measurement file is a "
            "CSV with columns kind (radiance, luminance, dni, dhi, aod), time (ISO 8601 with offset, with --lat "
            "and --lon) or sun_elevation_deg and sun_azimuth_deg, azimuth_deg, elevation_deg, wavelength_nm and "
            "value (docs/aerosols.md). Prints the fitted air with uncertainties and the residual by region and "
            "writes it as JSON, which --atmosphere FILE reads in 'skyscatter sky --model bruneton'. Example: "
            "skyscatter fit-atmosphere scan.csv --lat 40.0 --lon -105.2 --out air.json"
        ),
        formatter_class=HELP_FORMATTER,
    )
    p.add_argument("measurements", type=Path, metavar="MEASUREMENTS.csv", help="measurement file (columns above)")
    p.add_argument("--out", type=Path, default=Path("air.json"), metavar="FILE.json",
                   help="JSON file to write (default air.json)")
    p.add_argument("--lat", type=float_in(-90.0, 90.0), default=None, metavar="DEG", help="site latitude [deg]")
    p.add_argument("--lon", type=float_in(-180.0, 180.0), default=None, metavar="DEG", help="site longitude [deg]")
    p.add_argument("--free", default="aerosol_optical_depth,mie_phase_g,ground_albedo", metavar="LIST",
                   help="parameters to fit, comma-separated: aerosol_optical_depth, angstrom_alpha, mie_phase_g, "
                        "mie_single_scattering_albedo, ground_albedo; with --aerosol or --mixture: "
                        "aerosol_optical_depth, relative_humidity, ground_albedo (default "
                        "aerosol_optical_depth,mie_phase_g,ground_albedo; with --aerosol or --mixture "
                        "aerosol_optical_depth,ground_albedo)")
    p.add_argument("--aerosol", default=None, metavar="TYPE",
                   help="fit an OPAC aerosol type (continental-average, maritime-clean, urban, desert, ...) instead "
                        "of the analytic aerosol")
    p.add_argument("--mixture", default=None, metavar="LIST",
                   help="fit an external mixture of OPAC components or types, comma-separated (e.g. waso,sscm: a "
                        "fine and a coarse mode; components inso, waso, soot, ssam, sscm, minm, miam, micm, mitr, "
                        "suso, or type names): aerosol_optical_depth in --free then stands for each member's "
                        "optical depth at 550 nm; prints the total and each member's fraction with uncertainties")
    p.add_argument("--noise", type=float_in(1e-4, 1.0), default=0.03, metavar="REL",
                   help="relative noise of radiance, luminance and irradiance (default 0.03)")
    p.set_defaults(func=run)


def _float(row: dict, key: str, line: int, path: Path) -> float:
    text = (row.get(key) or "").strip()
    try:
        v = float(text)
    except ValueError:
        raise FileFormatError(f"{path}, line {line}: column {key} must be a number; got {text!r}") from None
    if not math.isfinite(v):
        raise FileFormatError(f"{path}, line {line}: column {key} is not finite ({text})")
    return v


def read_measurements(path: Path, lat: float | None, lon: float | None):
    """``(scan, irradiance, aod)`` from a measurement file (module docstring); FileFormatError or
    InvalidParameterError for anything missing or out of range."""
    import numpy as np

    from ..fit.atmosphere import AerosolOpticalDepth, Irradiance, SkyScan

    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise FileFormatError(f"cannot read {path}: {exc.strerror or exc}") from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    reader = csv.DictReader(lines)
    if reader.fieldnames is None:
        raise FileFormatError(f"{path}: empty file")
    cols = [c.strip() for c in reader.fieldnames]
    reader.fieldnames = cols
    missing = [c for c in REQUIRED if c not in cols]
    if missing:
        raise FileFormatError(f"{path}: missing column(s) {', '.join(missing)}; columns are kind, time or "
                              "sun_elevation_deg/sun_azimuth_deg, azimuth_deg, elevation_deg, wavelength_nm, value")
    has_sun = "sun_elevation_deg" in cols and "sun_azimuth_deg" in cols
    if not has_sun and "time" not in cols:
        raise FileFormatError(f"{path}: needs a time column (with --lat, --lon) or sun_elevation_deg and "
                              "sun_azimuth_deg columns")
    sky: dict[float | None, list[tuple[float, float, float]]] = {}
    irr: dict[str, dict[float, float]] = {"dni": {}, "dhi": {}}
    aod: dict[float, float] = {}
    suns: set[tuple[float, float]] = set()
    times: set[str] = set()
    for line, row in enumerate(reader, start=2):
        kind = (row.get("kind") or "").strip().lower()
        if kind not in KINDS:
            raise FileFormatError(f"{path}, line {line}: kind must be one of {', '.join(KINDS)}; got {kind!r}")
        value = _float(row, "value", line, path)
        if value < 0 or (value == 0 and kind != "aod"):
            raise InvalidParameterError(f"{path}, line {line}: value must be > 0 (>= 0 for aod); got {value:g}")
        if kind != "aod":
            if has_sun and (row.get("sun_elevation_deg") or "").strip():
                el = _float(row, "sun_elevation_deg", line, path)
                az = _float(row, "sun_azimuth_deg", line, path)
                if not (1.0 < el <= 90.0 and -360.0 <= az <= 360.0):
                    raise InvalidParameterError(f"{path}, line {line}: sun elevation must be in (1, 90] deg and "
                                                f"azimuth in [-360, 360] deg; got {el:g}, {az:g}")
                suns.add((el, az % 360.0))
            else:
                t = (row.get("time") or "").strip()
                if not t:
                    raise FileFormatError(f"{path}, line {line}: no time and no sun position")
                times.add(t)
        if kind in ("radiance", "luminance"):
            az = _float(row, "azimuth_deg", line, path)
            el = _float(row, "elevation_deg", line, path)
            if not (0.0 < el <= 90.0 and -360.0 <= az <= 360.0):
                raise InvalidParameterError(f"{path}, line {line}: view elevation must be in (0, 90] deg and azimuth "
                                            f"in [-360, 360] deg; got {el:g}, {az:g}")
            wl = None if kind == "luminance" else _float(row, "wavelength_nm", line, path)
            sky.setdefault(wl, []).append((math.radians(90.0 - el), math.radians(az % 360.0), value))
        else:
            wl = _float(row, "wavelength_nm", line, path)
            if not 300.0 <= wl <= 1000.0:
                raise InvalidParameterError(f"{path}, line {line}: wavelength must be in 300-1000 nm; got {wl:g}")
            (aod if kind == "aod" else irr[kind])[wl] = value
    if len(suns) + len(times) > 1:
        raise InvalidParameterError(f"{path}: one scan per file (one time or one sun position); found "
                                    f"{len(suns) + len(times)}")
    sun_z = sun_a = None
    if suns:
        el, az = next(iter(suns))
        sun_z, sun_a = math.radians(90.0 - el), math.radians(az)
    elif times:
        if lat is None or lon is None:
            raise InvalidParameterError("the file gives a time: pass --lat and --lon for the sun position")
        import datetime

        from ..sun import sun_position

        t = next(iter(times))
        try:
            when = datetime.datetime.fromisoformat(t.replace("Z", "+00:00"))
        except ValueError:
            raise FileFormatError(f"{path}: time {t!r} is not ISO 8601") from None
        pos = sun_position(math.radians(lat), math.radians(lon), when)
        sun_z, sun_a = float(pos.zenith), float(pos.azimuth)
    scan = irradiance = tau = None
    if sky:
        if None in sky and len(sky) > 1:
            raise InvalidParameterError(f"{path}: radiance and luminance rows in one scan")
        if None in sky:
            z, a, v = (np.array(c) for c in zip(*sky[None], strict=True))
            scan = SkyScan(z, a, v, sun_z, sun_a)
        else:
            wls = sorted(sky)
            first = [(zz, aa) for zz, aa, _ in sky[wls[0]]]
            for w in wls:
                if [(zz, aa) for zz, aa, _ in sky[w]] != first:
                    raise InvalidParameterError(f"{path}: every wavelength of the scan needs the same directions")
            values = np.array([[v for _, _, v in sky[w]] for w in wls]).T
            z, a = (np.array(c) for c in zip(*first, strict=True))
            scan = SkyScan(z, a, values, sun_z, sun_a, np.array(wls))
    if irr["dni"] or irr["dhi"]:
        wls = sorted(set(irr["dni"]) | set(irr["dhi"]))
        for key in ("dni", "dhi"):
            if irr[key] and sorted(irr[key]) != wls:
                raise InvalidParameterError(f"{path}: dni and dhi need the same wavelengths")
        irradiance = Irradiance(np.array(wls), sun_z, sun_a,
                                np.array([irr["dni"][w] for w in wls]) if irr["dni"] else None,
                                np.array([irr["dhi"][w] for w in wls]) if irr["dhi"] else None)
    if aod:
        wls = sorted(aod)
        tau = AerosolOpticalDepth(np.array(wls), np.array([aod[w] for w in wls]))
    return scan, irradiance, tau


def run(args: argparse.Namespace) -> int:
    import dataclasses

    from ..fit.atmosphere import fit_atmosphere

    if args.out.suffix != ".json":
        raise InvalidParameterError(f"--out must name a .json file; got {args.out}")
    check_output_path(args.out)
    if args.aerosol is not None:
        from ..atmosphere.aerosol_types import AEROSOL_TYPES

        if args.aerosol not in AEROSOL_TYPES:
            raise InvalidParameterError(f"--aerosol must be one of {', '.join(AEROSOL_TYPES)}; got {args.aerosol!r}")
    free = tuple(s.strip() for s in args.free.split(",") if s.strip())
    mixture = None
    if args.mixture is not None:
        mixture = tuple(s.strip() for s in args.mixture.split(",") if s.strip())
        if args.aerosol is not None:
            raise InvalidParameterError("give --aerosol or --mixture, not both")
    if (args.aerosol is not None or mixture is not None) and \
            args.free == "aerosol_optical_depth,mie_phase_g,ground_albedo":
        free = ("aerosol_optical_depth", "ground_albedo")
        default_free = True
    else:
        default_free = False
    scan, irradiance, aod = read_measurements(args.measurements, args.lat, args.lon)
    if scan is not None:
        scan = dataclasses.replace(scan, relative_noise=args.noise)
    if irradiance is not None:
        irradiance = dataclasses.replace(irradiance, relative_noise=args.noise)
    if default_free and scan is None and irradiance is None:
        free = ("aerosol_optical_depth",)  # optical depths alone do not see the ground
    fit = fit_atmosphere(scan, irradiance, aod, free=free, aerosol_type=args.aerosol, mixture=mixture)
    print(f"fitted air ({fit.builds} table builds, {fit.seconds:.1f} s, reduced chi^2 {fit.chi2_reduced:.3g}):")
    for name in fit.free:
        print(f"  {name:30s} {fit.values[name]:.4g} +- {fit.uncertainties[name]:.2g}")
    for name, (value, sd) in fit.derived.items():
        print(f"  {name:30s} {value:.4g} +- {sd:.2g}")
    for region, value in fit.residuals.items():
        unit = "" if region == "aod" else " %"
        print(f"  residual RMS {region:18s} {value:.3g}{unit}")
    fit.parameters.save_json(str(args.out), {"fit": fit.report()})
    print(f"wrote {args.out} (use it with: skyscatter sky --model bruneton --atmosphere {args.out})")
    return 0
