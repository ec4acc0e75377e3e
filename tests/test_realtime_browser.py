"""The viewer of ``skyscatter view`` in a real browser: headless Chromium (Debian's package, WebGL2 through
SwiftShader/ANGLE) driven by playwright, against the Python renderer of the same tables.

Each fixed view is rendered by the page's shaders into an RGBA32F framebuffer, read back as float32
(``readPixels(FLOAT)``) and compared with :mod:`skyscatter.render.bruneton` (spectral lookups, then colour): per
pixel, the largest channel difference over the reference's largest channel, floored at 1e-3 of the image's
99th percentile (space and night pixels are near 0); pixels within 5 solar radii of the sun are left out (neither
side draws the disc here). Required: RMS < 1 %, worst < 5 %. A screenshot of every view (the page as a user sees
it, tone mapped) is written to ``test-artefacts/realtime/`` (or ``$SKYSCATTER_ARTEFACTS``).
Skips, saying why, where Chromium or playwright is missing.
"""

from __future__ import annotations

import base64
import json
import math
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from skyscatter.conventions import direction_from_angles, equirect_directions
from skyscatter.precomputed import PrecomputedAtmosphere
from skyscatter.realtime import MANIFEST_NAME, export_realtime
from skyscatter.realtime.server import serve
from skyscatter.render.bruneton import camera_view, fisheye_view, render_directions

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
if CHROMIUM is None:
    pytest.skip("Debian's chromium is not installed (apt-get install chromium); the browser test needs it",
                allow_module_level=True)
sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed (pip install playwright)")

#: WebGL2 without a GPU: ANGLE on SwiftShader.
CHROMIUM_ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--use-gl=angle",
                 "--ignore-gpu-blocklist", "--no-sandbox"]
SIZES = dict(transmittance_mu=64, transmittance_r=16, irradiance_mu_s=16, irradiance_r=8, scattering_r=8,
             scattering_mu=32, scattering_mu_s=8, scattering_nu=4)
ARTEFACTS = Path(os.environ.get("SKYSCATTER_ARTEFACTS", Path(__file__).parent.parent / "test-artefacts")) / "realtime"

#: name: (viewer parameters, image size); heading/pitch/fov in degrees as the page takes them.
VIEWS = {
    "ground-sun30": (dict(sun_elevation=30, sun_azimuth=180, altitude=0, projection=0, heading=160, pitch=10,
                          fov=90), (192, 108)),
    "ground-sun4": (dict(sun_elevation=4, sun_azimuth=180, altitude=0, projection=0, heading=180, pitch=5,
                         fov=90), (192, 108)),
    "ground-sun-4": (dict(sun_elevation=-4, sun_azimuth=180, altitude=0, projection=0, heading=180, pitch=5,
                          fov=90), (192, 108)),
    "10km-sun30": (dict(sun_elevation=30, sun_azimuth=200, altitude=10e3, projection=0, heading=150, pitch=-10,
                        fov=90), (192, 108)),
    "orbit-sun30": (dict(sun_elevation=30, sun_azimuth=180, altitude=400e3, projection=0, heading=180, pitch=-19,
                         fov=90), (192, 108)),
    "fisheye-sun30": (dict(sun_elevation=30, sun_azimuth=135, altitude=0, projection=1, heading=0), (128, 128)),
    "equirect-sun4": (dict(sun_elevation=4, sun_azimuth=250, altitude=0, projection=2, heading=0), (192, 96)),
}


@pytest.fixture(scope="module")
def atm():
    return PrecomputedAtmosphere.compute(orders=3, sizes=SIZES, progress=False)


@pytest.fixture(scope="module")
def luts(atm, tmp_path_factory):
    folder = tmp_path_factory.mktemp("luts")
    export_realtime(atm, folder, formats=("rgba32f", "rgba16f"))
    return folder


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield b
        b.close()


def _open(browser, folder: Path, query: str = ""):
    """The viewer page for ``folder``; (page, server, whether it is ready, console errors)."""
    server = serve(folder)
    page = browser.new_page(viewport={"width": 1280, "height": 720})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(server.url + query)
    ready = page.evaluate("() => window.skyscatterViewer.ready")
    return page, server, ready, errors


@pytest.fixture(scope="module")
def viewer(browser, luts):
    page, server, ready, errors = _open(browser, luts)
    assert ready, page.evaluate("() => window.skyscatterViewer.error")
    yield page
    page.close()
    server.close()


def _python_image(atm, params, size):
    el, az = math.radians(params["sun_elevation"]), math.radians(params["sun_azimuth"])
    zen = math.pi / 2 - el
    if params["projection"] == 0:
        return camera_view(atm, zen, az, altitude=params["altitude"], heading=math.radians(params["heading"]),
                           pitch=math.radians(params["pitch"]), fov=math.radians(params["fov"]), width=size[0],
                           height=size[1], include_sun=False)
    if params["projection"] == 1:
        return fisheye_view(atm, zen, az, altitude=params["altitude"], size=size[0], include_sun=False)
    pos = np.array([0.0, 0.0, atm.parameters.bottom_radius + params["altitude"]])
    return render_directions(atm, pos, equirect_directions(*size), direction_from_angles(zen, az),
                             include_sun=False)


