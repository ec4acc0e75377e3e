"""The figure of the ``broken-cloud`` sky's light shafts (docs/images/broken_cloud_shafts.png): a pinhole camera
on the ground below a broken field (cover 0.5, seed 5, base 1000 m, tops 2500 m, optical depth 10), the sun 6 deg
high in the east-south-east, looking at it: left without the shafts
(``_SHAFTS = False``, the default), right with them, the same exposure.
Usage: ``python benchmarks/picture_broken_cloud_shafts.py [--width 640]``."""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np

import skyscatter.sky.broken_cloud as bc
from skyscatter.render import sky_image, write_exr_and_png


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--out", type=Path,
                    default=Path(__file__).parents[1] / "docs" / "images" / "broken_cloud_shafts.png")
    args = ap.parse_args()
    zen, azi = math.radians(84.0), math.radians(110.0)
    panels = []
    for on in (False, True):
        bc._SHAFTS = on
        sky = bc.BrokenCloudSky(zen, azi, cloud_cover=0.5, cloud_seed=5)
        img = sky_image(sky, projection="pinhole", width=args.width, heading=azi, pitch=math.radians(12.0),
                        fov=math.radians(100.0))
        panels.append(img)
        print(f"shafts={on}: mean Y {img[..., 1].mean():.4g}")
    gap = np.zeros((panels[0].shape[0], 4, 3), dtype=panels[0].dtype)
    both = np.concatenate([panels[0], gap, panels[1]], axis=1)
    with tempfile.TemporaryDirectory() as tmp:
        _, png = write_exr_and_png(Path(tmp) / "s.exr", Path(tmp) / "s.png", both, key=0.3)
        args.out.write_bytes(Path(png).read_bytes())
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
