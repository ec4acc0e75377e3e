"""`skyscatter illuminance` and `skyscatter skymatrix`: outputs, options, exit codes and one-line errors."""

import json
import math

import numpy as np
import pytest

import skyscatter.cli as cli
from epw_records import write_epw


@pytest.fixture(autouse=True)
def only_these_commands(monkeypatch):
    """Build the real parser with just the subcommands under test (others are tested in their own files)."""
    monkeypatch.setattr(cli, "_COMMANDS", ["illuminance", "skymatrix"])


def run(capsys, *args):
    code = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def epw(tmp_path):
    return write_epw(tmp_path / "w.epw")


def test_illuminance_default_overcast(capsys):
    code, out, err = run(capsys, "illuminance")
    assert code == 0, err
    assert "horizontal: sky 10000.0 lx" in out


def test_illuminance_cie_json_with_planes_and_sun(capsys):
    code, out, err = run(capsys, "illuminance", "--model", "cie", "--sky-type", "12", "--sun-elevation", "40",
                         "--sun-azimuth", "180", "--diffuse-illuminance", "15000", "--sun-illuminance", "80000",
                         "--vertical", "180", "0", "--tilted", "30", "180", "--include-sun", "--json")
    assert code == 0, err
    res = json.loads(out)
    planes = {p["plane"]: p for p in res["planes"]}
    assert planes["horizontal"]["sky_lx"] == pytest.approx(15000.0, rel=1e-9)
    assert planes["horizontal"]["total_lx"] == pytest.approx(15000.0 + 80000.0 * math.sin(math.radians(40)), rel=1e-9)
    south, north = planes["vertical facing 180 deg"], planes["vertical facing 0 deg"]
    assert south["sky_lx"] > north["sky_lx"] and north["total_lx"] == north["sky_lx"]
    assert south["total_lx"] - south["sky_lx"] == pytest.approx(80000.0 * math.cos(math.radians(40)), rel=1e-9)
    assert "tilted 30 deg facing 180 deg" in planes


def test_illuminance_perez_from_irradiance(capsys):
    code, out, err = run(capsys, "illuminance", "--model", "perez", "--dni", "700", "--dhi", "120",
                         "--sun-elevation", "50", "--day-of-year", "172", "--dew-point", "12", "--include-sun")
    assert code == 0, err
    assert "PerezSky(" in out and "sky + sun" in out and "sun, direct normal:" in out


@pytest.mark.parametrize(
    "args,message",
    [
        (["--model", "cie-overcast", "--epsilon", "3"], "--epsilon: does not apply to --model cie-overcast"),
        (["--model", "perez", "--epsilon", "3"], "epsilon and delta must be given together"),
        (["--model", "perez", "--dni", "1e6", "--dhi", "1e6"], "exceeds the extraterrestrial solar irradiance"),
        (["--model", "cie-overcast", "--include-sun"], "has no sun"),
        (["--model", "cie", "--zenith-luminance", "5", "--diffuse-illuminance", "5"], "not both"),
        (["--tilted", "200", "0"], "tilt must be within 0-180"),
        (["--model", "cie", "--sky-type", "16"], "sky_type 16 is outside 1 to 15"),
        (["--model", "perez", "--day-of-year", "400", "--epsilon", "2", "--delta", "0.2"],
         "day_of_year 400 is outside 1 to 366"),
    ],
)
def test_illuminance_errors_are_one_line(capsys, args, message):
    code, out, err = run(capsys, "illuminance", *args)
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1


def test_help_explains_units(capsys):
    code, text, _ = run(capsys, "illuminance", "--help")
    assert code == 0
    for unit in ("[lx]", "[cd m^-2]", "[W m^-2]", "[deg"):
        assert unit in text
    code, text, _ = run(capsys, "skymatrix", "--help")
    assert code == 0
    assert "reinhart2" in text and "[cd m^-2]" in text and "--include-sun" in text


def test_skymatrix_writes_npz_and_csv(capsys, epw, tmp_path):
    out, csv = tmp_path / "m.npz", tmp_path / "m.csv"
    code, stdout, err = run(capsys, "skymatrix", epw, "--patches", "tregenza", "--out", out, "--csv", csv,
                            "--include-sun")
    assert code == 0, err
    assert "48 hours" in stdout and "145 patches" in stdout and "sun included" in stdout
    assert "48/48" not in err and "it/s" not in err  # issue 12, item 11: no bar when stderr is not a terminal
    with np.load(out) as data:
        assert data["luminance"].shape == (48, 145) and bool(data["include_sun"])
    assert len(csv.read_text().splitlines()) == 49


def test_skymatrix_default_scheme_no_progress(capsys, epw, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, stdout, err = run(capsys, "skymatrix", epw, "--no-progress")
    assert code == 0, err
    assert "577 patches (reinhart2)" in stdout and err == ""
    assert (tmp_path / "skymatrix.npz").exists()


@pytest.mark.parametrize(
    "mutate,message",
    [
        (lambda p: p.write_text("garbage\n"), "w.epw: line 1: an EPW file starts with a LOCATION line"),
        (lambda p: p.write_text(p.read_text().replace("2023,6,20,5,", "2023,6,20,5,7,", 1)), "line 13: a data record"),
        (lambda p: p.unlink(), "no such file"),
    ],
)
def test_skymatrix_bad_epw(capsys, epw, tmp_path, mutate, message):
    mutate(epw)
    code, out, err = run(capsys, "skymatrix", epw, "--out", tmp_path / "m.npz")
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "m.npz").exists()


@pytest.mark.parametrize(
    "args,message",
    [
        (["--out", "m.txt"], "--out must end in .npz"),
        (["--out", "missing_dir/m.npz"], "does not exist"),
        (["--samples", "20"], "at most 16"),
    ],
)
def test_skymatrix_bad_options(capsys, epw, tmp_path, monkeypatch, args, message):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "skymatrix", epw, *args)
    assert code == 2 and message in err
