"""`skyscatter demo`: Figures 7 and 8, a custom panel, and bad input that writes nothing."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import skyscatter.cli as cli
from skyscatter.render.image_io import read_exr

FIGURE_FILES = {
    f"{name}{suffix}"
    for name in ("fig7a_morning_T2", "fig7b_evening_T2", "fig7c_evening_T6", "fig7d_overcast_T10",
                 "fig8a_cie_clear_ward_larson", "fig8b_preetham")
    for suffix in (".exr", ".png")
} | {"fig7.png", "fig8.png"}


@pytest.fixture(autouse=True)
def _demo_registered(monkeypatch):
    # The lead registers "demo" in skyscatter.cli._COMMANDS; make the tests independent of that timing.
    if "demo" not in cli._COMMANDS:
        monkeypatch.setattr(cli, "_COMMANDS", [*cli._COMMANDS, "demo"])


def run(capsys, *args):
    code = cli.main(["demo", *args])
    out, err = capsys.readouterr()
    return code, out, err


def test_bare_demo_writes_both_figures(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "--width", "24", "--height", "16")
    assert code == 0, err
    assert {p.name for p in tmp_path.iterdir()} == FIGURE_FILES
    for name in FIGURE_FILES:
        if name.endswith(".exr"):
            img = read_exr(tmp_path / name)
            assert img.shape == (16, 24, 3) and np.all(np.isfinite(img)) and img.max() > 0
    # the evening panels look west into a warm sky, the morning one is bluer at the top
    morning = read_exr(tmp_path / "fig7a_morning_T2.exr")
    evening = read_exr(tmp_path / "fig7b_evening_T2.exr")
    assert morning[0, :, 2].mean() > morning[0, :, 0].mean()
    assert evening[3, :, 0].mean() > evening[3, :, 2].mean()
    assert "Figure 8b" in out


def test_custom_panel_into_out_dir(tmp_path, capsys):
    code, out, err = run(capsys, "--out-dir", str(tmp_path), "--width", "20", "--height", "12",
                         "--sun-elevation", "15", "--turbidity", "3", "--aerial", "constant", "--no-glare",
                         "--heading", "200", "--camera-height", "50")
    assert code == 0, err
    assert {p.name for p in tmp_path.iterdir()} == {"landscape.exr", "landscape.png"}
    assert read_exr(tmp_path / "landscape.exr").shape == (12, 20, 3)


def test_custom_panel_from_dem(tmp_path, capsys):
    x = np.linspace(0, 1, 30)
    dem = 500.0 * np.outer(np.sin(np.pi * x), np.sin(np.pi * x))
    np.save(tmp_path / "dem.npy", dem)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    code, out, err = run(capsys, "--dem", str(tmp_path / "dem.npy"), "--dem-spacing", "100", "--model", "cie-overcast",
                         "--turbidity", "8", "--out-dir", str(out_dir), "--width", "16", "--height", "10")
    assert code == 0, err
    img = read_exr(out_dir / "landscape.exr")
    assert np.all(np.isfinite(img)) and img.min() >= 0


@pytest.mark.parametrize(
    "make_args,message",
    [
        (lambda d: ["--dem", str(d / "nan.npy"), "--dem-spacing", "30"], "NaN"),
        (lambda d: ["--dem", str(d / "line.npy"), "--dem-spacing", "30"], "2-D"),
        (lambda d: ["--dem", str(d / "nan.npy")], "spacing"),
        (lambda d: ["--camera-altitude", "-200"], "below the terrain surface"),
        (lambda d: ["--width", "0"], "whole number > 0"),
        (lambda d: ["--height", "-3"], "whole number > 0"),
        (lambda d: ["--out-dir", str(d / "nan.npy")], "is a file, not a folder"),
        (lambda d: ["--figure", "7", "--turbidity", "4"], "--figure custom"),
        (lambda d: ["--turbidity", "20"], "turbidity"),
        (lambda d: ["--lat", "40"], "together"),
    ],
)
def test_bad_input_exits_2_and_writes_nothing(tmp_path, monkeypatch, capsys, make_args, message):
    np.save(tmp_path / "nan.npy", np.array([[1.0, np.nan], [2.0, 3.0]]))
    np.save(tmp_path / "line.npy", np.arange(10.0))
    before = {p.name for p in tmp_path.iterdir()}
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "--width", "8", "--height", "6", *make_args(tmp_path))
    assert code == 2
    assert message in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert {p.name for p in tmp_path.iterdir()} == before


def test_failure_while_writing_leaves_nothing(tmp_path, monkeypatch, capsys):
    import skyscatter.render.image_io as image_io

    real = image_io.write_png
    calls = []

    def failing(path, *args, **kwargs):
        calls.append(path)
        if len(calls) == 2:
            raise OSError(28, "No space left on device", str(path))
        return real(path, *args, **kwargs)

    monkeypatch.setattr(image_io, "write_png", failing)
    code, out, err = run(capsys, "--out-dir", str(tmp_path), "--width", "8", "--height", "6", "--figure", "8")
    assert code == 2 and "No space left" in err
    assert list(tmp_path.iterdir()) == []


def test_help_explains_units(capsys):
    assert cli.main(["demo", "--help"]) == 0
    out = capsys.readouterr().out
    for text in ("[deg]", "[px]", "[m]", "--no-glare", "--dem", "--out-dir", "Figure 7", "default: 640"):
        assert text in out


def test_a_folder_named_like_an_output_is_refused_before_rendering(tmp_path, capsys, monkeypatch):
    blocker = tmp_path / "fig8b_preetham.png"
    blocker.mkdir()
    import skyscatter.render.scene as scene

    monkeypatch.setattr(scene.Scene, "render", lambda *a, **k: pytest.fail("rendered before checking outputs"))
    code, out, err = run(capsys, "--out-dir", str(tmp_path), "--width", "8", "--height", "6", "--figure", "8")
    assert code == 2 and str(blocker) in err and "folder" in err
    assert len(err.strip().splitlines()) == 1
    assert [p.name for p in tmp_path.iterdir()] == [blocker.name]


def test_a_failed_rename_restores_the_folder(tmp_path, capsys, monkeypatch):
    """All or nothing: if the 3rd rename fails, the two files renamed before it are removed (or, if they
    existed, restored) and no temporary file is left; the message names the target."""
    import os

    old = tmp_path / "fig8a_cie_clear_ward_larson.exr"
    old.write_bytes(b"previous version")
    real = os.replace
    calls = []

    def flaky(src, dst):
        if str(src).endswith(".tmp.png"):
            calls.append(dst)
            if Path(dst).name == "fig8b_preetham.png":
                raise IsADirectoryError(21, "Is a directory", str(src))
        return real(src, dst)

    monkeypatch.setattr(os, "replace", flaky)
    code, out, err = run(capsys, "--out-dir", str(tmp_path), "--width", "8", "--height", "6", "--figure", "8")
    assert code == 2 and str(tmp_path / "fig8b_preetham.png") in err and ".tmp" not in err
    assert calls  # the failure happened during the renames
    assert [p.name for p in tmp_path.iterdir()] == [old.name]
    assert old.read_bytes() == b"previous version"


def test_overcast_sky_with_constant_density_haze_is_not_black(tmp_path, capsys):
    """CIE overcast has no sun; the constant-density haze is lit by the sky, so the distant terrain fades
    towards the sky's brightness instead of to black."""
    code, out, err = run(capsys, "--out-dir", str(tmp_path), "--width", "24", "--height", "14", "--no-glare",
                         "--model", "cie-overcast", "--turbidity", "10", "--aerial", "constant")
    assert code == 0, err
    img = read_exr(tmp_path / "landscape.exr").astype(float)
    lum = img @ np.array([0.2126, 0.7152, 0.0722])
    assert np.all(np.isfinite(img))
    assert lum.min() > 0.1 * lum.max()  # was ~0 for the distant ridges before


