"""Benchmark the Hosek-Wilkie sky (issue 10) side by side with Mitsuba 3's ``sunsky`` on the same directions.

Run: python benchmarks/bench_hosek_wilkie.py   (prints the figures; target: faster per direction than Mitsuba's
scalar variant); ``python benchmarks/bench_hosek_wilkie.py --rounds=N``: ``luminance`` (10^6 directions) and
``spectral_radiance`` at 41 wavelengths in N rounds alternating with Mitsuba's LLVM RGB sunsky, per-round ratios
(needs ``DRJIT_LIBLLVM_PATH``, below). Mitsuba's scalar variants are called once per direction from Python (the
only way to use them from Python; the binding overhead is part of what a Python caller pays); its LLVM variants take
all directions in one call (timed after a warm-up call that JIT-compiles the kernel). The spectral figures are for
the 11 bands 320-720 nm: three calls of Mitsuba's 4-wavelength spectrum per direction, one call of ours. Mitsuba
evaluates the sky only (``sun_scale`` 0), like skyscatter's ``spectral_radiance``.

The LLVM variants run in a child process: with the system's LLVM 15 Dr.Jit 1.5's LLVM backend aborts the whole
process ("LLVM ERROR: Cannot select ... fminimum": LLVM 15 cannot lower the ``llvm.minimum`` intrinsic on x86).
Point ``DRJIT_LIBLLVM_PATH`` at a newer libLLVM (the recorded figures used LLVM 22) to get them.
"""

from __future__ import annotations

import math
import os
import platform
import subprocess
import sys
import time

import numpy as np

from skyscatter import HosekWilkieSky
from skyscatter.conventions import direction_from_angles
from skyscatter.sky.hosek_wilkie import BANDS


def best_of(fn, repeats=5):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times), float(np.median(times))


def report(name: str, n: int, best: float, med: float) -> None:
    print(f"{name:58s} {n:8d} dirs: best {best:8.4f} s, median {med:8.4f} s -> {n / best / 1e6:8.3f} M dir/s "
          f"({best / n * 1e9:8.1f} ns/dir)")


ZEN, AZI, T, A = math.radians(50.0), math.radians(140.0), 3.0, 0.1


def directions(n: int) -> np.ndarray:
    rng = np.random.default_rng(0)
    return direction_from_angles(np.arccos(rng.uniform(0, 1, n)), rng.uniform(0, 2 * np.pi, n))


def main(n: int = 262144, n_scalar: int = 4000) -> None:
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}, "
          f"{os.cpu_count()} cpus, load average {os.getloadavg()[0]:.1f}")
    d = directions(n)
    zen, azi, t, a = ZEN, AZI, T, A
    sky = HosekWilkieSky(zen, azi, turbidity=t, ground_albedo=a)
    sky.spectral_radiance(d[:10], BANDS)
    report("skyscatter HosekWilkieSky.spectral_radiance (11 bands)", n,
           *best_of(lambda: sky.spectral_radiance(d, BANDS)))
    report("skyscatter HosekWilkieSky.xyz (XYZ dataset)", n, *best_of(lambda: sky.xyz(d)))
    report("skyscatter HosekWilkieSky.rgb (RGB dataset)", n, *best_of(lambda: sky.rgb(d)))
    report("skyscatter HosekWilkieSky.spectral_radiance (11 bands)", n_scalar,
           *best_of(lambda: sky.spectral_radiance(d[:n_scalar], BANDS)))
    report("skyscatter HosekWilkieSky() construction (per sky)", 1,
           *best_of(lambda: HosekWilkieSky(zen, azi, turbidity=t, ground_albedo=a)))
    try:
        import mitsuba as mi
    except ImportError:
        print("mitsuba not installed: no comparison")
        return
    print(f"mitsuba {mi.__version__}")
    s = sky.sun_direction.tolist()
    bands = [BANDS[0:4], BANDS[4:8], np.concatenate([BANDS[8:11], [720.0]])]

    mi.set_variant("scalar_spectral")
    em = mi.load_dict({"type": "sunsky", "sun_direction": s, "turbidity": t, "albedo": a, "sun_scale": 0.0})
    sub = d[:n_scalar]
    specs = [mi.Spectrum(b) for b in bands]

    def scalar_spectral():
        si = mi.SurfaceInteraction3f()
        for v in sub:
            si.wi = mi.Vector3f(-v[0], -v[1], -v[2])
            for sp in specs:
                si.wavelengths = sp
                em.eval(si)

    report("mitsuba scalar_spectral sunsky eval (11 bands, 3 calls)", n_scalar, *best_of(scalar_spectral, 3))

    mi.set_variant("scalar_rgb")
    em = mi.load_dict({"type": "sunsky", "sun_direction": s, "turbidity": t, "albedo": a, "sun_scale": 0.0})

    def scalar_rgb():
        si = mi.SurfaceInteraction3f()
        for v in sub:
            si.wi = mi.Vector3f(-v[0], -v[1], -v[2])
            em.eval(si)

    report("mitsuba scalar_rgb sunsky eval (RGB)", n_scalar, *best_of(scalar_rgb, 3))
    for variant in ("llvm_ad_spectral", "llvm_ad_rgb"):
        run = subprocess.run([sys.executable, __file__, variant, str(n)], capture_output=True, text=True)
        lines = [ln for ln in run.stdout.splitlines() if ln.startswith("mitsuba")]
        if run.returncode == 0 and lines:
            print(*lines, sep="\n")
        else:
            err = [ln for ln in run.stderr.splitlines() if "ERROR" in ln or "Error" in ln][:1]
            print(f"mitsuba {variant}: failed (exit {run.returncode}): {err[0] if err else run.stderr[-200:]}")


