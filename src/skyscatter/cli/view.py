"""``skyscatter view``: the precomputed atmosphere in the browser (WebGL2), served from the package on 127.0.0.1."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .common import HELP_FORMATTER


def _port(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a port number in 0..65535; got {text!r}") from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"a port number in 0..65535; got {value}")
    return value


def register(subparsers: argparse._SubParsersAction) -> None:
    from .precompute import add_table_options

    p = subparsers.add_parser(
        "view",
        help="look at the precomputed sky in a browser (WebGL2 page served on 127.0.0.1)",
        description=(
            "Serve a local page that renders the sky from the engine-ready textures (docs/realtime.md) with the "
            "package's GLSL library: drag to look around; sun elevation and azimuth, altitude from the ground to "
            "1000 km, exposure, perspective / fisheye / equirect, the ground and the aerial perspective over it. "
            "The page, its script and the shaders come from the package; nothing is fetched from the network. "
            "Textures come from --luts DIR (an 'export-luts --formats rgba32f,rgba16f' folder), else they are "
            "exported from the cached tables of the atmosphere options below into the cache folder. The server "
            "listens on 127.0.0.1 only and runs until Ctrl-C."
        ),
        formatter_class=HELP_FORMATTER,
    )
    p.add_argument("--luts", type=Path, default=None, metavar="DIR",
                   help="export folder holding skyscatter_realtime.json (default: export the cached tables)")
    p.add_argument("--port", type=_port, default=8642, metavar="N",
                   help="TCP port on 127.0.0.1 (0: any free port)")
    p.add_argument("--no-browser", action="store_true", help="do not open a browser; only print the address")
    p.add_argument("--check", action="store_true",
                   help="serve, fetch the page, its script, the shaders, the manifest and every texture over HTTP "
                        "from 127.0.0.1, report what was served and exit (no browser)")
    # an OPAC type's Mie phase is tabulated per wavelength: the colour-folded textures cannot carry it
    add_table_options(p, exclude=("aerosol_type",))
    p.set_defaults(func=run)


def _luts_folder(args: argparse.Namespace) -> Path:
    """The export folder to serve: --luts, or the cached tables' real-time export (written once per cache key)."""
    from ..precomputed.cache import cache_dir, cached_atmosphere
    from ..realtime import MANIFEST_NAME, export_realtime
    from ..realtime.loader import read_manifest
    from .common import one_line_warnings
    from .precompute import tables_from_args

    if args.luts is not None:
        read_manifest(args.luts)  # refuse a wrong folder before serving it
        return args.luts
    params, sizes, table_options = tables_from_args(args)
    with one_line_warnings():
        atm = cached_atmosphere(params, sizes=sizes, progress=not args.no_progress and sys.stderr.isatty(),
                                **table_options)
    folder = Path(cache_dir()) / "realtime" / atm.cache_key[:32]
    try:
        ok = read_manifest(folder).get("cache_key") == atm.cache_key
    except Exception:  # absent or from another version: export again
        ok = False
    if not ok or not all((folder / f"{n}.rgba32f").exists() for n in ("rayleigh", "mie", "multiple")):
        export_realtime(atm, folder, formats=("rgba32f", "rgba16f"))
    assert (folder / MANIFEST_NAME).exists()
    return folder


def _check(url: str) -> int:
    """Fetch everything the page needs over HTTP and report it (the --check run)."""
    import json
    import urllib.request

    def get(path: str) -> bytes:
        with urllib.request.urlopen(url + path.lstrip("/"), timeout=30) as response:  # noqa: S310 - 127.0.0.1
            return response.read()

    page = get("/").decode("utf-8")
    scripts = [s.split('"')[0] for s in page.split('src="')[1:]]
    if any("://" in s for s in scripts):
        raise SystemExit(f"skyscatter view: the page loads a remote script: {scripts}")
    total = len(page)
    for path in ("/viewer/viewer.js", "/viewer/style.css", "/glsl/atmosphere.glsl"):
        total += len(get(path))
    manifest = json.loads(get("/luts/skyscatter_realtime.json"))
    for entry in manifest["textures"].values():
        for f in entry["files"].values():
            body = get("/luts/" + f["file"])
            if len(body) != f["bytes"]:
                raise SystemExit(f"skyscatter view: {f['file']} served with {len(body)} bytes, expected {f['bytes']}")
            total += len(body)
    print(f"served the page, its script and shaders, the manifest (version {manifest['version']}) and "
          f"{sum(len(e['files']) for e in manifest['textures'].values())} textures from {url} ({total / 1e6:.1f} MB)")
    return 0


def run(args: argparse.Namespace) -> int:
    from ..realtime.server import ViewerServer

    folder = _luts_folder(args)
    server = ViewerServer(folder, port=args.port, quiet=True)
    print(f"skyscatter view: serving {folder} at {server.url}", flush=True)
    if args.check:
        with server:
            return _check(server.url)
    if not args.no_browser:
        import webbrowser

        webbrowser.open(server.url)
    print("press Ctrl-C to stop", flush=True)
    try:
        server.serve_forever()
    finally:
        server.close()
    return 0
