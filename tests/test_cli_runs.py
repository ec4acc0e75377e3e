"""Every subcommand runs to its end with every documented option (issue 18, item 2), and its output is checked.

``RUNS`` lists command lines on small inputs; each runs in a fresh folder and its check reads what it wrote.
``test_every_documented_option_is_run`` asks the parsers for every option of every subcommand (and every choice of
the choice options) and requires each in at least one of the runs, so a new option needs a run here.
The precomputed atmosphere is built at tiny sizes here (the command's own code, with smaller tables, so that
every atmosphere option costs a second rather than a minute); ``precompute`` and ``export-luts`` are given tiny
sizes on their command line; ``skymatrix --spectral``'s table presets (``--tables default`` and ``coarse``)
keep their wavelengths but take the tiny sizes. Likewise the cloud table of ``skymatrix --spectral``'s cloudy
hours has 3 x 3 nodes here (9 DISORT solves instead of 108: each air's table cost about 40 s of CPU) and the
clear-sky tables that light a cloud top are tiny: the retrieval's code runs on every cloudy hour; its accuracy is
tested with the real nodes and sizes in tests/test_cloud_retrieval.py and tests/test_spectral_skymatrix.py.
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from skyscatter.cli import build_parser, main
from skyscatter.realtime.export import MANIFEST_VERSION

DATA = Path(__file__).parent / "data"
TINY = dict(transmittance_mu=16, transmittance_r=4, irradiance_mu_s=4, irradiance_r=4, scattering_r=4,
            scattering_mu=8, scattering_mu_s=4, scattering_nu=2)
TINY_FLAGS = ["--transmittance-size", "16x4", "--irradiance-size", "4x4", "--scattering-size", "4x8x4x2",
              "--orders", "2", "--no-progress"]


#: Cloud optical depths [-] and sun zenith angles [rad] of the cloud table here (the real one: 12 x 9 nodes over
#: the same ranges, skyscatter.fit.weather.CLOUD_OPTICAL_DEPTH_NODES and CLOUD_ZENITH_NODES_DEG).
TINY_CLOUD_TAU = (0.5, 5.5, 60.0)
TINY_CLOUD_ZENITH = tuple(np.radians([0.0, 62.0, 87.0]))


@pytest.fixture(autouse=True)
def _tiny_tables(monkeypatch):
    import skyscatter.fit.weather as weather
    import skyscatter.precomputed.cache as cache
    import skyscatter.sky.cloudy as cloudy

    real = cache.load_or_compute

    def tiny(params=None, **kwargs):
        if kwargs.get("sizes") is None or kwargs.get("sizes") is TINY:
            kwargs["sizes"] = TINY
            kwargs["orders"] = 2
        return real(params, **kwargs)

    monkeypatch.setattr(cache, "load_or_compute", tiny)
    for preset in weather.TABLE_PRESETS.values():  # skymatrix --spectral's family (--tables default and coarse)
        monkeypatch.setitem(preset, "sizes", TINY)
        monkeypatch.setitem(preset, "orders", 2)
    monkeypatch.setattr(cloudy, "COUPLING_TABLE_SIZES", TINY)
    real_cloud_table = weather.cloud_table

    def tiny_cloud_table(atmosphere, optical_depth_nodes=TINY_CLOUD_TAU, zenith_nodes=TINY_CLOUD_ZENITH):
        return real_cloud_table(atmosphere, optical_depth_nodes, zenith_nodes)

    monkeypatch.setattr(weather, "cloud_table", tiny_cloud_table)


# -------------------------------------------------------------------------------------------- checks


def _exr(name, shape=None, positive=True, png=None):
    def check(folder: Path, out: str) -> None:
        from skyscatter.render import read_exr

        img = read_exr(folder / name)
        assert np.all(np.isfinite(img)) and img.min() >= 0
        if shape is not None:
            assert img.shape == shape, img.shape
        if positive:
            assert img.max() > 0
        preview = folder / (png or Path(name).with_suffix(".png"))
        assert preview.stat().st_size > 50, preview
    return check


def _broken_and_overcast_skies(folder: Path, out: str) -> None:
    """--figure clouds: the cumulus panel's sky is patchy (clouds and gaps), the overcast one's smooth."""
    from skyscatter.render import read_exr

    def spread(name: str) -> float:
        sky = read_exr(folder / name)[:4].sum(axis=-1)  # the top rows: sky above the mountains
        return float(sky.std() / sky.mean())

    assert spread("clouds_a_broken_cumulus.exr") > 2.0 * spread("clouds_b_overcast_evening.exr")


def _files(*names):
    def check(folder: Path, out: str) -> None:
        for n in names:
            assert (folder / n).is_file() and (folder / n).stat().st_size > 0, n
    return check


def _stdout(*words):
    def check(folder: Path, out: str) -> None:
        for w in words:
            assert w in out, (w, out)
    return check


def _json_keys(*keys):
    def check(folder: Path, out: str) -> None:
        data = json.loads(out)
        for k in keys:
            assert k in data, (k, data)
    return check


def _npz(name, n_patches, n_rows=48):
    def check(folder: Path, out: str) -> None:
        with np.load(folder / name) as f:
            assert f["luminance"].shape == (n_rows, n_patches) and np.all(f["luminance"] >= 0)
            assert f["luminance"].max() > 0
    return check


def _radiance_matrix(name, rows):
    def check(folder: Path, out: str) -> None:
        from skyscatter.radiance import read_radiance_matrix

        values, keys = read_radiance_matrix(folder / name)
        assert values.shape == (rows, 48, 3) and values.max() > 0 and keys["NCOMP"] == "3"
    return check


def _radiance_sky(name):
    def check(folder: Path, out: str) -> None:
        stem = folder / name
        text = stem.with_suffix(".rad").read_text()
        assert "colorpict" in text and stem.with_suffix(".hdr").read_bytes().startswith(b"#?RADIANCE")
        assert stem.with_suffix(".cal").is_file() and stem.with_suffix(".png").is_file()
    return check


def _radiance_spectral(name):
    def check(folder: Path, out: str) -> None:
        from skyscatter.radiance import read_radiance_matrix

        values, keys = read_radiance_matrix(folder / name)
        assert keys["NCOMP"] == "3" and values.shape[0] == 146 and np.nanmax(values) > 0
    return check


def _zarr(name, cells):
    def check(folder: Path, out: str) -> None:
        import xarray as xr

        ds = xr.open_zarr(folder / name, consolidated=False)
        assert int(ds["done"].sum()) == cells and np.all(np.isfinite(ds["radiance"].values))
    return check


def _almucantars(name, n_zenith, n_azimuth):
    """The store's directions are the almucantars asked for (zenith angles of equal-area bands, N/K azimuths)."""
    def check(folder: Path, out: str) -> None:
        import xarray as xr

        ds = xr.open_zarr(folder / name, consolidated=False)
        zen = np.sort(np.unique(np.round(ds["view_zenith"].values, 9)))
        expected = np.degrees(np.arccos(1.0 - (np.arange(n_zenith) + 0.5) / n_zenith))
        np.testing.assert_allclose(zen, expected, rtol=1e-9)
        assert ds.sizes["direction"] == n_zenith * n_azimuth
    return check


