"""An exponential that numba's loops can vectorise: :func:`exp_lane` (one value) and :func:`exp_lanes` (an array).

Numba compiles ``math.exp`` to a call to the C library (to Intel's vector library SVML only where llvmlite was built
with it, which its wheels are not: docs/clouds.md "Speed"), and a loop with a call in it stays scalar; the call also
makes the compiled code save its floating-point registers around it. The compiled loops that need many exponentials
at once (the transmittances of a ray at 11 wavelengths, a march's octaves) call :func:`exp_lane` instead: the
reduction of [Cody1980] Ch. 6, a Taylor polynomial and ``2^k`` written into a float's exponent bits, all arithmetic
that LLVM runs in SIMD lanes. Layer 0: used by the Monte Carlo (layer 4) and the sky models (layer 5).
"""

from __future__ import annotations

import math

from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from .jit import inline

__all__ = ["exp_lane", "exp_lanes"]


@intrinsic
def _bits_of(typingctx, x):
    """The IEEE 754 bits of a float64 as an int64 (a register's reinterpretation, no conversion)."""
    if x != types.float64:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))
    return types.int64(types.float64), codegen


@intrinsic
def _float_of(typingctx, i):
    """The float64 whose IEEE 754 bits are the int64 ``i`` (the inverse of :func:`_bits_of`)."""
    if i != types.int64:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())
    return types.float64(types.int64), codegen


@intrinsic
def _fma(typingctx, a, b, c):
    """``a b + c`` with one rounding (LLVM's ``llvm.fma``: one instruction on CPUs with FMA, which the compiled code
    is built for; a loop of them runs in SIMD lanes), whatever ``fastmath`` flags the caller was compiled with."""
    if not (a == b == c == types.float64):
        return None

    def codegen(context, builder, signature, args):
        d = ir.DoubleType()
        fn = builder.module.declare_intrinsic("llvm.fma", [d], ir.FunctionType(d, [d, d, d]))
        return builder.call(fn, args)
    return types.float64(types.float64, types.float64, types.float64), codegen


#: exp's argument reduction: ln 2 split in a part exact in 32 bits and the rest ([Cody1980] Ch. 6)
_LN2_HI = 0.693147180369123816490
_LN2_LO = 1.90821492927058770002e-10
_LOG2E = 1.4426950408889634
#: 1.5 * 2^52: ``x + _SHIFT`` rounds ``x`` (|x| < 2^51) to the nearest integer, which then fills the low bits of the
#: sum's mantissa (the exponent of ``2^k`` is taken from there: no float-to-integer conversion, which AVX2 lacks)
_SHIFT = 6755399441055744.0
#: Below this argument the result is 0 (exp(-708) = 3.3e-308, the smallest normal float 2.2e-308: ``2^k`` stays a
#: normal number for every argument above it)
EXP_LANE_MIN = -708.0
#: Above this argument the result is inf (exp(709) = 8.2e307; the largest float is exp(709.78), but ``2^k`` would
#: pass the largest exponent there): the callers' arguments are optical depths' negatives, <= 0
EXP_LANE_MAX = 709.0


@inline
def exp_lane(z):
    """``exp(z)`` for ``z`` [-] (float64), without a call: a loop of these runs in SIMD lanes (module docstring).

    The reduction of [Cody1980] Ch. 6: ``z = k ln 2 + r`` with ``k`` the nearest integer to ``z / ln 2`` (``|r| <=
    ln 2 / 2``, ``k ln 2`` subtracted in two parts, the first exact, so that ``r`` is exact to some 1e-19);
    ``exp(r)`` by its Taylor polynomial of degree 13 (the remainder ``(ln 2 / 2)^14 / 14! = 4e-18``, below a
    twentieth of a unit in the last place), evaluated with fused multiply-adds in Estrin's scheme ([Knuth1997]
    Sec. 4.6.4) as ``1 + (r + r^2 Q(r))``; times ``2^k``, built in the exponent's bits (exact). Within 1 unit in the
    last place of the C library's ``exp`` (2.4 million arguments over [-708, 709], tests/test_vecmath.py), the same
    value for some 92 % of them; ``exp(0) = 1`` exactly (``k = 0``, ``r = 0``). Below :data:`EXP_LANE_MIN` it gives
    0 (where the C library gives numbers below 3.3e-308: subnormals or 0), above :data:`EXP_LANE_MAX` (709) inf;
    NaN gives NaN."""
    # clamped so that 2^k stays a normal float; the ends are selected below (NaN passes the clamp)
    zc = EXP_LANE_MIN if z < EXP_LANE_MIN else z
    zc = EXP_LANE_MAX if zc > EXP_LANE_MAX else zc
    t = zc * _LOG2E + _SHIFT
    kf = t - _SHIFT
    r = _fma(-kf, _LN2_LO, _fma(-kf, _LN2_HI, zc))
    # exp(r) = 1 + (r + r^2 Q(r)), Q's 12 coefficients by Estrin's scheme: in pairs, then by r^2 and r^4 (a
    # dependency chain of 6 operations where Horner's form has 13; the 1 added last keeps the rounding error of the
    # rest below half a unit of the result)
    r2 = r * r
    r4 = r2 * r2
    a1 = _fma(r, 1.0 / 6.0, 0.5)
    a2 = _fma(r, 1.0 / 120.0, 1.0 / 24.0)
    a3 = _fma(r, 1.0 / 5040.0, 1.0 / 720.0)
    a4 = _fma(r, 1.0 / 362880.0, 1.0 / 40320.0)
    a5 = _fma(r, 1.0 / 39916800.0, 1.0 / 3628800.0)
    a6 = _fma(r, 1.0 / 6227020800.0, 1.0 / 479001600.0)
    b0 = _fma(r2, a2, a1)
    b1 = _fma(r2, a4, a3)
    b2 = _fma(r2, a6, a5)
    q = _fma(r4, _fma(r4, b2, b1), b0)
    p = 1.0 + _fma(r2, q, r)
    # the low 12 bits of t's bits are k's (two's complement): shifted into the exponent field with its bias
    v = p * _float_of((_bits_of(t) + 1023) << 52)
    if z < EXP_LANE_MIN:
        v = 0.0
    elif z > EXP_LANE_MAX:
        v = math.inf
    return v


@inline
def exp_lanes(z, n):
    """``exp(z[:n])`` in place for ``z`` (>= n,) [-] (:func:`exp_lane`, one loop that LLVM vectorises)."""
    for i in range(n):
        z[i] = exp_lane(z[i])
