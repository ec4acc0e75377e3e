"""How skyscatter compiles its loops with numba: the four decorators every compiled function uses, and why.

Loops that cannot be vectorised with numpy (rays through tables, paths through the medium, walks over a
heightfield) are compiled with numba. Every compiled function uses one of these decorators, so that a reader
sees by its decorator what a function is and which rules it follows:

* :func:`kernel` - a loop called from Python, usually on a slice ``start..stop`` of its items by
  :func:`skyscatter.precomputed.parallel.parallel_for` (``nogil``: the pool's threads run it at once). It may
  allocate its buffers (numba's runtime, NRT, counts their references).
* :func:`helper` - a function called from compiled code that never allocates: compiled without numba's runtime
  (``_nrt=False``), so a call that passes arrays on does not increment and decrement their reference counts.
  Those counts are atomic and, in the kernels' inner loops, contended between threads: the ground term of a sky
  lookup took 0.30 us per ray and thread with them, 0.19 us without (docs/architecture.md, "numba kernels"). A
  helper that allocates does not compile (numba says so): make it a :func:`kernel`.
* :func:`inline` - a small helper inlined where it is called (numba inlines at its own level; LLVM does not inline
  large numba functions, and a call left in a loop keeps the loop scalar). The inlined body is compiled with the
  caller's options.
* :func:`parallel_kernel` - a loop over ``numba.prange`` (numba's own threads, sized by
  :func:`skyscatter.runtime.set_num_threads`), for whole images: the heightfield tracer, light shafts, the
  analytic aerial perspective.

Options shared by all: ``cache=True`` (compiled once per installation, into numba's cache folder; see
:func:`skyscatter.fileio.ensure_numba_cache`), ``nogil=True`` and numpy's error model (``error_model="numpy"``):
a float division by zero gives inf or NaN instead of raising, so numba emits no test and branch per division and
loops can be vectorised; every division that can meet a zero is guarded in the code.

Floating-point contraction and reordering (``fastmath``) are off unless a function asks for one of the two sets
below; a set is chosen per function where it was measured to pay, and never includes ``nnan``, ``ninf`` or
``nsz``, so the NaN and infinity checks of the kernels (bad directions are flagged, not traced) keep working:

* :data:`CONTRACT_ARCP` (``contract``, ``arcp``) - fused multiply-adds (one rounding instead of two) and
  ``x / y`` as ``x * (1 / y)`` with the reciprocal computed once outside a loop (at most one unit in the last
  place per operation). Used by the table coordinates and lookups of :mod:`skyscatter.precomputed` (geometry,
  lookup helpers, the sun cells of the precomputation), whose loops over directions are vectorised.
* :data:`CONTRACT_REASSOC` (``contract``, ``reassoc``) - fused multiply-adds and reordered sums, so that a
  sum over a loop runs in several SIMD lanes. Used by the scattering density of the precomputation, whose inner
  sums over quadrature directions are its cost.

The effect of both sets on speed and results is measured in docs/architecture.md ("numba kernels").

Compilation is serialised between processes per function: a process that compiles a function (a signature not yet
in numba's cache) holds an exclusive ``flock`` on ``.MODULE.NAME-LINE.numba.lock`` in the function's numba cache
folder (:func:`skyscatter.fileio.build_lock`) from its cache look-up to its cache write. Another process that needs
the same function at the same time waits and then loads the first one's machine code from the cache instead of
compiling it again: the processes of a parallel test run (pytest-xdist workers) or of a cluster started on a fresh
installation compile each function once (compiling a precomputation's kernels costs a minute of CPU). The lock is
taken inside numba's own (per-process, re-entrant) compiler lock, and a process that already holds a function's
lock (numba compiles callees while compiling their caller) does not take it again. Functions call each other
without cycles, so processes that hold some locks and wait for others cannot wait for each other in a circle.

Numba checks a cached function against its own source file only (a hash of that file): a kernel whose file did not
change keeps the machine code of the helpers it called from another file when they did, in a developer's tree or an
editable install, so the tables of a changed helper were computed with its old code until the kernel's file changed
too (it happened: numba's in-tree cache kept a changed ``sampling`` helper in an unchanged ``kernels`` module's
code, 2026-12-06). Every function here is checked against the whole package's source as well
(:func:`_package_digest`, added to the cache index's stamp by :func:`_stamp_with_package`): any change to any
module of the package compiles every function again on first use (a minute of CPU for the precomputation's
kernels), and an installed package, whose files do not change, loads its cache as before.

A function is compiled for the types of its arguments, never for their values: numba types a constant argument of
a call from compiled code as a literal (``Literal[bool](True)``, ``Literal[int](0)``) and would compile the callee
once per constant and once more for a variable (``geometry.scattering_r_mu_coord`` 5 times, ``sampling.r_mu_cell``
3 times in one process of the precomputed tests), each a full numba and LLVM pass, in every process. The compile
hook below compiles the plain types instead (``numba.core.types.unliteral``), which the call with the constant then
uses; no function here asks for a literal (``numba.literally``). The machine code is not slower: numba links a
helper into its caller's LLVM module, where the constant is propagated as before.

``exp`` and ``log`` are bound to glibc's entry points without its error-handling wrapper where glibc has them
(:func:`_bind_libm`): numba binds the compiled code's ``exp`` to the one its own C helpers were linked against, on
Linux glibc's compatibility wrapper ``exp@GLIBC_2.2.5`` (the SVID and errno checks of glibc before 2.29), which took
a third of the time of each ``exp`` in the Monte Carlo kernels (``perf``: 4.2 % of a cloudy path's samples in the
wrapper, 7.9 % in the computation it calls). ``__exp_finite`` and ``__log_finite`` (exported by glibc since 2.15 for
``-ffinite-math-only`` callers, kept for compatibility) are the same computation (``__ieee754_exp``, chosen by CPU
features as for ``exp``) without the wrapper: the same value to the bit for every input, infinities, NaN, zero,
overflow and underflow included (checked on 5 million numbers across the whole range, docs/clouds.md "Speed"); only
``errno`` is not set, which compiled code never reads. Where glibc lacks them (another C library or OS), numba's
binding stays.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import hashlib
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, TypeVar

import numba
from numba.core import sigutils, types
from numba.core.compiler_lock import global_compiler_lock

from .fileio import build_lock

__all__ = ["CONTRACT_ARCP", "CONTRACT_REASSOC", "helper", "inline", "kernel", "parallel_kernel"]

F = TypeVar("F", bound=Callable[..., Any])

#: ``fastmath`` set: fused multiply-adds and reciprocal multiplication (module docstring).
CONTRACT_ARCP = frozenset({"contract", "arcp"})
#: ``fastmath`` set: fused multiply-adds and reordered (SIMD) sums (module docstring).
CONTRACT_REASSOC = frozenset({"contract", "reassoc"})

_COMMON: dict[str, Any] = {"cache": True, "nogil": True, "error_model": "numpy"}


def _bind_libm() -> dict[str, int]:
    """Bind the compiled code's ``exp`` and ``log`` to glibc's ``__exp_finite`` and ``__log_finite`` (module
    docstring); returns the symbols bound and their addresses (empty where glibc does not have them). Numba binds its
    math symbols once, when its CPU target is first set up: that is done here first, so that these bindings replace
    its own. Every function compiled here is finalised (compiled, or loaded from numba's cache: the calls are bound
    then) after this module is imported."""
    if not sys.platform.startswith("linux"):
        return {}
    try:
        libm = ctypes.CDLL("libm.so.6")
        dlvsym = ctypes.CDLL(None).dlvsym
    except (OSError, AttributeError):
        return {}
    dlvsym.restype = ctypes.c_void_p
    dlvsym.argtypes = (ctypes.c_void_p, ctypes.c_char_p, ctypes.c_char_p)
    from llvmlite import binding as llvm
    from numba.core.registry import cpu_target

    _ = cpu_target.target_context  # sets up numba's CPU target, which binds its math symbols
    bound = {}
    for name in ("exp", "log"):
        addr = dlvsym(libm._handle, f"__{name}_finite".encode(), b"GLIBC_2.15")
        if addr:
            llvm.add_symbol(name, addr)
            bound[name] = int(addr)
    return bound


#: The math symbols bound by :func:`_bind_libm` (name: address).
LIBM_BINDINGS = _bind_libm()


def _fastmath(flags: frozenset[str] | None) -> bool | set[str]:
    if flags is None:
        return False
    if flags not in (CONTRACT_ARCP, CONTRACT_REASSOC):
        raise ValueError(f"fastmath must be None, CONTRACT_ARCP or CONTRACT_REASSOC; got {flags!r}")
    return set(flags)


#: Compile-lock files this process holds (under numba's compiler lock), and how many times (module docstring).
_held: dict[Path, int] = {}


@contextlib.contextmanager
def _compile_lock(path: Path) -> Iterator[None]:
    """Hold the inter-process compile lock of one function (``build_lock`` of ``path``); re-entrant per process."""
    if path in _held:
        _held[path] += 1
        try:
            yield
        finally:
            _held[path] -= 1
        return
    with build_lock(path):
        _held[path] = 1
        try:
            yield
        finally:
            del _held[path]


def _compile_lock_path(dispatcher: Any) -> Path | None:
    """The file whose ``build_lock`` is the compile lock of a compiled function (module docstring): in the
    function's numba cache folder, named after its module, name and first line as numba names its cache files;
    None without a numba on-disk cache (``NUMBA_DISABLE_JIT``, or a numba without ``cache_path``)."""
    cache_path = getattr(getattr(dispatcher, "_cache", None), "cache_path", None)
    py_func = getattr(dispatcher, "py_func", None)
    if not isinstance(cache_path, str) or py_func is None:
        return None
    return Path(cache_path) / f"{py_func.__module__}.{py_func.__qualname__}-{py_func.__code__.co_firstlineno}.numba"


def _lock_compilation(dispatcher: Any) -> Any:
    """Make ``dispatcher.compile`` compile the plain (non-literal) argument types and hold the function's
    inter-process compile lock (module docstring) when the signature is not compiled in this process yet (numba
    calls ``compile`` for a call with new argument types and when it types a caller); without a numba on-disk cache
    it only takes the plain types, and without numba (``NUMBA_DISABLE_JIT``) the function is returned unchanged."""
    path = _compile_lock_path(dispatcher)
    compile_unlocked = getattr(dispatcher, "compile", None)
    if compile_unlocked is None:
        return dispatcher

    def compile(sig: Any) -> Any:
        args, ret = sigutils.normalize_signature(sig)
        plain = tuple(types.unliteral(a) for a in args)
        if plain != tuple(args):  # a call from compiled code with constants (module docstring)
            sig = plain if ret is None else ret(*plain)
            args = plain
        if path is None or tuple(args) in dispatcher.overloads:  # no disk cache, or compiled in this process
            return compile_unlocked(sig)
        with global_compiler_lock, _compile_lock(path):  # numba's lock first: one thread of this process waits
            return compile_unlocked(sig)

    dispatcher.compile = compile
    return dispatcher


@functools.cache
def _package_digest(root: Path | None = None) -> str:
    """SHA-256 (hex) of every ``.py`` file under ``root`` (default: this package), each file's path relative to
    ``root`` and its bytes, in sorted order (module docstring); empty where the package is not a folder of files
    (a zip import, a frozen application) or a file cannot be read."""
    root = Path(__file__).resolve().parent if root is None else Path(root)
    if not root.is_dir():
        return ""
    h = hashlib.sha256()
    try:
        for path in sorted(root.rglob("*.py")):
            h.update(path.relative_to(root).as_posix().encode())
            h.update(b"\0")
            h.update(path.read_bytes())
            h.update(b"\0")
    except OSError:
        return ""
    return h.hexdigest()


def _stamp_with_package(dispatcher: Any) -> Any:
    """Add :func:`_package_digest` to the source stamp that numba stores in a cached function's index and compares
    when it loads it (module docstring), so that a change anywhere in the package invalidates the cache; without a
    numba on-disk cache (or a numba whose cache keeps its stamp elsewhere) the function is returned unchanged."""
    cache_file: Any = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    stamp = getattr(cache_file, "_source_stamp", None)
    if stamp is not None:
        cache_file._source_stamp = (stamp, _package_digest())
    return dispatcher


def _decorator(fastmath: frozenset[str] | None, **options: Any) -> Callable[[F], F]:
    njit = numba.njit(**_COMMON, fastmath=_fastmath(fastmath), **options)

    def deco(func: F) -> F:
        locked: F = _lock_compilation(_stamp_with_package(njit(func)))
        return locked
    return deco


def kernel(func: F | None = None, *, fastmath: frozenset[str] | None = None) -> Any:
    """Compile a loop called from Python (module docstring); ``@kernel`` or ``@kernel(fastmath=...)``."""
    deco = _decorator(fastmath)
    return deco if func is None else deco(func)


def helper(func: F | None = None, *, fastmath: frozenset[str] | None = None) -> Any:
    """Compile a non-allocating helper without numba's runtime (module docstring); ``@helper`` or
    ``@helper(fastmath=...)``."""
    deco = _decorator(fastmath, _nrt=False)
    return deco if func is None else deco(func)


def inline(func: F | None = None, *, fastmath: frozenset[str] | None = None) -> Any:
    """Compile a helper that numba inlines into its callers (module docstring); ``@inline`` or
    ``@inline(fastmath=...)`` (the options apply when it is called from Python)."""
    deco = _decorator(fastmath, inline="always")
    return deco if func is None else deco(func)


def parallel_kernel(func: F | None = None, *, fastmath: frozenset[str] | None = None) -> Any:
    """Compile a loop over ``numba.prange`` run on numba's threads (module docstring)."""
    deco = _decorator(fastmath, parallel=True)
    return deco if func is None else deco(func)