def _reference_air(name, aerosol_type, air_file):
    """The store's job holds the air the options asked for: an OPAC type's Mie aerosol with the cells' optical
    depths, or the air of a JSON file with its Angstrom exponent."""
    def check(folder: Path, out: str) -> None:
        import xarray as xr

        from skyscatter.atmosphere import AtmosphereParameters

        ds = xr.open_zarr(folder / name, consolidated=False)
        air = AtmosphereParameters.from_dict(json.loads(ds.attrs["job"])["atmosphere"])
        if aerosol_type is not None:
            expected = AtmosphereParameters.from_options(aerosol_type=aerosol_type).aerosol
            assert air.aerosol == expected and "tabulated" in ds.attrs["mie_phase_function"]
        else:
            fitted = AtmosphereParameters.load_json(folder / air_file)
            assert air.aerosol is None and air.mie_angstrom_alpha == fitted.mie_angstrom_alpha != 1.3
    return check


def _tables(name):
    def check(folder: Path, out: str) -> None:
        from skyscatter.precomputed import PrecomputedAtmosphere

        atm = PrecomputedAtmosphere.load(folder / name)
        assert atm.tables["transmittance"].shape[:2] == (4, 16)
    return check


def _luts(folder_name, channels):
    def check(folder: Path, out: str) -> None:
        desc = json.loads((folder / folder_name / "atmosphere.json").read_text())
        assert len(desc["channels_wavelength_nm"]) == channels
        for entry in desc["textures"].values():
            assert (folder / folder_name / entry["file"]).stat().st_size == entry["bytes"]
    return check


def _realtime(folder_name, formats):
    def check(folder: Path, out: str) -> None:
        from skyscatter.realtime import load_realtime

        for fmt in formats:
            data = load_realtime(folder / folder_name, fmt=fmt)  # checks version, every file and its size
            assert data.textures["rayleigh"].shape[-1] == 4 and np.isfinite(data.textures["multiple"]).all()
            assert data.textures["transmittance"].max() <= 1.0 + 1e-6
        assert not (folder / folder_name / "atmosphere.json").exists() or "raw" in formats
    return check


def _dataset(name, n_wl):
    def check(folder: Path, out: str) -> None:
        from skyscatter.sky.hosek_wilkie import HosekWilkieDataset, HosekWilkieSky

        ds = HosekWilkieDataset.load(folder / name)
        assert ds.wavelengths.size == n_wl
        sky = HosekWilkieSky(0.8, 1.0, dataset=ds)
        assert np.all(np.isfinite(sky.spectral_radiance([[0.0, 0.0, 1.0]], ds.wavelengths)))
    return check


def _mixture_json(name):
    """fit-atmosphere --mixture wrote the members' optical depths, their fractions (summing to 1) and the mixture."""
    def check(folder: Path, out: str) -> None:
        data = json.loads((folder / name).read_text())
        fit = data["fit"]
        assert fit["mixture"] == ["waso", "sscm"] and fit["free"] == ["optical_depth:waso", "optical_depth:sscm"]
        fractions = [fit["derived"][f"fraction:{m}"][0] for m in ("waso", "sscm")]
        assert abs(sum(fractions) - 1) < 1e-9 and all(0 <= f <= 1 for f in fractions)
        # the optical depths 0.25, 0.15, 0.11 at 440, 675, 870 nm: about 0.19 at 550 nm
        assert 0.15 < fit["derived"]["aerosol_optical_depth"][0] < 0.21
        air = data["atmosphere"]["aerosol"]
        assert air["kind"] == "opac" and air["name"] == "waso+sscm"
    return check


