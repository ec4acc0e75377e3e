"""``skyscatter demo``: render the built-in landscape as in Preetham, Shirley & Smits (1999), Figures 7 and 8.

With no options it writes, into the current folder, one HDR OpenEXR file (linear sRGB, Y = luminance / 683)
and one tone-mapped PNG per panel, plus a PNG of each figure with its panels stacked top to bottom:

* Figure 7, looking west: (a) morning, T = 2; (b) evening, T = 2; (c) evening, T = 6; (d) overcast, T = 10
  (CIE overcast sky, achromatic; aerial perspective with T = 10 lit by that sky only).
* ``--figure clouds`` (not part of ``all``: it needs the precomputed tables and a DISORT solve), looking west:
  (a) broken cumulus with the sun 30 deg high (the ``broken-cloud`` model: a procedural field of cover 0.4 and
  its shadows on the terrain); (b) an overcast evening (the ``cloudy`` model: a stratus of optical depth 20 with
  the sun 4 deg high behind it).
* Figure 8, looking east half an hour before sunset, T = 6: (a) the CIE clear sky with one colour
  everywhere (the spectrum of the Preetham zenith) and Ward-Larson's direction-independent aerial
  perspective; (b) the Preetham sky and aerial perspective.

Any scene option (sky, turbidity, sun, aerial model) renders one custom panel instead.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import InvalidParameterError
from ..fileio import atomic_paths, check_output_path, ensure_output_folder
from .atmosphere_options import NAMES as ATMOSPHERE_NAMES
from .atmosphere_options import add_atmosphere_options, add_deprecated_option
from .common import HELP_FORMATTER, add_sun_options, finite_float, float_in, positive_int, sun_angles_from_args
from .sky_options import add_model_options, add_parameter_options, build_sky_from_args, parameter_values

if TYPE_CHECKING:
    from ..sky.base import SkyModel

#: (elevation, azimuth) [deg] of the sun in the figure panels.
MORNING_SUN = (25.0, 120.0)
EVENING_SUN = (4.0, 290.0)
#: The sun of the broken-cumulus panel of ``--figure clouds`` (elevation, azimuth) [deg]: 30 deg high, behind the
#: camera's left so that the clouds' shadows fall on the terrain in view.
CUMULUS_SUN = (30.0, 200.0)
#: Camera headings [deg]: Figure 7 looks west, Figure 8 east.
WEST, EAST = 270.0, 90.0
#: Camera (x, y) [m] on the built-in landscape: Figure 7 (and custom panels) and Figure 8, chosen for ranges of
#: mountains at several distances in the view.
FIG7_CAMERA_XY = (12_000.0, 0.0)
FIG8_CAMERA_XY = (-26_000.0, -16_000.0)

#: Bounds of the camera options [m]: the flat-earth scene's horizontal extent and the flat atmosphere's height
#: (as PinholeCamera.MAX_CAMERA_OFFSET and MAX_CAMERA_HEIGHT).
_MAX_CAMERA_XY = 1e7
_MAX_CAMERA_Z = 1e5

_SCENE_OPTIONS = ("sun_elevation", "sun_azimuth", "lat", "lon", "time", "aerial")
#: Parameters of the precomputed atmosphere that ``--model bruneton`` takes: the atmosphere's options
#: (:data:`skyscatter.atmosphere.options.ATMOSPHERE_OPTIONS`; ``--turbidity`` is shared with the skies and
#: ``--ground-albedo`` with the skies that have a ground, such as hosek-wilkie) and its tables. The terrain's albedo
#: is ``--terrain-albedo``.
_BRUNETON_OPTIONS = (*ATMOSPHERE_NAMES, "tables")
#: Default turbidity of the haze for skies that have none of their own (the CIE and Perez skies).
DEFAULT_HAZE_TURBIDITY = 2.5


def _scene_options(args: argparse.Namespace) -> list[str]:
    """Names of the scene options given: the fixed ones and every sky-model parameter from the registry."""
    names = [k for k in (*_SCENE_OPTIONS, "ground_albedo") if getattr(args, k, None) is not None]
    if getattr(args, "model", None) is not None:
        names.insert(0, "model")
    from ..sky import registry

    for spec in registry.models():
        for p in spec.parameters:
            own_option = p.name in getattr(args, "_model_shared", ())  # --ground-albedo, listed above
            if p.cli and not own_option and getattr(args, p.name, None) is not None and p.name not in names:
                names.append(p.name)
    return names


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "demo",
        help="render the landscape of Preetham et al. 1999, Figures 7 and 8 (EXR + PNG)",
        description="Render the built-in procedural mountains (fixed seed) under the Preetham sky with its "
        "aerial perspective, as in Preetham, Shirley & Smits 1999. With no options: Figure 7 (looking west: "
        "morning T=2, evening T=2, evening T=6, overcast T=10) and Figure 8 (looking east before sunset, T=6: "
        "CIE clear sky of one colour with Ward-Larson's ambient aerial perspective, then the Preetham model), "
        "one EXR (linear sRGB, Y = luminance/683) and one PNG per panel plus fig7.png and fig8.png, in the "
        "current folder. --figure clouds renders broken cumulus (sun 30 deg) and an overcast evening under "
        "physical cloud models (clouds.png). Giving --model, --turbidity, a sun option or --aerial renders one "
        "custom panel "
        "(landscape.exr/.png) instead. Nothing is written unless every image renders and every file can be "
        "written.",
        formatter_class=HELP_FORMATTER,
    )
    p.add_argument("--figure", choices=["all", "7", "8", "clouds", "custom"], default=None,
                   help="which figure to render (default: all = 7 and 8, or custom when a scene option is given); "
                   "clouds: broken cumulus at a 30 deg sun and an overcast evening (the broken-cloud and cloudy "
                   "models, with the precomputed tables: the first run computes and caches them, about 20 s)")
    p.add_argument("--out-dir", type=Path, default=Path("."), metavar="DIR",
                   help="folder for the output files (created if missing)")
    g = p.add_argument_group("image")
    g.add_argument("--width", type=positive_int, default=640, metavar="PX", help="width of each panel [px]")
    g.add_argument("--height", type=positive_int, default=360, metavar="PX", help="height of each panel [px]")
    g.add_argument("--no-glare", dest="glare", action="store_false",
                   help="leave out the glare of the eye (Spencer et al. 1995 point-spread function), which is "
                   "applied by default")
    g.add_argument("--no-sun-disc", dest="sun_disc", action="store_false",
                   help="leave out the solar disc (drawn by default)")
    g.add_argument("--exposure", type=float_in(-30.0, 30.0), default=None, metavar="EV",
                   help="PNG exposure compensation [EV stops] on top of the automatic exposure (default 0)")
    g.add_argument("--wavelength-step", type=float_in(1.0, 50.0), default=10.0, metavar="NM",
                   help="spacing of the spectral samples over 380-780 nm [nm]")
    s = p.add_argument_group("custom scene (any of these renders one custom panel)")
    from ..sky import registry

    add_model_options(s, registry.names(), default=None, shown_default="preetham", shared=("ground_albedo",),
                      parameters_of=[m for m in registry.names() if m != "bruneton"], deprecated=False)
    add_deprecated_option(s, "--sky", "--model", "sky_old", choices=[m for m in registry.names() if m != "bruneton"])
    s.description = (f"--turbidity is the sky's and the haze's turbidity; with a sky that has none (cie*, perez, "
                     f"asrc-cie) it is the haze's alone (1.65 to 11, default {DEFAULT_HAZE_TURBIDITY}). --model "
                     "bruneton renders the precomputed multiple scattering of Bruneton & Neyret 2008 (cached after "
                     "the first run, about 15 s): sky, sunlight, aerial perspective, and light shafts from the "
                     "mountains' shadow; --aerial and the other skies' parameters do not apply to it.")
    s.add_argument("--aerial", choices=["analytic", "numeric", "constant", "ward-larson", "none"], default=None,
                   help="aerial perspective: analytic (Preetham 1999 closed form), numeric (quadrature), "
                   "constant (constant density; lit by the sun only, or by the sky for the sunless cie-overcast "
                   "sky), ward-larson (ambient), none (default analytic)")
    b = p.add_argument_group("precomputed atmosphere (--model bruneton; --turbidity also applies, and --ground-albedo "
                             "also to the skies with a ground)",
                             "The Earth defaults unless changed; each atmosphere's tables are computed once "
                             "(about 15 s) and cached.")
    add_atmosphere_options(b, [n for n in ATMOSPHERE_NAMES if n != "turbidity"])
    add_parameter_options(b, "bruneton", ["tables"])
    add_deprecated_option(b, "--wavelengths", "--tables", "tables", choices=["spectral", "rgb"])
    add_sun_options(p, default_elevation=EVENING_SUN[0], default_azimuth=EVENING_SUN[1])
    c = p.add_argument_group("camera and terrain")
    c.add_argument("--dem", type=Path, default=None, metavar="PATH",
                   help="elevation model instead of the built-in landscape: .npy (2-D heights [m], north-up; "
                   "needs --dem-spacing) or GeoTIFF .tif/.tiff (needs the optional tifffile package)")
    c.add_argument("--dem-spacing", type=float_in(1e-3, 1e6), default=None, metavar="M",
                   help="sample spacing of the elevation model [m] (GeoTIFF: default from the file)")
    c.add_argument("--terrain-albedo", type=float_in(0.0, 1.0), default=0.2, metavar="RHO",
                   help="Lambertian albedo of the terrain (the atmosphere's ground is --ground-albedo)")
    add_deprecated_option(c, "--albedo", "--terrain-albedo", "terrain_albedo", type=float_in(0.0, 1.0))
    c.add_argument("--camera-x", type=float_in(-_MAX_CAMERA_XY, _MAX_CAMERA_XY), default=None, metavar="M",
                   help="camera east coordinate [m], within +-1e7 (default on the built-in landscape: 12000 for "
                   "figure 7 and custom panels, -26000 for figure 8; the centre of a DEM)")
    c.add_argument("--camera-y", type=float_in(-_MAX_CAMERA_XY, _MAX_CAMERA_XY), default=None, metavar="M",
                   help="camera north coordinate [m], within +-1e7 (default on the built-in landscape: 0 for "
                   "figure 7 and custom panels, -16000 for figure 8; the centre of a DEM)")
    h = c.add_mutually_exclusive_group()
    h.add_argument("--camera-height", type=float_in(0.01, _MAX_CAMERA_Z), default=None, metavar="M",
                   help="camera height above the ground [m], up to 1e5 (default 300)")
    h.add_argument("--camera-altitude", type=float_in(-_MAX_CAMERA_Z, _MAX_CAMERA_Z), default=None, metavar="M",
                   help="camera height above sea level [m], within +-1e5 (the flat atmosphere's domain) and "
                   "above the terrain (default: --camera-height over the ground)")
    c.add_argument("--heading", type=finite_float, default=None, metavar="DEG",
                   help="azimuth of the view centre from north towards east [deg] (default: 270 for figure 7 "
                   "and custom panels, 90 for figure 8)")
    c.add_argument("--pitch", type=float_in(-89.0, 89.0), default=-3.0, metavar="DEG",
                   help="elevation of the view centre [deg]")
    c.add_argument("--fov", type=float_in(1.0, 150.0), default=60.0, metavar="DEG",
                   help="horizontal field of view [deg]")
    p.set_defaults(func=run)


@dataclass
class _Panel:
    name: str
    title: str
    sky: Any
    aerial: Any
    heading: float
    camera_xy: tuple[float, float] = FIG7_CAMERA_XY
    #: (zenith, azimuth) [rad] of the sun for a Bruneton panel, whose sky depends on the camera's altitude.
    bruneton_sun: tuple[float, float] | None = None
    #: The precomputed atmosphere's options of a Bruneton panel (BrunetonSky keywords).
    bruneton_medium: dict[str, Any] | None = None


def _preetham(turbidity: float, elevation: float, azimuth: float):
    from ..sky.preetham import PreethamSky

    return PreethamSky(turbidity, math.radians(90.0 - elevation), math.radians(azimuth))


def _cie_clear_like(preetham_sky):
    """CIE 1973 clear sky scaled to the Preetham zenith luminance, coloured with its zenith spectrum, with the
    Preetham sun's illuminance (Figure 8, top)."""
    import numpy as np

    from ..aerial.ward_larson import ConstantColourSky
    from ..sky.cie import CIEClearSky
    from ..spectral import REFERENCE_WAVELENGTHS, spectrum_to_luminance

    wl = REFERENCE_WAVELENGTHS
    sun_lum = float(spectrum_to_luminance(preetham_sky.sun_spectral_radiance(wl), wl))
    cie = CIEClearSky(preetham_sky.sun_zenith, preetham_sky.sun_azimuth,
                      zenith_luminance=preetham_sky.zenith_luminance(),
                      sun_illuminance_normal=sun_lum * preetham_sky.sun_solid_angle)
    zenith = preetham_sky.spectral_radiance(np.array([0.0, 0.0, 1.0]), wl)
    sky = ConstantColourSky(cie, zenith, wl)
    sky.turbidity = preetham_sky.turbidity
    return sky


