"""The aerial-perspective protocol and shared argument checks.

An aerial-perspective model describes how the air between an observer and an object changes the object's
radiance: ``L = L_0 tau + L_in`` ([Preetham1999] Sec. 4). Every
model derives from :class:`AerialPerspective` and implements one method,

* ``evaluate_rays(origins, directions, distances, wavelengths)`` -> ``(tau, L_in)``, each (..., n):
  transmittance [-] and in-scattered spectral radiance [W m^-2 sr^-1 nm^-1] of the paths that start at
  ``origins`` (ENU positions [m]; ``z`` is the height above sea level), run along ``directions`` (unit ENU
  vectors from the observer towards the object) and end after ``distances`` [m].

The base class derives the rest from it:

* ``sky_radiance(origins, directions, wavelengths, sky=...)``: the radiance of rays that leave the scene.
  By default it is the sky model's own radiance (a sky model already includes the air between the observer and
  space); models whose air changes what the sky looks like from a given place override it (terrain light
  shafts, :class:`skyscatter.aerial.bruneton.BrunetonAerialPerspective`).
* ``evaluate``, ``transmittance`` and ``inscattered(directions, distances, observer_height, wavelengths)``:
  the same for an observer at ``(0, 0, observer_height)`` (scalar or broadcastable; within +-100 km, the domain
  of the flat exponential atmosphere), the form of the original protocol.

Wavelengths are in nm (default 380-780 nm every 10 nm). Models whose light shafts need the terrain's shadow
take a :class:`ShadowCaster` (implemented by :class:`skyscatter.render.heightfield.HeightfieldTracer`).

Objects written for the original protocol (any object with ``transmittance`` and ``inscattered`` taking
``(directions, distances, observer_height, wavelengths)``, :class:`PathFunctions`) are accepted where a model is
expected: :func:`as_aerial_perspective` wraps them.
"""

from __future__ import annotations

import abc
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..conventions import as_directions
from ..errors import InvalidParameterError
from ..spectral import as_wavelengths
from .integrals import check_observer_height

if TYPE_CHECKING:
    from ..sky.base import SkyModel

__all__ = ["DEFAULT_REFINE", "DEFAULT_SHADOW_SAMPLES", "AerialPerspective", "PathFunctions", "ShadowCaster",
           "as_aerial_perspective", "check_path", "check_rays"]

#: Equal steps along each view ray of a shadow-length estimate by ray marching (:class:`ShadowCaster`).
DEFAULT_SHADOW_SAMPLES = 32
#: Bisections of each step whose ends disagree (the boundary is then placed within step / 2**(refine + 1)).
DEFAULT_REFINE = 8


