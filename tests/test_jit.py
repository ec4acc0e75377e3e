"""The numba conventions (skyscatter.jit): one place for the compilation options, used by every compiled function."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from skyscatter import jit

SRC = Path(jit.__file__).parent


def test_no_module_but_jit_calls_numba_njit():
    """Every compiled function goes through one of the four decorators: the options are decided in one place."""
    offenders = []
    for path in sorted(SRC.rglob("*.py")):
        if path.name == "jit.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.Attribute) and node.attr in {"njit", "jit", "vectorize", "generated_jit"}
                    and isinstance(node.value, ast.Name) and node.value.id == "numba"):
                offenders.append(f"{path.relative_to(SRC)}:{node.lineno}")
    assert offenders == []


def _options(dispatcher):
    return dispatcher.targetoptions


def test_decorators_set_the_documented_options():
    def f(x):
        return x + 1.0

    k = jit.kernel(f)
    assert _options(k)["nogil"] and _options(k)["error_model"] == "numpy"
    assert type(k._cache).__name__ == "FunctionCache"  # cache=True (numba keeps no option for it)
    assert not _options(k)["fastmath"] and "_nrt" not in _options(k)
    h = jit.helper(fastmath=jit.CONTRACT_ARCP)(f)
    assert _options(h)["_nrt"] is False and set(_options(h)["fastmath"]) == {"arcp", "contract"}
    assert _options(jit.inline(f))["inline"] == "always"
    assert _options(jit.parallel_kernel(f))["parallel"]
    assert set(_options(jit.kernel(fastmath=jit.CONTRACT_REASSOC)(f))["fastmath"]) == {"reassoc", "contract"}
    assert h(1.0) == 2.0


def test_only_the_two_documented_fastmath_sets_are_accepted():
    """No set with nnan/ninf: the kernels' NaN and infinity checks must survive compilation."""
    with pytest.raises(ValueError, match="CONTRACT_ARCP"):
        jit.kernel(fastmath=frozenset({"nnan"}))


def test_helper_keeps_nan_checks_with_its_fastmath_set():
    @jit.helper(fastmath=jit.CONTRACT_ARCP)
    def finite_or_zero(x):
        return x if np.isfinite(x) else 0.0

    assert finite_or_zero(np.nan) == 0.0 and finite_or_zero(np.inf) == 0.0 and finite_or_zero(2.0) == 2.0
