"""The aerial-perspective protocol and shared argument checks.

An aerial-perspective model describes how the air between an observer and an object changes the object's
radiance: ``L = L_0 tau + L_in`` (Preetham et al. 1999, Sec. 4). Any object with the two methods below can be
plugged into :class:`skyscatter.render.Scene`:

* ``transmittance(directions, distances, observer_height, wavelengths)`` -> tau, shape (..., n);
* ``inscattered(directions, distances, observer_height, wavelengths)`` -> L_in
  [W m^-2 sr^-1 nm^-1], shape (..., n).

``directions`` (..., 3) point from the observer towards the object (ENU unit vectors), ``distances`` (...)
are path lengths [m], ``observer_height`` is the observer's height above sea level [m] (scalar or
broadcastable; within +-100 km, the domain of the flat exponential atmosphere), ``wavelengths`` [nm]
(default 380-780 nm every 10 nm). Models may also offer ``evaluate(...) -> (tau, L_in)`` to share work; the
renderer uses it when present.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..conventions import as_directions
from ..errors import InvalidParameterError
from ..spectral import as_wavelengths
from .integrals import check_observer_height

__all__ = ["AerialPerspective", "check_path"]


@runtime_checkable
class AerialPerspective(Protocol):
    """Anything that gives the transmittance and in-scattered radiance of a path through the air."""

    def transmittance(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                      wavelengths: ArrayLike | None = None) -> NDArray[np.float64]: ...

    def inscattered(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                    wavelengths: ArrayLike | None = None) -> NDArray[np.float64]: ...


def check_path(directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
               wavelengths: ArrayLike | None):
    """Validate and broadcast the arguments of the protocol.

    Returns unit directions (..., 3), distances (...), observer heights (...), wavelengths (n,).

    Raises
    ------
    InvalidDirectionError
        Malformed directions.
    InvalidParameterError
        Negative or non-finite distances, observer heights not finite or beyond +-100 km
        (:data:`~skyscatter.aerial.integrals.MAX_OBSERVER_HEIGHT`), or shapes that do not broadcast.
    """
    d = as_directions(directions)
    s = np.asarray(distances, dtype=float)
    h = np.asarray(observer_height, dtype=float)
    if not np.all(np.isfinite(s)) or np.any(s < 0):
        raise InvalidParameterError("distances must be finite and >= 0 [m]")
    check_observer_height(h)
    try:
        shape = np.broadcast_shapes(d.shape[:-1], s.shape, h.shape)
    except ValueError:
        raise InvalidParameterError(
            f"directions {d.shape}, distances {s.shape} and observer_height {h.shape} do not broadcast"
        ) from None
    d = np.broadcast_to(d, shape + (3,))
    return d, np.broadcast_to(s, shape), np.broadcast_to(h, shape), as_wavelengths(wavelengths)
