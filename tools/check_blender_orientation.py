"""Check where Blender puts the sun of a skyscatter environment map (issue 12; docs/conventions.md).

Blender's Python module (PyPI ``bpy``) pins its own numpy, so run this in its own environment:

    python3.11 -m venv /work/bpy-venv && /work/bpy-venv/bin/pip install bpy
    /work/bpy-venv/bin/python tools/check_blender_orientation.py --skyscatter-python /work/venv/bin/python

For each sun position and layout it
1. writes the map with ``skyscatter sky --layout LAYOUT`` (run by the interpreter that has skyscatter);
2. loads it in Blender as a World Environment Texture with the default mapping (no Mapping node);
3. renders, with Cycles, a narrow pinhole camera aimed where the sun should be in a Z-up scene with north = +Y
   and east = +X (Blender's camera looks down its local -Z with +Y up; aimed with ``to_track_quat('-Z', 'Y')``),
   and finds the brightest pixel;
4. prints the angle between the brightest pixel's direction and the expected sun direction.

With ``--layout blender`` the sun must land where skyscatter says (offset below one pixel of the map). With
``--layout skyscatter`` (north at the centre column) the script also reports where the sun lands instead: Blender
puts the image centre on +X, so the map appears turned by +90 deg about Z (north on +X).
"""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
import tempfile
from pathlib import Path

SUNS = [(35.0, 120.0), (20.0, 300.0), (60.0, 10.0)]  # (elevation, azimuth) [deg], azimuth from north to east


def enu(elevation_deg: float, azimuth_deg: float) -> tuple[float, float, float]:
    """Unit vector (east, north, up) of a direction: Blender's (X, Y, Z) in a scene with north = +Y."""
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return (math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e))


def write_map(python: str, layout: str, elevation: float, azimuth: float, out: Path, width: int) -> None:
    cmd = [python, "-m", "skyscatter", "sky", "--layout", layout, "--width", str(width),
           "--sun-elevation", str(elevation), "--sun-azimuth", str(azimuth), "--out", str(out)]
    subprocess.run(cmd, check=True, capture_output=True, text=True)


def brightest_offset(exr: Path, aim: tuple[float, float, float], fov_deg: float = 20.0, size: int = 96):
    """Render the world through a camera aimed along ``aim``; angle [deg] of the brightest pixel off the aim."""
    import bpy
    import numpy as np
    from mathutils import Vector

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 4
    scene.cycles.use_denoising = False
    scene.render.resolution_x = scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"

    world = bpy.data.worlds.new("skyscatter")
    scene.world = world
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    env = nodes.new("ShaderNodeTexEnvironment")  # default mapping: no Mapping node
    env.image = bpy.data.images.load(str(exr))
    background = nodes["Background"]
    links.new(env.outputs["Color"], background.inputs["Color"])

    cam_data = bpy.data.cameras.new("cam")
    cam_data.angle = math.radians(fov_deg)
    cam = bpy.data.objects.new("cam", cam_data)
    scene.collection.objects.link(cam)
    scene.camera = cam
    cam.location = (0.0, 0.0, 0.0)
    cam.rotation_mode = "QUATERNION"
    cam.rotation_quaternion = Vector(aim).to_track_quat("-Z", "Y")

    out = Path(tempfile.mkdtemp()) / "render.exr"
    scene.render.filepath = str(out)
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(str(out))
    px = np.array(img.pixels[:], dtype=float).reshape(size, size, 4)[::-1]  # Blender stores bottom row first
    lum = px[..., :3] @ np.array([0.2126, 0.7152, 0.0722])
    row, col = np.unravel_index(int(np.argmax(lum)), lum.shape)
    # pixel centre -> camera-space direction (x right, y up, looking down -z)
    half = math.tan(math.radians(fov_deg) / 2)
    x = ((col + 0.5) / size * 2 - 1) * half
    y = (1 - (row + 0.5) / size * 2) * half
    return math.degrees(math.atan(math.hypot(x, y))), float(lum.max()), float(np.median(lum))


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--skyscatter-python", default=sys.executable,
                   help="interpreter that has skyscatter installed (default: this one)")
    p.add_argument("--width", type=int, default=2048, help="width of the maps [px]")
    args = p.parse_args()
    import bpy

    print(f"Blender {bpy.app.version_string}")
    failures = 0
    with tempfile.TemporaryDirectory() as tmp:
        for elevation, azimuth in SUNS:
            for layout, landing_azimuth in (("blender", azimuth), ("skyscatter", azimuth + 90.0)):
                exr = Path(tmp) / f"{layout}_{elevation:g}_{azimuth:g}.exr"
                write_map(args.skyscatter_python, layout, elevation, azimuth, exr, args.width)
                off, peak, median = brightest_offset(exr, enu(elevation, landing_azimuth))
                ok = off < 1.0 and peak > 100 * median
                failures += layout == "blender" and not ok
                print(f"layout {layout:<10s} sun elevation {elevation:4.0f} deg azimuth {azimuth:5.0f} deg: "
                      f"brightest pixel {off:.2f} deg from azimuth {landing_azimuth % 360:.0f} deg "
                      f"(peak / median {peak / max(median, 1e-30):.3g}) -> {'ok' if ok else 'NOT THERE'}")
    print("all blender-layout suns where skyscatter says" if not failures else f"{failures} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
