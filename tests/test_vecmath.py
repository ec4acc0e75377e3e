"""The vectorisable exponential of the compiled loops (``skyscatter.vecmath``): its values against the C library's,
its ends, and that a loop of it runs in SIMD lanes."""

import math

import numba
import numpy as np

from skyscatter.jit import kernel
from skyscatter.vecmath import EXP_LANE_MAX, EXP_LANE_MIN, exp_lane, exp_lanes


@kernel
def _exp_loop(z, out):
    """``out[i] = exp_lane(z[i])``: a loop of the kind the Monte Carlo's transmittances run."""
    for i in range(out.shape[0]):
        out[i] = exp_lane(z[i])


def _exp_in_place(z):
    out = np.array(z, dtype=np.float64)
    exp_lanes(out, out.size)
    return out


def test_exponentials_within_one_unit_of_libm():
    """``exp_lanes`` (Cody-Waite reduction, degree-13 Taylor polynomial in Estrin's scheme) against Python's
    ``math.exp`` (the C library's, an independent implementation) over the whole normal range [-708, 709], densely
    over the Monte Carlo's and the march's optical depths [-60, 0], at the ends of the reduction's interval and at
    the smallest arguments: within 1 unit in the last place of the C library's value (2.2e-16 relative where the
    result is just above a power of two), and the same value for most arguments."""
    rng = np.random.default_rng(7)
    z = np.concatenate([-np.geomspace(1e-300, 708.0, 200_001), rng.uniform(-60.0, 0.0, 500_000),
                        rng.uniform(EXP_LANE_MIN, EXP_LANE_MAX, 500_000),
                        [(k + 0.5) * math.log(2.0) for k in range(-1020, 1022)],
                        [(k - 0.5) * math.log(2.0) for k in range(-1020, 1022)]])
    z = z[(z >= EXP_LANE_MIN) & (z <= EXP_LANE_MAX)]
    out = _exp_in_place(z)
    expected = np.array([math.exp(v) for v in z])
    assert np.all(np.abs(out - expected) <= np.spacing(expected))
    assert np.max(np.abs(out / expected - 1.0)) < 2.3e-16
    assert np.mean(out == expected) > 0.85
    loop = np.empty_like(z)
    _exp_loop(z, loop)
    assert np.array_equal(loop, out)  # the scalar form in a loop: the same numbers


def test_exponential_ends():
    """``exp(0) = 1`` exactly (either sign of zero; the transmittance of an empty path), 0 below ``EXP_LANE_MIN``
    (an opaque path: the C library's values there are below 3.3e-308), inf above ``EXP_LANE_MAX`` and for inf, NaN
    for NaN."""
    z = [0.0, -0.0, EXP_LANE_MIN, np.nextafter(EXP_LANE_MIN, -np.inf), -745.2, -1e6, -np.inf, np.inf, 709.5, np.nan,
         EXP_LANE_MAX]
    out = _exp_in_place(z)
    assert out[0] == 1.0 and out[1] == 1.0
    assert out[2] == math.exp(EXP_LANE_MIN) or abs(out[2] / math.exp(EXP_LANE_MIN) - 1.0) <= 2.3e-16
    assert out[2] > 0.0
    assert np.all(out[3:7] == 0.0)
    assert np.all(np.isposinf(out[7:9]))
    assert np.isnan(out[9])
    assert np.isfinite(out[10]) and abs(out[10] / math.exp(EXP_LANE_MAX) - 1.0) <= 2.3e-16


def test_a_loop_of_exponentials_runs_in_simd_lanes():
    """The reason the function exists: LLVM vectorises a loop of it (the IR holds vectors of doubles and calls
    nothing named exp), where a loop of ``math.exp`` stays a loop of calls to the C library."""
    # compiled here without the disk cache: a function loaded from numba's cache has no LLVM IR to inspect
    loop = numba.njit(error_model="numpy")(_exp_loop.py_func)
    z = np.linspace(-30.0, 0.0, 11)
    out = np.empty_like(z)
    loop(z, out)
    assert np.array_equal(out, _exp_in_place(z))
    ir = loop.inspect_llvm(loop.signatures[0])
    assert "x double>" in ir
    assert "@exp(" not in ir and "@llvm.exp" not in ir
