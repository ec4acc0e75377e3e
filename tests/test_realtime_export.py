"""Engine-ready textures (skyscatter.realtime): the manifest's mapping code and the folded RGBA textures, read the
way a GPU reads them (linear filtering, clamp to edge), against the library's own spectral lookups; the loader's
refusals; half floats and EXR against float32."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from gl_sampling import sample_texture as _sample
from skyscatter.conventions import direction_from_angles
from skyscatter.errors import FileFormatError, InvalidParameterError
from skyscatter.precomputed import PrecomputedAtmosphere
from skyscatter.precomputed.sampling import irradiance_lookup
from skyscatter.realtime import MANIFEST_NAME, export_realtime, load_realtime
from skyscatter.realtime.export import MANIFEST_VERSION, fold_matrix, glsl_library, glsl_mappings
from skyscatter.spectral import HDR_SCALE, xyz_to_linear_srgb

SMALL = dict(transmittance_mu=32, transmittance_r=8, irradiance_mu_s=8, irradiance_r=4, scattering_r=6,
             scattering_mu=16, scattering_mu_s=6, scattering_nu=4)


@pytest.fixture(scope="module")
def atm():
    a = PrecomputedAtmosphere.compute(orders=2, sizes=SMALL, progress=False)
    # the real-time textures hold the stored texels: the Python side reads them in twilight too (not the observer's
    # computed single scattering, which the textures cannot hold)
    a.compute_twilight_single = False
    return a


@pytest.fixture(scope="module")
def luts(atm, tmp_path_factory):
    folder = tmp_path_factory.mktemp("rt")
    export_realtime(atm, folder, formats=("rgba32f", "rgba16f", "exr"))
    return folder


def _gpu_sky(ns, tex, r, mu, mu_s, nu):
    """Sky radiance (RGB) as a shader computes it, from the manifest's Python mappings."""
    if mu_s < ns["MU_S_MIN"]:
        return np.zeros(3)
    hits = ns["ray_hits_ground"](r, mu)
    uvw0, uvw1, w = ns["scattering_uvw"](r, mu, mu_s, nu, hits)
    cell = ns["scattering_ground_cell"](r, mu, hits)

    def read(n, uvw):
        return ns["scattering_texture"](lambda q: _sample(tex[n], q), uvw, cell)

    parts = [ns["single_scattering_lerp"](read(n, uvw0), read(n, uvw1), r, mu, mu_s, nu, w, n)
             for n in ("rayleigh", "mie")]
    uvws, w4, lagrange = ns["scattering_uvw4"](r, mu, mu_s, nu, hits)
    parts.append(ns["azimuth_read"]([read("multiple", q) for q in uvws], w4, lagrange))
    return np.array(ns["inscattered_radiance"](*parts, nu))


def test_manifest_mappings_and_textures_give_the_spectral_lookup(atm, luts):
    data = load_realtime(luts)
    ns = data.mappings()
    rng = np.random.default_rng(7)
    p = atm.parameters
    m = fold_matrix(atm)
    worst = 0.0
    shadowed = 0
    for alt in (0.0, 20.0, 1500.0, 12e3, 45e3):  # 20 m: the cell touching the ground (rows read at their own mu)
        pos = np.array([0.0, 0.0, p.bottom_radius + alt])
        # three random suns and two in twilight (-3 and -6 deg: the observer in the Earth's shadow below 12 km;
        # both within SMALL's split sun-zenith cell, at 0.80 and 0.47 of the stored axis)
        for zenith in (*rng.uniform(0.0, 1.75, 3), np.radians(93.0), np.radians(96.0)):
            sun = direction_from_angles(zenith, rng.uniform(0, 2 * np.pi))
            shadowed += ns["in_earth_shadow"](float(pos[2]), max(float(sun[2]), ns["MU_S_MIN"]))
            dirs = direction_from_angles(rng.uniform(0.0, np.pi, 40), rng.uniform(0, 2 * np.pi, 40))
            want = atm.sky_radiance(pos, dirs, sun, include_ground=False) @ m.T
            r = float(pos[2])
            for d, ref in zip(dirs, want, strict=True):
                got = _gpu_sky(ns, data.textures, r, d[2], sun[2], float(d @ sun))
                scale = max(np.abs(ref).max(), 1e-6)
                worst = max(worst, float(np.abs(got - ref).max() / scale))
    # float32 textures: the mapping code and the GPU read reproduce the float64 lookup to rounding, also where the
    # observer is in the Earth's shadow (the single scattering's shadow factors: shadow_factors of the mappings)
    assert shadowed >= 2, shadowed
    assert worst < 2e-5, worst


