"""`skyscatter demo`: Figures 7 and 8, a custom panel, and bad input that writes nothing."""

from __future__ import annotations

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
    code, out, err = run(capsys, "--dem", str(tmp_path / "dem.npy"), "--dem-spacing", "100", "--sky", "cie-overcast",
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
        (lambda d: ["--out-dir", str(d / "missing")], "does not exist"),
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