@pytest.mark.parametrize("option,value", [("--camera-x", "1e300"), ("--camera-y", "-2e7"),
                                          ("--camera-altitude", "1e6"), ("--camera-height", "2e5")])
def test_camera_options_are_bounded(tmp_path, capsys, option, value):
    code, out, err = run(capsys, "--out-dir", str(tmp_path), f"{option}={value}")
    assert code == 2 and option in err and "expected a number in" in err
    assert list(tmp_path.iterdir()) == []


def test_help_shows_each_default_once(capsys):
    assert cli.main(["demo", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "(default: None)" not in out and "(default: True)" not in out
    assert "(default preetham) (default" not in out and "(default 2.5) (default" not in out
    assert "default: 640" in out and "default: 0.2" in out


def test_bruneton_model_refuses_preetham_options(tmp_path, capsys):
    from skyscatter.cli import main

    for extra in (["--aerial", "numeric"], ["--sky-type", "3"]):
        code = main(["demo", "--model", "bruneton", *extra, "--out-dir", str(tmp_path)])
        err = capsys.readouterr().err
        assert code == 2 and "does not apply to --model bruneton" in err and len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def _demo_args(*args):
    import argparse

    from skyscatter.cli import demo

    parser = argparse.ArgumentParser()
    demo.register(parser.add_subparsers(dest="command"))
    return demo, parser.parse_args(["demo", *args])


def test_bruneton_model_takes_the_atmosphere_options():
    """Issue 11 item 5: demo --model bruneton takes the precomputed atmosphere's options (turbidity or aerosol
    optical depth and Angstrom exponent, ozone, table wavelengths), range-checked by the registry's spec."""
    demo, args = _demo_args("--model", "bruneton", "--aod", "0.3", "--angstrom-alpha", "1.1", "--ozone", "250",
                            "--tables", "rgb")
    (panel,) = demo._panels(args, "custom")
    assert panel.bruneton_medium == {"aerosol_optical_depth": 0.3, "angstrom_alpha": 1.1, "ozone_column": 250.0,
                                     "tables": "rgb"}
    demo, args = _demo_args("--model", "bruneton", "--turbidity", "4")
    assert demo._panels(args, "custom")[0].bruneton_medium == {"turbidity": 4.0}


def test_bruneton_atmosphere_options_are_checked(tmp_path, capsys):
    from skyscatter.cli import main

    for args, message in ((["--model", "bruneton", "--aod", "20"], "--aod 20"),
                          (["--aod", "0.3"], "--aod applies to --model bruneton"),
                          (["--model", "bruneton", "--ozone", "-5"], "--ozone -5")):
        code = main(["demo", *args, "--out-dir", str(tmp_path)])
        err = capsys.readouterr().err
        assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert list(tmp_path.iterdir()) == []