def test_twilight_reads_between_the_stored_sun_zenith_texels_give_the_lookup(atm, luts):
    """With the sun 3.5 and 5.5 deg below the horizon the read lies within the split sun-zenith cell, between the
    stored texels and within two different sub-cells: SMALL's 6 texels have 2 below the horizon (-12 and -1.41
    deg), so the cell between them and the one across the horizon are split (geometry.twilight_cells; the single
    scattering's sub-texels computed at their suns, the multiple scattering's the four-point rule over texels 0-3)
    and the refined axis has 6 + 2 x 2 = 10 texels; -3.5 deg reads at 0.74 of the stored axis, 2.22 of the refined
    one (between sub-texel 2 and the stored texel 1 at 3), -5.5 deg at 0.52 (mid-cell), 1.57 (between sub-texels 1
    and 2). The textures hold the lookups' refined
    tables folded, and the mappings' position on the refined axis is the lookups', so the GPU read gives the
    spectral lookup to rounding there too (measured worst 2.6e-7; the stored axis' textures, version 10's: 36; a
    linear read between the stored texels is off by far more:
    test_scattering_alpha_is_the_middle_wavelength_and_its_weight_the_lookups)."""
    from skyscatter.precomputed.geometry import MU_S_SPLIT, scattering_mu_s_coord, twilight_cells

    data = load_realtime(luts)
    ns = data.mappings()
    p = atm.parameters
    m = fold_matrix(atm)
    n_s = atm.sizes.scattering_mu_s
    cells = twilight_cells(p.bottom_radius, p.top_radius, p.mu_s_min, n_s)
    assert cells >= 1 and ns["SCATTERING_N_MU_S"] == n_s + (MU_S_SPLIT - 1) * cells
    assert ns["SCATTERING_MU_S_CELLS"] == cells and ns["MU_S_SPLIT"] == MU_S_SPLIT
    rng = np.random.default_rng(17)
    worst = 0.0
    for el in (-3.5, -5.5):  # SMALL's 6 texels, 2 split cells: at 2.22 and 1.57 of the refined axis of 10
        sun = direction_from_angles(np.radians(90.0 - el), 0.4)
        stored = scattering_mu_s_coord(float(sun[2]), p.bottom_radius, p.top_radius, p.mu_s_min, n_s)
        fine = ns["scattering_mu_s_index"](float(sun[2]))
        # within a split cell, between two stored texels and between two sub-texels
        assert stored < cells and 0.2 < stored % 1.0 < 0.8 and 0.1 < fine % 1.0 < 0.9, (el, stored, fine)
        for alt in (0.0, 1500.0, 12e3):
            pos = np.array([0.0, 0.0, p.bottom_radius + alt])
            dirs = direction_from_angles(rng.uniform(0.0, np.pi, 40), rng.uniform(0, 2 * np.pi, 40))
            want = atm.sky_radiance(pos, dirs, sun, include_ground=False) @ m.T
            for d, ref in zip(dirs, want, strict=True):
                got = _gpu_sky(ns, data.textures, float(pos[2]), d[2], sun[2], float(d @ sun))
                worst = max(worst, float(np.abs(got - ref).max() / max(np.abs(ref).max(), 1e-6)))
    assert worst < 2e-5, worst  # as the other suns (test above)


def test_scattering_mu_s_index_is_the_lookups_refined_position(atm, luts):
    """The mappings' sun-zenith position is the lookups' cell (geometry.refined_mu_s_cell of the stored axis'
    position) over the whole range: below, across and above the split cells."""
    from skyscatter.precomputed.geometry import refined_mu_s_cell, scattering_mu_s_coord

    ns = load_realtime(luts).mappings()
    p = atm.parameters
    n_s, n_f, cells = atm.sizes.scattering_mu_s, ns["SCATTERING_N_MU_S"], ns["SCATTERING_MU_S_CELLS"]
    for mu_s in np.linspace(p.mu_s_min, 1.0, 397):
        i, w = refined_mu_s_cell(scattering_mu_s_coord(float(mu_s), p.bottom_radius, p.top_radius, p.mu_s_min,
                                                       n_s), n_f, cells)
        # the lookups' arc cosine (geometry.acos_table) is within 2.2e-8 rad of math.acos': 1e-7 of a texel here
        assert abs(ns["scattering_mu_s_index"](float(mu_s)) - (i + w)) < 1e-7, mu_s
    assert ns["scattering_mu_s_index"](p.mu_s_min) == 0.0 and ns["scattering_mu_s_index"](1.0) == n_f - 1


