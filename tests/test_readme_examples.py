"""Every command of the README's "Command line" section runs (issue 12, item 10), with the README's first
install only (issue 18: "a fresh venv from the README runs every command of the README's command-line section").

The commands are read from README.md itself, so the test follows the README. Each runs in a fresh, empty
folder (so output folders such as ``renders`` do not exist beforehand), with ``weather.epw`` copied from
tests/data (a two-day EPW). Commands with image-size options run with the sizes below appended (argparse
keeps the last value), which changes only the pixel count (or the Monte Carlo sample count), not the command:
the README gives the run time of the full size. Commands that need the Bruneton tables at their default size
(built once per session into the test cache, about a minute) are marked slow. For the same reason
``skymatrix --spectral`` runs with a cloud table of 3 x 3 nodes instead of 12 x 9 (the node counts only, as
tests/test_cli_runs.py does; the table of this file's aerosol node, 108 DISORT solves, was about 60 CPU-s of this
test and no other test shares it): the command and its code path are unchanged; the full table's accuracy is
tested in tests/test_spectral_skymatrix.py and tests/test_cloud_retrieval.py.

The README's first install is ``pip install .``: pyproject.toml's dependencies without extras. While a command
runs, every installed package outside that install (the extras and the test tools, e.g. pvlib, pyradiance,
tifffile, distributed, mitsuba) is made unimportable, so a command that needs an extra fails here; the packages
the test runner itself needs (pytest and its plugins) stay, and the README says which extra a command needs.
"""

from __future__ import annotations

import importlib.metadata
import math
import re
import shlex
import shutil
import sys
import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

from skyscatter.cli import main

ROOT = Path(__file__).resolve().parents[1]
#: Cloud table nodes of ``skymatrix --spectral`` here (module docstring): optical depths [-], sun zeniths [rad].
SMALL_CLOUD_TAU = (0.5, 5.5, 60.0)
SMALL_CLOUD_ZENITH = tuple(math.radians(z) for z in (0.0, 62.0, 87.0))
SMALL = {"demo": ["--width", "32", "--height", "18"], "sky": ["--width", "64"], "reference": ["--samples", "16"],
         "view": ["--check", "--port", "0"]}  # view: serve, fetch everything over HTTP and exit (no browser)


def readme_commands() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("### Command line", 1)[1]
    block = re.search(r"```sh\n(.*?)```", section, re.S).group(1)
    commands = []
    for line in block.splitlines():
        line = line.split("#", 1)[0].strip()
        if line.startswith("skyscatter "):
            commands.append(line)
    return commands


def _closure(requirements: list[str]) -> set[str]:
    """Canonical names of the installed distributions these requirements pull in (their extras followed)."""
    seen: set[tuple[str, tuple[str, ...]]] = set()
    todo = [Requirement(r) for r in requirements]
    while todo:
        req = todo.pop()
        key = (canonicalize_name(req.name), tuple(sorted(req.extras)))
        if key in seen or (req.marker is not None and not req.marker.evaluate({"extra": ""})):
            continue
        try:
            dist = importlib.metadata.distribution(req.name)
        except importlib.metadata.PackageNotFoundError:
            continue  # not installed here, so nothing to hide either
        seen.add(key)
        for text in dist.requires or []:
            sub = Requirement(text)
            if sub.marker is None or any(sub.marker.evaluate({"extra": e}) for e in req.extras or ("",)):
                sub.marker = None
                todo.append(sub)
    return {name for name, _ in seen}


def first_install_only_modules() -> list[str]:
    """Top-level modules of installed distributions that ``pip install .`` would not install (and the test
    runner does not need): the ones to hide while a README command runs."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    keep = _closure(project["dependencies"])
    keep |= _closure(["pytest", "hypothesis", "pytest-benchmark", "packaging"])  # the runner and its plugins
    keep |= {"pip", "setuptools"}  # in every venv Python 3.11 makes
    hide = []
    for module, dists in importlib.metadata.packages_distributions().items():
        if module.isidentifier() and not {canonicalize_name(d) for d in dists} & (keep | {"skyscatter"}):
            hide.append(module)
    return sorted(hide)


@pytest.fixture
def first_install(monkeypatch):
    """Imports of anything outside the README's first install fail while the test runs."""
    hidden = set(first_install_only_modules())
    for name in list(sys.modules):
        if name.split(".", 1)[0] in hidden:
            monkeypatch.setitem(sys.modules, name, None)
    for name in hidden:
        monkeypatch.setitem(sys.modules, name, None)  # "import name" raises ModuleNotFoundError
    return hidden


def _needs_tables(args: list[str]) -> bool:
    return args[0] in ("precompute", "export-luts", "view") or "bruneton" in args


@pytest.mark.parametrize(
    "command",
    [pytest.param(c, marks=pytest.mark.slow) if _needs_tables(shlex.split(c)[1:]) else c for c in readme_commands()],
)
def test_readme_command_runs(command, tmp_path, monkeypatch, capsys, first_install):
    args = shlex.split(command)[1:]
    if args[0] == "COMMAND":
        args[0] = "sky"
    shutil.copy(ROOT / "tests" / "data" / "weather.epw", tmp_path / "weather.epw")
    if "--spectral" in args:  # a small cloud table (module docstring)
        import skyscatter.fit.weather as weather

        real_cloud_table = weather.cloud_table

        def small_cloud_table(atmosphere, optical_depth_nodes=SMALL_CLOUD_TAU, zenith_nodes=SMALL_CLOUD_ZENITH):
            return real_cloud_table(atmosphere, optical_depth_nodes, zenith_nodes)

        monkeypatch.setattr(weather, "cloud_table", small_cloud_table)
    monkeypatch.chdir(tmp_path)
    code = main(args + SMALL.get(args[0], []))
    out, err = capsys.readouterr()
    assert code == 0, f"{command}: {err}"
    if "--help" not in args:
        assert out.strip()  # every command reports what it did


def test_readme_lists_the_commands():
    commands = readme_commands()
    assert len(commands) >= 10
    assert any(c.startswith("skyscatter skymatrix weather.epw") for c in commands)


def test_first_install_hides_the_extras():
    """The emulation hides what the extras and the test tools add (when installed here), not the core."""
    hidden = set(first_install_only_modules())
    for module, dist in (("pvlib", "pvlib"), ("pyradiance", "pyradiance"), ("tifffile", "tifffile"),
                         ("distributed", "distributed"), ("mitsuba", "mitsuba")):
        try:
            importlib.metadata.distribution(dist)
        except importlib.metadata.PackageNotFoundError:
            continue
        assert module in hidden, module
    for core in ("numpy", "scipy", "numba", "OpenEXR", "xarray", "zarr", "dask", "h5netcdf", "h5py", "colour"):
        assert core not in hidden, core