def _spectral_air(report, dataset):
    """skymatrix --spectral --aerosol urban --aod 0.3 --ozone 320 --ground-albedo 0.3: the hours without a retrieval
    have optical depth 0.3, every hour ozone 320 DU, the daylit hours urban's Mie albedo at 550 nm (0.754 at 50 %
    RH: OPAC's urban is strongly absorbing), the tables the ground albedo 0.3."""
    def check(folder: Path, out: str) -> None:
        import csv

        import xarray as xr

        from skyscatter.atmosphere.aerosol_types import OpacAerosol

        rows = list(csv.DictReader((folder / report).read_text().splitlines()))
        assert rows and all(float(r["ozone"]) == 320.0 for r in rows)
        lit = [r for r in rows if r["status"] != "0"]
        assert lit and all(r["aerosol_source"] != "default" or float(r["aerosol_optical_depth"]) == 0.3 for r in lit)
        ssa = float(OpacAerosol.preset("urban", 0.3).single_scattering_albedo_at([550.0])[0])
        assert 0.7 < ssa < 0.8 and all(abs(float(r["single_scattering_albedo"]) - ssa) < 1e-5 for r in lit)
        assert float(xr.open_dataset(folder / dataset, engine="h5netcdf").attrs["ground_albedo"]) == 0.3
    return check


def _all(*checks):
    def check(folder: Path, out: str) -> None:
        for c in checks:
            c(folder, out)
    return check


EPW = "weather.epw"  # copied into each run's folder
S = ["--width", "24"]
D = ["--width", "16", "--height", "9", "--no-glare"]

