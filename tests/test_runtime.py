"""Process-wide settings: one thread setting for every pool; atomic files without touching the umask."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
import threading

import pytest

from skyscatter import runtime
from skyscatter.errors import InvalidParameterError
from skyscatter.fileio import atomic_path
from skyscatter.precomputed.parallel import n_threads


def test_set_num_threads_sizes_every_pool():
    import numba

    before = runtime.num_threads()
    try:
        runtime.set_num_threads(1)
        assert runtime.num_threads() == 1 and n_threads() == 1 and numba.get_num_threads() == 1
    finally:
        runtime.set_num_threads(before)


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "2"])
def test_bad_thread_counts_are_refused(bad):
    with pytest.raises(InvalidParameterError):
        runtime.set_num_threads(bad)


def test_environment_variable_is_the_default_and_is_checked():
    code = "from skyscatter import runtime; print(runtime.num_threads())"
    env = {**os.environ, "SKYSCATTER_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "1"
    env["SKYSCATTER_NUM_THREADS"] = "many"
    bad = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert bad.returncode != 0 and "SKYSCATTER_NUM_THREADS must be a whole number" in bad.stderr


def test_atomic_files_get_umask_permissions_and_never_change_the_umask(tmp_path):
    """Many threads writing at once: each file has 0666 & ~umask, and the umask is never toggled (old code set it)."""
    old = os.umask(0o027)
    try:
        seen = []
        real_umask = os.umask

        def spy(mask):  # pragma: no cover - must not be called
            seen.append(mask)
            return real_umask(mask)

        os.umask = spy
        try:
            def write(k):
                with atomic_path(tmp_path / f"f{k}.txt") as tmp:
                    tmp.write_text("x")

            threads = [threading.Thread(target=write, args=(k,)) for k in range(16)]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
        finally:
            os.umask = real_umask
        assert seen == []
        for k in range(16):
            assert stat.S_IMODE((tmp_path / f"f{k}.txt").stat().st_mode) == 0o640
        assert not list(tmp_path.glob(".*tmp*"))
    finally:
        os.umask(old)


def test_set_num_threads_caps_the_blas_pools():
    from threadpoolctl import threadpool_info

    before = runtime.num_threads()
    try:
        runtime.set_num_threads(1)
        assert all(pool["num_threads"] == 1 for pool in threadpool_info())
    finally:
        runtime.set_num_threads(before)


def _fill_chunk(out, start, stop):
    """A stand-in kernel: writes each index of its chunk into ``out``."""
    out[start:stop] = range(start, stop)


def test_kernel_pool_is_kept_resized_and_safe_after_fork():
    """parallel_for keeps one pool per process (no thread start-up per call), re-creates it when the number of
    threads changes, covers the range exactly, runs inline when called from its own worker, and a forked child
    gets a fresh pool instead of the parent's dead threads."""
    import multiprocessing

    import numpy as np

    from skyscatter.precomputed import parallel

    before = runtime.num_threads()
    try:
        runtime.set_num_threads(2)
        out = np.full(10_000, -1.0)
        parallel.parallel_for(_fill_chunk, out.size, out, grain=100)
        np.testing.assert_array_equal(out, np.arange(out.size))
        pool = parallel._executor(2)
        parallel.parallel_for(_fill_chunk, out.size, out, grain=100)
        assert parallel._executor(2) is pool
        runtime.set_num_threads(3)
        parallel.parallel_for(_fill_chunk, out.size, out, grain=100)
        assert parallel._executor(3) is not pool
        # from a worker of the pool: inline, no deadlock
        inner = np.full(1000, -1.0)
        parallel._executor(3).submit(parallel.parallel_for, _fill_chunk, inner.size, inner).result(timeout=30)
        np.testing.assert_array_equal(inner, np.arange(inner.size))
        if "fork" in multiprocessing.get_all_start_methods():
            ctx = multiprocessing.get_context("fork")
            with ctx.Pool(1) as child:
                assert child.apply_async(_sum_in_child).get(timeout=60) == sum(range(5000))
    finally:
        runtime.set_num_threads(before)


def _sum_in_child():
    import numpy as np

    from skyscatter.precomputed import parallel

    out = np.zeros(5000)
    parallel.parallel_for(_fill_chunk, out.size, out, grain=100)
    return int(out.sum())
