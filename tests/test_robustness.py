"""Issue 12: outputs written all or nothing, interruption, read-only installs, bad inputs answered in one line.

Each test reproduces one failure the issue lists (it failed before the fix).
"""

from __future__ import annotations

import math
import os
import shutil
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

from epw_records import write_epw
from skyscatter.cli import main
from skyscatter.errors import (
    FileFormatError,
    InvalidDirectionError,
    InvalidParameterError,
    OutputError,
    SkyscatterError,
)
from skyscatter.fileio import atomic_paths, remove_stale_temporaries
from skyscatter.render import read_exr, sky_image, write_exr, write_exr_and_png, write_png
from skyscatter.sky.preetham import PreethamSky

SRC = Path(__file__).resolve().parents[1] / "src"


def run(capsys, *args):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def one_line(err: str) -> bool:
    return len(err.strip().splitlines()) == 1 and "Traceback" not in err


def hidden(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def small_sky():
    return PreethamSky(2.5, math.radians(50), math.radians(120))


def _epw(tmp_path: Path) -> Path:
    return write_epw(tmp_path / "w.epw")


# ---- item 2: half a pair -------------------------------------------------------------------------------------

def test_sky_refuses_a_folder_named_like_the_exr_and_writes_no_png(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sky.exr").mkdir()
    code, out, err = run(capsys, "sky", "--width", "16")
    assert code == 2 and one_line(err) and "sky.exr" in err and "folder" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sky.exr"]


def test_skymatrix_refuses_a_folder_named_like_the_csv_and_writes_no_npz(tmp_path, capsys):
    epw = _epw(tmp_path)
    (tmp_path / "m.csv").mkdir()
    code, out, err = run(capsys, "skymatrix", epw, "--patches", "tregenza", "--samples", "1",
                         "--out", tmp_path / "m.npz", "--csv", tmp_path / "m.csv")
    assert code == 2 and one_line(err) and "m.csv" in err
    assert not (tmp_path / "m.npz").exists() and hidden(tmp_path) == []


def test_pair_written_all_or_nothing_when_the_second_write_fails(tmp_path, monkeypatch):
    import skyscatter.render.image_io as io

    (tmp_path / "a.exr").write_bytes(b"old")

    def broken(path, display):
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(io, "_save_png", broken)
    with pytest.raises(OutputError, match=r"cannot write .*a\.png: No space left") as info:
        write_exr_and_png(tmp_path / "a.exr", tmp_path / "a.png", np.ones((2, 4, 3)))
    assert ".tmp" not in str(info.value)  # the user's path, never a hidden temporary
    assert (tmp_path / "a.exr").read_bytes() == b"old" and not (tmp_path / "a.png").exists()
    assert hidden(tmp_path) == []


def test_group_rename_failure_restores_earlier_targets(tmp_path, monkeypatch):
    first, second = tmp_path / "x.txt", tmp_path / "y.txt"
    first.write_text("old x")
    real_replace = os.replace

    def replace(src, dst):
        if Path(dst) == second:
            raise OSError(5, "Input/output error")
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(OutputError, match="y.txt"):
        with atomic_paths(first, second) as (a, b):
            a.write_text("new x")
            b.write_text("new y")
    monkeypatch.undo()
    assert first.read_text() == "old x" and not second.exists() and hidden(tmp_path) == []


# ---- item 3: SIGTERM and stale temporaries -------------------------------------------------------------------

_SLOW_WRITE = """
import sys, time
import skyscatter.render.image_io as io
real = io._save_png
def slow(path, display):
    real(path, display)
    open(sys.argv[1] + "/ready", "w").close()
    time.sleep(60)
io._save_png = slow
from skyscatter.cli import main
sys.exit(main(["sky", "--width", "16", "--out", sys.argv[1] + "/sky.exr"]))
"""


def test_sigterm_during_a_write_leaves_no_temporary(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(SRC))
    proc = subprocess.Popen([sys.executable, "-c", _SLOW_WRITE, str(tmp_path)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not (tmp_path / "ready").exists():
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "the write never started"
            time.sleep(0.05)
        assert hidden(tmp_path), "the temporaries should exist mid-write"
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 143, err
    assert "terminated" in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ready"]


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def test_stale_temporaries_of_a_killed_process_are_cleaned_next_time(tmp_path):
    pid = _dead_pid()
    stale = tmp_path / f".sky.exr.{pid}.0123456789ab.tmp.exr"
    stale.write_bytes(b"partial")
    moved_aside = tmp_path / f".sky.png.{pid}.0123456789ab.old.png"  # killed between the two renames
    moved_aside.write_bytes(b"previous png")
    mine = tmp_path / f".sky.exr.{os.getpid()}.0123456789ab.tmp.exr"  # a live process's: left alone
    mine.write_bytes(b"in progress")
    other = tmp_path / ".unrelated.tmp.exr"  # not ours: left alone
    other.write_bytes(b"x")
    write_exr(tmp_path / "sky.exr", np.ones((2, 4, 3)))
    assert not stale.exists() and not moved_aside.exists()
    assert (tmp_path / "sky.png").read_bytes() == b"previous png"  # restored under its name
    assert mine.exists() and other.exists()
    assert remove_stale_temporaries(tmp_path) == []


# ---- item 4: precompute with an unusable cache ---------------------------------------------------------------

@pytest.mark.parametrize("make", [lambda d: d / "afile", lambda d: d / "afile" / "sub"])
def test_precompute_refuses_an_unusable_cache_before_computing(tmp_path, monkeypatch, capsys, make):
    (tmp_path / "afile").write_text("not a folder")
    monkeypatch.setenv("SKYSCATTER_CACHE_DIR", str(make(tmp_path)))
    t0 = time.perf_counter()
    code, out, err = run(capsys, "precompute", "--orders", "1", "--scattering-size", "4x8x4x2")
    assert code == 2 and one_line(err) and "table cache" in err and "SKYSCATTER_CACHE_DIR" in err
    assert "wrote" not in out
    assert time.perf_counter() - t0 < 5  # refused before the tables are built


# ---- item 5: no negative values in EXR files ------------------------------------------------------------------

def test_sunset_sun_is_out_of_gamut_but_the_exr_has_no_negative_value(tmp_path):
    """As fig7's sunset panel: a low, reddened solar disc lies outside sRGB (a negative component); the file
    must not hold it."""
    sky = PreethamSky(8.0, math.radians(84.0), math.radians(290.0))
    image = sky_image(sky, width=2048, ground_albedo=None)  # 2048 px: the sun covers whole pixels
    assert image.min() < 0  # the colour really is out of gamut
    write_exr(tmp_path / "s.exr", image)
    stored = read_exr(tmp_path / "s.exr")
    assert stored.min() >= 0.0
    from skyscatter.spectral import linear_srgb_to_xyz

    np.testing.assert_allclose(linear_srgb_to_xyz(stored.astype(float))[..., 1],
                               linear_srgb_to_xyz(image.astype(float))[..., 1], rtol=1e-5, atol=1e-6)

    import OpenEXR

    with OpenEXR.File(str(tmp_path / "s.exr")) as f:
        np.testing.assert_allclose(f.header()["chromaticities"],
                                   (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290), atol=1e-7)


def test_gamut_mapping_properties(rng):
    from skyscatter.spectral import gamut_map_srgb, linear_srgb_to_xyz

    c = rng.normal(1.0, 2.0, size=(5000, 3))
    y = linear_srgb_to_xyz(c)[:, 1]
    m = gamut_map_srgb(c)
    assert m.min() >= 0
    keep = y > 0
    np.testing.assert_allclose(linear_srgb_to_xyz(m)[keep, 1], y[keep], rtol=1e-12, atol=1e-12)
    inside = c.min(axis=1) >= 0
    np.testing.assert_array_equal(m[inside], c[inside])  # in-gamut colours untouched
    np.testing.assert_array_equal(m[~keep], 0.0)
    # the mapped colour lies on the segment from the grey of equal luminance to the original colour
    out = ~inside & keep
    grey = y[out, None] / linear_srgb_to_xyz(np.ones(3))[1]
    t = (m[out] - grey) / (c[out] - grey)
    assert np.allclose(t, t[:, :1], rtol=1e-6, atol=1e-9) and np.all((t >= 0) & (t <= 1 + 1e-12))


# ---- item 6: read-only install, unwritable HOME, non-root user ------------------------------------------------

@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0 or shutil.which("setpriv") is None,
                    reason="needs root to switch to an unprivileged user (setpriv)")
def test_read_only_install_and_unwritable_home_as_a_non_root_user(tmp_path):
    """Run as 'nobody' (uid 65534): the package tree is not writable, HOME does not exist. Reading the
    interpreter under /root needs CAP_DAC_READ_SEARCH, which grants read access only, never write."""
    out = tmp_path / "out"
    out.mkdir()
    os.chmod(out, 0o777)
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": "/nonexistent", "PYTHONPATH": str(SRC),
           "SKYSCATTER_CACHE_DIR": "/nonexistent/cache", "TMPDIR": str(out), "MPLCONFIGDIR": str(out / "mpl")}
    cmd = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", "--inh-caps=+dac_read_search",
           "--ambient-caps=+dac_read_search", sys.executable, "-c",
           "import sys; from skyscatter.cli import main; sys.exit(main(sys.argv[1:]))",
           "sky", "--projection", "fisheye", "--width", "16", "--out", str(out / "s.exr")]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    warn = [line for line in proc.stderr.splitlines() if "numba" in line.lower()]
    assert len(warn) == 1 and "NUMBA_CACHE_DIR" in warn[0] and "Traceback" not in proc.stderr
    assert (out / "s.exr").is_file() and (out / "s.png").is_file()
    assert (out / "skyscatter-numba-65534").is_dir()


# ---- item 7: raw exceptions -----------------------------------------------------------------------------------

@pytest.mark.parametrize(
    "call,error",
    [
        (lambda: sky_image(small_sky(), width="256"), InvalidParameterError),
        (lambda: sky_image(small_sky(), width=2.5), InvalidParameterError),
        (lambda: sky_image(object(), width=8), InvalidParameterError),
        (lambda: sky_image("preetham", width=8), InvalidParameterError),
        (lambda: small_sky().luminance([[0, 0, 1], [0, 1]]), InvalidDirectionError),
        (lambda: small_sky().luminance(["up", "north", "east"]), InvalidDirectionError),
        (lambda: small_sky().luminance("zenith"), InvalidDirectionError),
        (lambda: write_png("folder.png", np.ones((2, 2, 3))), OutputError),
        (lambda: write_exr("folder.exr", [[1, 2], [3]]), (OutputError, InvalidParameterError)),
        (lambda: write_exr("x.exr", [["a", "b", "c"]]), InvalidParameterError),
    ],
)
def test_api_answers_bad_input_with_library_errors(tmp_path, monkeypatch, call, error):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "folder.png").mkdir()
    (tmp_path / "folder.exr").mkdir()
    with pytest.raises(error):
        call()
    assert issubclass(error if isinstance(error, type) else error[0], SkyscatterError)


