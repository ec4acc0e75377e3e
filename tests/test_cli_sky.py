"""`skyscatter sky`: defaults, options, exit codes and one-line errors."""

import math

import numpy as np
import pytest

from skyscatter.cli import main
from skyscatter.render import read_exr


def run(capsys, *args):
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_bare_command_writes_exr_and_png(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "sky", "--width", "64")
    assert code == 0, err
    img = read_exr(tmp_path / "sky.exr")
    assert img.shape == (32, 64, 3) and np.all(np.isfinite(img)) and img.max() > 0
    assert (tmp_path / "sky.png").stat().st_size > 0
    # default: clear mid-morning sky; the zenith (top row) is bluer than red
    assert img[0, :, 2].mean() > img[0, :, 0].mean()


def test_fisheye_with_place_and_time(tmp_path, capsys):
    out = tmp_path / "f.exr"
    code, stdout, err = run(capsys, "sky", "--projection", "fisheye", "--width", "32", "--lat", "48.85",
                            "--lon", "2.35", "--time", "2024-06-21T10:00+02:00", "--out", str(out),
                            "--png", str(tmp_path / "f.png"))
    assert code == 0, err
    assert read_exr(out).shape == (32, 32, 3)
    assert "sun zenith" in stdout


@pytest.mark.parametrize(
    "args,message",
    [
        (["--turbidity", "25"], "turbidity"),
        (["--turbidity", "1.2"], "turbidity"),
        (["--width", "0"], "whole number > 0"),
        (["--width", "-5"], "whole number > 0"),
        (["--time", "yesterday", "--lat", "1", "--lon", "1"], "cannot read time"),
        (["--time", "2024-06-21T10:00", "--lat", "1", "--lon", "1"], "no UTC offset"),
        (["--sun-elevation", "-10"], "below the horizon"),
        (["--lat", "10"], "together"),
        (["--sky-type", "3"], "does not apply"),
    ],
)
def test_bad_values_exit_2_with_one_line(tmp_path, monkeypatch, capsys, args, message):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "sky", "--width", "16", *args) if "--width" not in args else run(capsys, "sky", *args)
    assert code == 2
    assert message in err
    assert len(err.strip().splitlines()) == 1
    assert "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def test_unwritable_path(tmp_path, capsys):
    code, out, err = run(capsys, "sky", "--width", "16", "--out", str(tmp_path / "no" / "sky.exr"))
    assert code == 2 and "does not exist" in err and len(err.strip().splitlines()) == 1


def test_help_lists_units_and_defaults(capsys):
    code, text, err = run(capsys, "sky", "--help")
    assert code == 0
    for fragment in ("[deg]", "[px]", "default: 1024", "--turbidity", "--projection", "[m]"):
        assert fragment in text


def test_sun_angles_from_elevation(tmp_path, capsys):
    code, out, err = run(capsys, "sky", "--width", "16", "--sun-elevation", "30", "--sun-azimuth", "200",
                         "--out", str(tmp_path / "s.exr"))
    assert code == 0
    assert f"{60:.2f} deg" in out and f"{200:.2f} deg" in out
    assert math.isfinite(read_exr(tmp_path / "s.exr").sum())


@pytest.mark.parametrize(
    "args,message",
    [
        (["--out", "sky.png"], "must be an OpenEXR file"),
        (["--out", "a.exr", "--png", "a.exr"], "must end in .png"),
        (["--png", "nodir/p.png"], "does not exist"),
        (["--exposure", "2000"], "expected a number in [-30, 30]"),
        (["--width", "100000", "--height", "100000"], "exceeds"),
        (["--width", "1"], "width >= 2"),
        (["--turb", "3"], "unrecognized arguments"),
    ],
)
def test_output_and_size_errors_leave_nothing(tmp_path, monkeypatch, capsys, args, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "keep").mkdir()
    code, out, err = run(capsys, "sky", *args) if "--width" in args else run(capsys, "sky", "--width", "16", *args)
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep"]


def test_preetham_overcast_blend_model(tmp_path, capsys):
    code, out, err = run(capsys, "sky", "--model", "preetham-overcast", "--turbidity", "9", "--width", "16",
                         "--out", str(tmp_path / "b.exr"))
    assert code == 0, err
    assert read_exr(tmp_path / "b.exr").max() > 0


def test_bruneton_takes_the_atmosphere_options_and_refuses_mixtures(capsys):
    """Issue 11 item 5: the atmosphere's options reach --model bruneton; each is checked before any table build."""
    from skyscatter.cli import main

    for args, message in (
        (["--model", "bruneton", "--turbidity", "0.5"], "turbidity 0.5 is outside 1 to 20"),
        (["--model", "bruneton", "--aod", "11"], "aerosol_optical_depth 11 is outside 0 to 10"),
        (["--model", "bruneton", "--turbidity", "3", "--aod", "0.2"], "either turbidity or aerosol_optical_depth"),
        (["--model", "bruneton", "--angstrom-alpha", "1"], "angstrom_alpha goes with aerosol_optical_depth"),
        (["--model", "preetham", "--ozone", "200"], "--ozone: does not apply to --model preetham"),
    ):
        assert main(["sky", "--width", "8", *args]) == 2
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err


def test_bruneton_medium_options_build_the_atmosphere_they_name():
    from skyscatter.atmosphere import AtmosphereParameters

    _medium_from_options = AtmosphereParameters.from_options
    p = _medium_from_options(None, aerosol_optical_depth=0.2, angstrom_alpha=1.0, ground_albedo=0.3, ozone_column=0.0)
    # Angstrom's law: tau(550 nm) = beta 0.55^-alpha
    assert p.mie_angstrom_beta * 0.55 ** -1.0 == pytest.approx(0.2, rel=1e-12)
    assert (p.ozone_column, float(p.ground_albedo_at([550.0])[0])) == (0.0, 0.3)
    t = _medium_from_options(AtmosphereParameters(ozone_column=250.0), turbidity=3.0)
    assert t.mie_angstrom_beta == pytest.approx(0.04608 * 3 - 0.04586) and t.ozone_column == 250.0


def test_default_sky_command_needs_no_compiled_kernel_nor_heavy_imports(tmp_path):
    """Issue 12 (a quick command line): the Preetham sky is evaluated with numpy, so the command pays neither
    numba's import and first-use set-up (about 0.35 s, which also imports scipy.linalg) nor pandas/pvlib/colour."""
    import subprocess
    import sys

    code = ("import sys; from skyscatter.cli import main; "
            f"main(['sky', '--projection', 'fisheye', '--width', '32', '--out', {str(tmp_path / 's.exr')!r}]); "
            "print(sorted(m for m in ('numba', 'scipy', 'pandas', 'pvlib', 'colour', 'matplotlib', 'dask') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip().splitlines()[-1] == "[]"
    assert (tmp_path / "s.exr").is_file() and (tmp_path / "s.png").is_file()
