import os

import numpy as np
import pytest


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