def test_empty_out_path_is_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "sky", "--width", "8", "--out", "")
    assert code == 2 and one_line(err) and "must name a file" in err
    assert list(tmp_path.iterdir()) == []


# ---- item 8: leading minus, physical bounds, DEM files ---------------------------------------------------------

@pytest.mark.parametrize(
    "args,message",
    [
        (["sky", "--turbidity", "-inf"], "expected a finite number, got '-inf'"),
        (["sky", "--turbidity", "-3"], "turbidity -3 is outside"),
        (["sky", "--time", "-2000-01-01T00:00", "--lat", "1", "--lon", "2"], "years before 1 are not supported"),
        (["sky", "--sun-azimuth", "-400"], "expected a number in [-360, 360], got -400"),
        (["precompute", "--wavelengths", "-5,10,20"], "-5 nm is not a wavelength"),
        (["sky", "--model", "cie", "--diffuse-illuminance", "1e308"], "exceeds the extraterrestrial solar illuminance"),
        (["sky", "--model", "cie", "--zenith-luminance", "1e308"], "exceeds the luminance of the solar disc"),
        (["sky", "--model", "perez", "--dni", "1e6", "--dhi", "1e6"], "exceeds the extraterrestrial solar irradiance"),
        (["sky", "--model", "perez", "--dni", "600", "--dhi", "2000"], "diffuse_horizontal_irradiance 2000 W m^-2"),
        (["illuminance", "--model", "perez", "--dni", "1e6", "--dhi", "100"], "1414 W m^-2"),
        (["demo", "--exposure", "1e308"], "expected a number in [-30, 30]"),
        (["demo", "--out-dir", "afile"], "is a file, not a folder"),
    ],
)
def test_bad_values_get_the_real_reason_in_one_line(tmp_path, monkeypatch, capsys, args, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("x")
    t0 = time.perf_counter()
    code, out, err = run(capsys, *args)
    assert code == 2 and one_line(err), err
    assert message in err
    assert "expected one argument" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]
    assert time.perf_counter() - t0 < 30  # refused before any rendering or table build