def test_scattering_alpha_is_the_middle_wavelength_and_its_weight_the_lookups(atm, luts):
    """The scattering textures' alpha is each table at its middle wavelength (the lookups' azimuth weight comes
    from it: sampling.nu_weight), at the texel of the same (r, mu, mu_s, nu); the manifest's weight is
    geometry.log_lerp_weight, the floor included."""
    from skyscatter.precomputed.geometry import log_lerp_weight

    data = load_realtime(luts)
    k = atm.wavelengths.size // 2
    assert data.manifest["azimuth_weight_wavelength_nm"] == float(atm.wavelengths[k])
    n_r, n_mu, n_s, n_n = atm.sizes.scattering_shape
    cells, split = data.manifest["constants"]["SCATTERING_MU_S_CELLS"], data.manifest["constants"]["MU_S_SPLIT"]
    n_f = data.manifest["constants"]["SCATTERING_N_MU_S"]
    # the refined axis' texels that are stored ones: every split-th in the split cells, all above them
    kept = [split * i for i in range(cells)] + list(range(split * cells, n_f))
    for name, key in (("rayleigh", "single_rayleigh"), ("mie", "single_mie"), ("multiple", "multiple")):
        # the lookups' tables: refined along the sun zenith (the table as stored at its own texels)
        alpha = data.textures[name][..., 3].reshape(n_r, n_mu, n_n, n_f).transpose(0, 1, 3, 2)
        np.testing.assert_array_equal(alpha, atm.lookup_tables[key][..., k])
        np.testing.assert_array_equal(alpha[:, :, kept], np.asarray(atm.tables[key][..., k], dtype=np.float32))
        # the sub-texels are not the stored axis' linear read: the twilight sky is not linear along the sun zenith
        # (an export of the stored tables read at the refined positions would be off by this much; SMALL's split
        # cell, -12 to -1.41 deg, geometric between its two texels: below the linear read by up to 100 %)
        table = np.asarray(atm.tables[key][..., k], dtype=np.float64)
        lin = table[:, :, :cells] + (table[:, :, 1:cells + 1] - table[:, :, :cells]) / split
        sub = alpha[:, :, 1:split * cells:split]
        big = lin > 1e-3 * table.max()
        assert np.abs(sub / np.where(big, lin, 1.0) - 1.0)[big].max() > 0.05, name
    ns = data.mappings()
    rng = np.random.default_rng(11)
    a = rng.uniform(0.0, 1.0, 300) * 10.0 ** rng.uniform(-6, 1, 300)
    b = a * 10.0 ** rng.uniform(-5, 5, 300)
    a[:20], b[10:20], b[20:30] = 0.0, 0.0, a[20:30]  # one or both zero (the Earth's shadow), equal values
    w = rng.uniform(0.0, 1.0, 300)
    got = np.array([ns["log_lerp_weight"](x, y, t) for x, y, t in zip(a, b, w, strict=True)])
    want = np.array([log_lerp_weight(x, y, t) for x, y, t in zip(a, b, w, strict=True)])
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=0)
    np.testing.assert_allclose(got[20:30], w[20:30], rtol=1e-12)  # equal values: the linear weight
    # the geometric interpolation a^(1 - w) b^w at the centre of a cell (within the floor)
    c = np.array([ns["log_lerp_weight"](x, y, 0.5) for x, y in zip(a[30:], b[30:], strict=True)])
    lo, hi = np.minimum(a[30:], b[30:]), np.maximum(a[30:], b[30:])
    keep = lo > 1e-3 * hi
    mid = a[30:] + c * (b[30:] - a[30:])
    np.testing.assert_allclose(mid[keep], np.sqrt(a[30:] * b[30:])[keep], rtol=1e-12)


