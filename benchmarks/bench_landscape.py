"""Benchmark: a 1280 x 720 landscape with aerial perspective and glare (target < 10 s on 2 cores).

    python benchmarks/bench_landscape.py [--width 1280 --height 720] [--wavelength-step 10] [--repeat 3]
    python benchmarks/bench_landscape.py --clouds --width 640 --height 360 [--no-glare]

Renders Figure 7b of the demo (built-in terrain, evening Preetham sky, T = 2, analytic aerial perspective,
glare on) and prints the time of each stage. ``--clouds``: the demo's broken-cumulus panel instead (``demo
--figure clouds`` a: the ``broken-cloud`` sky, procedural field of cover 0.4, seed 1, sun 30 deg high at azimuth
200 deg, analytic aerial perspective T = 2.5, the camera looking west; the terrain lit through the field's
shadows; target <= 20 s at 640 x 360 on 2 cores); the sky's set-up (the field's generation, its shadow volume)
is timed on its own. The first render also pays for generating the terrain, loading
numba's compiled kernels and building the glare kernel; the table reports every run so warm and cold runs can
be told apart; each run also gives the process's CPU time (``time.process_time``, all threads: the figure that
does not move with the load of the shared machine) and the load average. Prints figures only (no assertions).
"""

from __future__ import annotations

import argparse
import math
import os
import time


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--height", type=int, default=720)
    parser.add_argument("--wavelength-step", type=float, default=10.0, help="spectral sampling [nm]")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-glare", dest="glare", action="store_false")
    parser.add_argument("--clouds", action="store_true", help="the demo's broken-cumulus panel (module docstring)")
    args = parser.parse_args()

    t_import = time.perf_counter()
    from skyscatter import PreethamSky
    from skyscatter.render.camera import PinholeCamera
    from skyscatter.render.scene import Scene
    from skyscatter.render.terrain import default_terrain
    from skyscatter.spectral import wavelength_grid

    t_import = time.perf_counter() - t_import
    terrain_t = time.perf_counter()
    terrain = default_terrain()
    terrain_t = time.perf_counter() - terrain_t
    aerial = "preetham"
    if args.clouds:
        from skyscatter.aerial import PreethamAerialPerspective
        from skyscatter.sky.broken_cloud import BrokenCloudSky

        t0, c0 = time.perf_counter(), time.process_time()
        sky = BrokenCloudSky(math.radians(60.0), math.radians(200.0), cloud_cover=0.4, cloud_seed=1)
        t1, c1 = time.perf_counter(), time.process_time()
        sky.xyz([[0.0, 0.0, 1.0]])  # the field, its shadow volume and the air's light
        print(f"broken-cloud sky set-up {time.perf_counter() - t0:.2f} s, CPU {time.process_time() - c0:.2f} s "
              f"(of it the field {t1 - t0:.2f} s, CPU {c1 - c0:.2f} s; then shadow volume, tables)")
        aerial = PreethamAerialPerspective(sky, method="analytic", turbidity=2.5)
    else:
        sky = PreethamSky(2.0, math.radians(86.0), math.radians(290.0))
    z = float(terrain.height_at(12_000.0, 0.0)) + 300.0
    camera = PinholeCamera.from_degrees((12_000.0, 0.0, z), 270.0, -3.0, 60.0)
    wl = wavelength_grid(380.0, 780.0, args.wavelength_step)
    print(f"{args.width} x {args.height}, {wl.size} wavelengths, glare {'on' if args.glare else 'off'}; "
          f"cpus: {os.cpu_count()}, load average: {', '.join(f'{v:.2f}' for v in os.getloadavg())}")
    print(f"import {t_import:.2f} s, terrain synthesis {terrain_t:.2f} s")
    stages = ["setup", "intersection", "shading", "aerial_perspective", "sky", "colour", "glare", "total"]
    print("run  " + "  ".join(f"{s:>18}" for s in stages) + "   scene build   CPU (build + render)   load")
    for run in range(args.repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        scene = Scene(sky, terrain=terrain, camera=camera, wavelengths=wl, aerial=aerial)
        build = time.perf_counter() - t0
        result = scene.render(args.width, args.height, glare=args.glare)
        cpu = time.process_time() - c0
        row = "  ".join(f"{result.timings[s]:>17.2f}s" for s in stages)
        print(f"{run:>3}  {row}   {build:.2f} s   {cpu:.2f} s   {os.getloadavg()[0]:.1f}", flush=True)


if __name__ == "__main__":
    main()