def _directions(params, size, bottom):
    """Pixel directions of the view (the reference's), for the mask around the sun."""
    from skyscatter.conventions import fisheye_directions, pinhole_directions

    if params["projection"] == 0:
        return pinhole_directions(*size, heading=math.radians(params["heading"]),
                                  pitch=math.radians(params["pitch"]), fov=math.radians(params["fov"]))
    if params["projection"] == 1:
        return fisheye_directions(size[0])[0]
    return equirect_directions(*size)


def _gpu_image(page, params, size, **extra):
    text = page.evaluate("([p, w, h]) => window.skyscatterViewer.readFloat(p, w, h)",
                         [dict(params, sun=False, **extra), size[0], size[1]])
    return np.frombuffer(base64.b64decode(text), dtype="<f4").reshape(size[1], size[0], 4)[..., :3]


def _errors(gpu, ref, params, size, atm):
    sun = direction_from_angles(math.radians(90 - params["sun_elevation"]), math.radians(params["sun_azimuth"]))
    d = _directions(params, size, atm.parameters.bottom_radius)
    away = (d @ sun) < math.cos(5 * atm.parameters.sun_angular_radius)
    peak = ref.max(-1)
    floor = 1e-3 * np.percentile(peak, 99)
    e = np.abs(gpu - ref).max(-1) / np.maximum(peak, floor)
    return e[away]


@pytest.mark.parametrize("name", list(VIEWS))
def test_browser_renders_the_python_image(name, viewer, atm):
    params, size = VIEWS[name]
    gpu = _gpu_image(viewer, params, size)
    ref = _python_image(atm, params, size)
    assert np.isfinite(gpu).all() and ref.max() > 0
    e = _errors(gpu, ref, params, size, atm)
    rms, worst = float(np.sqrt(np.mean(e**2))), float(e.max())
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    viewer.evaluate("(p) => window.skyscatterViewer.render(p)",
                    dict(params, sun=True, exposure=4.0 if params["sun_elevation"] < 0 else 0.0))
    viewer.screenshot(path=str(ARTEFACTS / f"{name}.png"))
    with open(ARTEFACTS / "figures.jsonl", "a", encoding="utf-8") as fh:
        fh.write(json.dumps({"view": name, "rms": rms, "worst": worst, "pixels": int(e.size)}) + "\n")
    assert rms < 0.01 and worst < 0.05, (name, rms, worst)


def test_half_float_textures_render_within_half_precision(browser, luts, atm):
    page, server, ready, _ = _open(browser, luts, "?format=rgba16f")
    try:
        assert ready, page.evaluate("() => window.skyscatterViewer.error")
        params, size = VIEWS["ground-sun30"]
        e = _errors(_gpu_image(page, params, size), _python_image(atm, params, size), params, size, atm)
        assert float(np.sqrt(np.mean(e**2))) < 0.01 and float(e.max()) < 0.05
    finally:
        page.close()
        server.close()


def test_aerial_perspective_and_fog_switch(viewer, atm):
    """From 10 km the ground seen through the air (inscatter + transmittance, the page's default) differs from the
    ground without the air, and the checker pattern shows through the fog."""
    params, size = VIEWS["10km-sun30"]
    fog = _gpu_image(viewer, params, size)
    clear = _gpu_image(viewer, params, size, fog=False)
    checker = _gpu_image(viewer, params, size, checker=True)
    ground = np.zeros(size[::-1], dtype=bool)
    ground[-20:, :] = True
    assert np.abs(fog - clear)[ground].mean() > 0.05 * fog[ground].mean()
    assert np.abs(checker - fog)[ground].max() > 0.1 * fog[ground].mean()


def _broken(luts: Path, tmp_path: Path, how: str) -> Path:
    folder = tmp_path / how
    shutil.copytree(luts, folder)
    manifest = json.loads((folder / MANIFEST_NAME).read_text())
    if how == "version":
        manifest["version"] = 2
        (folder / MANIFEST_NAME).write_text(json.dumps(manifest))
    elif how == "missing":
        (folder / "multiple.rgba32f").unlink()
    elif how == "truncated":
        data = (folder / "mie.rgba32f").read_bytes()
        (folder / "mie.rgba32f").write_bytes(data[:1000])
    return folder


@pytest.mark.parametrize("how, words", [("version", "manifest version 2"), ("missing", "multiple.rgba32f"),
                                        ("truncated", "truncated")])
def test_page_says_what_is_wrong_instead_of_a_black_canvas(how, words, browser, luts, tmp_path):
    page, server, ready, errors = _open(browser, _broken(luts, tmp_path, how))
    try:
        assert ready is False
        text = page.inner_text("#message")
        assert page.is_visible("#message") and words in text, text
        ARTEFACTS.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(ARTEFACTS / f"error-{how}.png"))
    finally:
        page.close()
        server.close()