def _overcast():
    """The CIE overcast sky (10 000 lx diffuse). The paper uses "a flat spectral curve", i.e. no colour; in
    skyscatter's sRGB (D65 white) images the achromatic spectrum is D65, the CIE sky's own (an equal-energy
    spectrum would show pink)."""
    from ..sky.cie import CIEOvercastSky

    return CIEOvercastSky()


def _aerial(kind: str, sky: SkyModel, turbidity: float):
    from ..aerial import (
        ConstantDensityAerialPerspective,
        PreethamAerialPerspective,
        WardLarsonAerialPerspective,
    )

    if kind == "none":
        return None
    if kind == "constant":
        # Sunlight only, as in the course notes; a sunless sky (CIE overcast) lights the haze itself.
        return ConstantDensityAerialPerspective(sky, turbidity=turbidity)
    if kind == "ward-larson":
        return WardLarsonAerialPerspective(sky, turbidity=turbidity)
    return PreethamAerialPerspective(sky, method="numeric" if kind == "numeric" else "analytic",
                                     turbidity=turbidity)


def _panels(args: argparse.Namespace, figure: str) -> list[_Panel]:
    panels: list[_Panel] = []
    if figure in ("all", "7"):
        for name, title, t, sun in (("fig7a_morning_T2", "Figure 7a: morning, T = 2", 2.0, MORNING_SUN),
                                    ("fig7b_evening_T2", "Figure 7b: evening, T = 2", 2.0, EVENING_SUN),
                                    ("fig7c_evening_T6", "Figure 7c: evening, T = 6", 6.0, EVENING_SUN)):
            sky = _preetham(t, *sun)
            panels.append(_Panel(name, title, sky, _aerial("analytic", sky, t), WEST))
        sky = _overcast()
        panels.append(_Panel("fig7d_overcast_T10", "Figure 7d: overcast (CIE), T = 10", sky,
                             _aerial("analytic", sky, 10.0), WEST))
    if figure in ("all", "8"):
        preetham = _preetham(6.0, *EVENING_SUN)
        cie = _cie_clear_like(preetham)
        panels.append(_Panel("fig8a_cie_clear_ward_larson", "Figure 8a: CIE clear sky + Ward-Larson ambient",
                             cie, _aerial("ward-larson", cie, 6.0), EAST, FIG8_CAMERA_XY))
        panels.append(_Panel("fig8b_preetham", "Figure 8b: Preetham sky + aerial perspective", preetham,
                             _aerial("analytic", preetham, 6.0), EAST, FIG8_CAMERA_XY))
    if figure == "clouds":
        from ..sky.broken_cloud import BrokenCloudSky
        from ..sky.cloudy import CloudySky

        cumulus = BrokenCloudSky(math.radians(90.0 - CUMULUS_SUN[0]), math.radians(CUMULUS_SUN[1]), cloud_cover=0.4,
                                 cloud_seed=1)
        panels.append(_Panel("clouds_a_broken_cumulus", "Clouds a: broken cumulus (cover 0.4), sun 30 deg",
                             cumulus, _aerial("analytic", cumulus, DEFAULT_HAZE_TURBIDITY), WEST))
        overcast = CloudySky(math.radians(90.0 - EVENING_SUN[0]), math.radians(EVENING_SUN[1]),
                             cloud_optical_depth=20.0)
        panels.append(_Panel("clouds_b_overcast_evening", "Clouds b: overcast evening (stratus, optical depth 20)",
                             overcast, _aerial("analytic", overcast, DEFAULT_HAZE_TURBIDITY), WEST))
    if figure == "custom":
        zenith, azimuth = sun_angles_from_args(args)
        elevation, az = 90.0 - math.degrees(zenith), math.degrees(azimuth)
        if args.model == "bruneton":
            from ..errors import InvalidParameterError

            for opt in _scene_options(args):
                if opt == "aerial" or opt not in ("model", *_SCENE_OPTIONS, *_BRUNETON_OPTIONS):
                    flag = "--" + opt.replace("_", "-")
                    raise InvalidParameterError(f"{flag} does not apply to --model bruneton (the precomputed "
                                                "atmosphere gives the sky and the aerial perspective)")
            medium = parameter_values(args, "bruneton", _BRUNETON_OPTIONS)
            title = (f"bruneton (precomputed, light shafts), sun {elevation:.1f} deg at {az:.1f} deg")
            panels.append(_Panel("landscape", title, None, None, WEST, bruneton_sun=(zenith, azimuth),
                                 bruneton_medium=medium))
            return panels
        from ..sky import registry

        model = args.model = args.model or "preetham"
        own = {p.name for p in registry.get(model).parameters}
        for p in registry.get("bruneton").parameters:
            if (p.name in _BRUNETON_OPTIONS and p.name not in (*own, "turbidity")  # the haze's without the sky's
                    and getattr(args, p.name, None) is not None):
                from ..errors import InvalidParameterError

                raise InvalidParameterError(f"{p.cli_flag} applies to --model bruneton (the precomputed atmosphere)")
        haze = None
        if not any(p.name == "turbidity" for p in registry.get(model).parameters):
            # --turbidity is the haze's alone for skies without one (checked as the Preetham range)
            haze = getattr(args, "turbidity", None)
            if haze is not None:
                registry.get("preetham").parameter("turbidity").check(haze, "haze")
                del args.turbidity
        sky = build_sky_from_args(args, zenith, azimuth)
        t = sky.turbidity if sky.turbidity is not None else (haze or DEFAULT_HAZE_TURBIDITY)
        panels.append(_Panel("landscape", f"{model}, T = {t:g}, sun {elevation:.1f} deg at {az:.1f} deg", sky,
                             _aerial(args.aerial or "analytic", sky, t), WEST))
    return panels


