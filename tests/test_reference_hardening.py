"""``skyscatter reference`` and its store under the failures a user meets (issue 18, item 3).

Arguments checked before the store is touched; the store created atomically and locked, so that of two runs on one
new store the loser stops with one line and leaves nothing; every finished cell verified on resume (checksum) and
recomputed if damaged; an incomplete store refused; a huge number of samples planned lazily (no memory up front)
and stopped by SIGTERM/SIGINT within a second (the command, end to end).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("xarray")
pytest.importorskip("zarr")

from skyscatter.cli import main  # noqa: E402
from skyscatter.errors import InvalidParameterError, OutputError  # noqa: E402
from skyscatter.montecarlo.dataset import (  # noqa: E402
    ReferenceStoreWarning,
    equal_area_directions,
    lock_path,
    reference,
)

JOB = dict(sun_elevations=np.radians([40.0]), turbidities=[2.0, 4.0], albedos=[0.2], wavelengths=[500.0],
           directions=equal_area_directions(2), samples=16, seed=1, scheduler="synchronous")
CLI_JOB = ["--sun-elevation", "30", "--wavelengths", "550", "--directions", "2", "--no-progress"]


def _entries(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


@pytest.mark.parametrize("args,message", [
    (["--seed", "-1"], "--seed"),
    (["--seed", "9223372036854775808"], "--seed"),
    (["--samples", "0"], "--samples"),
    (["--samples", "10000000000000000"], "--samples"),
    (["--directions", "0"], "--directions"),
    (["--altitude", "-5"], "--altitude"),
    (["--wavelengths", "200"], "360-830 nm"),
    (["--turbidity", "30"], "turbidit"),
    (["--aod", "-1"], "aerosol optical depth"),
    (["--ground-albedo", "2"], "albedo"),
    (["--sun-elevation", "100"], "sun elevation"),
    (["--scheduler", "nonsense"], "scheduler"),
])
def test_bad_arguments_leave_no_store(tmp_path, capsys, args, message):
    store = tmp_path / "a.zarr"
    assert main(["reference", str(store), *CLI_JOB, *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert _entries(tmp_path) == []
    # the corrected command then works (the bad one left no store behind to be refused as another job)
    if args[0] == "--seed":
        assert main(["reference", str(store), *CLI_JOB, "--samples", "16", "--scheduler", "synchronous"]) == 0


def test_bad_store_paths(tmp_path, capsys):
    (tmp_path / "file.zarr").write_text("x")
    for path, message in ((tmp_path / "file.zarr", "not a folder"), (tmp_path / "missing" / "a.zarr", "does not exist"),
                          ("", "empty")):
        assert main(["reference", str(path), *CLI_JOB]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and message in err[0], err


def test_a_store_locked_by_a_live_process_is_refused(tmp_path):
    """Another process writing the store (its pid in the lock): a one-line error, nothing written or left."""
    store = tmp_path / "a.zarr"
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        lock_path(store).write_text(f"{other.pid}\n")
        with pytest.raises(OutputError, match=f"being written by another skyscatter process \\(pid {other.pid}\\)"):
            reference(store, **JOB)
        assert _entries(tmp_path) == [lock_path(store).name]  # no store, no temporary
    finally:
        other.kill()
        other.wait()
    # a lock whose process has gone is taken over
    reference(store, **JOB)
    assert _entries(tmp_path) == ["a.zarr"]


@pytest.fixture
def compiled_kernels(tmp_path_factory):
    """The command's Monte Carlo kernels compiled into numba's on-disk cache before the two processes start, by
    running the same command in this process (free when the tests before it compiled them): on a fresh
    installation each process would otherwise compile them itself, about 50 s of CPU each, which is not what the
    race test is about (the processes still create, lock and write one new store together)."""
    assert main(["reference", str(tmp_path_factory.mktemp("warm") / "warm.zarr"), *CLI_JOB, "--samples", "1"]) == 0


def test_two_runs_started_together_on_a_new_store(tmp_path, compiled_kernels):
    """The race of issue 18: one run writes the store, the other stops with one line; nothing else is left."""
    cmd = [sys.executable, "-m", "skyscatter", "reference", "race.zarr", *CLI_JOB, "--samples", "64"]
    env = {**os.environ, "SKYSCATTER_NUM_THREADS": "1"}
    procs = [subprocess.Popen(cmd, cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for _ in range(2)]
    results = [(p.wait(timeout=300), p.stderr.read()) for p in procs]
    for p in procs:
        p.stdout.close()
        p.stderr.close()
    codes = sorted(code for code, _ in results)
    assert codes in ([0, 0], [0, 2]), results  # a loser that found the winner finished simply resumes (nothing to do)
    for code, err in results:
        if code == 2:
            lines = err.strip().splitlines()
            assert len(lines) == 1 and "being written by another skyscatter process" in lines[0], err
    assert _entries(tmp_path) == ["race.zarr"]
    import xarray as xr

    assert bool(xr.open_zarr(tmp_path / "race.zarr", consolidated=False)["done"].all())


def test_damaged_cells_are_found_and_recomputed(tmp_path):
    import xarray as xr
    import zarr

    store = tmp_path / "a.zarr"
    reference(store, **JOB)
    good = xr.open_zarr(store, consolidated=False)["radiance"].values.copy()
    # cell (0, 0, 0): a chunk file overwritten with garbage (undecodable); cell (0, 1, 0): valid but wrong numbers
    chunk = next(p for p in (store / "radiance").rglob("*") if p.is_file() and p.parts[-5:] == ("0",) * 5)
    chunk.write_bytes(b"\x00garbage" * 3)
    zarr.open_array(store / "stderr", mode="r+")[0, 1, 0] = 1.0
    with pytest.warns(ReferenceStoreWarning, match="2 cell"):
        ds = reference(store, **JOB)
    np.testing.assert_array_equal(ds["radiance"].values, good)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", ReferenceStoreWarning)
        reference(store, **JOB)  # all verified now: nothing recomputed


def test_an_incomplete_store_is_refused(tmp_path):
    import shutil

    store = tmp_path / "a.zarr"
    reference(store, **JOB)
    shutil.rmtree(store / "done")
    with pytest.raises(OutputError, match="'done' missing"):
        reference(store, **JOB)
    code = main(["reference", str(store), *CLI_JOB])
    assert code == 2


def test_huge_samples_cost_no_memory_up_front(tmp_path):
    """10^12 paths per direction: planned lazily, the first tasks run at once with little memory."""

    class Stop(Exception):
        pass

    def stop(done, total):
        assert total >= 10**12 // 512 // 64  # the whole plan is counted, not built
        raise Stop

    tracemalloc.start()
    t0 = time.perf_counter()
    with pytest.raises(Stop):
        reference(tmp_path / "a.zarr", **{**JOB, "samples": 10**12}, progress=stop)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert time.perf_counter() - t0 < 60
    assert peak < 64 * 2**20  # bytes; the per-batch reduction of before needed ~10^14
    with pytest.raises(InvalidParameterError):
        reference(tmp_path / "b.zarr", **{**JOB, "samples": 10**16})


def test_sigterm_ends_a_huge_run_within_a_second(tmp_path):
    """The command itself: --samples 10^12, SIGTERM once tracing has started; it exits within a second, status
    143, the lock released, and the store resumable."""
    cmd = [sys.executable, "-m", "skyscatter", "reference", "big.zarr", *CLI_JOB, "--samples", "1000000000000"]
    env = {**os.environ, "SKYSCATTER_NUM_THREADS": "2"}
    proc = subprocess.Popen(cmd, cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not (tmp_path / "big.zarr").exists() and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        time.sleep(1.0)  # tracing
        assert proc.poll() is None, proc.stderr.read()
        proc.send_signal(signal.SIGTERM)
        t0 = time.monotonic()
        code = proc.wait(timeout=30)
        elapsed = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
        out, err = proc.communicate()
    assert code == 143, err
    assert elapsed < 1.0, elapsed
    assert err.strip().splitlines()[-1] == "skyscatter reference: terminated"
    assert _entries(tmp_path) == ["big.zarr"]  # the lock is released


def test_ctrl_c_interrupts_a_huge_run_at_once(tmp_path, capsys):
    """SIGINT (Ctrl-C) while the tasks run: main() returns 130 within a second, queued tasks cancelled."""
    import threading

    # Python turns SIGINT into KeyboardInterrupt only where the process did not inherit it ignored (a shell
    # starts background jobs with SIGINT ignored): the test sets the default handler itself, or it would hang
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    t0 = time.monotonic()
    try:
        code = main(["reference", str(tmp_path / "big.zarr"), *CLI_JOB, "--samples", "1000000000000"])
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    assert code == 130
    assert time.monotonic() - t0 < 2.0  # 1 s until the signal, then at most one task's remainder
    assert capsys.readouterr().err.strip().splitlines()[-1] == "skyscatter reference: interrupted"
    assert _entries(tmp_path) in ([], ["big.zarr"])  # no lock, no temporary store left


_CONTENDER = """
import sys, time
from pathlib import Path
from skyscatter.errors import OutputError
from skyscatter.montecarlo import dataset
store = Path(sys.argv[1])
while time.time() < float(sys.argv[2]):  # start together
    pass
try:
    dataset._acquire(store)
except OutputError:
    print("refused")
    sys.exit(0)
t0 = time.time()
time.sleep(0.3)
t1 = time.time()
dataset._release(store)
print(f"held {t0!r} {t1!r}")
"""


def test_store_lock_is_held_by_one_process_at_a_time(tmp_path):
    """Six processes take the store's lock at the same instant: the intervals during which each believed it held
    the lock never overlap (the lock used to exist empty for a moment after its exclusive creation, and a second
    process read that as a stale lock and took it over: two writers, seen in CI), and no private lock file is
    left."""
    store = tmp_path / "s.zarr"
    start = time.time() + 1.5
    procs = [subprocess.Popen([sys.executable, "-c", _CONTENDER, str(store), repr(start)], stdout=subprocess.PIPE,
                              text=True) for _ in range(6)]
    outs = [p.communicate(timeout=60)[0].split() for p in procs]
    held = sorted((float(o[1]), float(o[2])) for o in outs if o and o[0] == "held")
    assert held, outs
    for (_, end), (begin, _) in zip(held[:-1], held[1:], strict=False):
        assert begin >= end, held
    assert sorted(p.name for p in tmp_path.iterdir()) == [], list(tmp_path.iterdir())
