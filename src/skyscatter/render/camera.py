"""A pinhole camera placed in the ENU frame (position in metres, orientation in radians)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..conventions import direction_from_angles, pinhole_directions
from ..errors import InvalidParameterError

__all__ = ["MAX_CAMERA_HEIGHT", "MAX_CAMERA_OFFSET", "PinholeCamera"]

#: Largest |x|, |y| [m] of a camera: 10 000 km from the ENU origin. The scene is a flat earth, and beyond this
#: double precision no longer resolves centimetres along the rays.
MAX_CAMERA_OFFSET = 1e7
#: Largest |z| [m] of a camera: the flat exponential atmosphere of the aerial-perspective models (Preetham et
#: al. 1999, Eq. 5) covers the lower atmosphere only.
MAX_CAMERA_HEIGHT = 1e5


@dataclass(frozen=True)
class PinholeCamera:
    """A rectilinear camera without roll.

    Parameters
    ----------
    position : array_like, shape (3,)
        Eye position [m] in the ENU frame (x east, y north, z height above sea level); ``|x|, |y| <= 1e7`` m
        and ``|z| <= 1e5`` m (:data:`MAX_CAMERA_OFFSET`, :data:`MAX_CAMERA_HEIGHT`).
    heading : float
        Azimuth of the optical axis [rad], from north towards east (3 pi / 2 looks west).
    pitch : float
        Elevation of the optical axis above the horizon [rad], in (-pi/2, pi/2).
    fov : float
        Horizontal field of view [rad], in (0, pi).
    """

    position: tuple[float, float, float]
    heading: float
    pitch: float = 0.0
    fov: float = math.radians(60.0)

    def __post_init__(self) -> None:
        p = np.asarray(self.position, dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise InvalidParameterError(
                f"camera position must be three finite coordinates (x east, y north, z up) [m]; got {self.position!r}"
            )
        if max(abs(p[0]), abs(p[1])) > MAX_CAMERA_OFFSET:
            raise InvalidParameterError(
                f"camera x and y must be within +-{MAX_CAMERA_OFFSET:g} m of the origin (a flat-earth scene); "
                f"got ({p[0]:.6g}, {p[1]:.6g}) m"
            )
        if abs(p[2]) > MAX_CAMERA_HEIGHT:
            raise InvalidParameterError(
                f"camera height must be within +-{MAX_CAMERA_HEIGHT:g} m of sea level (the flat atmosphere of the "
                f"aerial-perspective models); got {p[2]:.6g} m"
            )
        object.__setattr__(self, "position", tuple(float(v) for v in p))
        for name in ("heading", "pitch", "fov"):
            value = getattr(self, name)
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise InvalidParameterError(f"camera {name} must be a number [rad]; got {value!r}") from None
            object.__setattr__(self, name, value)
        if not (np.isfinite(self.fov) and 0.0 < self.fov < math.pi):
            raise InvalidParameterError(f"camera fov must be in (0, pi) rad; got {self.fov!r}")
        if not (np.isfinite(self.pitch) and abs(self.pitch) < math.pi / 2):
            raise InvalidParameterError(f"camera pitch must be in (-pi/2, pi/2) rad; got {self.pitch!r}")
        if not np.isfinite(self.heading):
            raise InvalidParameterError(f"camera heading must be finite [rad]; got {self.heading!r}")

    @classmethod
    def from_degrees(cls, position: ArrayLike, heading_deg: float, pitch_deg: float = 0.0,
                     fov_deg: float = 60.0) -> PinholeCamera:
        """Camera from angles in degrees (heading from north towards east, pitch above the horizon)."""
        return cls(tuple(np.asarray(position, dtype=float)), math.radians(heading_deg), math.radians(pitch_deg),
                   math.radians(fov_deg))

    @property
    def forward(self) -> NDArray[np.float64]:
        """Unit ENU vector of the optical axis."""
        return direction_from_angles(math.pi / 2 - self.pitch, self.heading)

    def ray_directions(self, width: int, height: int) -> NDArray[np.float64]:
        """Unit ENU directions through the pixel centres, shape (height, width, 3); row 0 is the top."""
        return pinhole_directions(width, height, heading=self.heading, pitch=self.pitch, fov=self.fov)

    def directions_at(self, rows: ArrayLike, cols: ArrayLike, width: int, height: int) -> NDArray[np.float64]:
        """Unit directions through fractional pixel positions (row, col) [px] of a width x height image.

        Pixel ``(i, j)`` spans ``[i, i + 1) x [j, j + 1)``; its centre is ``(i + 0.5, j + 0.5)``, which gives
        the same direction as :meth:`ray_directions`.
        """
        rows = np.asarray(rows, dtype=float)
        cols = np.asarray(cols, dtype=float)
        forward = self.forward
        right = np.array([math.cos(self.heading), -math.sin(self.heading), 0.0])
        up = np.cross(right, forward)
        half_w = math.tan(self.fov / 2.0)
        half_h = half_w * height / width
        sx = (cols / width * 2.0 - 1.0) * half_w
        sy = (1.0 - rows / height * 2.0) * half_h
        d = forward + sx[..., None] * right + sy[..., None] * up
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def pixel_angle(self, width: int) -> float:
        """Angle [rad] subtended by one pixel at the image centre for an image ``width`` pixels wide."""
        if int(width) != width or width < 1:
            raise InvalidParameterError(f"width must be a positive whole number of pixels; got {width!r}")
        return 2.0 * math.atan(math.tan(self.fov / 2.0) / width)
