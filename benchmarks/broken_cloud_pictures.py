"""Pictures of the ``broken-cloud`` sky for docs/clouds.md (docs/images/broken_cloud_*.png).

* ``broken_cloud_equirect.png``: a 1024 x 512 equirect map (north at the centre) of the default procedural field
  (cover 0.4, seed 1), sun 35 deg high in the south-east;
* ``broken_cloud_vs_montecarlo.png``: the stored Monte Carlo fisheye (tests/data/broken_cloud_montecarlo.npz,
  cover 0.6, 32 x 32 pixels, 1024 paths per pixel, 450 / 550 / 650 nm shown as blue / green / red) beside the
  model on the same field and pixels (``interpolation="voxel"``), one exposure for both, each pixel drawn 8 x 8.

Usage: ``python benchmarks/broken_cloud_pictures.py``.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from broken_cloud_montecarlo import OUT as DATA  # noqa: E402
from broken_cloud_montecarlo import field_for  # noqa: E402
from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.render import sky_image, write_png  # noqa: E402
from skyscatter.sky.broken_cloud import BrokenCloudSky  # noqa: E402

IMAGES = Path(__file__).parents[1] / "docs" / "images"


def main() -> None:
    sky = BrokenCloudSky(math.radians(55.0), math.radians(135.0), cloud_cover=0.4, cloud_seed=1)
    img = sky_image(sky, projection="equirect", width=1024)
    print(write_png(IMAGES / "broken_cloud_equirect.png", img, key=0.45))
    data = np.load(DATA)
    meta = json.loads(str(data["meta"]))
    inside = data["inside"]
    model_sky = BrokenCloudSky(math.radians(meta["sun_zenith_deg"]), math.radians(meta["sun_azimuth_deg"]),
                               clouds=field_for(0.6, meta), atmosphere=AtmosphereParameters(
                                   ground_albedo=meta["ground_albedo"]), interpolation="voxel")
    model = model_sky.spectral_radiance(data["directions"], data["wavelengths"])
    pics = []
    for values in (data["radiance_1"], model):
        pic = np.zeros((*inside.shape, 3))
        pic[inside] = values[:, ::-1]  # 650, 550, 450 nm as R, G, B
        pics.append(np.kron(pic, np.ones((8, 8, 1))))
    gap = np.zeros((pics[0].shape[0], 8, 3))
    both = np.concatenate([pics[0], gap, pics[1]], axis=1)
    print(write_png(IMAGES / "broken_cloud_vs_montecarlo.png", both / both[both > 0].mean() * 0.18, key=0.45))


if __name__ == "__main__":
    main()
