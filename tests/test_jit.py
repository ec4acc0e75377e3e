"""The numba conventions (skyscatter.jit): one place for the compilation options, used by every compiled function."""

from __future__ import annotations

import ast
import os
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


def test_a_second_process_loads_the_first_ones_compilation(tmp_path):
    """The compile lock (skyscatter.jit module docstring): while one process compiles a function, another that
    needs it waits and then loads the machine code from numba's cache instead of compiling it again. Here this
    process holds the lock; the child, started first, is still waiting 2 s later (a compilation of this function
    takes well under a second), and after this process has compiled the function and released the lock the child
    reports a cache hit and no compilation of its own."""
    import importlib
    import subprocess
    import sys
    import time

    (tmp_path / "lockdemo.py").write_text(
        "from skyscatter import jit\n\n\n@jit.kernel\ndef twice(x):\n    return 2.0 * x\n")
    child = (
        "import sys\nimport lockdemo\nprint('ready', flush=True)\nassert lockdemo.twice(1.5) == 3.0\n"
        "print(sum(lockdemo.twice.stats.cache_misses.values()), sum(lockdemo.twice.stats.cache_hits.values()))\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), str(SRC.parent)]))
    env.pop("NUMBA_DISABLE_JIT", None)
    sys.path.insert(0, str(tmp_path))
    try:
        lockdemo = importlib.import_module("lockdemo")
        path = jit._compile_lock_path(lockdemo.twice)
        assert path is not None
        with jit._compile_lock(path):
            proc = subprocess.Popen([sys.executable, "-c", child], env=env, cwd=tmp_path, stdout=subprocess.PIPE,
                                    text=True)
            assert proc.stdout.readline().strip() == "ready"
            time.sleep(2.0)
            assert proc.poll() is None  # waiting for the lock
            assert lockdemo.twice(1.5) == 3.0  # compiles here (the lock is this process's: re-entered)
            assert sum(lockdemo.twice.stats.cache_misses.values()) == 1
        out, _ = proc.communicate(timeout=120)
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop("lockdemo", None)
    assert proc.returncode == 0
    assert out.split() == ["0", "1"]  # no compilation, one load from the cache


def test_exp_and_log_bound_without_the_wrapper_give_the_same_bits():
    """Compiled ``exp`` and ``log`` bound to glibc's ``__exp_finite`` / ``__log_finite`` (``jit._bind_libm``): on glibc
    the binding is made (the Monte Carlo's speed counts on it), and the values are libm's own to the bit across the
    whole range, overflow, underflow, subnormals, zeros, infinities and NaN included (numpy's ``exp``/``log`` call the
    same glibc functions through their default symbol versions, but vectorise some loops: Python's ``math`` is the
    reference)."""
    import ctypes
    import math
    import platform

    if platform.system() == "Linux" and platform.libc_ver()[0] == "glibc":
        libm = ctypes.CDLL("libm.so.6")
        dlvsym = ctypes.CDLL(None).dlvsym
        dlvsym.restype = ctypes.c_void_p
        dlvsym.argtypes = (ctypes.c_void_p, ctypes.c_char_p, ctypes.c_char_p)
        assert set(jit.LIBM_BINDINGS) == {"exp", "log"}
        for name, addr in jit.LIBM_BINDINGS.items():
            assert addr == dlvsym(libm._handle, f"__{name}_finite".encode(), b"GLIBC_2.15")

    @jit.kernel
    def both(x, out_exp, out_log):
        for i in range(x.shape[0]):
            out_exp[i] = math.exp(x[i])
            out_log[i] = math.log(x[i]) if x[i] > 0.0 else 0.0

    rng = np.random.default_rng(11)
    x = np.concatenate([rng.uniform(-760.0, 720.0, 20000), rng.uniform(-1.0, 1.0, 20000),
                        10.0 ** rng.uniform(-320.0, 308.0, 20000), [0.0, -0.0, 5e-324, 709.78, 709.79, -745.2, -745.1,
                                                                    np.inf, -np.inf, np.nan]])
    out_exp = np.empty_like(x)
    out_log = np.empty_like(x)
    both(x, out_exp, out_log)
    def py_exp(v):
        try:
            return math.exp(v)
        except OverflowError:
            return math.inf

    ref_exp = np.array([py_exp(v) for v in x])
    ref_log = np.array([math.log(v) if v > 0.0 else 0.0 for v in x])
    assert np.array_equal(out_exp, ref_exp, equal_nan=True)
    assert np.array_equal(out_log, ref_log, equal_nan=True)


def test_package_digest_follows_every_module(tmp_path):
    """:func:`jit._package_digest` changes when any module's bytes change, not when nothing does, and is empty for a
    package that is not a folder (a zip import): the stamp numba's cache of every function is checked against."""
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "a.py").write_text("x = 1\n")
    (pkg / "sub" / "b.py").write_text("y = 2\n")
    (pkg / "data.txt").write_text("not a module\n")
    first = jit._package_digest.__wrapped__(pkg)
    assert len(first) == 64 and first == jit._package_digest.__wrapped__(pkg)
    (pkg / "data.txt").write_text("changed, still not a module\n")
    assert jit._package_digest.__wrapped__(pkg) == first
    (pkg / "sub" / "b.py").write_text("y = 3\n")
    assert jit._package_digest.__wrapped__(pkg) != first
    assert jit._package_digest.__wrapped__(tmp_path / "missing.zip") == ""
    assert jit._package_digest() == jit._package_digest.__wrapped__(SRC)  # the package's own, once per process


def test_a_change_anywhere_in_the_package_invalidates_the_cache(tmp_path):
    """numba checks a cached function against its own file only; the decorators add the package's digest to that
    stamp (skyscatter.jit module docstring), so that a kernel whose file did not change is compiled again when a
    helper in another module did. Each run is a new process with its own numba cache folder: compiled and saved,
    loaded, compiled again under another package digest (as after an edit elsewhere), and again under the real one."""
    import subprocess
    import sys

    (tmp_path / "stampdemo.py").write_text(
        "from skyscatter import jit\n\n\n@jit.kernel\ndef plus_one(x):\n    return x + 1.0\n")
    child = (
        "import os\nfrom skyscatter import jit\nfake = os.environ.get('FAKE_DIGEST')\n"
        "if fake:\n    jit._package_digest = lambda root=None: fake\n"
        "import stampdemo\nassert stampdemo.plus_one(1.5) == 2.5\n"
        "s = stampdemo.plus_one.stats\nprint(sum(s.cache_misses.values()), sum(s.cache_hits.values()))\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), str(SRC.parent)]),
               NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    env.pop("NUMBA_DISABLE_JIT", None)

    def run(**extra: str) -> list[str]:
        out = subprocess.run([sys.executable, "-c", child], env={**env, **extra}, cwd=tmp_path, capture_output=True,
                             text=True, timeout=120, check=True)
        return out.stdout.split()

    assert run() == ["1", "0"]  # compiled (and saved)
    assert run() == ["0", "1"]  # loaded
    assert run(FAKE_DIGEST="0" * 64) == ["1", "0"]  # another package: compiled again
    assert run() == ["1", "0"]  # and back
