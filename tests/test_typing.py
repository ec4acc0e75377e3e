"""Type checkers see the real signatures of the documented names, although they are imported on first use.

The lazy namespaces (:mod:`skyscatter.lazy`) import each public name on first access; every one of them also
imports the same names under ``if TYPE_CHECKING:``. Checked here: the two lists agree in every namespace, and mypy
run on a user's script (as a user runs it, on the installed package) flags a wrong argument type in a call of a
top-level name, while the README's tour passes.
"""

from __future__ import annotations

import ast
import importlib
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import skyscatter

SRC = Path(skyscatter.__file__).resolve().parent

#: Every module that uses skyscatter.lazy.
LAZY_MODULES = ("skyscatter", "skyscatter.sun", "skyscatter.atmosphere", "skyscatter.sky", "skyscatter.render",
                "skyscatter.atmosphere.phase", "skyscatter.atmosphere.phase_table")


def _type_checking_names(module: str) -> dict[str, str]:
    """name -> defining module (relative to the package, as in ``_LAZY``) from the ``if TYPE_CHECKING:`` block."""
    mod = importlib.import_module(module)
    tree = ast.parse(Path(mod.__file__).read_text(encoding="utf-8"))
    package = mod.__package__
    out: dict[str, str] = {}
    for node in tree.body:
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            for imp in node.body:
                assert isinstance(imp, ast.ImportFrom) and imp.level == 1
                for alias in imp.names:
                    assert alias.asname == alias.name, "re-export with 'import X as X'"
                    if imp.module is None:  # a submodule
                        out[alias.name] = "<submodule>"
                    else:
                        out[alias.name] = imp.module
    assert out, f"{module} has no TYPE_CHECKING block"
    assert package
    return out


@pytest.mark.parametrize("module", LAZY_MODULES)
def test_type_checking_imports_list_exactly_the_lazy_names(module):
    mod = importlib.import_module(module)
    seen = _type_checking_names(module)
    lazy = dict(mod._LAZY)
    subs = set(getattr(mod, "_SUBMODULES", ()))
    assert {k: v for k, v in seen.items() if v != "<submodule>"} == lazy
    assert {k for k, v in seen.items() if v == "<submodule>"} == subs
    for name in [*lazy, *subs]:  # and every name resolves at run time
        assert getattr(mod, name) is not None


def test_sky_package_exports_its_model_classes():
    from skyscatter.sky import BrunetonSky, PreethamSky
    from skyscatter.sky.bruneton import BrunetonSky as B
    from skyscatter.sky.preetham import PreethamSky as P

    assert PreethamSky is P and BrunetonSky is B and skyscatter.PreethamSky is P


def _mypy(tmp_path: Path, script: str) -> subprocess.CompletedProcess:
    pytest.importorskip("mypy")
    path = tmp_path / "user_script.py"
    path.write_text(textwrap.dedent(script), encoding="utf-8")
    env = {**os.environ, "MYPYPATH": str(SRC.parent)}
    config = tmp_path / "mypy.ini"  # a user's default settings, not the package's own
    config.write_text("[mypy]\n", encoding="utf-8")
    # --follow-imports=silent: errors inside skyscatter are the package's own check (pyproject [tool.mypy]),
    # not the user's; the user's calls are checked against skyscatter's signatures all the same.
    return subprocess.run([sys.executable, "-m", "mypy", "--follow-imports=silent", "--no-error-summary",
                           "--cache-dir", str(tmp_path / ".mypy_cache"), "--config-file", str(config), str(path)],
                          capture_output=True, text=True, cwd=tmp_path, env=env)


README_TOUR = """
    import datetime as dt, math
    import numpy as np
    import skyscatter
    from skyscatter.conventions import direction_from_angles
    from skyscatter.render import Scene, sky_image, write_exr_and_png
    from skyscatter.sky import PreethamSky

    when = dt.datetime(2024, 6, 21, 9, 30, tzinfo=dt.timezone(dt.timedelta(hours=2)))
    sun = skyscatter.sun_position(math.radians(48.85), math.radians(2.35), when)
    sky = skyscatter.PreethamSky(2.5, sun.zenith, sun.azimuth)
    same: PreethamSky = sky
    d = direction_from_angles(np.radians([0, 45, 80]), np.radians([0, 90, 180]))
    sky.luminance(d); sky.spectral_radiance(d); sky.xyz(d); sky.zenith_luminance()
    image = sky_image(sky, projection="equirect", width=2048)
    cie = skyscatter.CIEStandardSky(12, sun.zenith, sun.azimuth, diffuse_illuminance=15000.0)
    perez = skyscatter.PerezSky(sun.zenith, sun.azimuth, direct_normal_irradiance=650.0,
                                diffuse_horizontal_irradiance=110.0)
    skyscatter.photometry.horizontal_illuminance(perez, include_sun=True)
    bruneton = skyscatter.BrunetonSky(sun.zenith, sun.azimuth, turbidity=3.0, ground_albedo=0.2, tables="rgb")
"""


def test_mypy_passes_the_readme_tour_and_flags_a_wrong_argument_type(tmp_path):
    ok = _mypy(tmp_path, README_TOUR)
    assert ok.returncode == 0, ok.stdout + ok.stderr
    bad = _mypy(tmp_path, README_TOUR + """
    wrong = skyscatter.PreethamSky("2.5", sun.zenith, sun.azimuth)
    also_wrong = skyscatter.sun_position("48.85", 2.35, when)
    """)
    assert bad.returncode == 1
    errors = [line for line in bad.stdout.splitlines() if ": error:" in line]
    assert len(errors) == 2, bad.stdout
    assert '"PreethamSky" has incompatible type "str"; expected "float"' in errors[0]
    assert '"sun_position" has incompatible type "str"' in errors[1]