RUNS = {
    # sun
    "sun-spa": (["sun", "--lat", "48.85", "--lon", "2.35", "--time", "2024-06-21T09:30+02:00", "--altitude", "35",
                 "--pressure", "100000", "--temperature", "20"], _stdout("zenith", "azimuth")),
    "sun-geometric-json": (["sun", "--lat", "-33.9", "--lon", "18.4", "--time", "2024-01-01T12:00Z", "--geometric",
                            "--json"], _json_keys("zenith_deg")),
    "sun-preetham": (["sun", "--lat", "40", "--lon", "-105", "--time", "2024-03-20T12:00-07:00", "--method",
                      "preetham1999"], _stdout("elevation")),
    # the air: fit-atmosphere, then the fitted air in sky and illuminance (and an OPAC aerosol type)
    "fit-atmosphere": (["fit-atmosphere", "aod.csv", "--lat", "40", "--lon", "-105", "--noise", "0.02", "--free",
                        "aerosol_optical_depth,angstrom_alpha", "--out", "air.json", "&&",
                        "sky", "--width", "16", "--model", "bruneton", "--atmosphere", "air.json", "--tables",
                        "rgb", "&&",
                        "illuminance", "--model", "bruneton", "--atmosphere", "air.json", "--aerosol", "maritime-clean",
                        "--tables", "rgb", "&&",
                        "demo", "--model", "bruneton", "--atmosphere", "air.json", "--aerosol", "maritime-clean",
                        "--tables", "rgb", *D],
                       _all(_files("air.json"), _exr("sky.exr"), _stdout("lx"), _exr("landscape.exr"))),
    "fit-atmosphere-opac": (["fit-atmosphere", "aod.csv", "--aerosol", "continental-average", "--free",
                             "aerosol_optical_depth"], _files("air.json")),
    # a fine + coarse mixture from the optical depths (no table build), its air in the sky
    "fit-atmosphere-mixture": (["fit-atmosphere", "aod.csv", "--mixture", "waso,sscm", "--out", "mix.json", "&&",
                                "sky", "--width", "16", "--model", "bruneton", "--atmosphere", "mix.json", "--tables",
                                "rgb"], _all(_mixture_json("mix.json"), _stdout("fraction:waso"), _exr("sky.exr"))),
    "sky-bruneton-opac": (["sky", "--width", "16", "--model", "bruneton", "--aerosol", "urban", "--aod", "0.2",
                           "--tables", "rgb"], _exr("sky.exr")),
    # sky: every model, projection, layout and format
    "sky-preetham-equirect": (["sky", *S, "--turbidity", "4", "--exposure", "1", "--png", "p.png", "--out", "a.exr"],
                              _exr("a.exr", (12, 24, 3), png="p.png")),
    "sky-fisheye-time": (["sky", "--projection", "fisheye", "--width", "20", "--lat", "48.85", "--lon", "2.35",
                          "--time", "2024-06-21T18:30+02:00"], _exr("sky.exr", (20, 20, 3))),
    "sky-pinhole": (["sky", "--projection", "pinhole", "--width", "24", "--height", "12", "--heading", "120",
                     "--pitch", "20", "--fov", "70", "--no-sun-disc", "--terrain-albedo", "0.5"],
                    _exr("sky.exr", (12, 24, 3))),
    "sky-layouts": (["sky", *S, "--layout", "blender", "--out", "b.exr"], _exr("b.exr")),
    "sky-mitsuba": (["sky", *S, "--layout", "mitsuba", "--layout", "skyscatter", "--layout", "mitsuba",
                     "--out", "m.exr"], _exr("m.exr")),
    "sky-radiance": (["sky", *S, "--format", "radiance", "--out", "r.rad"], _radiance_sky("r.rad")),
    "sky-exr-format": (["sky", *S, "--format", "exr"], _exr("sky.exr")),
    "sky-preetham-overcast": (["sky", *S, "--model", "preetham-overcast", "--turbidity", "9"], _exr("sky.exr")),
    "sky-cie": (["sky", *S, "--model", "cie", "--sky-type", "7", "--diffuse-illuminance", "20000",
                 "--sun-illuminance", "50000"], _exr("sky.exr")),
    "sky-cie-overcast": (["sky", *S, "--model", "cie-overcast", "--zenith-luminance", "3000"], _exr("sky.exr")),
    "sky-cie-clear": (["sky", *S, "--model", "cie-clear", "--zenith-luminance", "5000"], _exr("sky.exr")),
    "sky-perez-irradiance": (["sky", *S, "--model", "perez", "--dni", "600", "--dhi", "120", "--day-of-year", "172",
                              "--dew-point", "5"], _exr("sky.exr")),
    "sky-perez-epsilon": (["sky", *S, "--model", "perez", "--epsilon", "3", "--delta", "0.2",
                           "--diffuse-illuminance", "15000"], _exr("sky.exr")),
    "sky-asrc-cie": (["sky", *S, "--model", "asrc-cie", "--dni", "400", "--dhi", "150", "--sun-azimuth", "200"],
                     _exr("sky.exr")),
    "sky-hosek-wilkie": (["sky", *S, "--model", "hosek-wilkie", "--turbidity", "5", "--ground-albedo", "0.3"],
                         _exr("sky.exr")),
    "sky-bruneton-aod": (["sky", *S, "--model", "bruneton", "--aod", "0.2", "--angstrom-alpha", "1.1", "--ozone",
                          "280", "--ground-albedo", "0.2", "--altitude", "1000", "--mie-g", "0.7"], _exr("sky.exr")),
    "sky-bruneton-rgb": (["sky", *S, "--model", "bruneton", "--turbidity", "3", "--tables", "rgb"],
                         _exr("sky.exr")),
    "sky-bruneton-spectral": (["sky", *S, "--model", "bruneton", "--tables", "spectral", "--sun-elevation",
                               "-3"], _exr("sky.exr")),
    # a sun below the fisheye's horizon: until 2026-12-06 the sun's disc stopped this with a numpy casting error
    "sky-bruneton-twilight-fisheye": (["sky", *S, "--model", "bruneton", "--tables", "rgb", "--sun-elevation", "-3",
                                       "--projection", "fisheye"], _exr("sky.exr", (24, 24, 3))),
    "sky-montecarlo": (["sky", "--width", "8", "--model", "montecarlo", "--samples", "2", "--seed", "4",
                        "--altitude", "10"], _exr("sky.exr", (4, 8, 3))),
    "sky-montecarlo-cloud": (["sky", "--width", "8", "--model", "montecarlo", "--samples", "2", "--cloud-optical-depth",
                              "10", "--cloud-base", "800", "--cloud-top", "1200", "--cloud-effective-radius", "8e-6"],
                             _exr("sky.exr", (4, 8, 3))),
    "sky-cloudy": (["sky", "--width", "16", "--model", "cloudy", "--cloud-optical-depth", "20", "--cloud-base", "800",
                    "--cloud-top", "1400", "--cloud-effective-radius", "12e-6", "--ground-albedo", "0.3",
                    "--altitude", "100",
                    "--projection", "fisheye", "--sun-elevation", "25"], _exr("sky.exr", (16, 16, 3))),
    "sky-broken-cloud": (["sky", "--width", "16", "--model", "broken-cloud", "--cloud-cover", "0.4", "--cloud-seed",
                          "3", "--cloud-optical-depth", "8", "--cloud-base", "900", "--cloud-top", "2200",
                          "--cloud-effective-radius", "12e-6", "--ground-albedo", "0.2", "--altitude", "50",
                          "--projection", "fisheye"], _exr("sky.exr", (16, 16, 3))),
    "sky-broken-cloud-file": (["sky", "--width", "16", "--model", "broken-cloud", "--cloud-field", "field.nc",
                               "--projection", "pinhole", "--pitch", "30"], _exr("sky.exr", (12, 16, 3))),
    # illuminance
    "illuminance-planes": (["illuminance", "--model", "perez", "--dni", "700", "--dhi", "120", "--vertical", "180",
                            "90", "--tilted", "30", "180", "--include-sun"], _stdout("lx")),
    "illuminance-json": (["illuminance", "--model", "cie", "--sky-type", "3", "--sun-elevation", "40",
                          "--sun-azimuth", "200", "--json"], _json_keys("planes", "model")),
    "illuminance-bruneton": (["illuminance", "--model", "bruneton", "--tables", "rgb", "--lat", "48",
                              "--lon", "11", "--time", "2024-06-21T12:00+02:00"], _stdout("lx")),
    "illuminance-bruneton-spectral": (["illuminance", "--model", "bruneton", "--tables", "spectral",
                                       "--aod", "0.15", "--angstrom-alpha", "1.2", "--ozone", "310", "--mie-g", "0.75",
                                       "--ground-albedo", "0.25", "--altitude", "500"], _stdout("lx")),
    "illuminance-cloudy": (["illuminance", "--model", "cloudy", "--cloud-optical-depth", "8", "--cloud-base", "600",
                            "--cloud-top", "1200", "--cloud-effective-radius", "8e-6", "--vertical", "180", "--json"],
                           _json_keys("planes", "model")),
    "illuminance-broken-cloud": (["illuminance", "--model", "broken-cloud", "--cloud-cover", "0.5", "--cloud-seed",
                                  "1", "--vertical", "180"], _stdout("lx")),
    "illuminance-broken-cloud-file": (["illuminance", "--model", "broken-cloud", "--cloud-field", "field.nc",
                                       "--json"], _json_keys("planes", "model")),
    "illuminance-preetham": (["illuminance", "--model", "preetham", "--turbidity", "3", "--include-sun"],
                             _stdout("lx")),
    "illuminance-preetham-overcast": (["illuminance", "--model", "preetham-overcast", "--turbidity", "7"],
                                      _stdout("lx")),
    "illuminance-cie-overcast": (["illuminance", "--model", "cie-overcast", "--zenith-luminance", "2000"],
                                 _stdout("lx")),
    "illuminance-cie-clear": (["illuminance", "--model", "cie-clear", "--diffuse-illuminance", "12000",
                               "--sun-illuminance", "70000", "--include-sun"], _stdout("lx")),
    "illuminance-asrc-cie": (["illuminance", "--model", "asrc-cie", "--epsilon", "2", "--delta", "0.3",
                              "--day-of-year", "80", "--dew-point", "4"], _stdout("lx")),
    "illuminance-hosek-wilkie": (["illuminance", "--model", "hosek-wilkie", "--turbidity", "4", "--ground-albedo",
                                  "0.2", "--include-sun"], _stdout("lx")),
    # skymatrix
    "skymatrix-npz-csv": (["skymatrix", EPW, "--patches", "tregenza", "--csv", "m.csv", "--out", "m.npz",
                           "--include-sun", "--samples", "2", "--no-progress"],
                          _all(_npz("m.npz", 145), _files("m.csv"))),
    "skymatrix-hourly-asrc": (["skymatrix", EPW, "--patches", "reinhart1", "--timestep", "hourly", "--model",
                               "asrc-cie", "--night-irradiance", "error"], _npz("skymatrix.npz", 145)),
    "skymatrix-reinhart": (["skymatrix", EPW, "--patches", "reinhart4", "--samples", "1", "--timestep", "records",
                            "--night-irradiance", "dark", "--format", "npz"], _npz("skymatrix.npz", 2305)),
    # spectral (issue 24): the test EPW's sky cover is 5 tenths in every hour, so no hour is clear and no table is
    # built; tests/test_spectral_skymatrix.py runs the same options on a file with clear hours. The air's options
    # of every command (an OPAC type, its optical depth for hours without a retrieval, ozone, ground albedo)
    "skymatrix-spectral-cloudy": (["skymatrix", "--spectral", EPW, "--tables", "coarse", "--aod-nodes", "0,0.5",
                                   "--bands", "41", "--patches", "tregenza", "--samples", "1", "--radiance", "s.mtx",
                                   "--radiance-rgb", "r.mtx", "--report", "h.csv", "--bad-hours", "flag",
                                   "--aerosol", "urban", "--aod", "0.3", "--ozone", "320", "--ground-albedo", "0.3",
                                   "--out", "s.nc"],
                                  _all(_files("s.nc", "s.mtx", "r.mtx", "h.csv"), _spectral_air("h.csv", "s.nc"))),
    "skymatrix-spectral-sites": (["fit-atmosphere", "aod.csv", "--free", "aerosol_optical_depth,angstrom_alpha",
                                  "--out", "air.json", "&&",
                                  "skymatrix", "--spectral", EPW, EPW, "--tables", "default", "--bad-hours", "error",
                                  "--scheduler", "threads", "--workers", "1", "--atmosphere", "air.json", "--out",
                                  "sites.zarr"],
                                 _stdout("2 of 2 sites")),
    "skymatrix-radiance": (["skymatrix", EPW, "--patches", "reinhart2", "--format", "radiance", "--ground-albedo",
                            "0.3", "--include-sun"], _radiance_matrix("skymatrix.mtx", 578)),
    "skymatrix-spectral": (["skymatrix", "--spectral", "synth.epw", "--out", "s.nc", "--tables", "coarse",
                            "--aod-nodes", "0,0.2,0.5", "--patches", "tregenza", "--samples", "1", "--bands", "41",
                            "--turbidity", "3", "--angstrom-alpha", "1.1", "--mie-g", "0.75",
                            "--radiance-rgb", "s3.mtx", "--bad-hours", "flag", "--scheduler", "threads",
                            "--no-progress"], _all(_files("s.nc"), _radiance_spectral("s3.mtx"))),
    # demo
    "demo-figure-7": (["demo", "--figure", "7", *D, "--exposure", "0.5", "--wavelength-step", "20"],
                      _all(_exr("fig7a_morning_T2.exr", (9, 16, 3)), _files("fig7.png"))),
    "demo-figure-8": (["demo", "--figure", "8", *D, "--no-sun-disc"], _files("fig8.png")),
    "demo-custom": (["demo", "--figure", "custom", *D, "--model", "preetham", "--turbidity", "3", "--aerial",
                     "numeric", "--sun-elevation", "10", "--sun-azimuth", "250", "--heading", "250", "--pitch",
                     "-2", "--fov", "50", "--camera-x", "1000", "--camera-y", "-500", "--camera-height", "200",
                     "--terrain-albedo", "0.3", "--out-dir", "out"], _exr("out/landscape.exr")),
    "demo-aerials": (["demo", *D, "--model", "cie-clear", "--aerial", "ward-larson", "--zenith-luminance", "6000",
                      "--sun-illuminance", "60000", "--camera-altitude", "800"], _exr("landscape.exr")),
    "demo-constant-dem": (["demo", *D, "--model", "cie-overcast", "--aerial", "constant", "--diffuse-illuminance",
                           "12000", "--dem", "dem.npy", "--dem-spacing", "100"], _exr("landscape.exr")),
    "demo-analytic-none": (["demo", *D, "--model", "cie", "--sky-type", "5", "--aerial", "none"],
                           _exr("landscape.exr")),
    "demo-analytic": (["demo", *D, "--model", "perez", "--epsilon", "4", "--delta", "0.25", "--day-of-year", "100",
                       "--dew-point", "8", "--aerial", "analytic"], _exr("landscape.exr")),
    "demo-hosek": (["demo", *D, "--model", "hosek-wilkie", "--lat", "45", "--lon", "7", "--time",
                    "2024-06-21T19:00+02:00"], _exr("landscape.exr")),
    "demo-overcast-blend": (["demo", *D, "--model", "preetham-overcast", "--turbidity", "8"],
                            _exr("landscape.exr")),
    "demo-asrc-cie": (["demo", *D, "--model", "asrc-cie", "--dni", "300", "--dhi", "200"], _exr("landscape.exr")),
    "demo-montecarlo": (["demo", "--width", "6", "--height", "4", "--no-glare", "--model", "montecarlo", "--samples",
                         "1", "--seed", "2", "--altitude", "5"], _exr("landscape.exr")),
    "demo-montecarlo-cloud": (["demo", "--width", "6", "--height", "4", "--no-glare", "--model", "montecarlo",
                               "--samples", "1", "--cloud-optical-depth", "5", "--cloud-base", "900", "--cloud-top",
                               "1100", "--cloud-effective-radius", "12e-6"], _exr("landscape.exr")),
    "demo-figure-clouds": (["demo", "--figure", "clouds", "--width", "32", "--height", "18", "--no-glare"],
                           _all(_exr("clouds_a_broken_cumulus.exr", (18, 32, 3)),
                                _exr("clouds_b_overcast_evening.exr", (18, 32, 3)), _files("clouds.png"),
                                _broken_and_overcast_skies)),
    "demo-cloudy": (["demo", "--width", "6", "--height", "4", "--no-glare", "--model", "cloudy",
                     "--cloud-optical-depth", "30", "--cloud-base", "500", "--cloud-top", "1000"],
                    _exr("landscape.exr")),
    "demo-broken-cloud": (["demo", "--width", "6", "--height", "4", "--no-glare", "--model", "broken-cloud",
                           "--cloud-cover", "0.5", "--cloud-seed", "2", "&&", "demo", "--width", "6", "--height", "4",
                           "--no-glare", "--model", "broken-cloud", "--cloud-field", "field.nc"],
                          _exr("landscape.exr")),
    "demo-bruneton-rgb": (["demo", "--figure", "custom", "--model", "bruneton", "--tables", "rgb", *D,
                           "--sun-elevation", "6", "--sun-azimuth", "270"], _exr("landscape.exr")),
    "demo-bruneton-aod": (["demo", "--model", "bruneton", "--aod", "0.1", "--angstrom-alpha", "1.3", "--ozone", "300",
                           "--tables", "spectral", "--mie-g", "0.75", "--ground-albedo", "0.15", *D],
                          _exr("landscape.exr")),
    # the atmosphere's options are one list (skyscatter.atmosphere.options): the fitted air and an OPAC aerosol in
    # every command that builds an atmosphere
    "air-everywhere": (["fit-atmosphere", "aod.csv", "--free", "aerosol_optical_depth", "--out", "air.json", "&&",
                        "demo", "--model", "bruneton", "--atmosphere", "air.json", "--aerosol", "maritime-clean",
                        "--tables", "rgb", *D, "&&",
                        "precompute", "--out", "p.npz", *TINY_FLAGS, "--atmosphere", "air.json", "--aerosol", "urban",
                        "--tables", "spectral", "&&",
                        "export-luts", "--out-dir", "luts", *TINY_FLAGS, "--atmosphere", "air.json", "--aod", "0.2",
                        "--angstrom-alpha", "1.1", "--tables", "rgb", "--formats", "raw", "&&",
                        # the spectral raw export takes a Mie (tabulated) phase; the real-time textures refuse it
                        "export-luts", "--out-dir", "luts2", *TINY_FLAGS, "--aerosol", "desert", "--tables", "spectral",
                        "--formats", "raw", "&&",
                        "view", *TINY_FLAGS, "--atmosphere", "air.json", "--aod", "0.2", "--angstrom-alpha", "1.1",
                        "--tables", "rgb", "--port", "0", "--no-browser", "--check", "&&",
                        "view", *TINY_FLAGS, "--wavelengths", "680,550,440", "--port", "0", "--no-browser", "--check",
                        "&&",
                        "precompute", "--out", "q.npz", *TINY_FLAGS, "--aod", "0.3", "--angstrom-alpha", "0.8"],
                       _all(_exr("landscape.exr"), _tables("p.npz"), _luts("luts", 3), _luts("luts2", 16),
                            _tables("q.npz"))),
    # precompute, export-luts
    "precompute-out": (["precompute", "--out", "t.npz", *TINY_FLAGS, "--turbidity", "3", "--ground-albedo", "0.2",
                        "--ozone", "250", "--mie-g", "0.7", "--max-sun-zenith", "110", "--tables", "rgb"],
                       _tables("t.npz")),
    "precompute-cache-force": (["precompute", *TINY_FLAGS, "--wavelengths", "680,550,440", "--force"],
                               _stdout("wrote")),
    "export-luts-from": (["precompute", "--out", "t.npz", *TINY_FLAGS, "--tables", "rgb", "&&", "export-luts",
                          "--out-dir", "luts", "--from", "t.npz", "--formats", "raw"], _luts("luts", 3)),
    "export-luts-cache": (["export-luts", "--out-dir", "luts16", *TINY_FLAGS, "--formats", "raw,rgba32f",
                           "--wavelengths", "400:700:20",
                           "--turbidity", "2", "--ground-albedo", "0.15", "--ozone", "320", "--mie-g", "0.75",
                           "--max-sun-zenith", "105"], _luts("luts16", 16)),
    "export-luts-realtime": (["export-luts", "--out-dir", "rt", *TINY_FLAGS, "--formats", "rgba32f,rgba16f,exr"],
                             _realtime("rt", ("rgba32f", "rgba16f", "exr"))),
    # view (--check: serve on 127.0.0.1, fetch the page and every file over HTTP, exit)
    "view-luts": (["export-luts", "--out-dir", "rt", *TINY_FLAGS, "--formats", "rgba32f", "&&", "view", "--luts", "rt",
                   "--port", "0", "--no-browser", "--check"],
                  _stdout(f"manifest (version {MANIFEST_VERSION}) and 6 textures")),
    "view-cache": (["view", *TINY_FLAGS, "--turbidity", "3", "--ground-albedo", "0.2", "--ozone", "280", "--mie-g",
                    "0.7", "--max-sun-zenith", "104", "--tables", "spectral", "--port", "0", "--check"],
                   _stdout(f"manifest (version {MANIFEST_VERSION}) and 12 textures")),
    # reference
    "reference-turbidity": (["reference", "r.zarr", "--sun-elevation", "30,-3", "--turbidity", "2,4", "--ground-albedo",
                             "0.1", "--wavelengths", "450,550", "--directions", "3", "--samples", "8", "--seed",
                             "7", "--altitude", "100", "--phase", "henyey-greenstein", "--scheduler", "synchronous",
                             "--no-progress"], _zarr("r.zarr", 4)),
    "reference-aod": (["reference", "a.zarr", "--sun-elevation", "20:40:20", "--aod", "0.1", "--wavelengths",
                       "500", "--directions", "2", "--samples", "4", "--phase", "cornette-shanks"], _zarr("a.zarr", 2)),
    "reference-cloud": (["reference", "c.zarr", "--sun-elevation", "30", "--wavelengths", "500", "--directions", "4",
                         "--almucantars", "2", "--samples", "4", "--cloud-optical-depth", "10", "--cloud-base", "700",
                         "--cloud-top", "1200", "--cloud-effective-radius", "8"],
                        _all(_zarr("c.zarr", 1), _almucantars("c.zarr", 2, 2))),
    "reference-aerosol-type": (["reference", "t.zarr", "--sun-elevation", "30", "--aerosol", "maritime-clean", "--aod",
                                "0.05,0.3", "--wavelengths", "450,650", "--directions", "2", "--samples", "4"],
                               _all(_zarr("t.zarr", 2), _reference_air("t.zarr", "maritime-clean", None))),
    "reference-atmosphere-file": (["fit-atmosphere", "aod.csv", "--free", "aerosol_optical_depth,angstrom_alpha",
                                   "--out", "air.json", "&&", "reference", "f.zarr", "--sun-elevation", "30",
                                   "--atmosphere", "air.json", "--aod", "0.1", "--wavelengths", "500", "--directions",
                                   "2", "--samples", "4"],
                                  _all(_zarr("f.zarr", 1), _reference_air("f.zarr", None, "air.json"))),
    # fit-hosek-wilkie (the tables at tiny sizes)
    "fit": (["fit-hosek-wilkie", "--out", "t.npz", "--turbidity", "4", "--ground-albedo", "0.3", "--elevations",
             "6", "--fit-wavelengths", "550"], _dataset("t.npz", 1)),
    "fit-air": (["fit-atmosphere", "aod.csv", "--free", "aerosol_optical_depth", "--out", "air.json", "&&",
                 "fit-hosek-wilkie", "--out", "t.npz", "--atmosphere", "air.json", "--aod", "0.2", "--angstrom-alpha",
                 "1.1", "--ozone", "280", "--mie-g", "0.75", "--elevations", "6", "--fit-wavelengths", "550", "&&",
                 "fit-hosek-wilkie", "--out", "u.npz", "--aerosol", "maritime-clean", "--elevations", "6",
                 "--fit-wavelengths", "550"], _all(_dataset("t.npz", 1), _dataset("u.npz", 1))),
}