def test_option_missing_its_value_still_says_so(capsys):
    code, out, err = run(capsys, "sky", "--turbidity", "--width", "8")
    assert code == 2 and "expected one argument" in err


def test_bad_dem_files_get_a_clear_message(tmp_path):
    from skyscatter.render.terrain import Terrain

    (tmp_path / "garbage.npy").write_bytes(b"this is not numpy at all" * 10)
    np.save(tmp_path / "objects.npy", np.array([{"a": 1}, None], dtype=object), allow_pickle=True)
    huge = tmp_path / "huge.npy"
    with open(huge, "wb") as fh:  # a header claiming 1e6 x 1e6 heights, no data
        np.lib.format.write_array_header_1_0(fh, {"descr": "<f8", "fortran_order": False,
                                                  "shape": (1_000_000, 1_000_000)})
    for name, pattern in (("garbage.npy", "not a NumPy .npy file"), ("objects.npy", "holds object values"),
                          ("huge.npy", "1000000 x 1000000 samples is larger than")):
        with pytest.raises(FileFormatError, match=pattern) as info:
            Terrain.load(tmp_path / name, spacing=30.0)
        assert "allow_pickle" not in str(info.value) and "smaller image" not in str(info.value)


# ---- item 9: one-line warnings in the CLI ---------------------------------------------------------------------

