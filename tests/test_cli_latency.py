"""Issue 12, a quick command line: a command builds only its own parser and imports only what it needs.

The timings themselves are in benchmarks/bench_cli_latency.py and benchmarks/bench_skymatrix.py (the machine's
load makes them unfit for a test); here the causes are checked: which modules a command imports.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

import skyscatter.cli as cli
from epw_records import write_epw

HEAVY = ("numba", "scipy", "pandas", "pvlib", "colour", "matplotlib", "dask", "tqdm")


@pytest.mark.parametrize("name", sorted(cli._MODULE_OF))
def test_each_command_alone_builds_the_parser_of_that_command(name):
    parser = cli.build_parser(name)
    sub = next(a for a in parser._actions if a.dest == "command")
    assert list(sub.choices) == [name]


def test_help_and_unknown_commands_list_every_command(capsys):
    assert cli.main(["--help"]) == 0
    out = capsys.readouterr().out
    assert all(name in out for name in cli._MODULE_OF)
    assert cli.main(["skymatrx"]) == 2
    err = capsys.readouterr().err
    assert "invalid choice" in err and "skymatrix" in err and "fit-hosek-wilkie" in err


def _imported_by(args: list[str]) -> list[str]:
    code = ("import sys; from skyscatter.cli import main; rc = main(" + repr(args) + "); "
            f"print(rc, sorted(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    return out.strip().splitlines()[-1]


def test_skymatrix_command_imports_no_heavy_package(tmp_path):
    """Own SPA and Spencer series, numpy Perez kernel and time stamps: no pvlib (about 0.7 s to import), pandas
    (0.25 s), numba (0.25 s, plus 0.35 s at first use) or scipy."""
    epw = write_epw(tmp_path / "w.epw")
    args = ["skymatrix", str(epw), "--samples", "1", "--out", str(tmp_path / "m.npz"), "--csv",
            str(tmp_path / "m.csv"), "--no-progress"]
    assert _imported_by(args) == "0 []"
    assert (tmp_path / "m.npz").is_file() and (tmp_path / "m.csv").is_file()


def test_sun_command_imports_no_heavy_package():
    assert _imported_by(["sun", "--lat", "48.1", "--lon", "11.6", "--time", "2024-06-21T12:00+02:00"]) == "0 []"


@pytest.mark.parametrize("command,preset,expected", [
    ("skymatrix", None, "1"),  # small products only: OpenBLAS starts with one thread
    ("sky", "3", "3"),  # the user's setting is kept
    ("precompute", None, None),  # other commands keep numpy's default pool
])
def test_blas_starts_with_one_thread_for_commands_without_big_linear_algebra(command, preset, expected):
    env = {k: v for k, v in os.environ.items() if k not in cli._BLAS_THREAD_VARIABLES}
    if preset is not None:
        env["OPENBLAS_NUM_THREADS"] = preset
    code = ("import os, sys; import skyscatter.cli as c; c._one_blas_thread_for(sys.argv[1]); "
            "print(os.environ.get('OPENBLAS_NUM_THREADS'))")
    out = subprocess.run([sys.executable, "-c", code, command], env=env, capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == str(expected)
