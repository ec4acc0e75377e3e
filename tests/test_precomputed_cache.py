"""Disk cache of the precomputed tables: keyed, verified on load, rebuilt (with a warning) when damaged."""

import warnings

import numpy as np
import pytest

from skyscatter.precomputed import AtmosphereParameters, CacheRebuildWarning, PrecomputedAtmosphere, cached_atmosphere
from skyscatter.precomputed.cache import cache_dir, cache_path, clear_memory_cache

TINY = dict(transmittance_mu=32, transmittance_r=8, irradiance_mu_s=8, irradiance_r=4, scattering_r=4,
            scattering_mu=16, scattering_mu_s=4, scattering_nu=4)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("SKYSCATTER_CACHE_DIR", str(tmp_path / "cache"))
    clear_memory_cache()
    yield tmp_path / "cache"
    clear_memory_cache()


def _no_compute(*args, **kwargs):
    raise AssertionError("tables were recomputed")


def test_cache_location_from_environment(cache):
    assert cache_dir() == cache


def test_cache_writes_then_reads_without_recomputing(cache, monkeypatch):
    atm = cached_atmosphere(orders=1, sizes=TINY)
    path = cache_path(atm.cache_key)
    assert path.exists() and path.parent == cache
    assert cached_atmosphere(orders=1, sizes=TINY) is atm  # memory
    clear_memory_cache()
    monkeypatch.setattr(PrecomputedAtmosphere, "compute", classmethod(_no_compute))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        again = cached_atmosphere(orders=1, sizes=TINY)
    np.testing.assert_array_equal(again.tables["multiple"], atm.tables["multiple"])


def test_key_changes_with_parameters_sizes_orders_wavelengths():
    base = PrecomputedAtmosphere.compute(orders=1, sizes=TINY, progress=False).cache_key
    from skyscatter.precomputed.sizes import table_wavelengths
    from skyscatter.precomputed.tables import TableSizes, cache_key

    p = AtmosphereParameters()
    wl = table_wavelengths(None)
    sz = TableSizes(**TINY)
    assert cache_key(p, 1, wl, sz) == base
    assert cache_key(p.replace(ground_albedo=0.3), 1, wl, sz) != base
    assert cache_key(p, 2, wl, sz) != base
    assert cache_key(p, 1, wl + 1, sz) != base
    assert cache_key(p, 1, wl, TableSizes(**{**TINY, "scattering_nu": 6})) != base


