"""Sky patch schemes: Tregenza (145 patches) and its Reinhart subdivisions (MF = 1, 2, 4).

[Tregenza1987]: seven 12-degree altitude bands holding 30, 30, 24, 24, 18, 12 and 6 patches, and a
polar cap of 6 degrees radius (145 patches). Reinhart's subdivision ([ReinhartWalkenhorst2001]; the form of
Radiance's ``reinhartb.cal`` and ``gendaymtx -m MF``) splits every band into MF bands and every patch into MF
azimuth steps with a band height ``alpha = (pi / 2) / (7 MF + 1/2)``; the cap keeps half a band
(radius alpha / 2). MF = 1 is Tregenza's scheme, MF = 2 gives 577 patches, MF = 4 gives 2305.

Ordering and orientation follow Radiance (without its ground patch): bands from the horizon up, in each band
the first patch is centred on north and the numbering proceeds towards east; the zenith cap is last. A patch
is ``[alt_lo, alt_hi) x [az_c - pi/n, az_c + pi/n)``, its centre the mid-altitude and mid-azimuth, its solid
angle ``2 pi (sin alt_hi - sin alt_lo) / n`` [sr]; the solid angles of a scheme sum to 2 pi.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .conventions import as_directions, direction_from_angles
from .errors import InvalidParameterError
from .sky.base import SkyModel
from .validation import whole_number

__all__ = ["SCHEMES", "TREGENZA_BAND_COUNTS", "PatchScheme", "patch_luminance", "patch_scheme"]

#: Patches per 12-degree altitude band of the Tregenza sky, horizon band first (Tregenza 1987).
TREGENZA_BAND_COUNTS = (30, 30, 24, 24, 18, 12, 6)

#: Scheme name -> Reinhart subdivision factor MF ("tregenza" and "reinhart1" are the same 145 patches).
SCHEMES = {"tregenza": 1, "reinhart1": 1, "reinhart2": 2, "reinhart4": 4}


@dataclass(frozen=True, eq=False)
class PatchScheme:
    """Geometry of one patch scheme (all angles in radians, arrays of shape (n_patches,)).

    Attributes
    ----------
    name : str
        Scheme name ("tregenza", "reinhart1", "reinhart2" or "reinhart4").
    subdivisions : int
        Reinhart subdivision factor MF.
    altitude_low, altitude_high : ndarray
        Altitude bounds of each patch [rad].
    azimuth_centre, azimuth_width : ndarray
        Central azimuth [rad, from north towards east] and azimuthal width [rad] (2 pi for the cap).
    row : ndarray of int
        Altitude band of each patch, 0 at the horizon; the cap is band ``7 MF``.
    """

    name: str
    subdivisions: int
    altitude_low: NDArray[np.float64]
    altitude_high: NDArray[np.float64]
    azimuth_centre: NDArray[np.float64]
    azimuth_width: NDArray[np.float64]
    row: NDArray[np.int64]
    _row_start: NDArray[np.int64] = field(repr=False)
    _row_count: NDArray[np.int64] = field(repr=False)

    @property
    def n_patches(self) -> int:
        """Number of sky patches (145, 577 or 2305)."""
        return int(self.altitude_low.size)

    @property
    def band_height(self) -> float:
        """Altitude step alpha [rad] between bands: (pi / 2) / (7 MF + 1/2)."""
        return (np.pi / 2) / (7 * self.subdivisions + 0.5)

    @property
    def centre_altitude(self) -> NDArray[np.float64]:
        """Altitude of each patch centre [rad] (the cap's centre is the zenith)."""
        mid = 0.5 * (self.altitude_low + self.altitude_high)
        mid[-1] = np.pi / 2
        return mid

    @property
    def centre_zenith(self) -> NDArray[np.float64]:
        """Zenith angle of each patch centre [rad]."""
        return np.pi / 2 - self.centre_altitude

    @property
    def centre_directions(self) -> NDArray[np.float64]:
        """Unit ENU vectors to the patch centres, shape (n_patches, 3)."""
        return direction_from_angles(self.centre_zenith, self.azimuth_centre)

    @property
    def solid_angles(self) -> NDArray[np.float64]:
        """Solid angle of each patch [sr]; they sum to 2 pi."""
        return (np.sin(self.altitude_high) - np.sin(self.altitude_low)) * self.azimuth_width

    def patch_index(self, directions: ArrayLike) -> NDArray[np.int64]:
        """Index of the patch that contains each direction (..., 3); -1 below the horizon (z < 0)."""
        d = as_directions(directions)
        z = np.clip(d[..., 2], -1.0, 1.0)
        alt = np.arcsin(z)
        azi = np.mod(np.arctan2(d[..., 0], d[..., 1]), 2 * np.pi)
        n_rows = 7 * self.subdivisions
        row = np.clip(np.floor(alt / self.band_height).astype(np.int64), 0, n_rows)
        count = self._row_count[row]
        step = 2 * np.pi / count
        j = np.floor((azi + 0.5 * step) / step).astype(np.int64) % count
        index = self._row_start[row] + j
        return np.where(z < 0.0, -1, index)

    def sample_directions(self, samples: int) -> NDArray[np.float64]:
        """Centres of ``samples x samples`` equal-area cells in every patch, shape (n_patches, samples**2, 3).

        Cells split each patch evenly in sin(altitude) and in azimuth, so they have equal solid angles and the
        plain mean over a patch's cells is the midpoint rule for the patch's mean value.
        """
        s = whole_number("samples per patch side", samples, 1, 64, integral_floats=True)
        t = (np.arange(s) + 0.5) / s
        u_lo = np.sin(self.altitude_low)[:, None]
        u_hi = np.sin(self.altitude_high)[:, None]
        u = u_lo + (u_hi - u_lo) * t[None, :]  # (P, s)
        az = (
            self.azimuth_centre[:, None] + self.azimuth_width[:, None] * (t[None, :] - 0.5)
        )  # (P, s)
        uu = np.repeat(u, s, axis=1)  # (P, s*s): altitude index slow
        aa = np.tile(az, (1, s))
        zen = np.arccos(np.clip(uu, -1.0, 1.0))
        return direction_from_angles(zen, aa)



@cache
def patch_scheme(name: str) -> PatchScheme:
    """The patch geometry for ``name`` in ``SCHEMES`` ("tregenza", "reinhart1", "reinhart2", "reinhart4")."""
    key = str(name).lower()
    if key not in SCHEMES:
        raise InvalidParameterError(f"unknown patch scheme {name!r}; choose one of {', '.join(SCHEMES)}")
    mf = SCHEMES[key]
    alpha = (np.pi / 2) / (7 * mf + 0.5)
    counts = [TREGENZA_BAND_COUNTS[r // mf] * mf for r in range(7 * mf)] + [1]
    lo, hi, azc, azw, row = [], [], [], [], []
    for r, n in enumerate(counts):
        top = np.pi / 2 if r == 7 * mf else alpha * (r + 1)
        lo.append(np.full(n, alpha * r))
        hi.append(np.full(n, top))
        azc.append(2 * np.pi * np.arange(n) / n if n > 1 else np.zeros(1))
        azw.append(np.full(n, 2 * np.pi / n))
        row.append(np.full(n, r))
    count_arr = np.array(counts, dtype=np.int64)
    start = np.concatenate([[0], np.cumsum(count_arr)[:-1]]).astype(np.int64)
    arrays = [np.concatenate(a) for a in (lo, hi, azc, azw)]
    for a in arrays:
        a.flags.writeable = False
    scheme = PatchScheme(key, mf, *arrays, np.concatenate(row).astype(np.int64), start, count_arr)
    return scheme


def patch_luminance(sky: SkyModel, scheme: str | PatchScheme, *, samples: int = 4) -> NDArray[np.float64]:
    """Mean sky luminance [cd m^-2] over every patch of a scheme, shape (n_patches,).

    Parameters
    ----------
    sky : SkyModel
        Any sky model (its ``luminance(directions)`` [cd m^-2]); the solar disc is not included.
    scheme : str or PatchScheme
        "tregenza" (= "reinhart1", 145 patches), "reinhart2" (577) or "reinhart4" (2305).
    samples : int
        Each patch is averaged over ``samples x samples`` equal-area cells (midpoint rule). ``samples=1``
        instead samples the patch centre only (mid-altitude, mid-azimuth: what Radiance's gendaymtx does).
        Default 4.

    Returns
    -------
    ndarray, shape (n_patches,)
        In the scheme's order (bands from the horizon up, first patch of a band at north, then eastwards,
        zenith cap last). ``sum(L * solid_angles * sin(centre_altitude))`` approximates the horizontal
        illuminance of the sky [lx].
    """
    if not isinstance(sky, SkyModel):
        raise InvalidParameterError(f"expected a sky model (skyscatter.sky.SkyModel); got {type(sky).__name__}")
    geom = scheme if isinstance(scheme, PatchScheme) else patch_scheme(scheme)
    s = whole_number("samples per patch side", samples, 1, 64, integral_floats=True)
    if s == 1:
        return np.asarray(sky.luminance(geom.centre_directions), dtype=float)
    dirs = geom.sample_directions(s)
    return np.asarray(sky.luminance(dirs), dtype=float).mean(axis=-1)
