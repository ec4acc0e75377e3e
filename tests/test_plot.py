"""skyscatter.plot, headless (Agg): what is drawn is the model's values on the grid, in the right place.

* the mesh of a luminance map holds the sky's luminance in every cell (evaluated here directly on the grid's
  directions), the colour bar spans the values, and a sky brightest in the east is drawn on the left (the
  all-sky camera convention of docs/conventions.md);
* the chromaticity maps hold x = X / (X + Y + Z) and y = Y / (X + Y + Z) of the sky's XYZ;
* a model against itself has zero error everywhere; against half itself +100 %; against reference arrays;
* spectra lines are the sky's spectral radiance; labels carry units;
* bad input and a missing matplotlib give skyscatter errors naming what is allowed (the extra).
"""

from __future__ import annotations

import ast
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

mpl = pytest.importorskip("matplotlib")
mpl.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from skyscatter import plot  # noqa: E402
from skyscatter.conventions import direction_from_angles  # noqa: E402
from skyscatter.errors import InvalidParameterError, MissingDependencyError  # noqa: E402
from skyscatter.sky import registry  # noqa: E402

SUN = (math.radians(50.0), math.radians(200.0))
GRID = plot.sky_grid(18, 36)


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


@pytest.fixture(scope="module")
def preetham():
    return registry.build("preetham", *SUN, turbidity=3.0)


class _Scaled:
    """A sky through the protocol only: another sky's values times a factor."""

    def __init__(self, sky, factor):
        self.sky, self.factor = sky, factor

    def luminance(self, d):
        return self.factor * self.sky.luminance(d)

    def xyz(self, d):
        return self.factor * self.sky.xyz(d)

    def spectral_radiance(self, d, wavelengths=None):
        return self.factor * self.sky.spectral_radiance(d, wavelengths)


class _EastBright:
    """Luminance 1 + east component [cd m^-2]: brightest at the eastern horizon."""

    def luminance(self, d):
        return 1.0 + np.asarray(d)[..., 0]


def test_grid_cells_and_directions():
    g = plot.sky_grid(3, 4)
    np.testing.assert_allclose(np.degrees(g.zenith), [15.0, 45.0, 75.0])
    np.testing.assert_allclose(np.degrees(g.azimuth), [45.0, 135.0, 225.0, 315.0])
    np.testing.assert_allclose(g.directions, direction_from_angles(g.zenith[:, None], g.azimuth[None, :]))
    assert g.directions.shape == (3, 4, 3)
    for bad in (1, 0, 2.5, True, "9"):
        with pytest.raises(InvalidParameterError, match="n_zenith"):
            plot.sky_grid(bad, 8)


def test_luminance_map_draws_the_models_luminance(preetham):
    m = plot.luminance_map(preetham, grid=GRID, sun=SUN)
    expected = preetham.luminance(GRID.directions)  # (18, 36), straight from the model on the grid
    drawn = np.asarray(m.mesh.get_array()).reshape(GRID.shape)
    np.testing.assert_allclose(drawn, expected, rtol=1e-12)
    np.testing.assert_allclose([m.colorbar.vmin, m.colorbar.vmax], [expected.min(), expected.max()], rtol=1e-12)
    assert "cd m" in m.colorbar.ax.get_ylabel()
    assert m.axes.get_ylim() == (0.0, 90.0)
    # the brightest cell is the circumsolar one
    i, j = np.unravel_index(np.argmax(drawn), GRID.shape)
    assert abs(GRID.zenith[i] - SUN[0]) <= math.radians(5.0) and abs(GRID.azimuth[j] - SUN[1]) <= math.radians(10.0)
    log = plot.luminance_map(preetham, grid=GRID, log=True, vmin=100.0, vmax=1e5)
    assert isinstance(log.mesh.norm, mpl.colors.LogNorm)
    assert (log.colorbar.vmin, log.colorbar.vmax) == pytest.approx((100.0, 1e5), rel=1e-12)


def test_map_orientation_north_up_east_left():
    m = plot.luminance_map(_EastBright(), grid=plot.sky_grid(9, 72))
    i, j = np.unravel_index(np.argmax(m.values), m.values.shape)
    assert math.degrees(m.grid.azimuth[j]) == pytest.approx(87.5)  # the cell east of north, at the horizon
    to_px = m.axes.transData.transform
    east = to_px((m.grid.azimuth[j], math.degrees(m.grid.zenith[i])))
    centre = to_px((0.0, 0.0))
    north = to_px((0.0, 80.0))
    assert east[0] < centre[0] - 10 and abs(east[1] - centre[1]) < 0.2 * abs(centre[0] - east[0])
    assert north[1] > centre[1] + 10 and abs(north[0] - centre[0]) < 1.0


def test_chromaticity_maps(preetham):
    mx, my = plot.chromaticity_map(preetham, grid=GRID)
    xyz = preetham.xyz(GRID.directions)
    total = xyz.sum(axis=-1)
    np.testing.assert_allclose(mx.values, xyz[..., 0] / total, rtol=1e-12)
    np.testing.assert_allclose(my.values, xyz[..., 1] / total, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(my.mesh.get_array()).reshape(GRID.shape), my.values)
    assert (mx.colorbar.vmin, mx.colorbar.vmax) == (mx.values.min(), mx.values.max())
    assert "chromaticity x" in mx.colorbar.ax.get_ylabel() and "chromaticity y" in my.colorbar.ax.get_ylabel()
    assert mx.figure is my.figure
    # XYZ given as an array on the grid draws the same
    ax, ay = plot.chromaticity_map(xyz, grid=GRID)
    np.testing.assert_array_equal(ax.values, mx.values)


