"""The OPAC aerosol components' Mie optics stored in the disk cache (:func:`skyscatter.atmosphere.mie_optics.
stored_mie_optics`): read back bit-identical to the computed ones, keyed by what determines them, a damaged entry
refused and rebuilt, two processes at once safe. The expected values are those of :func:`mie_optics` itself
computed in the same process: the cache must return them to the bit (tolerance 0)."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import skyscatter.atmosphere.mie_optics as mo
from skyscatter.atmosphere.aerosol_types import OpacAerosol, opac_component
from skyscatter.atmosphere.refractive_index import RefractiveIndex
from skyscatter.diskcache import CacheRebuildWarning

WL = [450.0, 550.0]
ARRAYS = ("wavelengths", "extinction_cross_section", "scattering_cross_section", "asymmetry_mie", "angular_closure")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("SKYSCATTER_CACHE_DIR", str(tmp_path))
    mo._stored_mie_optics.cache_clear()
    yield tmp_path
    mo._stored_mie_optics.cache_clear()


def _assert_identical(a, b):
    for name in ARRAYS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes(), name
    for name in ("angles", "values"):
        assert getattr(a.phase, name).tobytes() == getattr(b.phase, name).tobytes(), name


def _no_mie(*args, **kwargs):
    pytest.fail("computed again instead of read from the disk cache")


def test_stored_optics_are_bit_identical_to_computed(cache, monkeypatch):
    mode, index = opac_component("waso", 50.0)
    computed = mo.mie_optics(mode, index, WL)
    mo.stored_mie_optics(mode, index, WL)  # builds and stores the entry
    assert len(list(cache.glob("mie-*.npz"))) == 1
    mo._stored_mie_optics.cache_clear()
    monkeypatch.setattr(mo, "mie_optics", _no_mie)
    _assert_identical(mo.stored_mie_optics(mode, index, WL), computed)


def test_key_holds_what_determines_the_optics(cache):
    """Another humidity (radii and index), other refractive index data under the same name, other wavelengths or
    another quadrature: each its own entry."""
    mode, index = opac_component("soot")
    mo.stored_mie_optics(mode, index, WL)
    other_k = RefractiveIndex(index.wavelengths, index.n, tuple(k * 1.01 for k in index.k), index.name)
    mo.stored_mie_optics(mode, other_k, WL)
    mo.stored_mie_optics(mode, index, [550.0])
    mo.stored_mie_optics(mode, index, WL, nodes_per_e=12.0)
    mo.stored_mie_optics(*opac_component("waso", 0.0), WL)
    mo.stored_mie_optics(*opac_component("waso", 80.0), WL)
    assert len(list(cache.glob("mie-*.npz"))) == 6


def test_aerosol_type_reads_its_components_from_the_cache(cache, monkeypatch):
    aerosol = OpacAerosol("test", (("soot", 1000.0), ("waso", 500.0)))
    ext, table = aerosol.extinction_at(WL), aerosol.phase_table(WL)
    assert len(list(cache.glob("mie-*.npz"))) == 2  # one per component (same wavelengths for both calls)
    mo._stored_mie_optics.cache_clear()
    monkeypatch.setattr(mo, "mie_optics", _no_mie)
    assert aerosol.extinction_at(WL).tobytes() == ext.tobytes()
    assert aerosol.phase_table(WL).values.tobytes() == table.values.tobytes()


def test_damaged_entry_is_warned_and_rebuilt(cache):
    mode, index = opac_component("soot")
    first = mo.stored_mie_optics(mode, index, WL)
    (path,) = cache.glob("mie-*.npz")
    with np.load(path) as z:
        arrays = {name: np.array(z[name]) for name in z.files}
    arrays["phase_values"][1, 10] *= 1.5  # the metadata (checksums) kept: the values no longer match
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)
    mo._stored_mie_optics.cache_clear()
    with pytest.warns(CacheRebuildWarning, match="damaged"):
        rebuilt = mo.stored_mie_optics(mode, index, WL)
    _assert_identical(rebuilt, first)
    mo._stored_mie_optics.cache_clear()
    _assert_identical(mo.stored_mie_optics(mode, index, WL), first)  # stored intact again


def test_two_processes_build_once(cache):
    """Two processes that need the same missing entry at once: one builds it (slowed by a second so that they
    overlap), the other waits for its lock and reads its file; both get the same values to the bit. The build is
    a stand-in for :func:`mie_optics` (isotropic scatterers) so that neither process pays miepython's start-up."""
    script = textwrap.dedent("""
        import json, time
        import numpy as np
        import skyscatter.atmosphere.mie_optics as mo
        from skyscatter.atmosphere.aerosol_types import opac_component
        from skyscatter.atmosphere.phase_table import PhaseTable
        built = []
        def stand_in(distribution, index, wl, angles, nodes_per_e):
            built.append(1)
            time.sleep(1.0)
            w = np.asarray(wl)
            th = np.linspace(0.0, np.pi, 181)
            one = np.full(w.size, 1e-13)
            return mo.MieOptics(w, one * w / 550.0, one, 0.0 * one, one / one,
                                PhaseTable(w, th, np.full((w.size, th.size), 0.25 / np.pi)))
        mo.mie_optics = stand_in
        o = mo.stored_mie_optics(*opac_component("soot"), [450.0, 550.0])
        print(json.dumps({"built": len(built), "ext": o.extinction_cross_section.tobytes().hex(),
                          "phase": o.phase.values.tobytes().hex()}))
    """)
    procs = [subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True) for _ in range(2)]
    out = [json.loads(p.communicate(timeout=120)[0]) for p in procs]
    assert all(p.returncode == 0 for p in procs)
    assert sorted(o["built"] for o in out) == [0, 1]
    assert out[0]["ext"] == out[1]["ext"] and out[0]["phase"] == out[1]["phase"]
    assert len(list(cache.glob("mie-*.npz"))) == 1
