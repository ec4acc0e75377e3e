"""The spellings the glossary replaced (docs/conventions.md, "Glossary") still work for one release, with a warning.

Python keywords and attributes give a DeprecationWarning naming the new spelling and the same result; a sky
dictionary saved with the old keys loads; the command line prints one warning line and does the same work.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.cli import main
from skyscatter.errors import InvalidParameterError
from skyscatter.precomputed import PrecomputedAtmosphere, cached_atmosphere
from skyscatter.precomputed.cache import resolve_atmosphere
from skyscatter.sky import BrunetonSky, HosekWilkieSky, registry

TINY = dict(transmittance_mu=16, transmittance_r=4, irradiance_mu_s=4, irradiance_r=4, scattering_r=4,
            scattering_mu=8, scattering_mu_s=4, scattering_nu=2)
TINY_FLAGS = ["--transmittance-size", "16x4", "--irradiance-size", "4x4", "--scattering-size", "4x8x4x2",
              "--orders", "1"]


@pytest.fixture(scope="module")
def tiny_rgb():
    return cached_atmosphere(orders=1, sizes=TINY, tables="rgb", progress=False)


def test_table_keywords_old_spellings_warn_and_give_the_same_tables(tiny_rgb, monkeypatch):
    with pytest.warns(DeprecationWarning, match="use tables=<name>"):
        old = cached_atmosphere(orders=1, sizes=TINY, wavelengths="rgb", progress=False)
    assert old is tiny_rgb  # the same cache key, so the same tables from memory
    with pytest.warns(DeprecationWarning, match="params is deprecated.*use atmosphere"):
        again = cached_atmosphere(params=AtmosphereParameters(), orders=1, sizes=TINY, tables="rgb", progress=False)
    assert again is tiny_rgb
    import skyscatter.precomputed.cache as cache

    monkeypatch.setattr(cache, "cached_atmosphere", lambda atmosphere=None, **kw: (kw["tables"], tiny_rgb)[1])
    with pytest.warns(DeprecationWarning, match="use tables"):
        assert resolve_atmosphere(None, wavelengths="rgb") is tiny_rgb
    monkeypatch.undo()
    with pytest.warns(DeprecationWarning, match="params is deprecated"):
        computed = PrecomputedAtmosphere.compute(params=AtmosphereParameters(), orders=1, sizes=TINY, tables="rgb",
                                                 progress=False)
    assert computed.cache_key == tiny_rgb.cache_key
    with pytest.raises(InvalidParameterError, match="not both"):
        cached_atmosphere(orders=1, sizes=TINY, tables="rgb", wavelengths=[440.0, 550.0], progress=False)


def test_bruneton_sky_old_keywords(tiny_rgb):
    new = BrunetonSky(0.6, 1.0, precomputed=tiny_rgb)
    with pytest.warns(DeprecationWarning, match="use precomputed=<tables>"):
        old = BrunetonSky(0.6, 1.0, atmosphere=tiny_rgb)
    d = np.array([[0.0, 0.0, 1.0], [0.5, 0.5, math.sqrt(0.5)]])
    np.testing.assert_array_equal(old.luminance(d), new.luminance(d))
    with pytest.warns(DeprecationWarning, match="BrunetonSky.precomputed"):
        assert new.atmosphere is tiny_rgb
    with pytest.warns(DeprecationWarning, match="albedo is deprecated.*use ground_albedo"):
        with pytest.raises(InvalidParameterError, match="not with precomputed tables"):
            BrunetonSky(0.6, 1.0, precomputed=tiny_rgb, albedo=0.3)
    with pytest.raises(InvalidParameterError, match="give ground_albedo only"):
        BrunetonSky(0.6, 1.0, albedo=0.3, ground_albedo=0.3)


def test_bruneton_sky_old_keywords_reach_the_same_atmosphere(monkeypatch, tiny_rgb):
    import skyscatter.precomputed.cache as cache

    asked = []

    def fake(atmosphere=None, **kwargs):
        asked.append((atmosphere.canonical_json(), kwargs.get("tables")))
        return tiny_rgb

    monkeypatch.setattr(cache, "cached_atmosphere", fake)
    BrunetonSky(0.5, 0.0, ground_albedo=0.3, tables="rgb")
    with pytest.warns(DeprecationWarning) as record:
        BrunetonSky(0.5, 0.0, albedo=0.3, wavelengths="rgb")
    assert {str(w.message).split(":")[1].split()[0] for w in record} == {"albedo", "wavelengths"}
    assert asked[0] == asked[1]


def test_hosek_wilkie_old_albedo():
    with pytest.warns(DeprecationWarning, match="use ground_albedo"):
        old = HosekWilkieSky(0.5, 0.0, turbidity=4.0, albedo=0.3)
    new = HosekWilkieSky(0.5, 0.0, turbidity=4.0, ground_albedo=0.3)
    d = np.array([0.0, 0.6, 0.8])
    np.testing.assert_array_equal(old.spectral_radiance(d), new.spectral_radiance(d))
    with pytest.warns(DeprecationWarning, match="HosekWilkieSky.ground_albedo"):
        assert old.albedo == 0.3
    with pytest.warns(DeprecationWarning, match="use ground_albedo"):
        built = registry.build("hosek-wilkie", 0.5, 0.0, turbidity=4.0, albedo=0.3)
    assert built.to_dict() == new.to_dict()


def test_saved_sky_dictionaries_with_the_old_keys_load():
    new = HosekWilkieSky(0.5, 0.2, turbidity=4.0, ground_albedo=0.3).to_dict()
    assert new["parameters"] == {"turbidity": 4.0, "ground_albedo": 0.3}
    old = {**new, "parameters": {"turbidity": 4.0, "albedo": 0.3}}
    with pytest.warns(DeprecationWarning, match="hosek-wilkie sky dictionary: albedo is deprecated"):
        assert registry.from_dict(old).to_dict() == new


def test_bruneton_scene_old_keywords(monkeypatch):
    import skyscatter.render.bruneton as rb

    seen = {}

    class Stop(Exception):
        pass

    def fake_sky(*args, **kwargs):
        seen.update(kwargs)
        raise Stop

    monkeypatch.setattr(rb, "BrunetonSky", fake_sky)
    with pytest.warns(DeprecationWarning) as record, pytest.raises(Stop):
        rb.bruneton_scene(None, type("C", (), {"position": (0.0, 0.0, 10.0)})(), 1.0, 0.0, albedo=0.3,
                          table_wavelengths="rgb")
    assert seen["tables"] == "rgb" and len(record) == 2


def test_scene_old_albedo():
    from skyscatter.render.camera import PinholeCamera
    from skyscatter.render.scene import Scene
    from skyscatter.render.terrain import Terrain
    from skyscatter.sky import PreethamSky

    sky = PreethamSky(2.5, 0.8, 3.0)
    terrain = Terrain.from_north_up(np.zeros((8, 8)), 50.0)
    camera = PinholeCamera((200.0, 200.0, 100.0), 0.0, -0.3, 1.0)
    new = Scene(sky, terrain=terrain, camera=camera, aerial=None, terrain_albedo=0.3, sun_disc=False).render(8, 6)
    with pytest.warns(DeprecationWarning, match="use terrain_albedo"):
        old = Scene(sky, terrain=terrain, camera=camera, aerial=None, albedo=0.3, sun_disc=False).render(8, 6)
    np.testing.assert_array_equal(old.rgb, new.rgb)


def _cli(capsys, *args):
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_old_table_and_albedo_options(tmp_path, capsys):
    code, out, err = _cli(capsys, "precompute", "--out", str(tmp_path / "old.npz"), *TINY_FLAGS, "--albedo", "0.3",
                          "--wavelengths", "rgb", "--no-progress")
    assert code == 0, err
    assert "--albedo is deprecated" in err and "use --ground-albedo" in err
    assert "--wavelengths rgb is deprecated" in err and "use --tables rgb" in err
    code, out, err = _cli(capsys, "precompute", "--out", str(tmp_path / "new.npz"), *TINY_FLAGS, "--ground-albedo",
                          "0.3", "--tables", "rgb", "--no-progress")
    assert code == 0 and "deprecated" not in err
    old, new = (PrecomputedAtmosphere.load(tmp_path / f"{n}.npz") for n in ("old", "new"))
    assert old.cache_key == new.cache_key


def test_cli_sky_old_options(tmp_path, capsys):
    code, out, err = _cli(capsys, "sky", "--model", "hosek-wilkie", "--albedo", "0.3", "--width", "16",
                          "--out", str(tmp_path / "a.exr"))
    assert code == 0 and "ground_albedo=0.3" in out and "use --ground-albedo" in err
    # --ground-albedo with a sky without a ground was the ground drawn below the horizon: now --terrain-albedo
    code, out, err = _cli(capsys, "sky", "--model", "preetham", "--ground-albedo", "0.5", "--width", "16",
                          "--out", str(tmp_path / "b.exr"))
    assert code == 0 and "use --terrain-albedo" in err
    code, out, err = _cli(capsys, "sky", "--model", "preetham", "--terrain-albedo", "0.5", "--width", "16",
                          "--out", str(tmp_path / "c.exr"))
    assert code == 0 and err == ""
    from skyscatter.render import read_exr

    np.testing.assert_array_equal(read_exr(tmp_path / "b.exr"), read_exr(tmp_path / "c.exr"))


def _parse(*args):
    from skyscatter.cli import build_parser

    return build_parser(args[0]).parse_args(list(args))


def test_cli_demo_and_reference_old_options(capsys):
    from skyscatter.cli import demo

    args = _parse("demo", "--sky", "cie", "--albedo", "0.3", "--wavelengths", "rgb")
    err = capsys.readouterr().err
    assert all(f"{o} is deprecated" in err for o in ("--sky", "--albedo", "--wavelengths"))
    assert args.terrain_albedo == 0.3 and args.tables == "rgb"
    demo._old_sky_option(args)
    assert args.model == "cie"
    args = _parse("demo", "--sky", "cie", "--model", "preetham")  # the old pair: atmosphere preetham, sky cie
    demo._old_sky_option(args)
    assert args.model == "cie"
    args = _parse("demo", "--sky", "cie", "--model", "bruneton")
    with pytest.raises(InvalidParameterError, match="--sky does not apply to --model bruneton"):
        demo._old_sky_option(args)
    args = _parse("reference", "r.zarr", "--albedo", "0.1,0.3")
    assert args.albedo == [0.1, 0.3] and "use --ground-albedo" in capsys.readouterr().err
    assert isinstance(args, argparse.Namespace)