def test_transmittance_and_irradiance_textures(atm, luts):
    data = load_realtime(luts)
    ns = data.mappings()
    p = atm.parameters
    m = fold_matrix(atm)
    solar = p.solar_irradiance_at(atm.wavelengths)
    for alt in (0.0, 3e3, 30e3):
        r = p.bottom_radius + alt
        for mu in (-0.05, 0.0, 0.1, 0.5, 1.0):
            t = atm.transmittance(r, mu) if not ns["ray_hits_ground"](r, mu) else None
            if t is None:
                continue
            want = (m @ (solar * t)) / (m @ solar)
            got = _sample(data.textures["transmittance"], ns["transmittance_uv"](r, mu))
            np.testing.assert_allclose(got[:3], want, rtol=2e-6, atol=1e-7)
        for el in (30.0, 4.0, -4.0):
            sun = direction_from_angles(np.radians(90 - el), 0.3)
            point = np.array([0.0, 0.0, r])
            _, e_sky = atm.table_irradiance(point, [0.0, 0.0, 1.0], sun)  # the table read the GLSL reproduces
            uv0, uv1, uv2, t, below = ns["irradiance_uvs"](r, sun[2])
            # the SMALL table's 8 texels: +-4 deg lie in the cell across the horizon (-8.2..+8.2 deg), read
            # log-quadratically over three columns
            assert below == (abs(el) < 8.0)
            tex = data.textures["irradiance"]
            got = ns["irradiance_lerp"](_sample(tex, uv0), _sample(tex, uv1), _sample(tex, uv2), t, below)
            if not below:  # linear along mu_s: the folded read is the read of the folded table
                np.testing.assert_allclose(got, m @ e_sky, rtol=2e-6, atol=1e-9)
                continue
            # below the horizon the lookups weigh each wavelength by its own three columns, the texture each colour
            # channel by its own: the same rule (log_quadratic_weight, Abramowitz & Stegun 25.2.11) on the folded
            # table, read by the library (numba, not the mappings' code)
            want = np.empty(3)
            irradiance_lookup(np.ascontiguousarray(np.asarray(atm.tables["irradiance"], np.float64) @ m.T), r,
                              sun[2], p.bottom_radius, p.top_radius, want)
            np.testing.assert_allclose(got, want, rtol=2e-6, atol=1e-9)


def test_fold_matrix_is_the_libraries_colour(atm):
    """The fold matrix applied to a spectrum gives the linear sRGB of the library's XYZ (the HDR scale included)."""
    spec = np.linspace(0.01, 0.03, atm.wavelengths.size)
    np.testing.assert_allclose(fold_matrix(atm) @ spec, xyz_to_linear_srgb(atm.to_xyz(spec)) * HDR_SCALE,
                               rtol=1e-12)


def test_half_and_exr_match_float32(luts):
    f32 = load_realtime(luts).textures
    f16 = load_realtime(luts, fmt="rgba16f").textures
    exr = load_realtime(luts, fmt="exr").textures
    for name, a in f32.items():
        np.testing.assert_array_equal(exr[name], a)
        big = np.abs(a) > 1e-4 * np.abs(a).max()  # half keeps 11 bits; its subnormals start at 6e-8
        np.testing.assert_allclose(f16[name][big], a[big], rtol=2 ** -10)


def test_manifest_states_version_units_scale_and_code(luts):
    manifest = json.loads((luts / MANIFEST_NAME).read_text())
    assert manifest["format"] == "skyscatter-realtime-luts" and manifest["version"] == 12
    assert manifest["hdr_scale"]["cd_m2_per_unit_Y"] == 683.0
    assert manifest["mappings"]["glsl"] == glsl_mappings() and manifest["mappings"]["glsl"] in glsl_library()
    for name in ("transmittance_uv", "irradiance_uv", "irradiance_uvs", "irradiance_lerp", "scattering_uvw",
                 "scattering_uvw4", "azimuth_read"):
        assert f"def {name}(" in manifest["mappings"]["python"]
    for glsl in ("TransmittanceUv", "IrradianceUv", "IrradianceUvs", "IrradianceLerp", "ScatteringMuRCoords",
                 "ScatteringMuSIndex", "ScatteringNuIndex", "AzimuthRead"):
        assert glsl in manifest["mappings"]["glsl"]
    for name, entry in manifest["textures"].items():
        f = entry["files"]["rgba32f"]
        assert (luts / f["file"]).stat().st_size == f["bytes"] == 16 * entry["width"] * entry["height"] * entry.get(
            "depth", 1), name


def _copy(luts, tmp_path):
    import shutil

    dst = tmp_path / "copy"
    shutil.copytree(luts, dst)
    return dst


