"""Evaluating the tables: the radiance, transmittance and irradiance of a precomputed atmosphere anywhere
(Bruneton & Neyret 2008, Sec. 5), and its colour.

:class:`TableLookups` holds what :class:`.PrecomputedAtmosphere` answers from its tables: the sky's radiance
along rays (Eq. 16; light shafts by Eq. 18), aerial perspective between two points (Eqs. 16, 17), the
transmittance and radiance of the sun, the irradiance on surfaces (Eq. 14), and the conversion of spectral
radiance at the table wavelengths to XYZ and to other wavelengths (:mod:`.conversion`). Arguments are checked
and broadcast here; the loops over rays are the numba kernels of :mod:`.lookup`, run on all cores by
:func:`.parallel.parallel_for`.

Reference: [Bruneton2008].
"""

from __future__ import annotations

from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere.phase import aerosol_phase_kind
from ..conventions import as_directions
from ..errors import InvalidDirectionError, InvalidParameterError
from ..sun.disc import solar_disc_solid_angle
from .conversion import SPECTRAL_MODE_MIN_WAVELENGTHS, ColourConversion, xyz_matrix
from .parallel import parallel_for
from .parameters import AtmosphereParameters

__all__ = ["TableLookups"]



def _kernels() -> ModuleType:
    """The numba kernels of :mod:`.lookup`, imported on the first lookup: importing the package stays free of
    numba (start-up of the commands that do not read tables)."""
    from . import lookup

    return lookup


