"""The solar disc as seen from the Earth: its mean angular radius and solid angle.

The angular radius is the sun's mean semi-diameter, 0.004675 rad = 0.2679 deg, the default of [Bruneton2017], the
reimplementation of [Bruneton2008] (``kSunAngularRadius``).
The solid angle of a disc of angular radius r is that of a spherical cap, ``2 pi (1 - cos r)``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SUN_ANGULAR_RADIUS", "solar_disc_solid_angle"]

#: Mean angular radius of the solar disc seen from the Earth [rad] (Bruneton's 2017 default, 0.2679 deg).
SUN_ANGULAR_RADIUS = 0.004675


def solar_disc_solid_angle(angular_radius: float = SUN_ANGULAR_RADIUS) -> float:
    """Solid angle [sr] of a disc of the given angular radius [rad]: ``2 pi (1 - cos r)`` (6.87e-5 sr for the sun)."""
    return float(2.0 * np.pi * (1.0 - np.cos(angular_radius)))