def _old_sky_option(args: argparse.Namespace) -> None:
    """--sky (deprecated) chose the sky when --model chose the atmosphere (preetham: the sky of --sky)."""
    old = getattr(args, "sky_old", None)
    if old is None:
        return
    if args.model == "bruneton":
        from ..errors import InvalidParameterError

        raise InvalidParameterError("--sky does not apply to --model bruneton (the precomputed atmosphere gives the "
                                    "sky and the aerial perspective)")
    if args.model not in (None, "preetham", old):
        from ..errors import InvalidParameterError

        raise InvalidParameterError(f"give the sky once: --model {args.model} (--sky is its old spelling)")
    args.model = old


#: Prefixes of the panels stacked into one figure PNG (``fig7.png``, ``fig8.png``, ``clouds.png``).
_FIGURES = ("fig7", "fig8", "clouds")


def _check_out_dir(out_dir: Path) -> None:
    """Create the output folder if missing (as ``export-luts`` does); refuse a file or a read-only folder."""
    ensure_output_folder(out_dir, what="--out-dir")


def _targets(out_dir: Path, panels: list[_Panel], figure: str) -> list[Path]:
    """Every file the run will write, in writing order: EXR and PNG per panel, then the figure montages."""
    targets = [out_dir / f"{panel.name}{suffix}" for panel in panels for suffix in (".exr", ".png")]
    if figure != "custom":
        targets += [out_dir / f"{fig}.png" for fig in _FIGURES if any(p.name.startswith(fig) for p in panels)]
    return targets


