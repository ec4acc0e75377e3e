"""The disk cache's verified entries (:mod:`skyscatter.diskcache`) and the droplets' Mie optics stored in it."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest

from skyscatter.diskcache import CacheRebuildWarning, cache_entry_path, cached_arrays, read_entry


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("SKYSCATTER_CACHE_DIR", str(tmp_path))
    return tmp_path


def _rewrite(path, change):
    """The entry at ``path`` written again with ``change(arrays)`` applied and its metadata (checksums) kept."""
    with np.load(path) as z:
        arrays = {name: np.array(z[name]) for name in z.files}
    change(arrays)
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)


def test_entry_round_trip_and_key(cache):
    built = []

    def build():
        built.append(1)
        return {"a": np.arange(5.0), "b": np.eye(2)}

    first = cached_arrays("demo", "key 1", build)
    again = cached_arrays("demo", "key 1", build)
    assert len(built) == 1
    np.testing.assert_array_equal(again["a"], first["a"])
    np.testing.assert_array_equal(again["b"], np.eye(2))
    path = cache_entry_path("demo", "key 1")
    assert path.parent == cache and path.name.startswith("demo-")
    assert read_entry(path, "demo", "another key") is None  # a file of another key is not this entry


@pytest.mark.parametrize("damage", ["values", "truncated", "metadata"])
def test_damaged_entry_is_refused_and_rebuilt(cache, damage):
    """An array that no longer matches its checksum, a truncated file or unreadable metadata: a
    CacheRebuildWarning, the entry built again and stored intact."""
    def build():
        return {"a": np.arange(5.0)}

    cached_arrays("demo", "k", build)
    path = cache_entry_path("demo", "k")
    if damage == "values":
        _rewrite(path, lambda arrays: arrays["a"].__setitem__(2, 7.0))
    elif damage == "truncated":
        path.write_bytes(path.read_bytes()[:200])
    else:
        _rewrite(path, lambda arrays: arrays.__setitem__("metadata", np.array("{not json")))
    with pytest.warns(CacheRebuildWarning):
        got = cached_arrays("demo", "k", build)
    np.testing.assert_array_equal(got["a"], np.arange(5.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_array_equal(read_entry(path, "demo", "k")["a"], np.arange(5.0))


def test_two_processes_build_once(cache):
    """Two processes that need the same missing entry at once: one builds it (holding its lock for a second), the
    other waits and reads its file; both get the same arrays."""
    script = textwrap.dedent("""
        import json, sys, time
        import numpy as np
        from skyscatter.diskcache import cached_arrays
        built = []
        def build():
            built.append(1)
            time.sleep(1.0)
            return {"a": np.arange(4.0) * 3.0}
        got = cached_arrays("demo", "shared", build)
        print(json.dumps({"built": len(built), "a": got["a"].tolist()}))
    """)
    procs = [subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True) for _ in range(2)]
    out = [json.loads(p.communicate(timeout=120)[0]) for p in procs]
    assert all(p.returncode == 0 for p in procs)
    assert sorted(o["built"] for o in out) == [0, 1]
    assert all(o["a"] == [0.0, 3.0, 6.0, 9.0] for o in out)


def test_droplet_optics_from_the_disk_cache(cache, monkeypatch):
    """The droplets' Mie optics are stored per wavelength and read back identical (a new process's first cloudy
    sky need not redo them); a damaged entry is refused and computed again."""
    import skyscatter.atmosphere.mie_optics as mo

    mo._stored_droplets.cache_clear()
    first = mo.water_droplets(2e-6, 0.1, [550.0, 650.0])
    files = sorted(cache.glob("droplets-*.npz"))
    assert len(files) == 2
    with monkeypatch.context() as m:
        m.setattr(mo, "mie_optics", lambda *a, **k: pytest.fail("computed again instead of read"))
        mo._stored_droplets.cache_clear()
        again = mo.water_droplets(2e-6, 0.1, [550.0, 650.0])
    for name in ("extinction_cross_section", "scattering_cross_section", "asymmetry_mie", "angular_closure"):
        np.testing.assert_array_equal(getattr(again, name), getattr(first, name))
    np.testing.assert_array_equal(again.phase.values, first.phase.values)
    _rewrite(files[0], lambda arrays: arrays["phase_values"].__setitem__((0, 10), 0.0))
    mo._stored_droplets.cache_clear()
    with pytest.warns(CacheRebuildWarning):
        rebuilt = mo.water_droplets(2e-6, 0.1, [550.0, 650.0])
    np.testing.assert_array_equal(rebuilt.phase.values, first.phase.values)
