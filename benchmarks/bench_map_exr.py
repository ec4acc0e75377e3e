"""A 2048 x 1024 environment map with its EXR file, side by side with Mitsuba 3's sunsky eval + EXR.

Ours: ``sky_image`` (equirect, sun disc, ground) of a Hosek-Wilkie and of a Bruneton sky (default 16-wavelength
tables, cached), then ``write_exr``. Mitsuba: its ``sunsky`` (``llvm_ad_rgb``, sun included) evaluated on the
same equirect directions in one vectorised call, then ``mi.Bitmap(...).write`` (Mitsuba's EXR writer, PIZ), in a
child process (its LLVM backend needs ``DRJIT_LIBLLVM_PATH``, see ``bench_hosek_wilkie.py``). Rounds alternate
ours and Mitsuba's so that both see the same load; each figure is the best of ``--repeat`` calls in its round.
Also the EXR writer alone with each lossless compression OpenEXR offers and that Mitsuba reads.

Usage: ``python benchmarks/bench_map_exr.py [--rounds N] [--repeat N]``.
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

WIDTH, HEIGHT = 2048, 1024
ZEN, AZI = math.radians(50.0), math.radians(140.0)


def best(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def mitsuba(repeat: int) -> None:
    """Child process: Mitsuba's sunsky on the equirect directions, then its EXR writer."""
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    from skyscatter import HosekWilkieSky

    s = HosekWilkieSky(ZEN, AZI).sun_direction.tolist()
    em = mi.load_dict({"type": "sunsky", "sun_direction": s, "turbidity": 3.0, "albedo": 0.1})
    u = (np.arange(WIDTH) + 0.5) / WIDTH
    v = (np.arange(HEIGHT) + 0.5) / HEIGHT
    phi, theta = np.meshgrid(2 * np.pi * u, np.pi * v)
    d = np.stack([np.sin(theta) * np.sin(phi), np.sin(theta) * np.cos(phi), np.cos(theta)], -1).reshape(-1, 3)
    out = Path(tempfile.mkdtemp()) / "m.exr"

    def run():
        si = dr.zeros(mi.SurfaceInteraction3f, d.shape[0])
        si.wi = mi.Vector3f(np.ascontiguousarray(-d[:, 0]), np.ascontiguousarray(-d[:, 1]),
                            np.ascontiguousarray(-d[:, 2]))
        img = np.array(em.eval(si)).reshape(HEIGHT, WIDTH, 3).astype(np.float32)
        mi.Bitmap(img).write(str(out))

    run()
    t = best(run, repeat)
    print(f"mitsuba llvm_ad_rgb sunsky eval + EXR: {t:.3f} s ({out.stat().st_size / 2**20:.1f} MiB)")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    from skyscatter import BrunetonSky, HosekWilkieSky
    from skyscatter.render.image_io import write_exr
    from skyscatter.render.sky_image import sky_image

    folder = Path(tempfile.mkdtemp())
    skies = {"Hosek-Wilkie": HosekWilkieSky(ZEN, AZI), "Bruneton": BrunetonSky(ZEN, AZI)}
    for sky in skies.values():
        sky_image(sky, projection="equirect", width=64)
    rows: dict[str, list[float]] = {}
    for k in range(args.rounds):
        load = os.getloadavg()[0]
        for name, sky in skies.items():
            def ours(sky=sky):
                write_exr(folder / "o.exr", sky_image(sky, projection="equirect", width=WIDTH))

            ours()
            t_map = best(lambda sky=sky: sky_image(sky, projection="equirect", width=WIDTH), args.repeat)
            t = best(ours, args.repeat)
            rows.setdefault(name, []).append(t)
            print(f"round {k + 1} (load {load:.1f}): {name} map {t_map:.3f} s, map + EXR {t:.3f} s "
                  f"({(folder / 'o.exr').stat().st_size / 2**20:.1f} MiB)")
        run = subprocess.run([sys.executable, __file__, "--mitsuba", str(args.repeat)], capture_output=True,
                             text=True)
        line = [ln for ln in run.stdout.splitlines() if ln.startswith("mitsuba")]
        if run.returncode or not line:
            print(f"mitsuba: not measured (exit {run.returncode}): {run.stderr.strip()[-200:]}")
            continue
        print(f"round {k + 1}: {line[0]}")
        rows.setdefault("Mitsuba", []).append(float(line[0].split(": ")[1].split(" s")[0]))
    for name, ts in rows.items():
        print(f"{name}: best {min(ts):.3f} s, median {np.median(ts):.3f} s over {len(ts)} rounds")
    if "Mitsuba" in rows:
        m = np.array(rows["Mitsuba"])
        for name in skies:
            r = np.array(rows[name][: m.size]) / m
            print(f"{name} / Mitsuba per round: {r.min():.2f}-{r.max():.2f} (median {np.median(r):.2f}; < 1 is faster)")
    return 0


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--mitsuba":
        mitsuba(int(sys.argv[2]))
    else:
        sys.exit(main())
