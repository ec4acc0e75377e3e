"""Packaging: one version source, the licence files and the documentation shipped.

Building a distribution needs setuptools >= 77 in an isolated build environment (network), too heavy for the
test suite; these tests check the declarations the build reads (pyproject.toml, MANIFEST.in) and the installed
metadata. The build itself was checked by hand with ``python -m build`` (sdist and wheel listed in the note).
"""

from __future__ import annotations

import importlib.metadata
import subprocess
import sys
import tomllib
from pathlib import Path

import skyscatter

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def test_version_is_the_installed_metadata_version():
    assert skyscatter.__version__ == importlib.metadata.version("skyscatter")


def test_version_is_written_once():
    project = PYPROJECT["project"]
    assert "version" not in project and "version" in project["dynamic"]
    assert PYPROJECT["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "skyscatter.__version__"}


def test_cli_prints_the_package_version():
    out = subprocess.run([sys.executable, "-m", "skyscatter", "--version"], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == f"skyscatter {skyscatter.__version__}"


def test_licence_is_an_spdx_expression_and_its_files_exist():
    project = PYPROJECT["project"]
    assert project["license"] == "MIT AND BSD-3-Clause"
    assert "MIT License" in (ROOT / "LICENSE").read_text(encoding="utf-8")
    for name in project["license-files"]:
        assert (ROOT / name).is_file(), name
    # the legacy licence classifier conflicts with an SPDX expression (PEP 639)
    assert not [c for c in project["classifiers"] if c.startswith("License ::")]
    requires = PYPROJECT["build-system"]["requires"]
    assert any(r.replace(" ", "") == "setuptools>=77" for r in requires), requires


def test_sdist_ships_licence_changelog_and_docs():
    lines = [ln.split() for ln in (ROOT / "MANIFEST.in").read_text(encoding="utf-8").splitlines()
             if ln.strip() and not ln.startswith("#")]
    included = {name for words in lines if words[0] == "include" for name in words[1:]}
    grafted = {words[1] for words in lines if words[0] == "graft"}
    assert {"LICENSE", "CHANGELOG.md", "README.md"} <= included
    assert {"docs", "tests"} <= grafted
    assert (ROOT / "CHANGELOG.md").read_text(encoding="utf-8").startswith("# Changelog")


def test_readme_links_resolve_in_the_source_distribution():
    """Every relative link of the README names a file that exists (and is shipped: docs/ is grafted)."""
    import re

    text = (ROOT / "README.md").read_text(encoding="utf-8")
    targets = [t.split("#")[0] for t in re.findall(r"\]\(([^)\s]+)\)", text) if "://" not in t]
    assert targets
    missing = [t for t in targets if not (ROOT / t).exists()]
    assert not missing, missing
