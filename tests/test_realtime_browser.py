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

from gl_sampling import sample_texture as _sample
from skyscatter.conventions import direction_from_angles, equirect_directions
from skyscatter.precomputed import PrecomputedAtmosphere
from skyscatter.precomputed.sampling import irradiance_lookup
from skyscatter.realtime import MANIFEST_NAME, export_realtime
from skyscatter.realtime.server import serve
from skyscatter.render.bruneton import camera_view, fisheye_view, render_directions

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
if CHROMIUM is None and os.environ.get("CI"):
    # .ci/run installs Chromium: a CI run without it must not pass by skipping the browser test
    raise RuntimeError("CI is set but Debian's chromium is not installed: .ci/run should have installed it")
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
    # twilight between the stored sun-zenith texels: SIZES' 8 have 2 below the horizon (-12 and -3.73 deg), so 1
    # cell is split (geometry.twilight_cells) and the refined axis has 8 + 2 = 10 texels; -5 deg reads within the
    # split cell at 0.80 of the stored axis, 2.41 of the refined one (between sub-texel 2 and the stored texel 1 at
    # 3; -4 deg at 0.96 and 2.87, next to the stored texel; _split_position): the sky only (0.6-59 deg elevation),
    # every term of which folds exactly (the ground's light carries the sky irradiance's fold, ground-sun-4)
    "sky-sun-5": (dict(sun_elevation=-5, sun_azimuth=180, altitude=0, projection=0, heading=170, pitch=30,
                       fov=90), (192, 108)),
    "10km-sun30": (dict(sun_elevation=30, sun_azimuth=200, altitude=10e3, projection=0, heading=150, pitch=-10,
                        fov=90), (192, 108)),
    "orbit-sun30": (dict(sun_elevation=30, sun_azimuth=180, altitude=400e3, projection=0, heading=180, pitch=-19,
                         fov=90), (192, 108)),
    "fisheye-sun30": (dict(sun_elevation=30, sun_azimuth=135, altitude=0, projection=1, heading=0), (128, 128)),
    "equirect-sun4": (dict(sun_elevation=4, sun_azimuth=250, altitude=0, projection=2, heading=0), (192, 96)),
}


#: (RMS, worst) that the design reaches per view where it is not float32 rounding (1e-4, 1e-4): measured 4.2e-4,
#: 1.3e-3 (10 km), 3.4e-4, 6.5e-4 (orbit), 1.4e-4, 1.9e-3 (fisheye), 5.5e-4, 1.2e-2 (equirect); the ground with the
#: sun below the horizon 2.3e-4, 3.5e-4 (manifest 9: the sky irradiance read along mu_s with a weight per colour
#: channel, the lookups' with a weight per wavelength, so it no longer folds exactly).
TIGHT = {"10km-sun30": (2e-3, 5e-3), "orbit-sun30": (2e-3, 5e-3), "fisheye-sun30": (1e-3, 5e-3),
         "equirect-sun4": (2e-3, 2e-2), "ground-sun-4": (1e-3, 1e-3)}


@pytest.fixture(scope="module")
def atm():
    a = PrecomputedAtmosphere.compute(orders=3, sizes=SIZES, progress=False)
    # the real-time textures hold the stored texels: the Python side reads them in twilight too (not the observer's
    # computed single scattering, which the textures cannot hold)
    a.compute_twilight_single = False
    return a


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


def _split_position(atm, elevation):
    """(position on the stored sun-zenith axis, on the refined one, the split cells) of a sun ``elevation`` [deg]."""
    from skyscatter.precomputed import geometry

    p = atm.parameters
    n_s = atm.sizes.scattering_mu_s
    mu_s = math.sin(math.radians(elevation))
    stored = geometry.scattering_mu_s_coord(mu_s, p.bottom_radius, p.top_radius, p.mu_s_min, n_s)
    cells = geometry.twilight_cells(p.bottom_radius, p.top_radius, p.mu_s_min, n_s)
    i, w = geometry.refined_mu_s_cell(stored, geometry.refined_mu_s_count(n_s, cells), cells)
    return stored, i + w, cells


