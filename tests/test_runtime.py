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