@pytest.mark.parametrize("name", list(RUNS))
def test_command_runs_and_writes_its_output(name, tmp_path, monkeypatch, capsys):
    args, check = RUNS[name]
    monkeypatch.chdir(tmp_path)
    shutil.copy(DATA / "weather.epw", tmp_path / EPW)
    x = np.linspace(0.0, 1.0, 24)
    np.save(tmp_path / "dem.npy", 400.0 * np.outer(np.sin(np.pi * x), np.sin(np.pi * x)))
    from weather_synth import write_epw

    write_epw(tmp_path / "synth.epw")
    if any("--cloud-field" in a for a in args):
        from skyscatter.atmosphere.clouds import CloudField, CloudLayer

        CloudField.procedural(cover=0.5, base=800.0, top=1600.0, particles=CloudLayer(0.0, 1.0, 1.0), size=4000.0,
                              resolution=(16, 16, 8), feature_size=2000.0, seed=2).save(tmp_path / "field.nc")
    (tmp_path / "aod.csv").write_text("kind,time,azimuth_deg,elevation_deg,wavelength_nm,value\n"
                                      "aod,,,,440,0.25\naod,,,,675,0.15\naod,,,,870,0.11\n")
    out_parts = []
    commands = [list(g) for g in _split(args)]
    for command in commands:
        if command[0] == "demo" and "--out-dir" in command:
            (tmp_path / command[command.index("--out-dir") + 1]).mkdir(exist_ok=True)
        code = main(command)
        out, err = capsys.readouterr()
        assert code == 0, f"{' '.join(command)}: {err}"
        assert "Traceback" not in err
        out_parts.append(out)
    check(tmp_path, "".join(out_parts))