@pytest.mark.parametrize("name", list(VIEWS))
def test_browser_renders_the_python_image(name, viewer, atm):
    params, size = VIEWS[name]
    gpu = _gpu_image(viewer, params, size)
    ref = _python_image(atm, params, size)
    assert np.isfinite(gpu).all() and ref.max() > 0
    if name.startswith("sky-"):  # a view of the sky alone, the sun within a split cell between the stored texels
        assert (_directions(params, size, atm.parameters.bottom_radius)[..., 2] > 0.0).all(), name
        stored, fine, cells = _split_position(atm, params["sun_elevation"])
        assert stored < cells and 0.1 < stored % 1.0 < 0.9 and 0.1 < fine % 1.0 < 0.9, (stored, fine, cells)
    e = _errors(gpu, ref, params, size, atm)
    rms, worst = float(np.sqrt(np.mean(e**2))), float(e.max())
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    viewer.evaluate("(p) => window.skyscatterViewer.render(p)",
                    dict(params, sun=True, exposure=4.0 if params["sun_elevation"] < 0 else 0.0))
    viewer.screenshot(path=str(ARTEFACTS / f"{name}.png"))
    with open(ARTEFACTS / "figures.jsonl", "a", encoding="utf-8") as fh:
        fh.write(json.dumps({"view": name, "rms": rms, "worst": worst, "pixels": int(e.size)}) + "\n")
    assert rms < 0.01 and worst < 0.05, (name, rms, worst)  # the requirement
    # and what the design gives (docs/realtime.md), so that a small error in a mapping shows: from the ground every
    # term folds exactly (float32 rounding); from altitude the ground's light is a product of folded colours;
    # fisheye and equirect take sin/cos of the GPU per pixel
    tight = TIGHT.get(name, (1e-4, 1e-4))
    assert rms < tight[0] and worst < tight[1], (name, rms, worst, tight)


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
        manifest["version"] = 1  # an export of before the scattering textures' alpha held the middle wavelength
        (folder / MANIFEST_NAME).write_text(json.dumps(manifest))
    elif how == "missing":
        (folder / "multiple.rgba32f").unlink()
    elif how == "truncated":
        data = (folder / "mie.rgba32f").read_bytes()
        (folder / "mie.rgba32f").write_bytes(data[:1000])
    return folder


