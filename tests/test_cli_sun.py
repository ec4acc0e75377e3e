"""``skyscatter sun`` command line."""

from __future__ import annotations

import json

import pytest

import skyscatter.cli as cli

SPA_ARGS = ["sun", "--lat", "39.742476", "--lon", "-105.1786", "--time", "2003-10-17T12:30:30-07:00",
            "--altitude", "1830.14", "--pressure", "82000", "--temperature", "11"]


def run(args: list[str]) -> int:
    """Exit status of ``skyscatter ARGS`` whether main returns it or argparse raises SystemExit."""
    try:
        return cli.main(args)
    except SystemExit as exc:
        return int(exc.code or 0)


@pytest.fixture(autouse=True)
def only_sun_command(monkeypatch):
    # build the parser from this subcommand alone, independently of the other subcommand modules
    monkeypatch.setattr(cli, "_COMMANDS", ["sun"])


def test_text_output(capsys):
    assert run(SPA_ARGS) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 3
    values = {line.split()[0]: float(line.split()[1]) for line in out}
    # SPA worked example (Reda & Andreas 2004): 50.11162 / 194.34024 deg with delta T = 67 s; the CLI uses
    # pvlib's delta T estimate for 2003 (64.5 s), which moves the azimuth by 4e-5 deg
    assert values["zenith"] == pytest.approx(50.11162, abs=2e-4)
    assert values["azimuth"] == pytest.approx(194.34024, abs=2e-4)
    assert values["elevation"] == pytest.approx(90.0 - values["zenith"], abs=1e-5)


def test_json_output_and_method(capsys):
    assert run([*SPA_ARGS, "--json", "--method", "preetham1999"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["method"] == "preetham1999"
    assert data["zenith_deg"] == pytest.approx(50.11, abs=1.2)
    assert data["azimuth_deg"] == pytest.approx(194.34, abs=1.2)
    assert data["elevation_deg"] == pytest.approx(90.0 - data["zenith_deg"])


def test_utc_z_suffix(capsys):
    assert run(["sun", "--lat", "0", "--lon", "0", "--time", "2024-03-20T12:00Z", "--geometric"]) == 0
    zenith = float(capsys.readouterr().out.split()[1])
    assert zenith < 3.0  # equinox noon on the equator at Greenwich: the sun is nearly overhead


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--lat", "10", "--lon", "5", "--time", "tomorrow"], "cannot read time 'tomorrow'"),
        (["--lat", "10", "--lon", "5", "--time", "2024-06-21T12:00"], "has no UTC offset"),
        (["--lat", "95", "--lon", "5", "--time", "2024-06-21T12:00Z"], "in [-90, 90], got 95"),
        (["--lat", "10", "--lon", "5"], "required: --time"),
        (["--lat", "10", "--lon", "5", "--time", "2024-06-21T12:00Z", "--method", "x"], "invalid choice"),
    ],
)
def test_bad_input_exits_2_with_one_line(capsys, args, message):
    assert run(["sun", *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert message in err
    assert err.startswith("skyscatter sun: error:")


def test_help_mentions_units(capsys):
    assert run(["sun", "--help"]) == 0
    text = capsys.readouterr().out
    for fragment in ("[deg]", "[Pa]", "[m]", "UTC offset", "preetham1999"):
        assert fragment in text
