"""``skyscatter skymatrix``: hourly Perez (or ASRC-CIE) sky luminance over sky patches from an EPW weather file."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..errors import InvalidParameterError
from ..fileio import atomic_path, check_output_path
from .atmosphere_options import NAMES as ATMOSPHERE_NAMES
from .atmosphere_options import add_atmosphere_options, atmosphere_values
from .common import HELP_FORMATTER, float_in, output_path, positive_int

#: The atmosphere options of --spectral: every command's (atmosphere_options), --ground-albedo being the
#: command's own option (the Radiance ground patch's reflectance; with --spectral the tables' ground albedo).
SPECTRAL_AIR = tuple(n for n in ATMOSPHERE_NAMES if n != "ground_albedo")


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "skymatrix",
        help="annual sky matrix (hours x patches) from an EPW weather file, like Radiance gendaymtx",
        description="Read an hourly EnergyPlus weather file (.epw), place the sun at the middle of every hour "
        "(NREL SPA), build the sky of every hour (--model: the Perez 1993 all-weather sky, or the ASRC-CIE sky) "
        "from its direct normal and diffuse horizontal irradiance (Perez 1990 sky clearness, brightness and "
        "luminous efficacies with the hour's dew point) and write the mean "
        "luminance [cd m^-2] of every sky patch: an hours x patches matrix in a .npz file (and optionally a "
        "CSV), or (--format radiance) a Radiance matrix file that rmtxop and dctimestep read, laid out as "
        "gendaymtx writes it. Patches: Tregenza (145) or Reinhart MF 2 (577) / MF 4 (2305), ordered from the "
        "horizon band up, each band starting at north and going east, zenith last (Radiance's order without its "
        "ground patch). "
        "Weather records are checked: a direct normal irradiance above the extraterrestrial value or a diffuse "
        "horizontal above the global is refused with the line; light while the sun stays below the horizon is "
        "left dark with a warning (--night-irradiance); a time zone more than 3 h from the longitude's is warned "
        "about. Example: skyscatter skymatrix weather.epw --patches reinhart2 --out matrix.npz --csv matrix.csv",
        formatter_class=HELP_FORMATTER,
    )
    from ..patches import SCHEMES
    from ..sky import registry

    # Sky models an hour of weather data defines: those taking direct normal and diffuse horizontal irradiance.
    needed = {"direct_normal_irradiance", "diffuse_horizontal_irradiance"}
    weather_models = [s.name for s in registry.models() if needed <= {q.name for q in s.parameters}]
    p.add_argument("epw", type=Path, nargs="+",
                   help="hourly EnergyPlus weather file (.epw); with --spectral also TMY3 or weather CSV files, "
                   "several of them for a multi-site Zarr store")
    p.add_argument("--model", choices=weather_models, default="perez",
                   help="sky model of every hour, from its direct normal and diffuse horizontal irradiance: "
                   + "; ".join(f"{m}: {registry.get(m).summary}" for m in weather_models))
    p.add_argument("--patches", choices=list(SCHEMES), default="reinhart2",
                   help="patch scheme: tregenza = reinhart1 (145 patches), reinhart2 (577), reinhart4 (2305)")
    p.add_argument("--format", choices=["npz", "radiance"], default="npz",
                   help="npz: luminance [cd m^-2] (hours x patches, float32), times, sun angles [rad], Perez "
                   "epsilon/delta, diffuse and sun illuminance [lx], patch zenith/azimuth [rad] and solid angle [sr]; "
                   "radiance: a Radiance matrix (#?RADIANCE header, FORMAT=float), patches x hours x RGB with the "
                   "ground patch first, RGB radiance [W sr^-1 m^-2] at Radiance's 179 lm/W, the sky in gendaymtx's "
                   "default colour (0.960 1.004 1.118), the sun white")
    p.add_argument("--out", type=output_path, default=None, metavar="PATH",
                   help="output file (default: skymatrix.npz, or skymatrix.mtx with --format radiance)")
    p.add_argument("--ground-albedo", type=float_in(0.0, 1.0), default=None, metavar="RHO",
                   help="--format radiance: reflectance of the ground patch, whose radiance is RHO x the global "
                   "horizontal illuminance / pi, 0 to 1 (gendaymtx's -g; default 0.2); with --spectral the "
                   "ground albedo of the tables (default 0.2)")
    p.add_argument("--night-irradiance", choices=["dark", "error"], default="dark",
                   help="records with light while the sun stays below the horizon for their whole interval (more "
                   "than 1 deg for direct, 6 deg for diffuse light; a time shift or the wrong place): dark = left "
                   "dark with one warning counting them; error = refuse the file at the first")
    p.add_argument("--csv", type=output_path, default=None, metavar="PATH",
                   help="also write a CSV: a time column (ISO 8601, mid-hour) and one luminance column per patch")
    p.add_argument("--include-sun", action="store_true",
                   help="add the direct sun, spread over the 4 nearest patches weighted by proximity as gendaymtx does")
    p.add_argument("--samples", type=positive_int, default=None, metavar="N",
                   help="average each patch over N x N equal-area cells (1: patch centre only, as gendaymtx); "
                   "default 3 (luminance) or 2 (--spectral, at most 4)")
    p.add_argument("--timestep", choices=["records", "hourly"], default="records",
                   help="sub-hourly files (N records per hour declared in the DATA PERIODS header): records = one "
                   "row per record, the sun at the middle of each record's interval (as gendaymtx, one row per "
                   "input time step); hourly = average each hour's records first, one row per hour")
    g = p.add_argument_group(
        "spectral sky (--spectral)",
        "physical spectral sky per hour: the aerosol optical depth from DNI in clear hours (the DNI retrieval "
        "wins over the file's aerosol field there), the aerosol albedo from DHI, precipitable water from the "
        "file, through a family of precomputed tables (built once and cached: about 18 builds by default). "
        "Cloudy hours are not retrieved yet (their sky is NaN, status says so). Writes an xarray Dataset (.nc "
        "NetCDF or .zarr) with time x patch x wavelength radiance [W m^-2 sr^-1 nm^-1], the sun's direct normal "
        "spectrum [W m^-2 nm^-1], and per hour the inputs used, the retrieved air and the DNI/DHI closure. "
        "Example: skyscatter skymatrix --spectral a.epw --out a.nc --radiance a.mtx; many sites: skyscatter "
        "skymatrix --spectral a.epw b.epw --out sites.zarr")
    g.add_argument("--spectral", action="store_true", help="compute the physical spectral sky matrix")
    g.add_argument("--bands", choices=["20", "41"], default="20",
                   help="output bands: 20 (20 nm over 380-780 nm, as gensdaymtx) or 41 (10 nm, centred 380-780 nm)")
    g.add_argument("--radiance", type=output_path, default=None, metavar="PATH",
                   help="also write Radiance's matrix (ground patch + patches x hours x bands, FORMAT=float) for "
                   "rmtxop/dctimestep (one site only)")
    g.add_argument("--radiance-rgb", type=output_path, default=None, metavar="PATH",
                   help="also write the matrix as Radiance RGB radiance (NCOMP=3, 179 lm/W), which this Radiance's "
                   "dctimestep needs (it takes 3 components only; rmtxop takes --radiance)")
    g.add_argument("--report", type=output_path, default=None, metavar="PATH",
                   help="also write a per-hour CSV report: status, reason, inputs used and their sources, retrieved "
                   "aerosol, DNI and DHI closure (one site only)")
    g.add_argument("--bad-hours", choices=["error", "flag"], default="error",
                   help="impossible records (DNI above extraterrestrial, DHI > GHI, light with the sun below the "
                   "horizon, missing fields): error, or flag the hour and leave its sky NaN")
    g.add_argument("--tables", choices=["default", "coarse"], default="default",
                   help="table preset of the family: default (paper sizes, 8 orders, 23 wavelengths) or coarse "
                   "(a quick look: small tables, 4 orders, 8 wavelengths)")
    g.add_argument("--aod-nodes", type=str, default=None, metavar="LIST",
                   help="aerosol optical depth grid at 550 nm, comma-separated (default "
                   "0,0.05,0.1,0.2,0.3,0.45,0.65,1,1.5)")
    a = p.add_argument_group(
        "the air of --spectral",
        "the medium the hourly retrieval starts from (the same options as every command that builds an "
        "atmosphere): --aerosol TYPE an OPAC type whose optical depth is retrieved per hour from DNI (its albedo "
        "and spectral shape are its Mie optics'; no albedo axis), --atmosphere FILE a fitted air, --mie-g, "
        "--ozone (hours without an ozone value), --angstrom-alpha (the analytic aerosol's spectral shape); "
        "--aod / --turbidity give the optical depth of hours with nothing to retrieve it from (cloudy hours "
        "without a clear hour or a file value)")
    add_atmosphere_options(a, SPECTRAL_AIR)
    g.add_argument("--scheduler", default="threads", metavar="NAME",
                   help="several sites: threads (Dask's threaded scheduler), local (a distributed LocalCluster) or "
                   "a scheduler address tcp://host:port")
    g.add_argument("--workers", type=positive_int, default=2, metavar="N",
                   help="several sites: threads or worker processes")
    p.add_argument("--no-progress", dest="progress", action="store_false",
                   help="hide the progress bar (shown only when stderr is a terminal)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from ..sky_matrix import skymatrix

    if args.spectral:
        return run_spectral(args)
    if len(args.epw) != 1:
        raise InvalidParameterError("several weather files need --spectral (one Zarr store with a site dimension)")
    for name in ("radiance", "radiance_rgb", "report"):
        if getattr(args, name) is not None:
            raise InvalidParameterError(f"--{name.replace('_', '-')} goes with --spectral")
    if atmosphere_values(args, SPECTRAL_AIR):
        raise InvalidParameterError("the atmosphere options (--aerosol, --aod, --atmosphere, ...) go with --spectral; "
                                    f"the luminance matrix is the {args.model} sky of the file's DNI and DHI")
    args.epw = args.epw[0]
    args.samples = 3 if args.samples is None else args.samples
    if args.out is None:
        args.out = Path("skymatrix.mtx" if args.format == "radiance" else "skymatrix.npz")
    if args.format == "npz" and args.out.suffix.lower() != ".npz":
        raise InvalidParameterError(f"--out must end in .npz; got {args.out} (a Radiance matrix: --format radiance)")
    if args.format == "radiance" and args.out.suffix.lower() == ".npz":
        raise InvalidParameterError(f"--out {args.out}: a Radiance matrix is not an .npz file (use e.g. .mtx)")
    if args.format == "npz" and args.ground_albedo is not None:
        raise InvalidParameterError("--ground-albedo applies to --format radiance only")
    check_output_path(args.out, option="--out")
    if args.csv is not None:
        check_output_path(args.csv, option="--csv")
        if args.csv.resolve() == args.out.resolve():
            raise InvalidParameterError("--out and --csv must be different files")
    if args.samples > 16:
        raise InvalidParameterError(f"--samples must be at most 16; got {args.samples}")
    t0 = time.perf_counter()
    matrix = skymatrix(args.epw, scheme=args.patches, include_sun=args.include_sun, samples=args.samples,
                       progress=args.progress and sys.stderr.isatty(), timestep=args.timestep, model=args.model,
                       night_irradiance=args.night_irradiance)
    elapsed = time.perf_counter() - t0
    written = [str(t) for t in matrix.save(args.out, args.csv, format=args.format,
                                           ground_reflectance=0.2 if args.ground_albedo is None
                                           else args.ground_albedo)]
    hours, patches = matrix.shape
    lit = int(np.count_nonzero(matrix.diffuse_illuminance > 0))
    loc = matrix.location
    print(f"{args.epw}: {loc.city}, {loc.country} ({loc.latitude_deg:.3f}, {loc.longitude_deg:.3f} deg, "
          f"UTC{loc.timezone_hours:+g} h); {hours} hours, {lit} with daylight")
    print(f"{patches} patches ({matrix.scheme.name}), {matrix.model} sky, sun "
          f"{'included' if matrix.include_sun else 'excluded'}; computed in {elapsed:.2f} s")
    print("wrote " + " and ".join(written))
    return 0


def _csv_report(ds, path: Path) -> None:
    import numpy as np

    cols = ["status", "reason", "ghi", "dni", "dhi", "aerosol_optical_depth", "aerosol_source",
            "aerosol_optical_depth_file", "single_scattering_albedo", "aerosol_phase_g", "precipitable_water",
            "precipitable_water_source", "ozone", "pressure", "cloud_optical_depth", "cloud_cover", "cloud_fraction",
            "dni_model", "dhi_matrix", "dni_closure", "dhi_closure"]
    times = [str(t)[:19] + "Z" for t in ds["time"].values]
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("time," + ",".join(cols) + "\n")
        arrays = [ds[c].values for c in cols]
        for i, t in enumerate(times):
            cells = []
            for c, a in zip(cols, arrays, strict=True):
                v = a[i]
                if c == "reason":
                    cells.append('"' + str(v).replace('"', "'") + '"')
                elif isinstance(v, (str, np.str_)):
                    cells.append(str(v))
                elif c == "status":
                    cells.append(str(int(v)))
                else:
                    cells.append("" if not np.isfinite(v) else f"{float(v):.6g}")
            fh.write(t + "," + ",".join(cells) + "\n")


def spectral_retrieval_options(values: dict, **settings):
    """The :class:`~skyscatter.fit.weather.RetrievalOptions` of ``skymatrix --spectral`` from the atmosphere
    options ``values`` (keyword names of :data:`~skyscatter.atmosphere.options.ATMOSPHERE_OPTIONS`) and the
    retrieval's other ``settings``: the options change the retrieval's default base medium (or replace it:
    ``atmosphere_file``) through :meth:`AtmosphereParameters.from_options`; ``angstrom_alpha`` alone sets the
    analytic aerosol's spectral shape; an optical depth (``aerosol_optical_depth``, ``turbidity``) becomes the
    optical depth of hours with nothing to retrieve it from, ``ozone_column`` that of hours without ozone data."""
    from ..atmosphere import AtmosphereParameters
    from ..fit.weather import RetrievalOptions

    alpha = float(values.get("angstrom_alpha", RetrievalOptions.angstrom_alpha))
    if not values or set(values) == {"angstrom_alpha"}:
        return RetrievalOptions(angstrom_alpha=alpha, **settings)
    air = {k: v for k, v in values.items() if k != "angstrom_alpha" or "aerosol_optical_depth" in values}
    start = None if "atmosphere_file" in air else RetrievalOptions(angstrom_alpha=alpha).base_atmosphere()
    base = AtmosphereParameters.from_options(start, **air)
    extra: dict = {}
    if base.aerosol is None:
        alpha = base.mie_angstrom_alpha
    if {"aerosol_optical_depth", "turbidity", "atmosphere_file"} & set(values):
        extra["default_aerosol_optical_depth"] = float(base.aerosol_component.optical_depth([550.0],
                                                                                           base.thickness)[0])
    if {"ozone_column", "atmosphere_file"} & set(values):
        extra["default_ozone"] = base.ozone_column
    return RetrievalOptions(angstrom_alpha=alpha, base=base, **extra, **settings)


def run_spectral(args: argparse.Namespace) -> int:
    import numpy as np

    from ..fit.spectral_matrix import (
        save_dataset,
        spectral_sky_matrix,
        spectral_sky_matrix_sites,
        write_radiance_matrix,
    )
    from ..fit.weather import DEFAULT_AOD_NODES, HOUR_STATUS

    if args.model != "perez" or args.include_sun or args.csv is not None or args.timestep != "records":
        raise InvalidParameterError("--model, --include-sun, --csv and --timestep go with the luminance matrix, "
                                    "not with --spectral (the sun is kept separately there)")
    samples = 2 if args.samples is None else args.samples
    if samples > 4:
        raise InvalidParameterError(f"--samples must be at most 4 with --spectral; got {samples}")
    nodes = DEFAULT_AOD_NODES
    if args.aod_nodes is not None:
        try:
            nodes = tuple(float(x) for x in args.aod_nodes.split(","))
        except ValueError:
            raise InvalidParameterError(
                f"--aod-nodes must be comma-separated numbers; got {args.aod_nodes!r}") from None
    if args.format != "npz" or args.night_irradiance != "dark":
        raise InvalidParameterError("--format and --night-irradiance go with the luminance matrix; with --spectral "
                                    "use --radiance / --radiance-rgb and --bad-hours")
    values = atmosphere_values(args, SPECTRAL_AIR)
    if args.ground_albedo is not None:
        values["ground_albedo"] = args.ground_albedo
    options = spectral_retrieval_options(values, aerosol_optical_depth_nodes=nodes, bad_hours=args.bad_hours,
                                         tables=args.tables)
    out = args.out
    if out is None:
        out = Path("skymatrix.nc") if len(args.epw) == 1 else Path("sites.zarr")
    progress = args.progress and sys.stderr.isatty()
    t0 = time.perf_counter()
    if len(args.epw) > 1:
        if args.radiance is not None or args.report is not None or args.radiance_rgb is not None:
            raise InvalidParameterError("--radiance and --report take one site; the multi-site store holds status "
                                        "and closure per site and hour")
        if out.suffix.lower() != ".zarr":
            raise InvalidParameterError(
                f"several sites are written to one Zarr store: --out must end in .zarr; got {out}")
        ds = spectral_sky_matrix_sites(args.epw, out, scheme=args.patches, bands=int(args.bands), samples=samples,
                                       options=options, scheduler=args.scheduler, workers=args.workers,
                                       progress=args.progress)
        done = int(ds["done"].values.sum())
        print(f"{done} of {ds.sizes['site']} sites in {out} ({ds.sizes['patch']} patches, {ds.sizes['wavelength']} "
              f"bands, {ds.sizes['hour']} hours); computed in {time.perf_counter() - t0:.1f} s")
        return 0
    if out.suffix.lower() not in (".nc", ".zarr"):
        raise InvalidParameterError(f"--out must end in .nc or .zarr with --spectral; got {out}")
    for opt, path in (("--out", out), ("--radiance", args.radiance), ("--radiance-rgb", args.radiance_rgb),
                      ("--report", args.report)):
        if path is not None:
            check_output_path(path, option=opt)
    ds = spectral_sky_matrix(args.epw[0], scheme=args.patches, bands=int(args.bands), samples=samples, options=options,
                             progress=progress)
    written = [str(save_dataset(ds, out))]
    if args.radiance is not None:
        written.append(str(write_radiance_matrix(ds, args.radiance)))
    if args.radiance_rgb is not None:
        written.append(str(write_radiance_matrix(ds, args.radiance_rgb, rgb=True)))
    if args.report is not None:
        _csv_report(ds, args.report)
        written.append(str(args.report))
    st = ds["status"].values
    counts = ", ".join(f"{int((st == k).sum())} {v}" for k, v in HOUR_STATUS.items() if (st == k).any())
    closure = ds["dhi_closure"].values[st == 1]
    dni_c = ds["dni_closure"].values[st == 1]
    print(f"{args.epw[0]}: {ds.sizes['time']} hours: {counts}")
    if closure.size:
        print(f"clear hours: DNI closure within {np.nanmax(np.abs(dni_c)) * 100:.2g} %, DHI closure of the matrix "
              f"within {np.nanmax(np.abs(closure)) * 100:.2g} %")
    for code, what in ((4, "cloudy"), (6, "broken"), (8, "broken, enhanced diffuse (by construction)")):
        c = ds["dhi_closure"].values[st == code]
        c = c[np.isfinite(c)]
        if c.size:
            print(f"{what} hours: DHI closure of the matrix within {np.max(np.abs(c)) * 100:.2g} %, median "
                  f"{np.median(np.abs(c)) * 100:.2g} %")
    if ds.attrs.get("notes"):
        print("notes: " + ds.attrs["notes"])
    print(f"{ds.sizes['patch']} patches ({ds.attrs['scheme']}), {ds.sizes['wavelength']} bands; computed in "
          f"{time.perf_counter() - t0:.1f} s")
    print("wrote " + ", ".join(written))
    return 0
