"""The Zarr reference front end (skyscatter.montecarlo.dataset) and the ``skyscatter reference`` command."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("xarray")
pytest.importorskip("zarr")

from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.cli import main  # noqa: E402
from skyscatter.errors import InvalidParameterError, OutputError  # noqa: E402
from skyscatter.montecarlo import sky_radiance  # noqa: E402
from skyscatter.montecarlo.dataset import equal_area_directions, reference  # noqa: E402

JOB = dict(sun_elevations=np.radians([40.0, -2.0]), turbidities=[2.0, 5.0], albedos=[0.2], wavelengths=[450.0, 600.0],
           directions=equal_area_directions(3), samples=48, seed=2, scheduler="synchronous")


def test_equal_area_directions():
    d = equal_area_directions(2000)
    assert np.allclose(np.linalg.norm(d, axis=-1), 1) and np.all(d[:, 2] > 0)
    # equal area: the fraction with cos(zenith) > 0.5 is one half of the hemisphere's points
    assert abs(np.mean(d[:, 2] > 0.5) - 0.5) < 1e-3


def test_reference_is_resumable_and_equals_direct_calls(tmp_path):
    store = tmp_path / "ref.zarr"

    class Stop(Exception):
        pass

    calls = []

    def interrupt(done, total):
        calls.append(done)
        if done == 2:  # the second cell's task: its cell is not marked done
            raise Stop

    with pytest.raises(Stop):
        reference(store, **JOB, progress=interrupt)
    import xarray as xr

    partial = xr.open_zarr(store, consolidated=False)
    assert int(partial["done"].sum()) == 1
    seen = []
    ds = reference(store, **JOB, progress=lambda d, t: seen.append((d, t)))
    assert seen[-1] == (3, 3)  # only the 3 remaining cells ran
    assert bool(ds["done"].all())
    assert ds.attrs["seed"] == 2 and "atmosphere" in ds.attrs["job"]
    # every cell equals a direct call with the same seed
    atm = AtmosphereParameters().replace(ground_albedo=0.2, mie_angstrom_alpha=1.3,
                                         mie_angstrom_beta=0.04608 * 5.0 - 0.04586)
    direct = sky_radiance(atm, JOB["directions"], JOB["wavelengths"], sun_zenith=math.radians(92.0), samples=48,
                          seed=2)
    np.testing.assert_array_equal(ds["radiance"].values[1, 1, 0], direct.radiance)
    np.testing.assert_array_equal(ds["stderr"].values[1, 1, 0], direct.stderr)
    assert np.all(np.isfinite(ds["solar_disc"].values))


def test_reference_refuses_a_store_of_another_job(tmp_path):
    store = tmp_path / "ref.zarr"
    small = {**JOB, "sun_elevations": [0.5], "turbidities": [2.0]}
    reference(store, **small)
    before = sorted(p.name for p in store.rglob("*"))
    with pytest.raises(OutputError, match="different reference job"):
        reference(store, **{**small, "seed": 3})
    with pytest.raises(OutputError, match="different reference job"):
        reference(store, **{**small, "albedos": [0.3]})
    assert sorted(p.name for p in store.rglob("*")) == before
    (tmp_path / "junk.zarr").mkdir()
    (tmp_path / "junk.zarr" / "x").write_text("x")
    with pytest.raises(OutputError):
        reference(tmp_path / "junk.zarr", **small)


@pytest.mark.parametrize("change", [dict(turbidities=[0.5]), dict(albedos=[1.5]), dict(sun_elevations=[2.0]),
                                    dict(wavelengths=[300.0]), dict(samples=0), dict(aerosol_optical_depths=[0.1])])
def test_reference_bad_input(tmp_path, change):
    with pytest.raises(InvalidParameterError):
        reference(tmp_path / "x.zarr", **{**JOB, **change})
    assert not (tmp_path / "x.zarr").exists()


def test_cli_reference(tmp_path, capsys):
    store = tmp_path / "cli.zarr"
    args = ["reference", str(store), "--sun-elevation", "30", "--directions", "2", "--samples", "32",
            "--wavelengths", "500,600", "--no-progress", "--scheduler", "synchronous"]
    assert main(args) == 0
    assert "1 cells x 2 directions x 2 wavelengths" in capsys.readouterr().out
    assert main(args) == 0  # resume: nothing to do
    assert main([*args, "--seed", "5"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "different reference job" in err[0]
    # --phase sets the atmosphere's aerosol phase function, which is part of the job
    assert main([*args, "--phase", "henyey-greenstein"]) == 2
    assert "different reference job" in capsys.readouterr().err
    hg = tmp_path / "hg.zarr"
    assert main([*args[:1], str(hg), *args[2:], "--phase", "henyey-greenstein"]) == 0
    import xarray as xr

    assert xr.open_zarr(hg, consolidated=False).attrs["mie_phase_function"] == "henyey-greenstein"
    assert xr.open_zarr(store, consolidated=False).attrs["mie_phase_function"] == "cornette-shanks"
    assert main(["reference", str(tmp_path / "b.zarr"), "--wavelengths", "100", "--no-progress"]) == 2
    assert main(["reference", str(tmp_path / "b.zarr"), "--ground-albedo", "x"]) == 2
    assert main(["reference", str(tmp_path / "b.zarr"), "--turbidity", "2", "--aod", "0.1"]) == 2


def test_cli_reference_orders(tmp_path, capsys):
    """--orders: each window's store equals the direct call with that window; the windows 1, 2 and 3: add up to the
    store of every order (the same seed: the same paths); the window is part of the job; refusals."""
    import json

    import xarray as xr

    base = ["--sun-elevation", "30", "--directions", "2", "--samples", "64", "--wavelengths", "500,650",
            "--no-progress", "--scheduler", "synchronous", "--seed", "4"]
    stores = {}
    for window in ("all", "1", "2", "3:"):
        stores[window] = tmp_path / f"o{window.strip(':')}.zarr"
        assert main(["reference", str(stores[window]), *base, "--orders", window]) == 0
    capsys.readouterr()
    rad = {w: xr.open_zarr(p, consolidated=False)["radiance"].values[0, 0, 0] for w, p in stores.items()}
    assert np.all(rad["2"] > 0) and np.all(rad["3:"] > 0) and np.all(rad["1"] > rad["2"])
    np.testing.assert_allclose(rad["1"] + rad["2"] + rad["3:"], rad["all"], rtol=1e-12)
    atm = AtmosphereParameters().replace(mie_angstrom_alpha=1.3, mie_angstrom_beta=0.04608 * 2.5 - 0.04586)
    direct = sky_radiance(atm, equal_area_directions(2), [500.0, 650.0], sun_zenith=math.radians(60.0), samples=64,
                          seed=4, orders=2)
    np.testing.assert_allclose(rad["2"], direct.radiance, rtol=1e-12)  # the turbidity's beta to rounding
    job = json.loads(xr.open_zarr(stores["3:"], consolidated=False).attrs["job"])
    assert job["orders"] == [3, 100_000]
    assert "orders" not in json.loads(xr.open_zarr(stores["all"], consolidated=False).attrs["job"])
    assert main(["reference", str(stores["2"]), *base, "--orders", "1"]) == 2  # another job
    assert "different reference job" in capsys.readouterr().err
    for bad in ("0", "3:2", "x", "1:2:3"):
        assert main(["reference", str(tmp_path / "bad.zarr"), *base, "--orders", bad]) == 2
        assert "--orders" in capsys.readouterr().err
    assert main(["reference", str(tmp_path / "cloud.zarr"), *base, "--orders", "2", "--cloud-optical-depth",
                 "5"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "forward peak" in err[-1]
    assert not (tmp_path / "cloud.zarr").exists() and not (tmp_path / "bad.zarr").exists()


def test_an_aerosol_type_keeps_its_mie_optics_per_cell(tmp_path, capsys):
    """With a particle aerosol (an OPAC type) each cell is that aerosol at the cell's optical depth at 550 nm: its
    spectral shape (maritime-clean's Mie extinction, Angstrom exponent about 0.1, not the analytic aerosol's 1.3)
    and its single-scattering albedo kept. Turbidities are refused (they define an Angstrom aerosol), as are the
    command's --turbidity and --phase beside --aerosol (one line, exit 2)."""
    from skyscatter.montecarlo.dataset import make_job

    air = AtmosphereParameters.with_aerosol_type("maritime-clean", 0.1)
    job = make_job(sun_elevations=[0.5], albedos=[0.2, 0.4], wavelengths=[450.0], directions=[[0.0, 0.0, 1.0]],
                   aerosol_optical_depths=[0.05, 0.3], atmosphere=air)
    for k, tau in enumerate((0.05, 0.3)):
        cell = job.cell_atmosphere(k, 1)
        assert cell.ground_albedo_at([550.0])[0] == 0.4 and cell.aerosol is not None
        t450, t550 = cell.aerosol_component.optical_depth([450.0, 550.0], cell.thickness)
        assert t550 == pytest.approx(tau, rel=1e-9)
        # the type's own spectrum: its extinction ratio from the Mie optics of the preset at its default depth
        e450, e550 = air.aerosol.extinction_at([450.0, 550.0])
        assert t450 / t550 == pytest.approx(e450 / e550, rel=1e-9) and t450 / t550 < (450 / 550) ** -0.5
        np.testing.assert_allclose(cell.aerosol.single_scattering_albedo_at([450.0, 550.0]),
                                   air.aerosol.single_scattering_albedo_at([450.0, 550.0]), rtol=1e-12)
    with pytest.raises(InvalidParameterError, match="not turbidities"):
        make_job(sun_elevations=[0.5], albedos=[0.2], wavelengths=[450.0], directions=[[0.0, 0.0, 1.0]],
                 turbidities=[2.0], atmosphere=air)
    base = ["reference", str(tmp_path / "x.zarr"), "--aerosol", "maritime-clean", "--no-progress"]
    for extra in (["--turbidity", "3"], ["--phase", "henyey-greenstein"]):
        assert main([*base, *extra]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--aerosol" in err[0]
    assert not (tmp_path / "x.zarr").exists()