class AerialPerspective(abc.ABC):
    """Transmittance and in-scattered radiance of paths through the air, for rays with origins.

    Subclasses implement :meth:`evaluate_rays`; they may override :meth:`sky_radiance` (rays that leave the
    scene) and, for speed, :meth:`transmittance` (when the in-scattered light is not needed).
    """

    #: The sky model whose sun and sky light the air (None for models that carry their own light).
    sky: SkyModel | None = None

    @abc.abstractmethod
    def evaluate_rays(self, origins: ArrayLike, directions: ArrayLike, distances: ArrayLike,
                      wavelengths: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Transmittance and in-scattered radiance of paths from ``origins``.

        Parameters
        ----------
        origins : array_like, shape (3,) or (..., 3)
            Observer positions [m, ENU]; ``z`` is the height above sea level. One origin may serve all rays.
        directions : array_like, shape (..., 3)
            Unit view directions from the observer towards the object (ENU).
        distances : array_like, shape (...)
            Path lengths [m].
        wavelengths : array_like, optional
            Wavelengths [nm]; default 380-780 nm every 10 nm.

        Returns
        -------
        tau, inscatter : ndarray, shape (..., n_wavelengths)
            ``L = tau L_0 + inscatter``; inscatter in [W m^-2 sr^-1 nm^-1].
        """

    def sky_radiance(self, origins: ArrayLike, directions: ArrayLike, wavelengths: ArrayLike | None = None, *,
                     sky: SkyModel | None = None) -> NDArray[np.float64]:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] of rays from ``origins`` that leave the scene, (..., n).

        The default is ``sky.spectral_radiance(directions, wavelengths)``: the sky model already holds the
        air between the observer and space. ``sky`` defaults to the model's own ``sky`` attribute.

        Raises
        ------
        InvalidParameterError
            No sky given and the model has none.
        """
        sky = self.sky if sky is None else sky
        if sky is None:
            raise InvalidParameterError(f"{type(self).__name__}.sky_radiance needs the sky model (sky=...)")
        return np.asarray(sky.spectral_radiance(as_directions(directions), as_wavelengths(wavelengths)),
                          dtype=float)

    def evaluate(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                 wavelengths: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(tau, L_in) for an observer at ``(0, 0, observer_height)`` [m], each (..., n_wavelengths).

        Arguments as in :meth:`evaluate_rays`, with ``observer_height`` [m above sea level] broadcast with the
        distances instead of the origins.
        """
        d, s, h, wl = check_path(directions, distances, observer_height, wavelengths)
        origins = np.zeros(h.shape + (3,))
        origins[..., 2] = h
        return self.evaluate_rays(origins, d, s, wl)

    def transmittance(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                      wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Transmittance [-] of the paths, shape (..., n_wavelengths); arguments as in :meth:`evaluate`."""
        return self.evaluate(directions, distances, observer_height, wavelengths)[0]

    def inscattered(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                    wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """In-scattered radiance [W m^-2 sr^-1 nm^-1] of the paths, (..., n); arguments as in :meth:`evaluate`."""
        return self.evaluate(directions, distances, observer_height, wavelengths)[1]


@runtime_checkable
class PathFunctions(Protocol):
    """The original, duck-typed aerial-perspective protocol: two functions of an observer height.

    Kept so that providers written for it still plug into :class:`skyscatter.render.Scene`
    (see :func:`as_aerial_perspective`).
    """

    def transmittance(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                      wavelengths: ArrayLike | None = None) -> NDArray[np.float64]: ...

    def inscattered(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                    wavelengths: ArrayLike | None = None) -> NDArray[np.float64]: ...


class _PathFunctionsModel(AerialPerspective):
    """An :class:`AerialPerspective` from a :class:`PathFunctions` object (observer height = origin's z)."""

    def __init__(self, functions: PathFunctions) -> None:
        self.functions = functions

    def __repr__(self) -> str:
        return f"as_aerial_perspective({self.functions!r})"

    def evaluate_rays(self, origins, directions, distances, wavelengths=None):
        o, d, s, wl = check_rays(origins, directions, distances, wavelengths)
        h = o[..., 2]
        return (self.functions.transmittance(d, s, h, wl), self.functions.inscattered(d, s, h, wl))


def as_aerial_perspective(model: AerialPerspective | PathFunctions) -> AerialPerspective:
    """``model`` as an :class:`AerialPerspective`: models are returned as they are, :class:`PathFunctions`
    objects are wrapped (their observer height is the ray origin's ``z``).

    Raises
    ------
    InvalidParameterError
        Anything else.
    """
    if isinstance(model, AerialPerspective):
        return model
    if isinstance(model, PathFunctions):
        return _PathFunctionsModel(model)
    raise InvalidParameterError(
        f"aerial must be an AerialPerspective (skyscatter.aerial.base) or provide transmittance(...) and "
        f"inscattered(...); got {type(model).__name__}"
    )


class ShadowCaster(abc.ABC):
    """Something that shadows the air from the sun (terrain): how much of each ray lies in its shadow.

    Used for light shafts ([Bruneton2008] Eqs. 17-18).
    """

    #: Longest ray [m] the caster follows; beyond it nothing is shadowed.
    max_distance: float

    @abc.abstractmethod
    def shadow_lengths(self, origins: ArrayLike, directions: ArrayLike, distances: ArrayLike,
                       sun_direction: ArrayLike, *, samples: int, refine: int) -> NDArray[np.float64]:
        """Length [m] of each ray (origins [m, ENU], unit directions, lengths [m]) that lies in shadow from
        the sun (unit ENU vector), shape (...), in [0, distance]. ``samples`` and ``refine`` set the accuracy
        of estimates by ray marching (steps per ray, bisections of each light/shadow boundary); exact casters
        may ignore them."""


def check_rays(origins: ArrayLike, directions: ArrayLike, distances: ArrayLike, wavelengths: ArrayLike | None):
    """Validate and broadcast the arguments of :meth:`AerialPerspective.evaluate_rays`.

    Returns origins (..., 3), unit directions (..., 3), distances (...) and wavelengths (n,).

    Raises
    ------
    InvalidDirectionError
        Malformed directions.
    InvalidParameterError
        Origins not finite ENU positions or with heights beyond +-100 km
        (:data:`~skyscatter.aerial.integrals.MAX_OBSERVER_HEIGHT`), negative or non-finite distances, or
        shapes that do not broadcast.
    """
    o = np.asarray(origins, dtype=float)
    if o.shape[-1:] != (3,) or not np.all(np.isfinite(o)):
        raise InvalidParameterError(f"ray origins must be finite ENU positions [m], shape (..., 3); got {o.shape}")
    d, s, h, wl = check_path(directions, distances, o[..., 2], wavelengths)
    try:
        o = np.broadcast_to(o, h.shape + (3,))
    except ValueError:
        raise InvalidParameterError(f"origins {o.shape} do not broadcast with directions {d.shape}") from None
    return o, d, s, wl


def check_path(directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
               wavelengths: ArrayLike | None):
    """Validate and broadcast the arguments of :meth:`AerialPerspective.evaluate`.

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
