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

import dataclasses
import threading
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
from .sizes import TableSizes

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
#: The hemisphere quadrature of :meth:`TableLookups.sky_irradiance_integral`: Gauss-Legendre nodes in the cosine of
#: the view zenith, and the trapezoid rule's step [deg] in the azimuth from the sun (0-180 deg, the sky being
#: symmetric about the sun's vertical plane).
SKY_IRRADIANCE_NODES = 8
SKY_IRRADIANCE_AZIMUTH_STEP = 2.5
#: Altitude [m] above which :meth:`TableLookups.ground_irradiance` integrates the sky radiance instead of reading
#: the irradiance table (whose rows are linear in the altitude, 4 km apart at the default sizes).
IRRADIANCE_TABLE_MAX_ALTITUDE = 1.0
#: In twilight the observer's single scattering is computed at its own sun on azimuth cells this many times finer
#: than the tables' (:meth:`PrecomputedAtmosphere._twilight_singles`; 29 texels for the default 8).
TWILIGHT_AZIMUTH_SPLIT = 4


class TableLookups:
    """The lookups of a precomputed atmosphere: a base of :class:`.PrecomputedAtmosphere`, which provides the
    attributes below. Positions are in metres in a planet-centred frame (the planet's centre at the origin);
    directions are unit vectors in the same frame; spectral results are at :attr:`wavelengths`.

    ``compute_twilight_single`` (default True): in twilight the observer's path (one position: :meth:`sky_radiance`,
    :meth:`sky_xyz`, :meth:`sky_luminance`, :meth:`sky_radiance_suns`) computes the single scattering at the
    observer's own sun (:meth:`_twilight_singles`); set it False on an instance to read the stored texels there, as
    the per-ray lookups and the real-time textures do (to compare with them).
    """

    #: the observer's single scattering in twilight computed (True) or read from the stored texels (False)
    compute_twilight_single: bool = True
    parameters: AtmosphereParameters
    wavelengths: NDArray[np.float64]
    sizes: TableSizes
    orders: int
    computed: bool
    ground_rows: bool
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

    @property
    def _mu_s_cells(self) -> int:
        """The sun-zenith cells of the 4D tables that the lookups split (:func:`.geometry.twilight_cells`)."""
        from .geometry import twilight_cells  # numba: imported on the first lookup (_kernels)

        bottom, top, mu_s_min = self._geometry()
        return twilight_cells(bottom, top, mu_s_min, self.stored["single_rayleigh"].shape[2])

    @property
    def lookup_tables(self) -> dict[str, NDArray[np.float32]]:
        """The tables the per-ray lookups read (the general sky and the aerial perspective): :attr:`tables` with
        the three 4D scattering tables refined along the sun zenith in twilight (:func:`.lookup.refine_sun_zenith`;
        48 sun-zenith texels for the stored 32; the single scattering's sub-texels computed at their suns,
        :meth:`_single_sub_texels`), float32, built on first use from the stored tables one at a time.
        The observer's lookups read the same values from refined radius layers (:meth:`_lookup_layer`)."""
        cached = getattr(self, "_lookup_tables_cache", None)
        if cached is not None:
            return cached
        with self._refine_lock:  # one build, when threads ask at once
            cached = getattr(self, "_lookup_tables_cache", None)
            if cached is not None:
                return cached
            lookup = _kernels()
            cells = self._mu_s_cells
            cached = dict(self.stored)
            names = ("single_rayleigh", "single_mie", "multiple")
            n_r, n_mu, n_s, n_nu, n_l = self.stored["multiple"].shape
            for name in names:
                cached[name] = np.empty((n_r, n_mu, lookup.refined_mu_s_count(n_s, cells), n_nu, n_l),
                                        dtype=np.float32)
            for i in range(n_r):  # one radius layer at a time: no whole decoded table besides the result
                singles = self._single_sub_texels(i)
                for name in names:
                    lookup.refine_sun_zenith(lookup.radius_layer(self.stored[name], i)[None], cells,
                                             out=cached[name][i:i + 1], sub_texels=singles.get(name))
            self._lookup_tables_cache = cached
            return cached

    def _single_sub_texels(self, i_r: int) -> dict[str, NDArray[np.float32]]:
        """The single-scattering tables' sub-texels of the refined sun-zenith axis at the radius index ``i_r``,
        computed at their suns (:func:`.compute.stored_single_scattering`, :func:`.lookup.sub_texel_suns`):
        ``{"single_rayleigh": ..., "single_mie": ...}``, each (1, n_mu, 2 cells, n_nu, n_wavelengths) float32;
        empty when no cell is split or the tables are not the precomputation's of :attr:`parameters`
        (:attr:`computed` False: then the sub-texels take the rule); the ground's in every row where
        :attr:`ground_rows`. The medium they come from is built once per atmosphere (a tabulated phase from the
        lookups' table, a file's: no Mie sums again) and the last row's pair is kept (the observer's layers ask for
        the two tables of a row one after the other). Called with the refine lock held."""
        cells = self._mu_s_cells
        if cells == 0 or not self.computed:
            return {}
        if self.ground_rows:
            i_r = 0  # every row holds the ground's
        kept = self.__dict__.get("_sub_texel_row")
        if kept is not None and kept[0] == i_r:
            return kept[1]
        from .compute import Medium, single_scattering_source, stored_single_scattering

        lookup = _kernels()
        source = self.__dict__.get("_sub_texel_source")
        if source is None:
            kind, _, mu, values = self._aerosol_phase
            medium = Medium.of(self.parameters, self.wavelengths, self.sizes,
                               (mu, values) if kind == lookup.TABLE_PHASE else None)
            bottom, top, mu_s_min = self._geometry()
            suns = lookup.sub_texel_suns(bottom, top, mu_s_min, self.stored["multiple"].shape[2], cells)
            transmittance = np.asarray(self.stored["transmittance"], dtype=np.float32)
            source = self.__dict__["_sub_texel_source"] = (
                single_scattering_source(medium, self.sizes, self.orders, transmittance), suns)
        ray, mie = stored_single_scattering(source[0], self.sizes, source[1], range(i_r, i_r + 1))
        out = {"single_rayleigh": ray, "single_mie": mie}
        self.__dict__["_sub_texel_row"] = (i_r, out)
        return out

    def _twilight_singles(self, r: float, mu_s: float) -> tuple | None:
        """The single scattering (Rayleigh, aerosol) of the observer slices' two radius rows computed at the
        observer's own sun, on :data:`TWILIGHT_AZIMUTH_SPLIT` times finer azimuth cells (for
        :func:`.lookup.observer_slices`' ``singles``: each (2, n_mu, n_f, n_wavelengths) float32, as the tables
        store it; :func:`.compute.stored_single_scattering`), or None by day: for an observer whose sun lies in the
        twilight cells of the sun-zenith axis (those the lookups split, :func:`.geometry.twilight_cells`), where
        the Earth's shadow crosses the views, and only for tables that are the precomputation's of
        :attr:`parameters` (:attr:`computed`). The last observer's pair is kept (a map asks in blocks).

        Cost: about 20-40 ms of CPU per observer on the ground and sun, twice that above it (default sizes, 16
        wavelengths; docs/bruneton.md, "Performance"), once per call. Measured against the Monte Carlo reference:
        docs/accuracy.md, "Low sun", "The observer's single scattering computed in twilight"."""
        if not self._twilight_applies(mu_s):
            return None
        n_r, n_mu, n_s, n_nu, _ = self.stored["single_rayleigh"].shape
        cells = self._mu_s_cells
        lookup = _kernels()
        bottom, top, mu_s_min = self._geometry()
        mu_s = max(mu_s, mu_s_min)
        i_r, w_r, _, _, w_g = lookup.r_mu_s_cell(min(max(r, bottom), top), mu_s, bottom, top, mu_s_min, n_r,
                                                 lookup.refined_mu_s_count(n_s, cells), cells)
        # the upper row only where it has a weight (an observer on the ground reads the lower alone)
        upper = i_r + 1 if max(w_r, w_g) > 0.0 else i_r
        rows = (0, 0) if self.ground_rows else (min(i_r, n_r - 1), min(upper, n_r - 1))
        key = (rows, mu_s)
        kept = self.__dict__.get("_twilight_kept")
        if kept is not None and kept[0] == key:
            return kept[1]
        from .compute import stored_single_scattering
        from .kernels import DISC_NODES as disc_nodes

        with self._refine_lock:
            self._single_sub_texels(rows[0])  # builds the medium and transmittance source once
            source = self.__dict__["_sub_texel_source"][0]
        sizes = dataclasses.replace(self.sizes, scattering_nu=TWILIGHT_AZIMUTH_SPLIT * (n_nu - 1) + 1)
        ray, mie = [], []
        for i in sorted(set(rows)):
            a, b = stored_single_scattering(source, sizes, np.array([mu_s]), range(i, i + 1), disc_nodes)
            ray.append(a[0, :, 0])
            mie.append(b[0, :, 0])
        if len(ray) == 1:
            ray, mie = ray * 2, mie * 2
        out = (np.stack(ray), np.stack(mie))
        self.__dict__["_twilight_kept"] = (key, out)
        return out

    @property
    def _refine_lock(self) -> threading.Lock:
        """The lock of the refined tables' and layers' caches (dict.setdefault is atomic: one lock per object)."""
        return self.__dict__.setdefault("_refine_lock_obj", threading.Lock())

    def _slice_layer(self, j: int, i_r: int) -> NDArray[np.float32]:
        """:meth:`_lookup_layer` of the 4D table ``j`` (0 single Rayleigh, 1 single Mie, 2 multiple), for
        :func:`.lookup.observer_slices`."""
        return self._lookup_layer(("single_rayleigh", "single_mie", "multiple")[j], i_r)

    def _lookup_layer(self, name: str, i_r: int) -> NDArray[np.float32]:
        """Radius layer ``i_r`` of the 4D table ``name`` as the lookups read it (refined along the sun zenith,
        :attr:`lookup_tables`): from those tables when they are built, otherwise refined from the stored layer and
        kept (the last six: the two radius rows of one observer's three tables), for the observer's paths."""
        built = getattr(self, "_lookup_tables_cache", None)
        if built is not None:
            return built[name][i_r]
        layers = self.__dict__.setdefault("_lookup_layers", {})
        key = (name, i_r)
        layer = layers.get(key)
        if layer is None:
            with self._refine_lock:  # the dict changed by one thread at a time
                layer = layers.get(key)
                if layer is None:
                    lookup = _kernels()
                    given = self._single_sub_texels(i_r).get(name) if name != "multiple" else None
                    layer = lookup.refine_sun_zenith(lookup.radius_layer(self.stored[name], i_r)[None],
                                                     self._mu_s_cells, sub_texels=given)[0]
                    while len(layers) >= 6:
                        layers.pop(next(iter(layers)))
                    layers[key] = layer
        return layer

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
        tab = self.lookup_tables
        parallel_for(lookup.sky_kernel, n, pos, dirs, sun, sh, tab["transmittance"],
                     tab["single_rayleigh"], tab["single_mie"], tab["multiple"],
                     tab["irradiance"], self._albedo, self._solar, bottom, top,
                     mu_s_min, self._mu_s_cells, self._mie_g, self._mie_kind, self._lobe, *self._aerosol_phase[2:],
                     *self._profiles,
                     self.parameters.sun_angular_radius, include_ground, rad, tr,
                     grain=2048)
        return rad, tr

    def sky_xyz(self, positions: ArrayLike, directions: ArrayLike, sun_direction: ArrayLike, *,
                include_ground: bool = True) -> NDArray[np.float64]:
        """CIE 1931 XYZ [cd m^-2] of :meth:`sky_radiance` (no light shafts), shape broadcast + (3,).

        In the spectral mode, for one position inside the atmosphere and one sun direction (a sky seen by one
        observer), the lookups run on 2D slices of the tables projected to XYZ (:func:`.lookup.observer_slices`):
        the same values as ``to_xyz(sky_radiance(...))`` to rounding, several times faster. Otherwise this is
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
        slices = lookup.observer_slices(stored["single_rayleigh"], stored["single_mie"], stored["multiple"],
                                        min(max(r, bottom), top), mu_s, bottom, top, mu_s_min, self._mu_s_cells,
                                        projection, layers=self._slice_layer,
                                        singles=self._twilight_singles(r, mu_s))
        out = np.empty((dirs.shape[0], projection.shape[0]))
        bad = np.zeros(dirs.shape[0], dtype=np.bool_)
        # Directions are normalised (and zero, NaN or infinite ones flagged) inside the kernel: no extra passes.
        parallel_for(lookup.observer_kernel, dirs.shape[0], pos, s, slices, stored["single_rayleigh"].shape[0],
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
        :meth:`sky_radiance`; so do the suns in twilight (below the top of the twilight cells of the sun-zenith axis),
        whose single scattering the observer's path computes at the sun itself (:meth:`_twilight_singles`).

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
        names = ("single_rayleigh", "single_mie", "multiple")
        n_r, n_s = stored[names[0]].shape[0], stored[names[0]].shape[2]
        cells = self._mu_s_cells
        i_r, w_r, _, _, w_g = lookup.r_mu_s_cell(rc, max(mu_s_min, 0.0), bottom, top, mu_s_min, n_r,
                                                 lookup.refined_mu_s_count(n_s, cells), cells)
        # the radius layers refined along the sun zenith, as the other lookups read the tables
        lower = [self._lookup_layer(name, min(i_r, n_r - 1)) for name in names]
        upper = [self._lookup_layer(name, min(i_r + 1, n_r - 1)) if max(w_r, w_g) > 0.0 else lo
                 for name, lo in zip(names, lower, strict=True)]
        dirs = np.ascontiguousarray(d)
        out = np.empty((s.shape[0], dirs.shape[0], n_l))
        bad = np.zeros((s.shape[0], dirs.shape[0]), dtype=np.bool_)
        projection = np.eye(n_l)
        parallel_for(lookup.observer_suns_kernel, s.shape[0], pos, rc, n_r, s, mu_s, *lower, *upper,
                     stored["transmittance"], stored["irradiance"], self._albedo, self._solar,
                     projection, True,
                     bottom, top, mu_s_min, cells, self._mie_g, self._mie_kind, self._lobe, *self._profiles,
                     self.parameters.sun_angular_radius, bool(include_ground), dirs, out, bad,
                     grain=max(1, 4096 // max(dirs.shape[0], 1)))
        if bad.any():
            return one_by_one()
        for k in range(s.shape[0]):
            # the observer's sky in twilight takes its single scattering computed at its own sun
            # (_twilight_singles), which this kernel's slices do not: those suns as sky_radiance has them
            if self._twilight_applies(float(mu_s[k])):
                out[k] = self.sky_radiance(pos, d, s[k], include_ground=include_ground)
        return out

    def _twilight_applies(self, mu_s: float) -> bool:
        """Whether the observer's path computes the single scattering for a sun of zenith cosine ``mu_s``
        (:meth:`_twilight_singles`)."""
        return (self.compute_twilight_single and mu_s <= self._twilight_top()
                and self.stored["single_rayleigh"].shape[3] >= 2)

    def _twilight_top(self) -> float:
        """The sun zenith cosine at the top of the twilight cells (:meth:`_twilight_singles`); -2 without them."""
        cells = self._mu_s_cells
        if cells == 0 or not self.computed:
            return -2.0
        bottom, top, mu_s_min = self._geometry()
        return float(_kernels().scattering_mu_s_param(cells, bottom, top, mu_s_min,
                                                      self.stored["single_rayleigh"].shape[2]))

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
        tab = self.lookup_tables
        parallel_for(lookup.aerial_kernel, n, cam, pts, sun, sh, tab["transmittance"], tab["single_rayleigh"],
                     tab["single_mie"], tab["multiple"], bottom, top, mu_s_min, self._mu_s_cells, self._mie_g,
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
        zeniths every 2 deg to 80 deg and every 0.5 deg from 80 to 98 deg (77 radiance integrals) and interpolated
        linearly; beyond 98 deg computed directly.

        This is the quantity a sky matrix integrates over its patches. The precomputed irradiance of
        :meth:`ground_irradiance` (Eq. 14) integrates the scattering orders on the coarser sphere quadrature of the
        table build (``irradiance_sphere_samples``) and differs from it by a few per cent (docs/sky_matrices.md).
        """
        from ..quadrature import plane_quadrature

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
            cached = (nodes, integrate(nodes))
            self._horizontal_sky_cache = cached
        nodes, values = cached
        out = np.empty((z.size, self.wavelengths.size))
        inside = z <= nodes[-1]
        zc = np.clip(z[inside], 0.0, None)
        k = np.clip(np.searchsorted(nodes, zc, side="right") - 1, 0, nodes.size - 2)
        w = ((zc - nodes[k]) / (nodes[k + 1] - nodes[k]))[:, None]
        out[inside] = (1.0 - w) * values[k] + w * values[k + 1]
        if np.any(~inside):
            out[~inside] = integrate(z[~inside])
        return out

    def ground_irradiance(self, points: ArrayLike, normals: ArrayLike,
                          sun_direction: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Sun and sky spectral irradiance [W m^-2 nm^-1] on surfaces at ``points`` [m] with ``normals``.

        The sky part is the irradiance on a horizontal surface times ``(1 + n . up) / 2`` (Eq. 14). On the ground
        (up to :data:`IRRADIANCE_TABLE_MAX_ALTITUDE` above it, and outside the atmosphere) the horizontal
        irradiance is the precomputed table's (Eq. 15; :meth:`table_irradiance`); above it, the tables' sky
        radiance integrated over the upper hemisphere (:meth:`sky_irradiance_integral`): the table's radius rows
        are linear in the altitude, 4 km apart at the default sizes, so between them it interpolated across an
        aerosol's 1.2 km scale height (aerosol optical depth 0.1, 1500 m: up to +48 % against DISORT;
        docs/bruneton.md).

        Parameters
        ----------
        points : array_like, shape (..., 3)
            Surface points [m] from the planet centre, on or above the ground.
        normals : array_like, shape (..., 3)
            Unit surface normals.
        sun_direction : array_like, shape (3,) or (..., 3)
            Direction towards the sun.
        """
        e_sun, e_sky = self.table_irradiance(points, normals, sun_direction)
        shape, pts, nrm, sun, _ = self._broadcast_rays(points, normals, sun_direction, None,
                                                       direction_name="normals")
        bottom, top, _ = self._geometry()
        r = np.sqrt(np.einsum("ij,ij->i", pts, pts))
        above = (r > bottom + IRRADIANCE_TABLE_MAX_ALTITUDE) & (r <= top)
        if np.any(above):
            flat = e_sky.reshape(-1, self.wavelengths.size)
            occl = 0.5 * (1.0 + np.einsum("ij,ij->i", nrm[above], pts[above]) / r[above])
            flat[above] = self.sky_irradiance_integral(pts[above], sun[above]) * occl[:, None]
            e_sky = flat.reshape(e_sky.shape)
        return e_sun, e_sky

    def table_irradiance(self, points: ArrayLike, normals: ArrayLike,
                         sun_direction: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Sun and sky spectral irradiance [W m^-2 nm^-1] on surfaces at ``points`` [m] with unit ``normals``, the
        sky part read from the precomputed irradiance table alone (Eq. 15) times ``(1 + n . up) / 2`` (Eq. 14).

        Exact at the table's radius rows (the ground, then every 4 km at the default sizes) and interpolated
        linearly in the altitude between them: :meth:`ground_irradiance` is the irradiance to use above the ground.
        This is the read the realtime export's GLSL reproduces (docs/realtime.md).
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

    def sky_irradiance_integral(self, points: ArrayLike, sun_direction: ArrayLike, *,
                                nodes: int = SKY_IRRADIANCE_NODES,
                                azimuth_step: float = SKY_IRRADIANCE_AZIMUTH_STEP) -> NDArray[np.float64]:
        """Sky spectral irradiance [W m^-2 nm^-1] on a horizontal surface at ``points`` [m] (inside the
        atmosphere), the tables' sky radiance (Eq. 16, :meth:`sky_radiance_suns`) integrated over the upper
        hemisphere:

            E(r, mu_s) = 2 integral_0^1 mu dmu integral_0^pi L(r, mu, mu_s, phi) dphi

        (the sky is symmetric about the sun's vertical plane), by ``nodes`` Gauss-Legendre nodes in ``mu`` and the
        trapezoid rule every ``azimuth_step`` [deg] in the azimuth ``phi`` from the sun. The radiance tables' rows
        follow ``rho`` ([Bruneton2008] Sec. 4), dense near the ground, unlike the irradiance table's (Eq. 15)
        rows linear in the altitude. Points of the same radius share one compiled call over their suns.

        Parameters
        ----------
        points : array_like, shape (..., 3)
            Points [m] from the planet centre, between the ground and the top of the atmosphere.
        sun_direction : array_like, shape (3,) or (..., 3)
            Direction towards the sun (normalised here).
        nodes : int
            Gauss-Legendre nodes in the cosine of the view zenith [-].
        azimuth_step : float
            Azimuth step [deg] of the trapezoid rule over 0-180 deg (a divisor of 180).

        Returns
        -------
        ndarray, shape broadcast + (n_wavelengths,)
        """
        shape, pts, sun, _, _ = self._broadcast_rays(points, sun_direction, sun_direction, None,
                                                     direction_name="sun_direction")
        self._check_above_ground(pts, "points")
        dirs, weights = _hemisphere_quadrature(int(nodes), float(azimuth_step))
        r = np.sqrt(np.einsum("ij,ij->i", pts, pts))
        mu_s = np.clip(np.einsum("ij,ij->i", pts, sun) / (r * np.linalg.norm(sun, axis=1)), -1.0, 1.0)
        # the sky at (r, mu_s) in a frame with the zenith along z and the sun in the x-z plane
        suns = np.stack([np.sqrt(1.0 - mu_s**2), np.zeros_like(mu_s), mu_s], axis=1)
        out = np.empty((r.size, self.wavelengths.size))
        radii, group = np.unique(r, return_inverse=True)
        for i, radius in enumerate(radii):
            rows = np.flatnonzero(group == i)
            rad = self.sky_radiance_suns(np.array([0.0, 0.0, radius]), dirs, suns[rows])
            out[rows] = np.einsum("d,kdw->kw", weights, rad)
        return out.reshape(*shape, -1)


def _hemisphere_quadrature(nodes: int, azimuth_step: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Directions (n, 3) of the upper hemisphere with the sun in the x-z plane and their weights (n,) [sr] times
    the cosine, for ``E = 2 int_0^1 mu dmu int_0^pi L dphi``: ``nodes`` Gauss-Legendre nodes in ``mu`` on (0, 1),
    the trapezoid rule every ``azimuth_step`` [deg] on [0, 180] deg (:meth:`TableLookups.sky_irradiance_integral`)."""
    count = round(180.0 / azimuth_step)
    if nodes < 1 or count < 1 or abs(count * azimuth_step - 180.0) > 1e-9:
        raise InvalidParameterError(f"the hemisphere quadrature needs nodes >= 1 and an azimuth step dividing 180 "
                                    f"deg; got {nodes}, {azimuth_step}")
    x, w = np.polynomial.legendre.leggauss(nodes)
    mu, w_mu = 0.5 * (x + 1.0), 0.5 * w
    phi = np.linspace(0.0, np.pi, count + 1)
    w_phi = np.full(phi.size, np.pi / count)
    w_phi[[0, -1]] *= 0.5
    s = np.sqrt(1.0 - mu**2)
    dirs = np.stack([np.outer(s, np.cos(phi)), np.outer(s, np.sin(phi)), np.outer(mu, np.ones_like(phi))], axis=-1)
    return np.ascontiguousarray(dirs.reshape(-1, 3)), 2.0 * np.outer(mu * w_mu, w_phi).ravel()
