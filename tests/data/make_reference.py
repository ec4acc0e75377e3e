"""Generate the render regression reference ``landscape_64x48.npz`` (and a PNG to look at).

Run from the repository root::

    python tests/data/make_reference.py

This is a separate, deliberate step: the test ``tests/test_scene.py::test_render_matches_stored_reference``
compares new renders against the stored file, so it guards against *unintended changes* (regressions), not
correctness -- the file holds whatever the code produced when it was generated. Correctness is checked by the
other tests (closed forms, quadrature, brute-force ray marching, illuminance integrals).

How the stored image was checked by eye (2026-11, at generation): the PNG, scaled up, shows the built-in
mountains looking west under an evening Preetham sky (T = 2.5, sun 10 deg high at azimuth 250 deg, visible
upper left): a warm yellow-orange sky brightest around the sun, ridges silhouetted against it, distant ridges
paler and closer to the sky's colour than near ones, the foreground darkest. It was compared side by side with
the same scene at 640 x 360 (``skyscatter demo --figure custom --sun-elevation 10 --sun-azimuth 250
--turbidity 2.5 --no-glare``), which shows the same layout. Regenerate (and look again) only after an
intended change to the renderer, the sky or the aerial perspective, and say so in the commit message.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

#: The scene of the reference image; the test renders exactly this.
REFERENCE = {
    "width": 64,
    "height": 48,
    "turbidity": 2.5,
    "sun_elevation_deg": 10.0,
    "sun_azimuth_deg": 250.0,
}
HERE = Path(__file__).resolve().parent
NPZ = HERE / "landscape_64x48.npz"


def render_reference() -> np.ndarray:
    """Render the reference scene (linear sRGB, Y = luminance / 683, float32, shape (48, 64, 3))."""
    from skyscatter import PreethamSky
    from skyscatter.render.scene import Scene

    sky = PreethamSky(REFERENCE["turbidity"], math.radians(90.0 - REFERENCE["sun_elevation_deg"]),
                      math.radians(REFERENCE["sun_azimuth_deg"]))
    return Scene(sky).render(REFERENCE["width"], REFERENCE["height"]).rgb


def main() -> None:
    from skyscatter import __version__
    from skyscatter.render.image_io import write_png

    rgb = render_reference()
    np.savez_compressed(NPZ, rgb=rgb, skyscatter_version=__version__,
                        **{k: np.asarray(v) for k, v in REFERENCE.items()})
    png = NPZ.with_suffix(".png")
    big = np.repeat(np.repeat(rgb, 8, axis=0), 8, axis=1)  # 512 x 384 for looking at
    write_png(png, big)
    print(f"wrote {NPZ} and {png}")


if __name__ == "__main__":
    main()
