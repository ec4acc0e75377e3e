"""Command-line edges of issue 18: interruptions anywhere are one line, export-luts' folder and report, the Monte
Carlo sky's estimate and progress, the demo's table wavelengths."""

from __future__ import annotations

import json

import pytest

from skyscatter import cli
from skyscatter.cli import main


def test_ctrl_c_while_a_library_initialises_is_one_line(monkeypatch, capsys):
    """Ctrl-C during a C extension's initialisation (OpenEXR's, on the first EXR) surfaces as
    ``ImportError: initialization failed`` caused by KeyboardInterrupt: reported as the interruption it is."""
    import skyscatter.cli.sky as sky_cli

    def interrupted_import(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise ImportError("initialization failed") from exc

    monkeypatch.setattr(sky_cli, "run", interrupted_import)  # register() reads it when the parser is built
    assert main(["sky", "--width", "8"]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["skyscatter sky: interrupted"]


def test_sigterm_while_the_parser_is_built_is_one_line(monkeypatch, capsys):
    def terminated(command=None):
        raise cli.Terminated

    monkeypatch.setattr(cli, "build_parser", terminated)
    assert main(["sun", "--lat", "1"]) == 143
    assert capsys.readouterr().err.strip().splitlines() == ["skyscatter sun: terminated"]


def test_export_luts_refuses_an_empty_folder_name(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["export-luts", "--out-dir", ""]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "empty string" in err[0]
    assert list(tmp_path.iterdir()) == []


def test_export_luts_reports_only_what_it_wrote(tmp_path, capsys):
    """A 3-channel export, then a 4-channel one into the same folder: the old scattering_rgba.raw is not reported
    as written (it is named as left from the earlier export) and atmosphere.json does not list it."""
    from skyscatter.precomputed import PrecomputedAtmosphere

    tiny = dict(transmittance_mu=16, transmittance_r=4, irradiance_mu_s=4, irradiance_r=4, scattering_r=4,
                scattering_mu=8, scattering_mu_s=4, scattering_nu=2)
    for name, wl in (("rgb.npz", dict(tables="rgb")), ("four.npz", dict(wavelengths=[680.0, 550.0, 500.0, 440.0]))):
        PrecomputedAtmosphere.compute(orders=1, sizes=tiny, progress=False, **wl).save(tmp_path / name)
    luts = tmp_path / "luts"
    assert main(["export-luts", "--out-dir", str(luts), "--from", str(tmp_path / "rgb.npz"), "--formats", "raw"]) == 0
    assert "scattering_rgba.raw" in capsys.readouterr().out
    assert main(["export-luts", "--out-dir", str(luts), "--from", str(tmp_path / "four.npz"), "--formats", "raw"]) == 0
    out, err = capsys.readouterr()
    assert "scattering_rgba.raw" not in out
    assert "scattering_rgba.raw" in err and "earlier export" in err
    desc = json.loads((luts / "atmosphere.json").read_text())
    assert "scattering_rgba" not in desc["textures"] and len(desc["channels_wavelength_nm"]) == 4


def test_monte_carlo_sky_says_how_long_and_shows_progress(tmp_path, capsys, monkeypatch):
    from skyscatter.sky.montecarlo import MonteCarloSky

    calls = []
    real = MonteCarloSky.radiance_and_error

    def spy(self, directions, wavelengths=None):
        calls.append(self.progress)
        return real(self, directions, wavelengths)

    monkeypatch.setattr(MonteCarloSky, "radiance_and_error", spy)
    assert main(["sky", "--model", "montecarlo", "--width", "8", "--samples", "2",
                 "--out", str(tmp_path / "mc.exr")]) == 0
    err = capsys.readouterr().err
    assert "estimated from a pilot run" in err and "about" in err
    assert calls and all(callable(c) for c in calls)  # the bar is attached to every evaluation
    seconds = MonteCarloSky(1.0, 0.0, samples=64).estimate_seconds(1000)
    assert 0 < seconds < 3600


def test_demo_bruneton_table_wavelengths_reach_the_tables(monkeypatch):
    """The crash of issue 18 (``--wavelengths`` given twice to bruneton_scene): the tables' wavelengths go to
    BrunetonSky, the renderer's stay the renderer's (the full run is in test_cli_runs.py)."""
    import skyscatter.render.bruneton as rb

    seen = {}

    class Stop(Exception):
        pass

    def fake_sky(*args, **kwargs):
        seen.update(kwargs)
        raise Stop

    monkeypatch.setattr(rb, "BrunetonSky", fake_sky)
    with pytest.raises(Stop):
        rb.bruneton_scene(_terrain(), _camera(), 1.0, 0.0,
                          wavelengths=[500.0, 600.0], tables="rgb", ozone_column=250.0)
    assert seen["tables"] == "rgb" and seen["ozone_column"] == 250.0


def _terrain():
    import numpy as np

    from skyscatter.render.terrain import Terrain

    return Terrain(np.zeros((3, 3)), 10.0)


def _camera():
    from skyscatter.render.camera import PinholeCamera

    return PinholeCamera((0.0, 0.0, 10.0), 0.0)