def test_loader_refuses_another_version_a_missing_and_a_truncated_file(luts, tmp_path):
    bad = _copy(luts, tmp_path)
    manifest = json.loads((bad / MANIFEST_NAME).read_text())
    manifest["version"] = 99
    (bad / MANIFEST_NAME).write_text(json.dumps(manifest))
    with pytest.raises(FileFormatError, match="version 99"):
        load_realtime(bad)
    manifest["version"] = MANIFEST_VERSION
    (bad / MANIFEST_NAME).write_text(json.dumps(manifest))
    (bad / "mie.rgba32f").unlink()
    with pytest.raises(FileFormatError, match="mie.rgba32f: texture file missing"):
        load_realtime(bad)
    data = (luts / "rayleigh.rgba32f").read_bytes()
    (bad / "mie.rgba32f").write_bytes(data[: len(data) // 2])
    with pytest.raises(FileFormatError, match="truncated"):
        load_realtime(bad)
    (bad / MANIFEST_NAME).write_text('{"format": "something-else"}')
    with pytest.raises(FileFormatError, match="not a skyscatter real-time manifest"):
        load_realtime(bad)
    with pytest.raises(FileFormatError, match="no real-time manifest"):
        load_realtime(tmp_path / "nowhere")
    with pytest.raises(InvalidParameterError):
        load_realtime(luts, fmt="png")


def test_export_refuses_unknown_formats(atm, tmp_path):
    with pytest.raises(InvalidParameterError, match="rgba32f"):
        export_realtime(atm, tmp_path, formats=("jpeg",))


def test_server_serves_the_viewer_and_only_the_exports_files(luts, tmp_path):
    import urllib.error
    import urllib.request

    from skyscatter.realtime.server import serve

    (luts / "secret.txt").write_text("not for the page")
    with serve(luts) as server:
        assert server.url.startswith("http://127.0.0.1:")

        def get(path):
            with urllib.request.urlopen(server.url + path.lstrip("/"), timeout=10) as r:
                return r.read()

        page = get("/").decode()
        assert 'src="/viewer/viewer.js"' in page and "://" not in page.split("<body>")[1]
        assert b"GetSkyRadianceToPoint" in get("/glsl/atmosphere.glsl")
        for path in ("/", "/viewer/viewer.js", "/viewer/style.css"):  # nothing loaded from the network
            assert b"http://" not in get(path) and b"https://" not in get(path) and b"//cdn" not in get(path)
        assert json.loads(get(f"/luts/{MANIFEST_NAME}"))["version"] == 12
        assert len(get("/luts/rayleigh.rgba32f")) == (luts / "rayleigh.rgba32f").stat().st_size
        for path in ("/luts/secret.txt", "/luts/../secret.txt", "/etc/passwd", "/viewer/../export.py"):
            with pytest.raises(urllib.error.HTTPError, match="404"):
                get(path)


def test_optical_depth_texture_and_segment_rule(atm, luts):
    """The optical_depth texture is the band average of -ln T at its texels; the manifest's segment rule gives the
    sunlight transmittance of a short segment high in the sky (well conditioned: the ratio) to float32 rounding."""
    data = load_realtime(luts)
    ns = data.mappings()
    m = fold_matrix(atm)
    solar = atm.parameters.solar_irradiance_at(atm.wavelengths)
    w = np.maximum(np.vstack([m, [0.2126, 0.7152, 0.0722] @ m]), 0) * solar
    w /= w.sum(axis=1, keepdims=True)
    tau = -np.log(np.maximum(atm.tables["transmittance"].astype(np.float64), 1e-30))
    np.testing.assert_allclose(data.textures["optical_depth"], tau @ w.T, rtol=1e-6, atol=1e-6)
    r = atm.parameters.bottom_radius + 5000.0
    for mu in (0.3, 0.7, 1.0):
        d = 3000.0
        r_d = math.sqrt(d * d + 2 * r * mu * d + r * r)
        mu_d = (r * mu + d) / r_d
        uv_a, uv_b = ns["transmittance_uv"](r, mu), ns["transmittance_uv"](r_d, mu_d)
        got = ns["segment_transmittance"](
            _sample(data.textures["transmittance"], uv_a)[:3], _sample(data.textures["transmittance"], uv_b)[:3],
            _sample(data.textures["optical_depth"], uv_a)[:3], _sample(data.textures["optical_depth"], uv_b)[:3])
        t_seg = np.minimum(atm.transmittance(r, mu) / atm.transmittance(r_d, mu_d), 1.0)
        np.testing.assert_allclose(got, (m @ (solar * t_seg)) / (m @ solar), atol=2e-3)


def test_view_refuses_a_folder_without_a_manifest_in_one_line(tmp_path, capsys):
    from skyscatter.cli import main

    assert main(["view", "--luts", str(tmp_path), "--port", "0", "--check"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no real-time manifest" in err[0]
    assert main(["export-luts", "--out-dir", str(tmp_path / "x"), "--formats", "png"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "rgba32f" in err[0]