def test_error_map_of_a_model_against_itself_is_zero(preetham):
    e = plot.error_map(preetham, preetham, grid=GRID)
    assert np.all(e.values == 0.0)
    assert (e.colorbar.vmin, e.colorbar.vmax) == (-1.0, 1.0)
    assert "%" in e.colorbar.ax.get_ylabel()


def test_error_map_against_other_skies_and_reference_values(preetham):
    lum = preetham.luminance(GRID.directions)
    e = plot.error_map(preetham, _Scaled(preetham, 0.5), grid=GRID)
    np.testing.assert_allclose(e.values, 100.0, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(e.mesh.get_array()).reshape(GRID.shape), 100.0, rtol=1e-12)
    assert (e.colorbar.vmin, e.colorbar.vmax) == pytest.approx((-100.0, 100.0))
    ref = lum * (1.0 + 0.01 * np.linspace(-3.0, 3.0, lum.size).reshape(lum.shape))  # reference values on the grid
    e = plot.error_map(preetham, ref, grid=GRID, limit=5.0)
    np.testing.assert_allclose(e.values, 100.0 * (lum / ref - 1.0), rtol=1e-12)
    assert (e.colorbar.vmin, e.colorbar.vmax) == (-5.0, 5.0)
    zero = ref.copy()
    zero[0, 0] = 0.0
    assert np.isnan(plot.error_map(preetham, zero, grid=GRID).values[0, 0])
    # spectral radiance at one wavelength
    rad = preetham.spectral_radiance(GRID.directions, [550.0])[..., 0]
    e = plot.error_map(_Scaled(preetham, 1.1), rad, wavelength=550.0, grid=GRID)
    np.testing.assert_allclose(e.values, 10.0, rtol=1e-9)
    assert "550 nm" in e.colorbar.ax.get_ylabel()


def test_spectra_lines_are_the_spectral_radiance(preetham):
    d = direction_from_angles([0.0, 1.2], [0.0, 0.5])
    wl = np.array([400.0, 500.0, 600.0, 700.0])
    s = plot.spectra([preetham, _Scaled(preetham, 2.0)], d, wl, labels=["a", "b"])
    expected = preetham.spectral_radiance(d, wl)
    assert len(s.lines) == 4
    np.testing.assert_allclose(s.lines[0].get_ydata(), expected[0], rtol=1e-12)
    np.testing.assert_allclose(s.lines[1].get_ydata(), expected[1], rtol=1e-12)
    np.testing.assert_allclose(s.lines[3].get_ydata(), 2.0 * expected[1], rtol=1e-12)
    np.testing.assert_array_equal(s.lines[2].get_xdata(), wl)
    assert s.axes.get_xlabel() == "wavelength [nm]" and "W m" in s.axes.get_ylabel()
    assert "zenith 69°" in s.lines[1].get_label()
    # one sky, default wavelengths; and an array source
    one = plot.spectra(preetham, [0.0, 0.0, 1.0])
    assert one.values.shape == (1, 1, 41)
    arr = plot.spectra(expected, d, wl, log=True)
    np.testing.assert_array_equal(arr.values[0], expected)
    assert arr.axes.get_yscale() == "log"


def test_bad_input_names_what_is_allowed(preetham):
    with pytest.raises(InvalidParameterError, match=r"shape \(18, 36\)"):
        plot.luminance_map(np.ones((4, 4)), grid=GRID)
    with pytest.raises(InvalidParameterError, match="polar"):
        plot.luminance_map(preetham, grid=GRID, ax=plt.figure().add_subplot())
    with pytest.raises(InvalidParameterError, match="360-830"):
        plot.error_map(preetham, preetham, wavelength=1000.0, grid=GRID)
    with pytest.raises(InvalidParameterError, match="limit"):
        plot.error_map(preetham, preetham, grid=GRID, limit=-1.0)
    with pytest.raises(InvalidParameterError, match="one name per source"):
        plot.spectra([preetham], [0.0, 0.0, 1.0], labels=["a", "b"])
    with pytest.raises(InvalidParameterError, match="directions"):
        plot.spectra(preetham, [0.0, 0.0, 0.0])
    with pytest.raises(InvalidParameterError, match=r"\(1, 3\)"):
        plot.spectra(np.ones((2, 3)), [0.0, 0.0, 1.0], [400.0, 500.0, 600.0])


def test_missing_matplotlib_names_the_extra(monkeypatch, preetham):
    for name in ("matplotlib", "matplotlib.pyplot", "matplotlib.colors"):
        monkeypatch.setitem(sys.modules, name, None)
    with pytest.raises(MissingDependencyError, match=r"skyscatter\[plot\]"):
        plot.luminance_map(preetham, grid=GRID)


def test_import_does_not_load_matplotlib_and_the_module_uses_only_the_protocol():
    code = "import sys, skyscatter.plot; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
    # Layering: skyscatter.plot reads skies through their methods only; it imports no model, renderer or CLI.
    src = Path(plot.__file__).read_text(encoding="utf-8")
    inside = set()
    for node in ast.walk(ast.parse(src)):
        if isinstance(node, ast.ImportFrom) and node.level:
            inside.add((node.module or "").split(".")[0])
        elif isinstance(node, ast.ImportFrom | ast.Import):
            names = [node.module] if isinstance(node, ast.ImportFrom) else [a.name for a in node.names]
            inside |= {n.split(".")[1] for n in names if n and n.startswith("skyscatter.")}
    assert inside == {"conventions", "errors", "spectral"}, inside
