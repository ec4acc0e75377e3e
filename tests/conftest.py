import os

import numpy as np
import pytest

#: Slow items that run first on their worker, in this order: this one alone is minutes of CPU (Radiance's own table
#: build, no numba), so it runs beside the first numba compilations of the other worker instead of ending the run.
FIRST = ("tests/test_spectral_skymatrix.py::test_gensdaymtx_unit_is_radiance_per_nm_times_400",)


def _xdist_shares(n: int, workers: int) -> list[int]:
    """How many items pytest-xdist's ``worksteal`` hands each worker at the start (``len(pending) // idle``)."""
    shares = []
    for k in range(workers, 0, -1):
        shares.append((n - sum(shares)) // k)
    return shares


@pytest.hookimpl(trylast=True)  # after pytest's own reordering by fixture parameters
def pytest_collection_modifyitems(config, items):
    """Start every worker on slow items (``@pytest.mark.slow``): pytest-xdist's ``worksteal`` hands each worker one
    contiguous share of the collection and then moves items from the end of a busy worker's share to an idle one,
    so a slow item late in the collection ends the run alone. The modules that have slow items go first, dealt to
    the workers' shares (most slow items first, to the share with the fewest), their slow items first within the
    module; the other modules follow in their order and fill the shares. A module stays in one piece, so its
    module-scoped fixtures (tables) are built once. Every worker reorders the same collection identically, as
    xdist requires; under ``-n 0`` there is one share."""
    workers = max(int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")), 1)
    modules: dict[str, list] = {}
    for item in items:
        modules.setdefault(item.nodeid.split("::", 1)[0], []).append(item)
    rank = {nodeid: i for i, nodeid in enumerate(FIRST)}

    def slow_first(group):  # stable: FIRST, then the other slow items, then the rest, each in its order
        return sorted(group, key=lambda it: (rank.get(it.nodeid, len(FIRST)) if it.get_closest_marker("slow")
                                             else len(FIRST) + 1))

    slow_mods = [m for m, group in modules.items() if any(it.get_closest_marker("slow") for it in group)]
    count = {m: sum(it.get_closest_marker("slow") is not None for it in modules[m]) for m in slow_mods}
    slow_mods.sort(key=lambda m: (min((rank.get(it.nodeid, len(FIRST)) for it in modules[m]), default=len(FIRST)),
                                  -count[m]))
    bins: list[list] = [[] for _ in range(workers)]
    load = [0] * workers
    for m in slow_mods:
        w = load.index(min(load))
        bins[w].extend(slow_first(modules[m]))
        load[w] += count[m]
    rest = [it for m, group in modules.items() if m not in count for it in group]
    ordered = []
    for w, share in enumerate(_xdist_shares(len(items), workers)):
        take = max(share - len(bins[w]), 0) if w < workers - 1 else len(rest)
        ordered += bins[w] + rest[:take]
        del rest[:take]
    assert len(ordered) == len(items)
    items[:] = ordered


def pytest_configure(config):
    """Rewrite the asserts of the suite's own modules only. pytest also rewrites every module of each installed
    distribution that has a pytest plugin (``pytest11`` entry point): here zarr (``zarr.testing``) and hypothesis,
    about 150 modules that the suite imports but whose asserts are not its checks. Rewriting them cost each
    worker about 10 CPU-s per run (an AST pass and a compile per module: no rewritten bytecode is kept between
    fresh runs). The test modules and conftest.py are rewritten as before (pytest finds them by name, not by this
    list), so every check of the suite reports as before; a plugin module imported already (xdist, benchmark) was
    rewritten at start-up and stays so. Reaches into pytest's hook (``_must_rewrite``, pytest 7-9); if that is
    gone, nothing changes but the cost."""
    marked = getattr(getattr(config.pluginmanager, "rewrite_hook", None), "_must_rewrite", None)
    if isinstance(marked, set):
        marked.clear()


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(autouse=True, scope="session")
def _isolated_cache(tmp_path_factory):
    """Keep generated lookup tables out of the user's cache folder, for the whole session: session-scoped so that
    it is set before any module- or session-scoped fixture builds tables (a function-scoped one came too late for
    those, and they wrote into ~/.cache/skyscatter).

    Under pytest-xdist each worker has its own base folder (``.../popen-gwN``): the cache goes one level up, shared
    by the workers of the run, so that a table several workers need is built once (the cache's build lock makes the
    others wait for it and then load it)."""
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SKYSCATTER_CACHE_DIR", str(base / "cache"))
        yield


@pytest.fixture
def epw_file(tmp_path):
    """The made two-day EPW file of tests/epw_records.py, written to a fresh temporary folder."""
    from epw_records import write_epw

    return write_epw(tmp_path / "test.epw")