def _as_points(name: str, value: ArrayLike) -> NDArray[np.float64]:
    a = np.asarray(value, dtype=float)
    if a.ndim == 0 or a.shape[-1] != 3:
        raise InvalidParameterError(f"{name} must have shape (..., 3) [m]; got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InvalidParameterError(f"{name} contains NaN or infinite values")
    return a


def _as_dirs(name: str, value: ArrayLike) -> NDArray[np.float64]:
    try:
        return as_directions(value)
    except InvalidDirectionError as exc:
        raise InvalidDirectionError(f"{name}: {exc}") from None



#: Gauss-Legendre nodes (zenith, azimuth) of :meth:`TableLookups.horizontal_sky_irradiance`.
HORIZONTAL_SKY_NODES = (48, 96)


class TableLookups:
    """The lookups of a precomputed atmosphere: a base of :class:`.PrecomputedAtmosphere`, which provides the
    attributes below. Positions are in metres in a planet-centred frame (the planet's centre at the origin);
    directions are unit vectors in the same frame; spectral results are at :attr:`wavelengths`.
    """

    parameters: AtmosphereParameters
    wavelengths: NDArray[np.float64]
    if TYPE_CHECKING:  # the float32 tables: a property of the subclass that holds them (PrecomputedAtmosphere)
        @property
        def tables(self) -> dict[str, NDArray[np.float32]]: ...
    #: the tables as stored (:class:`.storage.HalfTable` for the 4D ones); indexing one decodes only that part
    stored: dict[str, Any]
    #: solar irradiance [W m^-2 nm^-1] and ground albedo at the table wavelengths
    _solar: NDArray[np.float64]
    _albedo: NDArray[np.float64]
    _xyz_matrix: NDArray[np.float64] | None
    _colour: ColourConversion | None

    # ------------------------------------------------------------------ colour

    @property
    def spectral_mode(self) -> bool:
        """True when XYZ is integrated directly from the samples (>= 15 wavelengths)."""
        return self.wavelengths.size >= SPECTRAL_MODE_MIN_WAVELENGTHS

    @property
    def xyz_matrix(self) -> NDArray[np.float64]:
        """(3, n_wavelengths) matrix from table radiance to CIE XYZ [cd m^-2] (see :mod:`.conversion`)."""
        if self._xyz_matrix is None:
            self._xyz_matrix = xyz_matrix(self.wavelengths, self.parameters)
        return self._xyz_matrix

    @property
    def colour(self) -> ColourConversion:
        """The :class:`.conversion.ColourConversion` of these tables (built once)."""
        if self._colour is None:
            self._colour = ColourConversion(self.wavelengths, self.parameters)
        return self._colour

    def to_xyz(self, radiance: ArrayLike) -> NDArray[np.float64]:
        """CIE XYZ [cd m^-2] of spectral radiance (..., n_wavelengths) at the table wavelengths."""
        return self.colour.to_xyz(radiance)

    def luminance(self, radiance: ArrayLike) -> NDArray[np.float64]:
        """Luminance [cd m^-2] of spectral radiance (..., n_wavelengths) at the table wavelengths."""
        return self.to_xyz(radiance)[..., 1]

    def resample(self, radiance: ArrayLike, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Radiance (..., n_table) at the table wavelengths to (..., n) at ``wavelengths`` [nm], never negative
        (see :class:`.conversion.ColourConversion`)."""
        return self.colour.resample(radiance, wavelengths)

    # ------------------------------------------------------------------ lookups

    @property
    def _mie_kind(self) -> int:
        """Integer code of the aerosol phase function for the numba kernels (:data:`.sampling.TABLE_PHASE` for a
        tabulated one)."""
        return self._aerosol_phase[0]

    @property
    def _mie_g(self) -> float:
        return self._aerosol_phase[1]

    @property
    def _lobe(self) -> float:
        """Weight of the lobe by which the multiple-scattering table is stored divided
        (:func:`.sampling.multiple_lobe`, :func:`.sampling.lobe_weight`), computed once."""
        cached = getattr(self, "_lobe_cache", None)
        if cached is None:
            from .sampling import lobe_weight  # with the kernels' module, loaded on first lookup

            cached = self._lobe_cache = lobe_weight(self.parameters)
        return cached

    @property
    def _aerosol_phase(self) -> tuple[int, float, NDArray[np.float64], NDArray[np.float64]]:
        """``(kind, g, phase_mu, phase_values)`` of the aerosol for the lookup kernels, built once: a tabulated
        phase is the aerosol's phase table at the table wavelengths (single scattering exact to it)."""
        cached = getattr(self, "_aerosol_phase_cache", None)
        if cached is None:
            analytic = self.parameters.aerosol_component.analytic_phase
            if analytic is not None:
                cached = (aerosol_phase_kind(analytic.kind), analytic.g, np.array([-1.0, 1.0]), np.zeros((1, 2)))
            else:
                from .sampling import TABLE_PHASE

                arr = self.parameters.aerosol_phase_table(self.wavelengths).numba_arrays()
                cached = (TABLE_PHASE, 0.0, arr.mu, arr.values)
            self._aerosol_phase_cache = cached
        return cached

    @property
    def _profiles(self) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """The density profiles of :func:`.compute.density_profiles` for the lookup kernels (the Earth's shadow in
        the single scattering: :func:`.lookup._inscatter`), built once."""
        cached = getattr(self, "_profiles_cache", None)
        if cached is None:
            from .compute import density_profiles

            cached = density_profiles(self.parameters)
            self._profiles_cache = cached
        return cached

    def _geometry(self) -> tuple[float, float, float]:
        p = self.parameters
        return p.bottom_radius, p.top_radius, p.mu_s_min

    def transmittance(self, r: ArrayLike, mu: ArrayLike) -> NDArray[np.float64]:
        """Transmittance from radius ``r`` [m] along direction cosine ``mu`` to the top of the atmosphere, or to
        the ground for rays that meet it; shape broadcast(r, mu) + (n_wavelengths,)."""
        r_a, mu_a = np.broadcast_arrays(np.asarray(r, dtype=float), np.asarray(mu, dtype=float))
        bottom, top, _ = self._geometry()
        if not (np.all(np.isfinite(r_a)) and np.all(np.isfinite(mu_a))):
            raise InvalidParameterError("r and mu must be finite")
        if np.any((r_a < bottom * (1 - 1e-12)) | (r_a > top * (1 + 1e-12))):
            raise InvalidParameterError(f"r must lie in [{bottom:g}, {top:g}] m (inside the atmosphere)")
        if np.any(np.abs(mu_a) > 1.0 + 1e-12):
            raise InvalidParameterError("mu must be in [-1, 1]")
        shape = r_a.shape
        pos = np.zeros((r_a.size, 3))
        pos[:, 2] = np.clip(r_a.ravel(), bottom, top)
        mu_f = np.clip(mu_a.ravel(), -1.0, 1.0)
        dirs = np.stack([np.sqrt(1.0 - mu_f**2), np.zeros_like(mu_f), mu_f], axis=-1)
        _, t = self._sky(pos, dirs, np.tile([0.0, 0.0, 1.0], (r_a.size, 1)), None, False)
        return t.reshape(*shape, -1)

    def _broadcast_rays(self, positions: ArrayLike, directions: ArrayLike, sun_direction: ArrayLike,
                        extra: ArrayLike | None, direction_name: str = "directions"):
        pos = _as_points("positions", positions)
        if direction_name == "points":
            dirs = _as_points("points", directions)
        else:
            dirs = _as_dirs(direction_name, directions)
        sun = _as_dirs("sun_direction", sun_direction)
        arrays = [pos[..., 0], dirs[..., 0], sun[..., 0]]
        if extra is not None:
            ex = np.asarray(extra, dtype=float)
            if not np.all(np.isfinite(ex)) or np.any(ex < 0):
                raise InvalidParameterError("shadow_length must be finite and >= 0 [m]")
            arrays.append(ex)
        try:
            shape = np.broadcast_shapes(*(a.shape for a in arrays))
        except ValueError:
            raise InvalidParameterError(
                f"positions {pos.shape}, {direction_name} {dirs.shape} and sun_direction {sun.shape} do not broadcast"
            ) from None

        def flat(a: NDArray[np.float64], last: int | None) -> NDArray[np.float64]:
            # always C-contiguous and writable (a read-only view is copied): numba compiles a kernel once per
            # argument type, and read-only is another type, so an input that needed no broadcasting (a read-only
            # view of it) compiled the lookup kernels a second time (about 10 s of CPU each, per process)
            full = np.broadcast_to(a, (*shape, last) if last else shape)
            return np.require(full.reshape(-1, last) if last else full.reshape(-1), requirements=["C", "W"])

        sh = flat(np.asarray(extra, dtype=float), None) if extra is not None else None
        return shape, flat(pos, 3), flat(dirs, 3), flat(sun, 3), sh

    def _check_above_ground(self, pos: NDArray[np.float64], name: str = "positions") -> None:
        """Refuse points below the surface (the tables start at ``bottom_radius``); 1 m tolerance for rounding."""
        bottom = self.parameters.bottom_radius
        r = np.sqrt(np.einsum("ij,ij->i", pos, pos))
        if r.size and r.min() < bottom - 1.0:
            raise InvalidParameterError(
                f"{name} must be on or above the planet's surface (distance from its centre >= bottom_radius "
                f"= {bottom:.7g} m); got one at {r.min():.7g} m, {bottom - r.min():.4g} m below the surface"
            )

    def _sky(self, pos, dirs, sun, shadow, include_ground):
        lookup = _kernels()

        bottom, top, mu_s_min = self._geometry()
        n = pos.shape[0]
        sh = np.zeros(n) if shadow is None else shadow
        rad = np.zeros((n, self.wavelengths.size))
        tr = np.ones((n, self.wavelengths.size))
        parallel_for(lookup.sky_kernel, n, pos, dirs, sun, sh, self.tables["transmittance"],
                     self.tables["single_rayleigh"], self.tables["single_mie"], self.tables["multiple"],
                     self.tables["irradiance"], self._albedo, self._solar, bottom, top,
                     mu_s_min, self._mie_g, self._mie_kind, self._lobe, *self._aerosol_phase[2:], *self._profiles,
                     self.parameters.sun_angular_radius, include_ground, rad, tr,
                     grain=2048)
        return rad, tr

    def sky_xyz(self, positions: ArrayLike, directions: ArrayLike, sun_direction: ArrayLike, *,
                include_ground: bool = True) -> NDArray[np.float64]:
        """CIE 1931 XYZ [cd m^-2] of :meth:`sky_radiance` (no light shafts), shape broadcast + (3,).

        In the spectral mode, for one position inside the atmosphere and one sun direction (a sky seen by one
        observer), the lookups run on 2D slices of the tables projected to XYZ (:func:`.lookup.observer_slices`):
        the same values as ``to_xyz(sky_radiance(...))`` to rounding, several times faster, except with the sun
        0.5-10 deg below the horizon, where the geometric read along the sun zenith (:func:`.geometry.sun_zenith_value`)
        acts on each XYZ channel instead of each wavelength (docs/realtime.md). Otherwise this is
        ``to_xyz(sky_radiance(...))`` (with fewer wavelengths the colour rule is not linear in the spectrum: the
        negative-lobe guard of :mod:`.conversion`).
        """
        if self.spectral_mode:
            fast = self._observer(positions, directions, sun_direction, include_ground, self.xyz_matrix)
            if fast is not None:
                return fast
        return self.to_xyz(self.sky_radiance(positions, directions, sun_direction, include_ground=include_ground))

    def sky_luminance(self, positions: ArrayLike, directions: ArrayLike, sun_direction: ArrayLike, *,
                      include_ground: bool = True) -> NDArray[np.float64]:
        """Luminance [cd m^-2] of :meth:`sky_radiance` (no light shafts), shape broadcast: the Y of
        :meth:`sky_xyz`, with one projected channel instead of three on the observer's fast path."""
        if self.spectral_mode:
            fast = self._observer(positions, directions, sun_direction, include_ground, self.xyz_matrix[1:2])
            if fast is not None:
                return fast[..., 0]
        return self.sky_xyz(positions, directions, sun_direction, include_ground=include_ground)[..., 1]

    def sky_colour(self, positions: ArrayLike, directions: ArrayLike, sun_direction: ArrayLike,
                   matrix: ArrayLike, *, include_ground: bool = True) -> NDArray[np.float64]:
        """:meth:`sky_radiance` (no light shafts) projected to colour channels by ``matrix`` (C, n_wavelengths), shape
        broadcast + (C,): e.g. :func:`skyscatter.realtime.export.fold_matrix` for the linear sRGB of the GLSL library.

        On the observer's fast path (one position inside the atmosphere, one sun) the tables' slices are projected
        first and each channel is read along the sun zenith with its own weight (:func:`.geometry.sun_zenith_value`,
        with the sun 0.5-10 deg below the horizon), as the GLSL library reads its colour textures: the same values, to
        rounding, as the library. The per-wavelength read of :meth:`sky_radiance`, folded, differs from it there
        (docs/realtime.md). Elsewhere ``sky_radiance(...) @ matrix.T``."""
        m = np.asarray(matrix, dtype=float)
        if m.ndim != 2 or m.shape[1] != self.wavelengths.size:
            raise InvalidParameterError(f"matrix must be (C, {self.wavelengths.size}); got shape {m.shape}")
        fast = self._observer(positions, directions, sun_direction, include_ground, m)
        if fast is not None:
            return fast
        return self.sky_radiance(positions, directions, sun_direction, include_ground=include_ground) @ m.T

    def sky_spectrum(self, positions: ArrayLike, directions: ArrayLike, sun_direction: ArrayLike,
                     wavelengths: ArrayLike, *, include_ground: bool = True) -> NDArray[np.float64]:
        """:meth:`sky_radiance` (no light shafts) at other ``wavelengths`` [nm]: ``resample(sky_radiance(...))``,
        shape broadcast + (n_wavelengths,).

        Where the resampling is a matrix (not the guarded few-wavelength rule of :mod:`.conversion`) and the
        observer's fast path applies (:meth:`sky_xyz`), the tables' slices are projected to the wavelengths
        first: the same values to rounding, without the radiance at the table wavelengths in between.
        """
        wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
        if not self.colour.guarded:
            from .conversion import reconstruction_matrix

            key = wl.tobytes()
            cached = getattr(self, "_spectrum_projection", None)
            if cached is None or cached[0] != key:
                cached = (key, reconstruction_matrix(self.wavelengths, wl, self.parameters))
                self._spectrum_projection = cached
            fast = self._observer(positions, directions, sun_direction, include_ground, cached[1])
            if fast is not None:
                return np.maximum(fast, 0.0, out=fast)
        return self.resample(self.sky_radiance(positions, directions, sun_direction, include_ground=include_ground),
                             wl)

    def _observer(self, positions, directions, sun_direction, include_ground, projection):
        """The observer fast path of :meth:`sky_xyz`, :meth:`sky_luminance` and :meth:`sky_radiance` (radiance
        projected with ``projection`` (C, n_wavelengths)), or None where it does not apply."""
        # Anything unusual (several positions or suns, bad values, an observer outside the atmosphere, whose rays
        # the general kernel first moves to the top) goes the general way, which also says what is wrong.
        try:
            pos = np.asarray(positions, dtype=float)
            sun = np.asarray(sun_direction, dtype=float)
            d = np.asarray(directions)
        except (ValueError, TypeError):
            return None
        if (pos.shape != (3,) or sun.shape != (3,)
                or not (np.all(np.isfinite(pos)) and np.all(np.isfinite(sun)) and np.any(sun))
                or d.dtype.kind not in "fiu" or d.ndim == 0 or d.shape[-1] != 3):
            return None
        bottom, top, mu_s_min = self._geometry()
        r = float(np.linalg.norm(pos))
        if not (bottom - 1.0 <= r <= top):
            return None
        if self._aerosol_phase[3].shape[1] > 2:
            # a tabulated aerosol phase depends on wavelength: the slices projected to colour channels before the
            # phase is applied do not hold; the general kernel applies it per wavelength
            return None
        lookup = _kernels()

        shape = d.shape[:-1]
        dirs = np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float64)
        s = sun / np.linalg.norm(sun)
        mu_s = float(np.clip(pos @ s / r, -1.0, 1.0))
        projection = np.ascontiguousarray(projection, dtype=np.float64)
        # the slices at the observer's radius and sun, decoded from the stored tables (a memory-mapped file is
        # read there only: the first sky from a cached file does not wait for all of it)
        stored = self.stored
        # (or at the cell's two sun-zenith texels of the read along the sun zenith, lookup.observer_read_slices)
        slices, slices2, read_w, read_f = lookup.observer_read_slices(
            stored["single_rayleigh"], stored["single_mie"], stored["multiple"], min(max(r, bottom), top), mu_s,
            bottom, top, mu_s_min, projection)
        out = np.empty((dirs.shape[0], projection.shape[0]))
        bad = np.zeros(dirs.shape[0], dtype=np.bool_)
        # Directions are normalised (and zero, NaN or infinite ones flagged) inside the kernel: no extra passes.
        parallel_for(lookup.observer_kernel, dirs.shape[0], pos, s, slices, slices2, read_w, read_f,
                     stored["single_rayleigh"].shape[0],
                     stored["transmittance"], stored["irradiance"], self._albedo, self._solar,
                     projection,
                     bottom, top, mu_s_min, self._mie_g, self._mie_kind, self._lobe, *self._profiles,
                     self.parameters.sun_angular_radius,
                     bool(include_ground), dirs, out, bad, grain=2048)
        if bad.any():
            return None
        return out.reshape(*shape, projection.shape[0])

    def sky_radiance_suns(self, position: ArrayLike, directions: ArrayLike, sun_directions: ArrayLike, *,
                          include_ground: bool = True) -> NDArray[np.float64]:
        """:meth:`sky_radiance` of one observer under many suns: ``out[k] = sky_radiance(position, directions,
        sun_directions[k])``, shape (n_suns, n_directions, n_wavelengths) [W m^-2 sr^-1 nm^-1].

        The same values, to the bit on the observer's fast path (:meth:`sky_xyz`): the loop over the suns runs in
        one compiled call (:func:`.lookup.observer_suns_kernel`, in parallel over the suns), each sun's slices
        formed there from the two decoded radius layers of the tables, instead of one Python call, slice and
        kernel launch per sun (a year of hours: several thousand). Where the fast path does not apply (an
        observer outside the atmosphere, a tabulated aerosol phase, bad directions), each sun goes through
        :meth:`sky_radiance`.

        Parameters
        ----------
        position : array_like, shape (3,)
            Observer position [m] from the planet centre.
        directions : array_like, shape (n, 3)
            View directions (unit vectors).
        sun_directions : array_like, shape (n_suns, 3)
            Directions towards the sun (normalised here).
        include_ground : bool
            Add the ground for rays that meet it.
        """
        pos = np.asarray(position, dtype=float)
        suns = np.asarray(sun_directions, dtype=float)
        d = np.asarray(directions, dtype=float)
        n_l = self.wavelengths.size
        if suns.ndim != 2 or suns.shape[1] != 3 or d.ndim != 2 or d.shape[1] != 3:
            raise InvalidParameterError(f"sky_radiance_suns takes directions (n, 3) and sun_directions (n_suns, 3); "
                                        f"got {d.shape} and {suns.shape}")

        def one_by_one() -> NDArray[np.float64]:
            out = np.empty((suns.shape[0], d.shape[0], n_l))
            for k in range(suns.shape[0]):
                out[k] = self.sky_radiance(pos, d, suns[k], include_ground=include_ground)
            return out

        norms = np.linalg.norm(suns, axis=1) if suns.size else np.zeros(0)
        if (suns.shape[0] == 0 or pos.shape != (3,) or not np.all(np.isfinite(pos)) or not np.all(np.isfinite(suns))
                or not np.all(norms > 0) or self._aerosol_phase[3].shape[1] > 2):
            return one_by_one()
        bottom, top, mu_s_min = self._geometry()
        r = float(np.linalg.norm(pos))
        if not (bottom - 1.0 <= r <= top):
            return one_by_one()
        lookup = _kernels()
        s = np.ascontiguousarray(suns / norms[:, None])
        mu_s = np.clip(s @ pos / r, -1.0, 1.0)
        rc = min(max(r, bottom), top)
        stored = self.stored
        tables = [stored[name] for name in ("single_rayleigh", "single_mie", "multiple")]
        n_r, n_s = tables[0].shape[0], tables[0].shape[2]
        i_r, w_r, _, _, w_g = lookup.r_mu_s_cell(rc, max(mu_s_min, 0.0), bottom, top, mu_s_min, n_r, n_s)

        def layer(table: Any, i: int) -> NDArray[np.float32]:
            i = min(i, n_r - 1)
            a = table.radius_layer(i) if hasattr(table, "radius_layer") else table[i]
            return np.ascontiguousarray(a, dtype=np.float32)

        lower = [layer(t, i_r) for t in tables]
        upper = [layer(t, i_r + 1) if max(w_r, w_g) > 0.0 else lo for t, lo in zip(tables, lower, strict=True)]
        dirs = np.ascontiguousarray(d)
        out = np.empty((s.shape[0], dirs.shape[0], n_l))
        bad = np.zeros((s.shape[0], dirs.shape[0]), dtype=np.bool_)
        projection = np.eye(n_l)
        parallel_for(lookup.observer_suns_kernel, s.shape[0], pos, rc, n_r, s, mu_s, *lower, *upper,
                     stored["transmittance"], stored["irradiance"], self._albedo, self._solar,
                     projection, True,
                     bottom, top, mu_s_min, self._mie_g, self._mie_kind, self._lobe, *self._profiles,
                     self.parameters.sun_angular_radius, bool(include_ground), dirs, out, bad,
                     grain=max(1, 4096 // max(dirs.shape[0], 1)))
        if bad.any():
            return one_by_one()
        return out

    def sky_radiance(self, positions: ArrayLike, directions: ArrayLike, sun_direction: ArrayLike, *,
                     shadow_length: ArrayLike | None = None, include_ground: bool = True,
                     return_transmittance: bool = False):
        """Spectral radiance [W m^-2 sr^-1 nm^-1] seen from ``positions`` along ``directions`` (Eq. 16).

        Parameters
        ----------
        positions : array_like, shape (..., 3)
            Observer positions [m] from the planet centre; on or above the surface (1 m tolerance), also
            outside the atmosphere.
        directions : array_like, shape (..., 3)
            View directions (unit vectors, same frame).
        sun_direction : array_like, shape (3,) or (..., 3)
            Direction towards the sun.
        shadow_length : array_like, optional
            Length [m] of the shadowed part at the near end of each ray (light shafts, Eq. 18).
        include_ground : bool
            Add the ground (albedo of the parameters, lit by the sun and the sky) for rays that meet it.
        return_transmittance : bool
            Also return the transmittance to the end of each ray (1 for rays that miss the atmosphere).

        Returns
        -------
        ndarray, shape broadcast + (n_wavelengths,)
            The solar disc is not included (see :meth:`sun_radiance`); rays that miss the atmosphere give 0.
        """
        if shadow_length is None and not return_transmittance:
            fast = self._observer(positions, directions, sun_direction, include_ground,
                                  np.eye(self.wavelengths.size))
            if fast is not None:
                return fast
        shape, pos, dirs, sun, sh = self._broadcast_rays(positions, directions, sun_direction, shadow_length)
        self._check_above_ground(pos)
        rad, t = self._sky(pos, dirs, sun, sh, bool(include_ground))
        rad = rad.reshape(*shape, -1)
        if return_transmittance:
            return rad, t.reshape(*shape, -1)
        return rad

    def aerial_perspective(self, positions: ArrayLike, points: ArrayLike, sun_direction: ArrayLike, *,
                           shadow_length: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Transmittance and inscattered radiance between observers and points (Eq. 16; Eq. 17 with shadows).

        Parameters
        ----------
        positions, points : array_like, shape (..., 3)
            Observer and object positions [m] from the planet centre.
        sun_direction : array_like, shape (3,) or (..., 3)
            Direction towards the sun.
        shadow_length : array_like, optional
            Total shadowed length [m] along each ray, moved to the object's end (Eq. 17).

        Returns
        -------
        transmittance, inscatter : ndarray, shape broadcast + (n_wavelengths,)
            The object's radiance ``L_obj`` reaches the observer as ``transmittance * L_obj + inscatter``
            [W m^-2 sr^-1 nm^-1].
        """
        lookup = _kernels()

        shape, cam, pts, sun, sh = self._broadcast_rays(positions, points, sun_direction, shadow_length,
                                                        direction_name="points")
        bottom, top, mu_s_min = self._geometry()
        n = cam.shape[0]
        sh = np.zeros(n) if sh is None else sh
        t = np.ones((n, self.wavelengths.size))
        s = np.zeros((n, self.wavelengths.size))
        tab = self.tables
        parallel_for(lookup.aerial_kernel, n, cam, pts, sun, sh, tab["transmittance"], tab["single_rayleigh"],
                     tab["single_mie"], tab["multiple"], bottom, top, mu_s_min, self._mie_g,
                     self._mie_kind, self._lobe, *self._aerosol_phase[2:], *self._profiles, t, s, grain=2048)
        return t.reshape(*shape, -1), s.reshape(*shape, -1)

    def sun_transmittance(self, positions: ArrayLike, sun_direction: ArrayLike) -> NDArray[np.float64]:
        """Transmittance from ``positions`` [m] to the sun, times the fraction of its disc above the horizon."""
        lookup = _kernels()

        shape, pos, _, sun, _ = self._broadcast_rays(positions, sun_direction, sun_direction, None)
        self._check_above_ground(pos)
        bottom, top, _ = self._geometry()
        t = np.ones((pos.shape[0], self.wavelengths.size))
        parallel_for(lookup.sun_kernel, pos.shape[0], pos, sun, self.stored["transmittance"], bottom, top,
                     self.parameters.sun_angular_radius, t, grain=4096)
        return t.reshape(*shape, -1)

    def sun_radiance(self, positions: ArrayLike, sun_direction: ArrayLike) -> NDArray[np.float64]:
        """Mean spectral radiance of the solar disc [W m^-2 sr^-1 nm^-1] seen from ``positions`` (Eq. 9)."""
        omega = solar_disc_solid_angle(self.parameters.sun_angular_radius)
        return self.sun_transmittance(positions, sun_direction) * (self._solar / omega)

    def horizontal_sky_irradiance(self, sun_zenith: ArrayLike) -> NDArray[np.float64]:
        """Sky spectral irradiance [W m^-2 nm^-1] on a horizontal plane on the ground, shape (n, n_wavelengths),
        at sun zenith angles ``sun_zenith`` [rad], from the tables' sky radiance (:meth:`sky_radiance`, Eq. 16):

            E(theta_s) = integral over the upper hemisphere of L(theta, phi; theta_s) cos(theta) dOmega

        by the Gauss-Legendre rule of :func:`skyscatter.quadrature.plane_quadrature` with
        :data:`HORIZONTAL_SKY_NODES` (48 x 96 nodes; within 0.04 % of a 0.25 deg midpoint grid for aerosol optical
        depths up to 0.5, sun zenith 0-90 deg, 96 x 192 nodes within 0.005 %). Tabulated once per tables on sun
        zeniths every 2 deg to 80 deg, every 0.5 deg from 80 to 98 deg (77 radiance integrals) and at the sun
        zeniths of the scattering tables' sun-zenith texels from 90 to 98 deg, and read between these nodes as the
        radiance is read between the texels (:func:`.geometry.sun_zenith_value` with the share
        :func:`.geometry.sun_zenith_share` of the sun zenith: geometric with the sun 0.5-10 deg below the horizon,
        linear elsewhere); beyond 98 deg computed directly. Why the texels: below the horizon the radiance's
        geometric read changes its cell there (a kink along the sun zenith), which a node between them would smooth
        over; why the same rule: between two nodes within a texel cell the integral of the radiance read follows
        the read's curvature.

        This is the quantity a sky matrix integrates over its patches. The precomputed irradiance of
        :meth:`ground_irradiance` (Eq. 14) integrates the scattering orders on the coarser sphere quadrature of the
        table build (``irradiance_sphere_samples``) and differs from it by a few per cent (docs/sky_matrices.md).
        """
        from ..quadrature import plane_quadrature
        from . import geometry

        z = np.atleast_1d(np.asarray(sun_zenith, dtype=float))
        if z.ndim != 1 or not np.all(np.isfinite(z)):
            raise InvalidParameterError("sun_zenith must be a 1-D array of finite angles in radians")
        cached = getattr(self, "_horizontal_sky_cache", None)
        directions, weights = plane_quadrature(0.0, 0.0, nodes=HORIZONTAL_SKY_NODES)
        ground = np.array([0.0, 0.0, self._geometry()[0]])

        def integrate(zeniths: NDArray[np.float64]) -> NDArray[np.float64]:
            out = np.empty((zeniths.size, self.wavelengths.size))
            for k0 in range(0, zeniths.size, 16):  # 16 suns x 4608 directions per call (14 MB of radiances)
                zs = zeniths[k0:k0 + 16]
                suns = np.stack([np.sin(zs), np.zeros_like(zs), np.cos(zs)], axis=1)
                out[k0:k0 + 16] = np.einsum("d,kdw->kw", weights, self.sky_radiance_suns(ground, directions, suns))
            return out

        if cached is None:
            nodes = np.radians(np.concatenate([np.arange(0.0, 80.0, 2.0), np.arange(80.0, 98.001, 0.5)]))
            bottom, top, mu_s_min = self._geometry()
            n_s = self.stored["single_rayleigh"].shape[2]
            texels = np.arccos(np.clip([geometry.scattering_mu_s_param(i, bottom, top, mu_s_min, n_s)
                                        for i in range(n_s)], -1.0, 1.0))
            # (below the horizon, where the read is geometric: by day the nodes are as before)
            texels = texels[(texels > np.radians(90.0)) & (texels <= nodes[-1])]
            if texels.size:  # a regular node within 0.01 deg of a texel gives way to it (no near-empty cells)
                near = np.min(np.abs(nodes[:, None] - texels[None, :]), axis=1) < np.radians(0.01)
                nodes = np.unique(np.concatenate([nodes[~near], texels]))
            cached = (nodes, integrate(nodes))
            self._horizontal_sky_cache = cached
        nodes, values = cached
        out = np.empty((z.size, self.wavelengths.size))
        inside = z <= nodes[-1]
        zc = np.clip(z[inside], 0.0, None)
        k = np.clip(np.searchsorted(nodes, zc, side="right") - 1, 0, nodes.size - 2)
        w = ((zc - nodes[k]) / (nodes[k + 1] - nodes[k]))[:, None]
        lo, hi = values[k], values[k + 1]
        lin = lo + w * (hi - lo)
        m0, m1, m2, m3 = np.sin(np.radians(geometry.SUN_READ_ELEVATIONS))  # geometry.sun_zenith_share, vectorised
        mu_s = np.cos(zc)[:, None]
        f = np.clip((mu_s - m0) / (m1 - m0), 0.0, 1.0) * np.clip((m3 - mu_s) / (m3 - m2), 0.0, 1.0)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            geo = np.where((lo > 0.0) & (hi > 0.0), np.exp((1.0 - w) * np.log(lo) + w * np.log(hi)), lin)
        out[inside] = lin + f * (geo - lin)  # geometry.sun_zenith_value, vectorised
        if np.any(~inside):
            out[~inside] = integrate(z[~inside])
        return out

    def ground_irradiance(self, points: ArrayLike, normals: ArrayLike,
                          sun_direction: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Sun and sky spectral irradiance [W m^-2 nm^-1] on surfaces at ``points`` [m] with ``normals``.

        The sky part is the precomputed irradiance on a horizontal surface times ``(1 + n . up) / 2`` (Eq. 14).
        """
        lookup = _kernels()

        shape, pts, nrm, sun, _ = self._broadcast_rays(points, normals, sun_direction, None,
                                                       direction_name="normals")
        self._check_above_ground(pts, "points")
        bottom, top, _ = self._geometry()
        e_sun = np.zeros((pts.shape[0], self.wavelengths.size))
        e_sky = np.zeros((pts.shape[0], self.wavelengths.size))
        parallel_for(lookup.irradiance_kernel, pts.shape[0], pts, nrm, sun, self.stored["transmittance"],
                     self.stored["irradiance"], self._solar, bottom, top,
                     self.parameters.sun_angular_radius, e_sun, e_sky, grain=4096)
        return e_sun.reshape(*shape, -1), e_sky.reshape(*shape, -1)
