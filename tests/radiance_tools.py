"""Radiance's binaries (pyradiance) as the tests call them: run a program, trace sky radiance with rtrace, and
Radiance's azimuth convention (degrees west of south). A helper module shared by the Radiance peer tests."""

import math
import os
import subprocess

import numpy as np
import pytest

pyradiance = pytest.importorskip("pyradiance")

BIN = os.path.join(pyradiance.BINPATH)
ENV = dict(os.environ, RAYPATH=os.path.join(os.path.dirname(pyradiance.__file__), "lib"))
GLOW = "\nskyfunc glow skyglow\n0\n0\n4 1 1 1 0\n\nskyglow source sky\n0\n0\n4 0 0 1 180\n"


def run(*args, stdin=None):
    res = subprocess.run([os.path.join(BIN, args[0]), *map(str, args[1:])], input=stdin, capture_output=True,
                         env=ENV, check=True)
    return res.stdout


def trace(sky_text: bytes, dirs: np.ndarray, tmp_path) -> np.ndarray:
    """Radiance's sky radiance (grey: one channel) along directions (N, 3), via oconv + rtrace -ab 0."""
    scene = tmp_path / "sky.rad"
    scene.write_bytes(sky_text + GLOW.encode())
    octree = tmp_path / "sky.oct"
    octree.write_bytes(run("oconv", scene))
    rays = "".join(f"0 0 0 {x:.9f} {y:.9f} {z:.9f}\n" for x, y, z in dirs).encode()
    out = run("rtrace", "-h", "-ab", "0", "-ov", octree, stdin=rays)
    return np.array(out.split(), dtype=float).reshape(-1, 3)[:, 1]


def rad_azimuth(azimuth):
    return (math.degrees(azimuth) - 180.0) % 360.0
