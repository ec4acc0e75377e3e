"""The CIE tables shipped as package data equal colour-science's (issue 12: a quick command line).

colour-science (a peer we did not write) is the source the tables were generated from by
tools/generate_cie_tables.py; here they are compared value for value, and the formulas that replaced colour
calls (CIE daylight locus, sRGB encoding) are compared with colour's implementations.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from skyscatter.render.tonemap import srgb_encode
from skyscatter.spectral import cie_cmfs, daylight_basis, daylight_chromaticity
from skyscatter.spectral._colour import cie_table, colour_module

SRC = Path(__file__).resolve().parents[1] / "src"


def test_cmfs_equal_colour_science():
    colour = colour_module()
    ref = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    wl, values = cie_table("cie1931_2deg_cmfs")
    np.testing.assert_array_equal(wl, ref.wavelengths)
    np.testing.assert_array_equal(values, ref.values)  # exact: written with repr()
    np.testing.assert_array_equal(cie_cmfs(ref.wavelengths), ref.values)


def test_daylight_basis_equals_colour_science():
    basis = colour_module("colour.colorimetry").SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES
    wl, values = cie_table("cie_daylight_basis")
    np.testing.assert_array_equal(wl, basis["S0"].wavelengths)
    for i, k in enumerate(("S0", "S1", "S2")):
        np.testing.assert_array_equal(values[:, i], basis[k].values)
    np.testing.assert_array_equal(daylight_basis(wl), values)


def test_daylight_locus_equals_colour_science():
    cct_to_xy = colour_module("colour.temperature").CCT_to_xy_CIE_D
    t = np.linspace(4000.0, 25000.0, 211)
    x, y = daylight_chromaticity(t)
    np.testing.assert_allclose(np.stack([x, y], axis=-1), cct_to_xy(t), rtol=0, atol=1e-15)
    # colour-science's documented example (its CCT_to_xy_CIE_D docstring): 6504.38938305 K -> (0.3127077, 0.3291128)
    x, y = daylight_chromaticity(6504.38938305)
    assert abs(float(x) - 0.3127077) < 1e-7 and abs(float(y) - 0.3291128) < 1e-7


def test_srgb_encoding_equals_colour_science():
    encode = colour_module("colour.models").eotf_inverse_sRGB
    v = np.concatenate([np.linspace(0, 0.01, 101), np.linspace(0, 1, 1001)])
    np.testing.assert_allclose(srgb_encode(v), encode(v), rtol=0, atol=1e-15)


@pytest.mark.parametrize("args", [["sky", "--projection", "fisheye", "--width", "16"], ["sun", "--lat", "1",
                                  "--lon", "1", "--time", "2024-01-01T12:00Z"]])
def test_command_line_does_not_import_colour_science_or_matplotlib(tmp_path, args):
    """The import of colour-science (and through it matplotlib) was most of the 5.2 s of `skyscatter sky`."""
    code = ("import sys; from skyscatter.cli import main; rc = main(sys.argv[1:]); "
            "bad = sorted(m for m in ('colour', 'matplotlib') if m in sys.modules); "
            "print('IMPORTED', bad); sys.exit(rc)")
    proc = subprocess.run([sys.executable, "-c", code, *args], cwd=tmp_path, capture_output=True, text=True,
                          env={"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin",
                               "SKYSCATTER_CACHE_DIR": str(tmp_path / "c")}, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "IMPORTED []" in proc.stdout