def _split(args):
    part: list[str] = []
    for a in args:
        if a == "&&":
            yield part
            part = []
        else:
            part.append(a)
    yield part


def _subcommands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


#: Option values run to success (and their output checked) by another test.
ELSEWHERE = {("demo", "--figure", "all"): "test_cli_demo.py::test_bare_demo_writes_both_figures",
             **{("skymatrix", flag): "test_spectral_skymatrix.py::test_cli_spectral"
                for flag in ("--radiance", "--report", "--workers")},
             # the paper-size family is 18 table builds (minutes); the coarse preset runs the same code
             ("skymatrix", "--tables", "default"): "test_spectral_skymatrix.py::test_cli_spectral",
             # each window's store against the direct call, and the windows adding up to the whole
             ("reference", "--orders"): "test_montecarlo_dataset.py::test_cli_reference_orders"}
#: Choice options whose values are entries of a data table rather than code paths (the OPAC aerosol types): one
#: value run end to end shows the option works; a run per entry would cost a Mie computation each.
SAMPLED_CHOICES = {"--aerosol"}


def test_every_documented_option_is_run():
    """Each option of each subcommand, and each value of each choice option, appears in a run above (or in the
    test ``ELSEWHERE`` names)."""
    here = Path(__file__).parent
    for where in ELSEWHERE.values():
        module, test = where.split("::")
        assert f"def {test}(" in (here / module).read_text()
    used: dict[str, set[str]] = {}
    for args, _ in RUNS.values():
        for command in _split(args):
            used.setdefault(command[0], set()).update(command[1:])
    missing = []
    for name, sp in _subcommands().items():
        given = used.get(name, set())
        for action in sp._actions:
            flags = [o for o in action.option_strings if o not in ("-h", "--help")]
            if not flags or action.help == argparse.SUPPRESS:  # deprecated spellings: tests/test_deprecations.py
                continue
            if not any(f in given for f in flags) and (name, flags[0]) in ELSEWHERE:
                continue
            if not any(f in given for f in flags):
                missing.append(f"{name} {flags[0]}")
                continue
            if action.choices is not None:
                runs = [c for a, _ in RUNS.values() for c in _split(a) if c[0] == name]
                seen = {c[i + 1] for c in runs for i, tok in enumerate(c[:-1]) if tok in flags}
                if any(not set(flags) & set(c) for c in runs):
                    seen.add(str(action.default))  # a run without the option uses its default
                choices = [str(c) for c in action.choices]
                if flags[0] in SAMPLED_CHOICES and seen & set(choices):
                    continue
                missing += [f"{name} {flags[0]} {choice}" for choice in choices
                            if choice not in seen and (name, flags[0], choice) not in ELSEWHERE]
    assert missing == [], missing


@pytest.mark.parametrize("command", list(_subcommands()))
def test_help_says_only_what_means_something(command, capsys):
    """No "(default: True/False)" on flags, no "(default: None)" on options whose default the text describes or
    on required ones; every option of reference and fit-hosek-wilkie states its range or unit."""
    assert main([command, "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    for noise in ("(default: True)", "(default: False)", "(default: None)", "(default: [])", "(default: ==SUPPRESS==)"):
        assert noise not in text, (command, noise)
    if command in ("reference", "fit-hosek-wilkie"):
        for action in _subcommands()[command]._actions:
            if (action.help and action.help != argparse.SUPPRESS and action.option_strings and action.nargs != 0
                    and action.choices is None and action.metavar != "ADDR"):
                assert any(mark in action.help for mark in (" to ", "[", "0-1", "1-20", "list")), (command,
                                                                                                action.help)
