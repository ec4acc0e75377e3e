"""Process settings shared by every part of skyscatter: how many threads compute.

One setting sizes every pool: ``$SKYSCATTER_NUM_THREADS`` (read once, at first use) or
:func:`set_num_threads`. It caps numba's parallel kernels (``numba.set_num_threads``; set before numba starts,
it also sizes numba's pool through ``NUMBA_NUM_THREADS``), the BLAS/OpenMP pools numpy and scipy use (through
threadpoolctl: the least-squares fits otherwise oversubscribe the cores) and the thread pools of the
precomputation (:mod:`skyscatter.precomputed.parallel`). Dask workers that each run one skyscatter task set it
to 1 so that tasks do not oversubscribe the cores.

Progress bars follow one rule too: library calls are silent unless the caller passes ``progress=True``; the
command line turns them on (on a terminal; one summary line otherwise).
"""

from __future__ import annotations

import os
import sys
import threading

from .errors import InvalidParameterError
from .validation import whole_number

__all__ = ["num_threads", "set_num_threads"]

_lock = threading.Lock()
_threads: int | None = None


def _available_cpus() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


def _from_environment() -> int:
    env = os.environ.get("SKYSCATTER_NUM_THREADS", "").strip()
    if not env:
        return _available_cpus()
    try:
        value = int(env)
    except ValueError:
        raise InvalidParameterError(f"SKYSCATTER_NUM_THREADS must be a whole number >= 1; got {env!r}") from None
    if value < 1:
        raise InvalidParameterError(f"SKYSCATTER_NUM_THREADS must be >= 1; got {value}")
    return value


def num_threads() -> int:
    """Threads skyscatter computes with: :func:`set_num_threads`, else ``$SKYSCATTER_NUM_THREADS``, else the CPUs."""
    global _threads
    with _lock:
        if _threads is None:
            _threads = _from_environment()
            _apply_to_numba(_threads)
        return _threads


def set_num_threads(n: int) -> None:
    """Use ``n`` >= 1 threads from now on, in every pool skyscatter runs (numba's included)."""
    global _threads
    n = whole_number("the number of threads", n, 1)
    with _lock:
        _threads = n
        _apply_to_numba(n)


def _apply_to_numba(n: int) -> None:
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=n)  # BLAS and OpenMP pools of numpy/scipy, process-wide
    if "numba" not in sys.modules:
        # numba sizes its pool from this variable when it starts; later launches are capped by set_num_threads.
        os.environ["NUMBA_NUM_THREADS"] = str(max(n, 1))
        return
    import numba

    numba.set_num_threads(min(n, numba.config.NUMBA_NUM_THREADS))