def test_cli_prints_library_warnings_on_one_line(tmp_path, monkeypatch, capsys):
    import skyscatter.cli.sun as sun_cmd

    def noisy(args):
        warnings.warn("rebuilding cached atmosphere tables: checksum mismatch", UserWarning, stacklevel=1)
        return 0

    real_register = sun_cmd.register

    def register(sub):
        real_register(sub)
        sub.choices["sun"].set_defaults(func=noisy)

    monkeypatch.setattr(sun_cmd, "register", register)
    code, out, err = run(capsys, "sun", "--lat", "1", "--lon", "1", "--time", "2024-01-01T12:00Z")
    assert code == 0
    assert err == "skyscatter: warning: rebuilding cached atmosphere tables: checksum mismatch\n"


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0 or shutil.which("setpriv") is None,
                    reason="needs root to switch to an unprivileged user (setpriv)")
def test_export_luts_refuses_a_read_only_folder_before_building_tables(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    os.chmod(ro, 0o555)
    os.chmod(tmp_path, 0o755)
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": "/nonexistent", "PYTHONPATH": str(SRC),
           "SKYSCATTER_CACHE_DIR": str(tmp_path / "cache"), "NUMBA_CACHE_DIR": str(tmp_path / "nc")}
    cmd = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", "--inh-caps=+dac_read_search",
           "--ambient-caps=+dac_read_search", sys.executable, "-m", "skyscatter", "export-luts",
           "--out-dir", str(ro / "luts")]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and one_line(proc.stderr), proc.stderr
    assert "cannot create the folder" in proc.stderr and "luts" in proc.stderr
    assert time.perf_counter() - t0 < 30


# ---- item 10: output folders are created ----------------------------------------------------------------------

def test_demo_creates_its_output_folder(tmp_path, capsys):
    target = tmp_path / "renders" / "deeper"
    code, out, err = run(capsys, "demo", "--figure", "8", "--no-glare", "--width", "8", "--height", "6",
                         "--out-dir", target)
    assert code == 0, err
    assert (target / "fig8.png").is_file() and (target / "fig8b_preetham.exr").is_file()