@pytest.mark.parametrize("damage", ["flip", "truncate", "garbage"])
def test_corrupt_cache_file_is_rebuilt(cache, damage):
    atm = cached_atmosphere(orders=1, sizes=TINY)
    path = cache_path(atm.cache_key)
    data = bytearray(path.read_bytes())
    if damage == "flip":
        data[len(data) // 2] ^= 0x55
    elif damage == "truncate":
        data = data[: len(data) // 3]
    else:
        data = bytearray(b"not an npz file at all")
    path.write_bytes(bytes(data))
    clear_memory_cache()
    with pytest.warns(CacheRebuildWarning):
        rebuilt = cached_atmosphere(orders=1, sizes=TINY)
    np.testing.assert_array_equal(rebuilt.tables["multiple"], atm.tables["multiple"])
    # the rebuilt file is valid again
    assert PrecomputedAtmosphere.load(path, expected_key=atm.cache_key).cache_key == atm.cache_key


def test_mismatched_cache_file_is_rebuilt(cache):
    atm = cached_atmosphere(orders=1, sizes=TINY)
    other = PrecomputedAtmosphere.compute(AtmosphereParameters(ground_albedo=0.5), orders=1, sizes=TINY,
                                          progress=False)
    other.save(cache_path(atm.cache_key))  # a valid file, but for other parameters
    clear_memory_cache()
    with pytest.warns(CacheRebuildWarning, match="other parameters"):
        again = cached_atmosphere(orders=1, sizes=TINY)
    assert again.parameters == AtmosphereParameters()


def test_unwritable_cache_still_returns_tables(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    monkeypatch.setenv("SKYSCATTER_CACHE_DIR", str(blocker / "sub"))
    clear_memory_cache()
    with pytest.warns(RuntimeWarning, match="could not write"):
        atm = cached_atmosphere(orders=1, sizes=TINY, tables="rgb")
    assert atm.tables["transmittance"].shape == (8, 32, 3)
    clear_memory_cache()


def test_force_keeps_the_old_file_until_the_new_tables_are_written(cache, monkeypatch):
    """--force / load_or_compute(force=True): a failure during the computation leaves the valid cache file."""
    from skyscatter.precomputed.cache import load_or_compute

    atm, computed = load_or_compute(orders=1, sizes=TINY)
    assert computed
    path = cache_path(atm.cache_key)
    before = path.read_bytes()

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(PrecomputedAtmosphere, "compute", interrupted)
    with pytest.raises(KeyboardInterrupt):
        load_or_compute(orders=1, sizes=TINY, force=True)
    assert path.read_bytes() == before
    clear_memory_cache()
    again, computed = load_or_compute(orders=1, sizes=TINY)
    assert not computed and again.cache_key == atm.cache_key


def test_first_build_says_so_and_a_cached_atmosphere_is_silent(tmp_path, monkeypatch):
    """Issue 11 item 5: the first use of an uncached atmosphere warns that tables are built once (and how long)."""
    import warnings

    from skyscatter.precomputed.cache import TableBuildWarning, cached_atmosphere, clear_memory_cache

    monkeypatch.setenv("SKYSCATTER_CACHE_DIR", str(tmp_path))
    clear_memory_cache()
    small = dict(transmittance_mu=16, transmittance_r=8, irradiance_mu_s=8, irradiance_r=4, scattering_r=4,
                 scattering_mu=8, scattering_mu_s=8, scattering_nu=4)
    from skyscatter.atmosphere import AtmosphereParameters

    params = AtmosphereParameters(ozone_column=123.0)
    with pytest.warns(TableBuildWarning, match="building the precomputed tables for this atmosphere once"):
        cached_atmosphere(params, orders=1, wavelengths=[550.0], sizes=small)
    clear_memory_cache()
    with warnings.catch_warnings():
        warnings.simplefilter("error", TableBuildWarning)
        cached_atmosphere(params, orders=1, wavelengths=[550.0], sizes=small)  # from the disk cache: no warning


_BUILDER = """
import hashlib, sys, time
from skyscatter.precomputed import PrecomputedAtmosphere
from skyscatter.precomputed.cache import load_or_compute
compute = PrecomputedAtmosphere.compute.__func__

def slow(cls, *args, **kwargs):  # a build that lasts: the other process arrives while it runs
    time.sleep(1.5)
    return compute(cls, *args, **kwargs)

PrecomputedAtmosphere.compute = classmethod(slow)
while time.time() < float(sys.argv[1]):  # start together
    pass
atm, computed = load_or_compute(orders=1, sizes=%r, wavelengths=[550.0], progress=False)
print(computed, hashlib.sha256(atm.tables["multiple"].tobytes()).hexdigest())
"""


def test_two_processes_needing_the_same_tables_build_them_once(tmp_path):
    """Parallel test workers (pytest -n 2) or Dask workers share the cache folder: two processes asking for the
    same missing tables at the same instant get the same tables, built by one of them (the other waits for its
    lock, then loads its file), and the folder holds the one table file and its lock, no temporary."""
    import os
    import subprocess
    import sys
    import time

    env = {**os.environ, "SKYSCATTER_CACHE_DIR": str(tmp_path)}
    start = repr(time.time() + 3.0)
    procs = [subprocess.Popen([sys.executable, "-c", _BUILDER % (TINY,), start], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for _ in range(2)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert all(p.returncode == 0 for p in procs), [err for _, err in outs]
    results = [out.split() for out, _ in outs]
    assert sorted(r[0] for r in results) == ["False", "True"], results
    assert results[0][1] == results[1][1]
    names = sorted(p.name for p in tmp_path.iterdir())
    assert len(names) == 2 and names[0].startswith(".bruneton-") and names[0].endswith(".npz.lock"), names
    assert names[1] == names[0][1:-len(".lock")], names