@pytest.mark.parametrize("how, words", [("version", "manifest version 1"), ("missing", "multiple.rgba32f"),
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


def _cases(atm, rng, n):
    """Cameras (2 m, a person's eye, and 2 km), unit directions and suns (30, 4, -4, -5 deg: -4 and -5 within the
    split sun-zenith cell of SIZES' 8 texels, -12 to -3.73 deg, between its stored texels: at 0.96 and 0.80 of the
    stored axis, 2.87 and 2.41 of the refined one of 10, both between sub-texel 2 and the stored texel 1 at 3;
    _split_position) for the library probes."""
    bottom = atm.parameters.bottom_radius
    cams = np.zeros((n, 3))
    cams[:, 2] = bottom + rng.choice([2.0, 2000.0], n)
    suns = direction_from_angles(np.radians(90 - rng.choice([30.0, 4.0, -4.0, -5.0], n)),
                                 rng.uniform(0, 2 * np.pi, n))
    return cams, suns


def _fold(atm):
    from skyscatter.realtime.export import fold_matrix

    return fold_matrix(atm)


def test_library_sky_and_irradiance_functions_match_the_python_lookups(viewer, atm):
    rng = np.random.default_rng(3)
    n = 60
    cams, suns = _cases(atm, rng, n)
    views = direction_from_angles(rng.uniform(0.0, np.pi, n), rng.uniform(0, 2 * np.pi, n))
    m = _fold(atm)
    got = viewer.evaluate("([k, c]) => window.skyscatterViewer.probe(k, c)",
                          ["sky", [[list(a), list(b), list(c)] for a, b, c in zip(cams, views, suns, strict=True)]])
    want = np.array([m @ atm.sky_radiance(cams[i], views[i], suns[i], include_ground=False) for i in range(n)])
    sky = np.array([g[0] for g in got])
    e = np.abs(sky - want).max(-1) / (np.abs(want).max(-1) + 1e-30)
    night = np.einsum("ij,ij->i", cams, suns) < 0.0  # the sun below the horizon: the refined sun-zenith cells
    assert night.sum() >= 10, night.sum()
    for el in (-4.0, -5.0):  # both twilight suns read within the split cell, between two stored texels
        stored, fine, cells = _split_position(atm, el)
        assert stored < cells and 0.0 < stored % 1.0 and 0.0 < fine % 1.0, (el, stored, fine, cells)
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    with open(ARTEFACTS / "figures.jsonl", "a", encoding="utf-8") as fh:
        fh.write(json.dumps({"sky_probes": n, "sky_median": float(np.median(e)), "sky_worst": float(e.max()),
                             "twilight_probes": int(night.sum()), "twilight_rms": float(np.sqrt(np.mean(e[night]**2))),
                             "twilight_worst": float(e[night].max()), "day_rms": float(np.sqrt(np.mean(e[~night]**2))),
                             "day_worst": float(e[~night].max())}) + "\n")
    for i in range(n):
        assert np.abs(sky[i] - want[i]).max() <= 1e-4 * np.abs(want[i]).max() + 1e-9, (i, sky[i], want[i])
    normals = direction_from_angles(rng.uniform(0.0, np.pi / 2, n), rng.uniform(0, 2 * np.pi, n))
    got = viewer.evaluate("([k, c]) => window.skyscatterViewer.probe(k, c)",
                          ["irradiance", [[list(a), list(b), list(c)] for a, b, c in zip(cams, normals, suns,
                                                                                         strict=True)]])
    e_sun, e_sky = atm.table_irradiance(cams, normals, suns)  # the table read the GLSL reproduces
    p = atm.parameters
    folded = np.ascontiguousarray(np.asarray(atm.tables["irradiance"], np.float64) @ m.T)
    for i, (sun_rgb, sky_rgb) in enumerate(got):
        # sunlight folds exactly (the transmittance texture is sunlight's); the sky irradiance is a table value,
        # read along mu_s below the horizon with a weight per colour channel (per wavelength in the lookups): the
        # library's read of the folded table, times the sky's share of a tilted surface (Eq. 14)
        r = float(np.linalg.norm(cams[i]))
        up = cams[i] / r
        rgb_sky = np.empty(3)
        irradiance_lookup(folded, r, float(up @ suns[i]), p.bottom_radius, p.top_radius, rgb_sky)
        rgb_sky *= 0.5 * (1.0 + float(up @ normals[i]))
        if suns[i] @ up > 0.0:
            np.testing.assert_allclose(rgb_sky, m @ e_sky[i], rtol=1e-9, atol=0)  # linear above the horizon
        for gpu, want in ((sun_rgb, m @ e_sun[i]), (sky_rgb, rgb_sky)):
            assert np.abs(np.array(gpu) - want).max() <= 1e-4 * (np.abs(want).max() + 1e-3), (i, gpu, want)


def test_library_aerial_perspective_matches_the_python_lookup(viewer, atm, luts):
    """GetSkyRadianceToPoint against PrecomputedAtmosphere.aerial_perspective: the inscatter S|x - T S|p and the
    transmittance, folded. T S|p is a product of spectra, folded here as a product of colours (docs/realtime.md), so
    the limit is that of the ground term measured there (0.5 % worst from 10 km), not rounding."""
    rng = np.random.default_rng(5)
    n = 90
    cams, suns = _cases(atm, rng, n)
    bottom = atm.parameters.bottom_radius
    dist = rng.uniform(500.0, 50e3, n)
    az = rng.uniform(0, 2 * np.pi, n)
    # points on the ground (the sphere) or 0-3 km above it, dist away horizontally
    height = rng.choice([0.0, 1000.0, 3000.0], n)
    ang = dist / bottom
    unit = np.stack([np.sin(ang) * np.sin(az), np.sin(ang) * np.cos(az), np.cos(ang)], -1)
    points = unit * (bottom + height)[:, None]
    got = viewer.evaluate("([k, c]) => window.skyscatterViewer.probe(k, c)",
                          ["aerial", [[list(a), list(b), list(c)] for a, b, c in zip(cams, points, suns, strict=True)]])
    t_spec, s_spec = atm.aerial_perspective(cams, points, suns)
    m = _fold(atm)
    solar = atm.parameters.solar_irradiance_at(atm.wavelengths)
    err_s, err_t = [], []
    for i, (s_rgb, t_rgb) in enumerate(got):
        want_s = m @ s_spec[i]
        want_t = (m @ (solar * t_spec[i])) / (m @ solar)
        # the inscatter relative to the light reaching the camera from a white object there (T + S), so that a
        # near-cancellation S|x - T S|p does not inflate it
        err_s.append(float(np.abs(np.array(s_rgb) - want_s).max() / max((want_t + want_s).max(), 1e-9)))
        err_t.append(float(np.abs(np.array(t_rgb) - want_t).max()))
    err_s, err_t = np.array(err_s), np.array(err_t)
    figures = {"aerial_cases": n}
    for name, e in (("inscatter", err_s), ("transmittance", err_t)):
        figures.update({f"{name}_median": float(np.median(e)), f"{name}_p90": float(np.percentile(e, 90)),
                        f"{name}_worst": float(e.max())})
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    with open(ARTEFACTS / "figures.jsonl", "a", encoding="utf-8") as fh:
        fh.write(json.dumps(figures) + "\n")
    # The GPU computes exactly the documented rule: the manifest's Python mappings and segment rule on the same
    # textures (float64 here) give the GPU's values to float32 precision: 2 % for these near-horizontal rays along
    # the ground (the difference of two optical depths of ~30 read at float32 coordinates where they change fast
    # with mu; measured worst 1.3 % in T from 2 m, most cases below 0.1 %); a wrong rule (no horizon blend, the
    # plain ratio) is off by tens of percent.
    from skyscatter.realtime import load_realtime

    data = load_realtime(luts)
    ns = data.mappings()
    for i, (s_rgb, t_rgb) in enumerate(got):
        s_emu, t_emu = _emulate_aerial(ns, data.textures, cams[i], points[i], suns[i])
        assert np.abs(np.array(t_rgb) - t_emu).max() < 2e-2, (i, t_rgb, t_emu)
        # relative to the light of a white object there (T + S), as the figures above
        assert np.abs(np.array(s_rgb) - s_emu).max() < 2e-2 * (t_emu + s_emu).max(), (i, s_rgb, s_emu)
    # Against the spectral lookup the folded products set the limits (docs/realtime.md, "Folding"): the
    # transmittance of a segment from the fold of the default tables is within 7 % (median 0.25 %) on 395 segments;
    # these coarser tables and paths along the ground: median 1.9 %, worst 9.7 %.
    assert figures["transmittance_worst"] < 0.1 and figures["inscatter_median"] < 0.01, figures


def _emulate_aerial(ns, tex, cam, point, sun):
    """GetSkyRadianceToPoint of the GLSL library, from the manifest's Python code and the float32 textures."""

    bottom = ns["BOTTOM_RADIUS"]

    def seg(r, mu, d, hits):
        r_d = min(max(math.sqrt(max(d * d + 2 * r * mu * d + r * r, 0.0)), bottom), ns["TOP_RADIUS"])
        mu_d = min(max((r * mu + d) / r_d, -1.0), 1.0)
        uv_a, uv_b = ((ns["transmittance_uv"](r_d, -mu_d), ns["transmittance_uv"](r, -mu)) if hits
                      else (ns["transmittance_uv"](r, mu), ns["transmittance_uv"](r_d, mu_d)))
        return np.array(ns["segment_transmittance"](
            _sample(tex["transmittance"], uv_a)[:3], _sample(tex["transmittance"], uv_b)[:3],
            _sample(tex["optical_depth"], uv_a)[:3], _sample(tex["optical_depth"], uv_b)[:3]))

    def inscatter(r, mu, mu_s, nu, hits):
        if mu_s < ns["MU_S_MIN"] - 1e-6:
            return np.zeros(3)
        mu_s = max(mu_s, ns["MU_S_MIN"])
        uvw0, uvw1, w = ns["scattering_uvw"](r, mu, mu_s, nu, hits)
        cell = ns["scattering_ground_cell"](r, mu, hits)

        def read(n, uvw):
            return ns["scattering_texture"](lambda q: _sample(tex[n], q), uvw, cell)

        parts = [ns["single_scattering_lerp"](read(n, uvw0), read(n, uvw1), r, mu, mu_s, nu, w, n)
                 for n in ("rayleigh", "mie")]
        uvws, w4, lagrange = ns["scattering_uvw4"](r, mu, mu_s, nu, hits)
        parts.append(ns["azimuth_read"]([read("multiple", q) for q in uvws], w4, lagrange))
        return np.array(ns["inscattered_radiance"](*parts, nu))

    def to_point(r, mu, mu_s, nu, d, hits):
        c = inscatter(r, mu, mu_s, nu, hits)
        r_p = min(max(math.sqrt(max(d * d + 2 * r * mu * d + r * r, 0.0)), bottom), ns["TOP_RADIUS"])
        mu_p = min(max((r * mu + d) / r_p, -1.0), 1.0)
        mu_s_p = min(max((r * mu_s + d * nu) / r_p, -1.0), 1.0)
        return np.maximum(c - seg(r, mu, d, hits) * inscatter(r_p, mu_p, mu_s_p, nu, hits), 0.0)

    v = point - cam
    d = float(np.linalg.norm(v))
    v = v / d
    r = float(np.linalg.norm(cam))
    mu, mu_s, nu = float(cam @ v) / r, float(cam @ sun) / r, float(v @ sun)
    hits = ns["ray_hits_ground"](r, mu)
    mu_h = -math.sqrt(max(1.0 - (bottom / r) ** 2, 0.0))
    if abs(mu - mu_h) < 0.004:
        lo = to_point(r, mu_h - 0.004, mu_s, nu, d, True)
        hi = to_point(r, mu_h + 0.004, mu_s, nu, d, False)
        c = lo + (hi - lo) * (mu - (mu_h - 0.004)) / 0.008
    else:
        c = to_point(r, mu, mu_s, nu, d, hits)
    return c, seg(r, mu, d, hits)
