"""Failures of the machine while writing (issue 18, item 4): a full disk (ENOSPC), a file too large (EFBIG), the
permission lost mid-write (EACCES), for every writer: one error naming the target, nothing partial left.

In the library the error is an OutputError (the CLI prints it on one line and exits 2). Faults are injected where
each writer hands bytes to the system: the ``open`` a module's writer calls returns a file that writes half of
its first block and then fails as the system would, OpenEXR's writer fails as the real one does on a full disk
(``RuntimeError: ... No space left on device.``), Pillow's PNG writer and Zarr's cell writes raise the OSError.
Then the folder must hold exactly what it held before. One end-to-end case per command runs the real program with
a file-size limit (RLIMIT_FSIZE: the kernel's EFBIG) instead of an injection.
"""

from __future__ import annotations

import errno
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import skyscatter.precomputed.export as export_module
import skyscatter.precomputed.storage as storage_module
import skyscatter.radiance as radiance_module
import skyscatter.render.image_io as image_io
import skyscatter.sky.hosek_wilkie as hosek_wilkie_module
import skyscatter.sky_matrix as sky_matrix_module
from skyscatter import PreethamSky
from skyscatter.errors import OutputError
from skyscatter.render import write_exr, write_exr_and_png, write_hdr, write_png
from skyscatter.render.radiance_sky import write_radiance_sky

ERRNOS = [errno.ENOSPC, errno.EFBIG, errno.EACCES]
DATA = Path(__file__).parent / "data"
IMAGE = np.random.default_rng(0).random((64, 96, 3)).astype(np.float32) * 10