def llvm(variant: str, n: int) -> None:
    """Mitsuba's LLVM variant on the same directions (child process: see the module docstring)."""
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(variant)
    d = directions(n)
    s = HosekWilkieSky(ZEN, AZI).sun_direction.tolist()
    bands = [BANDS[0:4], BANDS[4:8], np.concatenate([BANDS[8:11], [720.0]])]
    em = mi.load_dict({"type": "sunsky", "sun_direction": s, "turbidity": T, "albedo": A, "sun_scale": 0.0})
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(-d[:, 0], -d[:, 1], -d[:, 2])
    if variant.endswith("spectral"):
        waves = [mi.Spectrum(*[mi.Float(np.full(n, w)) for w in b]) for b in bands]

        def run():
            for w in waves:
                si.wavelengths = w
                dr.eval(em.eval(si))
            dr.sync_thread()  # Dr.Jit launches kernels asynchronously: wait for them
    else:

        def run():
            dr.eval(em.eval(si))
            dr.sync_thread()

    run()
    name = "11 bands, 3 calls" if variant.endswith("spectral") else "RGB"
    report(f"mitsuba {variant} sunsky eval ({name})", n, *best_of(run, 3))
    if not variant.endswith("spectral"):
        def numpy_to_numpy():
            # What a Python caller pays: directions from numpy in, radiance as numpy out.
            s2 = dr.zeros(mi.SurfaceInteraction3f, n)
            s2.wi = mi.Vector3f(np.ascontiguousarray(-d[:, 0]), np.ascontiguousarray(-d[:, 1]),
                                np.ascontiguousarray(-d[:, 2]))
            return np.array(em.eval(s2))

        numpy_to_numpy()
        report(f"mitsuba {variant} sunsky, numpy in -> numpy out ({name})", n, *best_of(numpy_to_numpy, 3))


def side_by_side(rounds: int, n: int, repeat: int = 5) -> None:
    """``HosekWilkieSky.luminance`` and ``spectral_radiance`` (41 wavelengths) in rounds alternating with
    Mitsuba's ``llvm_ad_rgb`` sunsky (child process, numpy in -> numpy out and on device), so that both see the
    same load; per-round ratios, best and median over the rounds, and the load average."""
    d = directions(n)
    sky = HosekWilkieSky(ZEN, AZI, turbidity=T, albedo=A)
    sky.luminance(d[:10])
    sky.spectral_radiance(d[:10])
    ours, spec, theirs_np, theirs_dev, loads = [], [], [], [], []
    for k in range(rounds):
        loads.append(os.getloadavg()[0])
        t = best_of(lambda: sky.luminance(d), repeat)[0]
        ts = best_of(lambda: sky.spectral_radiance(d[: n // 4]), max(1, repeat // 2))[0]
        run = subprocess.run([sys.executable, __file__, "llvm_ad_rgb", str(n)], capture_output=True, text=True)
        lines = [ln for ln in run.stdout.splitlines() if ln.startswith("mitsuba")]
        if run.returncode != 0 or not lines:
            print(f"mitsuba llvm_ad_rgb: not measured (exit {run.returncode}; set DRJIT_LIBLLVM_PATH)")
            return
        ns = {("device" if "eval" in ln else "numpy"): float(ln.rsplit("(", 1)[1].split("ns/dir")[0])
              for ln in lines}
        ours.append(t / n * 1e9)
        spec.append(n / 4 / ts / 1e6)
        theirs_np.append(ns["numpy"])
        theirs_dev.append(ns["device"])
        print(f"round {k + 1} (load {loads[-1]:.1f}): HosekWilkieSky.luminance {ours[-1]:6.1f} ns/dir; Mitsuba "
              f"llvm_ad_rgb numpy in -> out {ns['numpy']:6.1f}, on device {ns['device']:6.1f} ns/dir; "
              f"spectral_radiance 41 wl {spec[-1]:5.2f} M dir/s")
    r_np = np.array(theirs_np) / np.array(ours)
    r_dev = np.array(theirs_dev) / np.array(ours)
    print(f"luminance, {n} dirs, {rounds} rounds, load {min(loads):.1f}-{max(loads):.1f}: ours best "
          f"{min(ours):.1f} / median {np.median(ours):.1f} ns/dir; Mitsuba numpy best {min(theirs_np):.1f} / median "
          f"{np.median(theirs_np):.1f}, device best {min(theirs_dev):.1f} / median {np.median(theirs_dev):.1f} ns/dir; "
          f"speed ratio ours/Mitsuba per round: numpy {r_np.min():.2f}-{r_np.max():.2f} (median "
          f"{np.median(r_np):.2f}), device {r_dev.min():.2f}-{r_dev.max():.2f} (median {np.median(r_dev):.2f})")
    print(f"spectral_radiance 41 wl, {n // 4} dirs: best {max(spec):.2f} / median {np.median(spec):.2f} M dir/s")


if __name__ == "__main__":
    if len(sys.argv) == 3:
        llvm(sys.argv[1], int(sys.argv[2]))
    elif len(sys.argv) == 2 and sys.argv[1].startswith("--rounds="):
        side_by_side(int(sys.argv[1].split("=", 1)[1]), 1_000_000)
    else:
        main()
