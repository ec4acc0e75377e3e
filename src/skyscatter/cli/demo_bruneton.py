"""``skyscatter demo --model bruneton``: the landscape under the precomputed atmosphere (Bruneton & Neyret 2008).

The sky, the sunlight on the terrain and the aerial perspective all come from the precomputed tables
(:class:`skyscatter.BrunetonSky`, :class:`skyscatter.precomputed.landscape.BrunetonAerialPerspective`); the
mountains' shadow in the air gives light shafts (Eqs. 17-18) from a ray-marched shadowed length per pixel. The
tables are the cached Earth defaults (computed once, about 20 s) unless an atmosphere is given.
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["bruneton_scene"]


def bruneton_scene(terrain: Any, camera: Any, sun_zenith: float, sun_azimuth: float, *, atmosphere: Any = None,
                   albedo: float = 0.2, sun_disc: bool = True, wavelengths: Any = None, shafts: bool = True,
                   samples: int | None = None, refine: int | None = None):
    """A :class:`~skyscatter.render.Scene` lit and hazed by the precomputed atmosphere.

    Parameters
    ----------
    terrain : Terrain
        The heightfield (heights above sea level [m]).
    camera : PinholeCamera
        The camera (ENU position [m]).
    sun_zenith, sun_azimuth : float
        Sun angles [rad] (azimuth from north towards east); the sun may be below the horizon down to the
        atmosphere's ``max_sun_zenith`` (then there are no terrain shadows, only the Earth's).
    atmosphere : PrecomputedAtmosphere or AtmosphereParameters, optional
        Tables (default: the cached Earth tables).
    albedo : float
        Lambertian albedo of the terrain [-].
    sun_disc : bool
        Draw the solar disc.
    wavelengths : array_like, optional
        Wavelengths [nm] of the renderer (default 380-780 nm every 10 nm).
    shafts : bool
        Light shafts from the terrain's shadow (Eqs. 17-18); False gives Eq. 16 only.
    samples, refine : int, optional
        Ray-marching steps and boundary bisections of the shadow-length estimate (defaults of
        :func:`skyscatter.precomputed.landscape.shadow_lengths`).

    Returns
    -------
    Scene
    """
    from ..precomputed.landscape import DEFAULT_REFINE, DEFAULT_SHADOW_SAMPLES, BrunetonAerialPerspective
    from ..precomputed.sky import BrunetonSky
    from ..render.scene import Scene

    x, y, z = (float(v) for v in camera.position)
    sky = BrunetonSky(sun_zenith, sun_azimuth, altitude=max(z, 0.0), atmosphere=atmosphere)
    aerial = BrunetonAerialPerspective(
        sky, terrain=terrain if shafts else None, camera_xy=(x, y),
        samples=DEFAULT_SHADOW_SAMPLES if samples is None else samples,
        refine=DEFAULT_REFINE if refine is None else refine,
    )
    return Scene(sky, terrain=terrain, camera=camera, aerial=aerial, albedo=albedo, sun_disc=sun_disc,
                 wavelengths=wavelengths)


def bruneton_panel_title(sun_zenith: float, sun_azimuth: float) -> str:
    """Caption of a demo panel: the model and the sun's elevation and azimuth [deg]."""
    return (f"bruneton (precomputed, light shafts), sun {90.0 - math.degrees(sun_zenith):.1f} deg at "
            f"{math.degrees(sun_azimuth):.1f} deg")