class _FailingFile:
    """A real file that writes half of its first block, then fails with ``code`` (as write(2) reports)."""

    def __init__(self, fh, code: int) -> None:
        self._fh, self._code = fh, code

    def write(self, data) -> int:
        view = memoryview(data).cast("B") if not isinstance(data, str) else data
        self._fh.write(view[: max(1, len(view) // 2)])
        self._fh.flush()
        raise OSError(self._code, os.strerror(self._code))

    def __getattr__(self, name):
        return getattr(self._fh, name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._fh.close()
        return False


def _failing_open(code: int):
    def fake(file, mode="r", *args, **kwargs):
        fh = open(file, mode, *args, **kwargs)  # noqa: SIM115 - closed by the wrapper
        return _FailingFile(fh, code) if any(c in mode for c in "wa+") else fh

    return fake


def _entries(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def _check(exc: pytest.ExceptionInfo, target: Path, code: int) -> None:
    text = str(exc.value)
    assert str(target) in text and os.strerror(code) in text, text
    assert ".tmp" not in text and "\n" not in text


@pytest.mark.parametrize("code", ERRNOS, ids=errno.errorcode.get)
def test_exr_writer(tmp_path, monkeypatch, code):
    import OpenEXR

    class FullDisk:
        def __init__(self, header, channels):
            pass

        def write(self, path):
            Path(path).write_bytes(b"\x76\x2f\x31\x01partial")
            raise RuntimeError(f'Failed to write pixel data to image file "{path}". {os.strerror(code)}.')

    monkeypatch.setattr(OpenEXR, "File", FullDisk)
    (tmp_path / "old.exr").write_bytes(b"previous version")
    for target in (tmp_path / "sky.exr", tmp_path / "old.exr"):
        with pytest.raises(OutputError) as exc:
            write_exr(target, IMAGE)
        _check(exc, target, code)
    with pytest.raises(OutputError):
        write_exr_and_png(tmp_path / "a.exr", tmp_path / "a.png", IMAGE)
    assert _entries(tmp_path) == ["old.exr"] and (tmp_path / "old.exr").read_bytes() == b"previous version"


@pytest.mark.parametrize("code", ERRNOS, ids=errno.errorcode.get)
def test_png_and_hdr_writers(tmp_path, monkeypatch, code):
    real = image_io._save_png

    def failing_png(path, display):
        real(path, display)
        with open(path, "r+b") as fh:
            fh.truncate(10)
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(image_io, "_save_png", failing_png)
    for call, target in ((lambda: write_png(tmp_path / "p.png", IMAGE), tmp_path / "p.png"),
                         (lambda: write_exr_and_png(tmp_path / "b.exr", tmp_path / "b.png", IMAGE), None)):
        with pytest.raises(OutputError) as exc:
            call()
        if target is not None:
            _check(exc, target, code)
    monkeypatch.setattr(image_io, "open", _failing_open(code), raising=False)
    with pytest.raises(OutputError) as exc:
        write_hdr(tmp_path / "r.hdr", IMAGE)
    _check(exc, tmp_path / "r.hdr", code)
    sky = PreethamSky(2.5, math.radians(50), math.radians(120))
    with pytest.raises(OutputError):
        write_radiance_sky(tmp_path / "s.rad", sky, width=64)
    assert _entries(tmp_path) == []


@pytest.mark.parametrize("code", ERRNOS, ids=errno.errorcode.get)
def test_sky_matrix_writers(tmp_path, monkeypatch, code):
    m = sky_matrix_module.skymatrix(DATA / "weather.epw", scheme="tregenza", samples=1)
    monkeypatch.setattr(sky_matrix_module, "open", _failing_open(code), raising=False)
    for call, target in ((lambda: m.save_npz(tmp_path / "m.npz"), tmp_path / "m.npz"),
                         (lambda: m.save_csv(tmp_path / "m.csv"), tmp_path / "m.csv"),
                         (lambda: m.save(tmp_path / "g.npz", tmp_path / "g.csv"), tmp_path / "g.npz")):
        with pytest.raises(OutputError) as exc:
            call()
        _check(exc, target, code)
    monkeypatch.undo()
    monkeypatch.setattr(radiance_module, "open", _failing_open(code), raising=False)
    with pytest.raises(OutputError) as exc:
        m.save_radiance(tmp_path / "m.mtx")
    _check(exc, tmp_path / "m.mtx", code)
    with pytest.raises(OutputError):
        m.save(tmp_path / "h.mtx", tmp_path / "h.csv", format="radiance")
    assert _entries(tmp_path) == []


@pytest.fixture(scope="module")
def tiny_tables():
    from skyscatter.precomputed import PrecomputedAtmosphere

    tiny = dict(transmittance_mu=16, transmittance_r=4, irradiance_mu_s=4, irradiance_r=4, scattering_r=4,
                scattering_mu=8, scattering_mu_s=4, scattering_nu=2)
    return PrecomputedAtmosphere.compute(orders=1, sizes=tiny, tables="rgb", progress=False)


@pytest.mark.parametrize("code", ERRNOS, ids=errno.errorcode.get)
def test_table_writers(tmp_path, monkeypatch, tiny_tables, code):
    """Raw LUTs (the export as one group: none of its files appears), the tables' .npz, a fitted dataset."""
    luts = tmp_path / "luts"
    luts.mkdir()
    (luts / "atmosphere.json").write_text("{}")  # an earlier export is left as it was
    monkeypatch.setattr(export_module, "open", _failing_open(code), raising=False)
    with pytest.raises(OutputError) as exc:
        tiny_tables.export(luts)
    _check(exc, luts / "transmittance.raw", code)
    assert _entries(luts) == ["atmosphere.json"] and (luts / "atmosphere.json").read_text() == "{}"
    monkeypatch.setattr(storage_module, "open", _failing_open(code), raising=False)
    with pytest.raises(OutputError) as exc:
        tiny_tables.save(tmp_path / "t.npz")
    _check(exc, tmp_path / "t.npz", code)
    dataset = hosek_wilkie_module._published().xyz  # a HosekWilkieDataset (the authors' XYZ one)
    monkeypatch.setattr(hosek_wilkie_module, "open", _failing_open(code), raising=False)
    with pytest.raises(OutputError) as exc:
        dataset.save(tmp_path / "hw.npz")
    _check(exc, tmp_path / "hw.npz", code)
    assert _entries(tmp_path) == ["luts"]


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EACCES], ids=errno.errorcode.get)
def test_zarr_store_writes(tmp_path, monkeypatch, code):
    """A reference store: failing at creation leaves no store; failing at a cell keeps the cells before it and
    marks none that is not complete."""
    import xarray as xr

    from skyscatter.montecarlo.dataset import equal_area_directions, lock_path, reference

    job = dict(sun_elevations=np.radians([40.0, 20.0]), turbidities=[2.0], albedos=[0.2], wavelengths=[500.0],
               directions=equal_area_directions(2), samples=16, seed=1, scheduler="synchronous")
    real = xr.Dataset.to_zarr
    calls = {"n": 0}

    def failing(self, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] == fail_at:
            raise OSError(code, os.strerror(code))
        return real(self, *args, **kwargs)

    monkeypatch.setattr(xr.Dataset, "to_zarr", failing)
    fail_at = 1  # the store itself
    with pytest.raises(OutputError, match=os.strerror(code)):
        reference(tmp_path / "a.zarr", **job)
    assert _entries(tmp_path) == []
    calls["n"], fail_at = 0, 4  # creation, cell 1 data, cell 1 done, cell 2 data
    with pytest.raises(OutputError, match="1 cell\\(s\\) finished before are kept"):
        reference(tmp_path / "a.zarr", **job)
    assert not lock_path(tmp_path / "a.zarr").exists()
    monkeypatch.undo()
    done = xr.open_zarr(tmp_path / "a.zarr", consolidated=False)["done"].values.ravel().tolist()
    assert done == [True, False]
    assert bool(reference(tmp_path / "a.zarr", **job)["done"].all())  # resumes


@pytest.mark.parametrize("command", [
    ["sky", "--width", "256", "--out", "sky.exr"],
    ["sky", "--width", "256", "--format", "radiance", "--out", "sky.rad"],
    ["skymatrix", str(DATA / "weather.epw"), "--format", "radiance", "--csv", "m.csv", "--out", "m.mtx"],
], ids=["sky", "sky-radiance", "skymatrix"])
def test_file_size_limit_end_to_end(tmp_path, command):
    """The real programs under a 16 KiB file-size limit (the kernel's EFBIG): one line, exit 2, nothing left
    (the Zarr store's failures are injected above: its cells go through zarr's own I/O threads)."""
    import resource

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (16384, 16384))

    res = subprocess.run([sys.executable, "-m", "skyscatter", *command], cwd=tmp_path, capture_output=True,
                         text=True, preexec_fn=limit, env={**os.environ, "SKYSCATTER_NUM_THREADS": "1"})
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1 and os.strerror(errno.EFBIG) in lines[0], res.stderr
    assert "Traceback" not in res.stderr and ".tmp" not in lines[0]
    assert _entries(tmp_path) == []
