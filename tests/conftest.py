import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(autouse=True, scope="session")
def _isolated_cache(tmp_path_factory):
    """Keep generated lookup tables out of the user's cache folder, for the whole session: session-scoped so that
    it is set before any module- or session-scoped fixture builds tables (a function-scoped one came too late for
    those, and they wrote into ~/.cache/skyscatter)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SKYSCATTER_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "cache"))
        yield


@pytest.fixture
def epw_file(tmp_path):
    """The made two-day EPW file of tests/epw_records.py, written to a fresh temporary folder."""
    from epw_records import write_epw

    return write_epw(tmp_path / "test.epw")