def _check_targets(targets: list[Path]) -> None:
    """Refuse, before any rendering, targets that cannot be replaced by a regular file."""
    for target in targets:
        check_output_path(target)


def _write_all(jobs: list[tuple[Path, Any]]) -> None:
    """Write every (target, writer) pair, all or none (:func:`skyscatter.fileio.atomic_paths`)."""
    with atomic_paths(*(target for target, _ in jobs)) as temps:
        for (_, writer), tmp in zip(jobs, temps, strict=True):
            writer(tmp)


def run(args: argparse.Namespace) -> int:
    import time

    import numpy as np
    from tqdm import tqdm

    from ..render.camera import PinholeCamera
    from ..render.image_io import write_exr, write_png
    from ..render.scene import DEFAULT_CAMERA_HEIGHT, Scene
    from ..render.terrain import Terrain, default_terrain
    from ..render.tonemap import tonemap
    from ..spectral import wavelength_grid

    _old_sky_option(args)
    scene_given = bool(_scene_options(args))
    figure = args.figure or ("custom" if scene_given else "all")
    if figure != "custom" and scene_given:
        given = [("--" + k.replace("_", "-")) for k in _scene_options(args)]
        raise InvalidParameterError(f"{', '.join(given)}: scene options apply to --figure custom only")
    if args.dem_spacing is not None and args.dem is None:
        raise InvalidParameterError("--dem-spacing needs --dem")
    if args.out_dir.exists() and not args.out_dir.is_dir():
        from ..errors import OutputError

        raise OutputError(f"--out-dir {args.out_dir}: is a file, not a folder")

    terrain = Terrain.load(args.dem, spacing=args.dem_spacing) if args.dem is not None else default_terrain()
    wavelengths = wavelength_grid(380.0, 780.0, args.wavelength_step)

    panels = _panels(args, figure)
    targets = _targets(args.out_dir, panels, figure)
    scenes = []
    for panel in panels:  # build (and validate) every scene before rendering anything
        if terrain.wrap:
            x, y = panel.camera_xy
        else:
            x0, x1, y0, y1 = terrain.extent
            x, y = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        x = x if args.camera_x is None else args.camera_x
        y = y if args.camera_y is None else args.camera_y
        if args.camera_altitude is not None:
            z = args.camera_altitude
        else:
            z = float(terrain.height_at(x, y)) + (DEFAULT_CAMERA_HEIGHT if args.camera_height is None
                                                   else args.camera_height)
        heading = panel.heading if args.heading is None else args.heading
        camera = PinholeCamera.from_degrees((x, y, z), heading, args.pitch, args.fov)
        if panel.bruneton_sun is not None:
            from ..render.bruneton import bruneton_scene

            medium = dict(panel.bruneton_medium or {})
            # --wavelengths chooses the tables' wavelengths; the renderer's come from --wavelength-step
            # --tables chooses the tables' wavelengths; the renderer's come from --wavelength-step
            scenes.append(bruneton_scene(terrain, camera, *panel.bruneton_sun, terrain_albedo=args.terrain_albedo,
                                         sun_disc=args.sun_disc, wavelengths=wavelengths, **medium))
            continue
        scenes.append(Scene(panel.sky, terrain=terrain, camera=camera, aerial=panel.aerial,
                            terrain_albedo=args.terrain_albedo, sun_disc=args.sun_disc, wavelengths=wavelengths))

    _check_out_dir(args.out_dir)
    _check_targets(targets)
    if not sys.stderr.isatty():  # a bar on a terminal, else one line saying what is going on
        print(f"skyscatter demo: rendering {len(panels)} panel(s) of {args.width} x {args.height} "
              "(a first run also compiles the numerical kernels, about a minute)", file=sys.stderr, flush=True)
    images = []
    t0 = time.perf_counter()
    with tqdm(total=len(panels) * args.height, unit="row", desc="skyscatter demo", disable=None) as bar:
        for panel, scene in zip(panels, scenes, strict=True):
            bar.set_postfix_str(panel.name)
            images.append(scene.render(args.width, args.height, glare=args.glare, progress=bar.update).rgb)
    elapsed = time.perf_counter() - t0

    # Tone-map, then write everything to temporary files and rename only when all are written.
    displays = {p.name: tonemap(rgb, exposure_ev=args.exposure) for p, rgb in zip(panels, images, strict=True)}
    jobs = []
    for panel, rgb in zip(panels, images, strict=True):
        jobs.append((args.out_dir / f"{panel.name}.exr", lambda path, im=rgb: write_exr(path, im)))
        jobs.append((args.out_dir / f"{panel.name}.png",
                     lambda path, d=displays[panel.name]: write_png(path, d, tonemapped=True)))
    if figure != "custom":
        for fig in _FIGURES:
            stack_panels = [displays[p.name] for p in panels if p.name.startswith(fig)]
            if stack_panels:
                gap = np.ones((max(2, args.height // 60), args.width, 3))
                montage = np.concatenate([x for d in stack_panels for x in (d, gap)][:-1], axis=0)
                jobs.append((args.out_dir / f"{fig}.png",
                             lambda path, m=montage: write_png(path, m, tonemapped=True)))
    outputs = [target for target, _ in jobs]
    if outputs != targets:  # pragma: no cover - both lists are built from the same panels
        raise RuntimeError("demo: the files written differ from the files checked")
    _write_all(jobs)
    for panel in panels:
        print(f"{panel.name}: {panel.title}")
    print(f"rendered {len(panels)} panel(s) of {args.width} x {args.height} in {elapsed:.1f} s; wrote "
          + ", ".join(str(o) for o in outputs))
    return 0
