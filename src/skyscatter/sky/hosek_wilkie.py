"""Hosek & Wilkie 2012 spectral sky with the Hosek & Wilkie 2013 solar-radiance function (reference code v1.4a).

Sky (Hosek & Wilkie 2012, Eqs. 9-11): for each of 11 bands (320, 360, ..., 720 nm)
``L(theta, gamma) = F(theta, gamma; A..I) * L_M`` with the extended Perez form F
(:func:`skyscatter.sky.perez_family.hosek_wilkie_f`). The nine parameters and the radiance scale L_M are
interpolated from the published datasets:

* in solar elevation eta by a quintic Bezier curve through six control points, with the curve parameter
  ``t = (eta / (pi / 2))^(1/3)`` (Sec. 5, Eq. 12);
* linearly in turbidity between the integer turbidities 1-10 and linearly in ground albedo between 0 and 1
  (``ArHosekSkyModel_CookConfiguration`` / ``..._CookRadianceConfiguration`` of the reference code).

Between bands the radiance is interpolated linearly, as ``arhosekskymodel_radiance`` does. The authors' CIE XYZ
and linear-sRGB datasets use the same form with three "bands" each (X, Y, Z with ``683 Y`` the luminance in
cd m^-2; R, G, B in the same radiometric scale).

Sun ([HosekWilkie2013]): per band and integer
turbidity, the radiance of the solar-disc centre is a piecewise cubic in the elevation of the view direction
(45 segments with breaks at ``(k / 45)^3 pi / 2``), times a 5th-order limb-darkening polynomial in the cosine
``mu`` of the angle on the solar surface (``arhosekskymodel_solar_radiance_internal2``). Data version 1.4
(February 2013) fixed the solar coefficients, which made the disc about 6 times too bright relative to the sky
in earlier releases; the package data are the 1.4a coefficients (see ``docs/hosek_wilkie.md``).

Data: ``skyscatter/data/hosek_wilkie_2013.npz``, converted by ``tools/generate_hosek_wilkie_data.py`` from the
authors' headers (BSD-3-Clause, Copyright (c) 2012-2013 Lukas Hosek and Alexander Wilkie; licence text in
``skyscatter/data/hosek_wilkie_LICENSE.txt``).

References: [HosekWilkie2012], [HosekWilkie2013].
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..conventions import as_directions
from ..deprecation import renamed_keywords, warn_renamed
from ..errors import FileFormatError, InvalidParameterError
from ..fileio import atomic_path
from ..spectral import as_wavelengths
from . import registry
from .base import SkyModel, SunSkyMixin, check_sun_angles
from .perez_family import HOSEK_WILKIE_OFFSET, gradation, indicatrix

__all__ = [
    "BANDS",
    "HosekWilkieDataset",
    "HosekWilkieSky",
    "SOLAR_RADIUS",
    "bezier_weights",
    "published_dataset",
]

#: Centre wavelengths [nm] of the 11 bands of the spectral model.
BANDS = np.arange(320.0, 721.0, 40.0)
#: Angular radius [rad] of the solar disc of the reference code (``TERRESTRIAL_SOLAR_RADIUS`` = 0.51 deg / 2).
SOLAR_RADIUS = np.radians(0.51) / 2.0
#: Solar spectrum at the top of the atmosphere used for the authors' reference simulations [W m^-2 sr^-1 nm^-1]
#: at the 11 bands (``originalSolarRadianceTable`` of the reference code: Preetham 1999's data extended to UV).
ORIGINAL_SOLAR_RADIANCE = np.array(
    [7500.0, 12500.0, 21127.5, 26760.5, 30663.7, 27825.0, 25503.8, 25134.2, 23212.1, 21526.7, 19870.8]
)

_DATA_FILE = "hosek_wilkie_2013.npz"
_LAYOUT_VERSION = 1
_N_CONTROL, _N_PARAMS, _N_SEGMENTS = 6, 9, 45
# key -> expected shape (None = any length on that axis, checked for consistency below)
_PUBLISHED_LAYOUT: dict[str, tuple[int, ...]] = {
    "wavelengths": (11,),
    "spectral_params": (11, 2, 10, 6, 9),
    "spectral_radiance": (11, 2, 10, 6),
    "solar_polynomials": (11, 10, 45, 4),
    "limb_darkening": (11, 6),
    "xyz_params": (3, 2, 10, 6, 9),
    "xyz_radiance": (3, 2, 10, 6),
    "rgb_params": (3, 2, 10, 6, 9),
    "rgb_radiance": (3, 2, 10, 6),
}


def bezier_weights(t: float) -> NDArray[np.float64]:
    """Quintic Bernstein weights ``C(5, k) (1 - t)^(5 - k) t^k``, k = 0..5 (Hosek & Wilkie 2012, Eq. 12)."""
    u = 1.0 - t
    return np.array([u**5, 5.0 * u**4 * t, 10.0 * u**3 * t**2, 10.0 * u**2 * t**3, 5.0 * u * t**4, t**5])


def _axis_weights(axis: NDArray[np.float64], value: float) -> list[tuple[int, float]]:
    """(index, weight) pairs for linear interpolation of ``value`` on a sorted axis (no extrapolation).

    On the published turbidity axis 1..10 this is the reference code's rule: low index ``int(T) - 1`` with
    weight ``1 - (T - int(T))``, the next one with ``T - int(T)``, and at T = 10 exactly the last entry alone
    (the reference returns early there instead of reading past the table).
    """
    n = axis.size
    if n == 1:
        return [(0, 1.0)]
    i = int(np.searchsorted(axis, value, side="right")) - 1
    i = min(max(i, 0), n - 1)
    if i == n - 1:
        return [(i, 1.0)]
    frac = (value - axis[i]) / (axis[i + 1] - axis[i])
    return [(i, 1.0 - frac), (i + 1, frac)]


@dataclass(frozen=True, eq=False)
class HosekWilkieDataset:
    """Coefficients of the Hosek-Wilkie sky form: per wavelength, albedo, turbidity and control point.

    Attributes
    ----------
    wavelengths : ndarray, shape (n_wl,)
        Band centres [nm], increasing.
    params : ndarray, shape (n_wl, n_albedo, n_turbidity, 6, 9)
        The nine parameters A..I (stored in the order A, B, C, D, E, F, G, I, H) at the six Bezier control
        points in ``t = (eta / (pi/2))^(1/3)``.
    radiance : ndarray, shape (n_wl, n_albedo, n_turbidity, 6)
        Radiance scale L_M [W m^-2 sr^-1 nm^-1] at the control points.
    albedos, turbidities : ndarray
        Axes of the dataset (increasing); a dataset for one atmosphere has length-1 axes.
    provenance : dict
        JSON-able description of where the coefficients come from (fits: the source atmosphere and settings).
    """

    wavelengths: NDArray[np.float64]
    params: NDArray[np.float64]
    radiance: NDArray[np.float64]
    albedos: NDArray[np.float64] = field(default_factory=lambda: np.array([0.0]))
    turbidities: NDArray[np.float64] = field(default_factory=lambda: np.array([1.0]))
    provenance: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        wl = np.asarray(self.wavelengths, dtype=np.float64)
        params = np.asarray(self.params, dtype=np.float64)
        rad = np.asarray(self.radiance, dtype=np.float64)
        alb = np.atleast_1d(np.asarray(self.albedos, dtype=np.float64))
        turb = np.atleast_1d(np.asarray(self.turbidities, dtype=np.float64))
        shape = (wl.size, alb.size, turb.size, _N_CONTROL)
        if wl.ndim != 1 or wl.size == 0 or params.shape != (*shape, _N_PARAMS) or rad.shape != shape:
            raise FileFormatError(
                "Hosek-Wilkie dataset arrays do not match: expected wavelengths (n,), params (n, n_albedo, "
                f"n_turbidity, 6, 9) and radiance (n, n_albedo, n_turbidity, 6); got {wl.shape}, {params.shape}, "
                f"{rad.shape} with {alb.size} albedos and {turb.size} turbidities"
            )
        for name, axis in (("wavelengths", wl), ("albedos", alb), ("turbidities", turb)):
            if not np.all(np.isfinite(axis)) or np.any(np.diff(axis) <= 0):
                raise FileFormatError(f"Hosek-Wilkie dataset {name} must be finite and increasing; got {axis}")
        if not (np.all(np.isfinite(params)) and np.all(np.isfinite(rad))):
            raise FileFormatError("Hosek-Wilkie dataset contains non-finite coefficients")
        for name, value in (("wavelengths", wl), ("params", params), ("radiance", rad), ("albedos", alb),
                            ("turbidities", turb)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    # -- configuration ----------------------------------------------------------------------------------
    def configuration(
        self, sun_elevation: float, turbidity: float | None = None, albedo: float | None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Parameters (n_wl, 9) and radiance scales (n_wl,) for a sun elevation [rad], turbidity and albedo.

        The reference code's ``ArHosekSkyModel_CookConfiguration``: Bezier in ``t = (eta / (pi/2))^(1/3)``
        (Eq. 12), linear in turbidity and albedo. ``sun_elevation`` must be in [0, pi/2] (the cube root of a
        negative elevation is NaN in the reference code). ``turbidity``/``albedo`` may be None on an axis of
        length 1.
        """
        eta = float(sun_elevation)
        if not 0.0 <= eta <= np.pi / 2:
            raise InvalidParameterError(
                f"Hosek-Wilkie needs a sun elevation in [0, 90] deg; got {np.degrees(eta):.6g} deg"
            )
        t = np.power(eta / (np.pi / 2.0), 1.0 / 3.0)
        w = bezier_weights(t)
        params = np.zeros((self.wavelengths.size, _N_PARAMS))
        rad = np.zeros(self.wavelengths.size)
        for ia, wa in _axis_weights(self.albedos, self._axis_value("albedo", albedo, self.albedos)):
            for it, wt in _axis_weights(self.turbidities, self._axis_value("turbidity", turbidity, self.turbidities)):
                params += wa * wt * np.einsum("k,wkp->wp", w, self.params[:, ia, it])
                rad += wa * wt * (self.radiance[:, ia, it] @ w)
        return params, rad

    @staticmethod
    def _axis_value(name: str, value: float | None, axis: NDArray[np.float64]) -> float:
        if value is None:
            if axis.size != 1:
                raise InvalidParameterError(f"this Hosek-Wilkie dataset needs a {name} ({axis[0]:g} to {axis[-1]:g})")
            return float(axis[0])
        v = float(value)
        if axis.size > 1 and not axis[0] <= v <= axis[-1]:
            raise InvalidParameterError(
                f"{name} must be within [{axis[0]:g}, {axis[-1]:g}] for this Hosek-Wilkie dataset; got {v:g}"
            )
        return v

    # -- files ------------------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able data (nested lists of floats; exact round trip through :meth:`from_dict`)."""
        return {"wavelengths": self.wavelengths.tolist(), "params": self.params.tolist(),
                "radiance": self.radiance.tolist(), "albedos": self.albedos.tolist(),
                "turbidities": self.turbidities.tolist(), "provenance": dict(self.provenance)}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> HosekWilkieDataset:
        """Inverse of :meth:`to_dict`; FileFormatError for missing or malformed entries."""
        try:
            return cls(**{k: data[k] for k in ("wavelengths", "params", "radiance", "albedos", "turbidities")},
                       provenance=dict(data.get("provenance", {})))
        except (KeyError, TypeError, ValueError) as exc:
            raise FileFormatError(f"Hosek-Wilkie dataset description is incomplete or malformed: {exc}") from None

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the dataset to ``path`` (.npz, written atomically) with its provenance as JSON."""
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            np.savez_compressed(
                fh,
                format=np.array("skyscatter.HosekWilkieDataset"),
                layout_version=np.array(_LAYOUT_VERSION),
                wavelengths=self.wavelengths,
                params=self.params,
                radiance=self.radiance,
                albedos=self.albedos,
                turbidities=self.turbidities,
                provenance=np.array(json.dumps(self.provenance, sort_keys=True)),
            )

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> HosekWilkieDataset:
        """Read a dataset written by :meth:`save`; raises FileFormatError for any other or damaged file."""
        p = Path(path)
        keys = ("format", "layout_version", "wavelengths", "params", "radiance", "albedos", "turbidities",
                "provenance")
        try:
            with np.load(p, allow_pickle=False) as z:
                missing = [k for k in keys if k not in z.files]
                if missing:
                    raise FileFormatError(f"{p}: not a Hosek-Wilkie dataset (missing {', '.join(missing)})")
                arrays = {k: z[k] for k in keys}
        except FileFormatError:
            raise
        except FileNotFoundError:
            raise FileFormatError(f"{p}: no such file") from None
        except Exception as exc:  # zip/np errors for truncated or foreign files
            raise FileFormatError(f"{p}: cannot read a Hosek-Wilkie dataset ({exc})") from exc
        if str(arrays["format"]) != "skyscatter.HosekWilkieDataset" or int(arrays["layout_version"]) != _LAYOUT_VERSION:
            raise FileFormatError(
                f"{p}: unsupported dataset format {arrays['format']!s} layout {arrays['layout_version']!s} "
                f"(this version reads skyscatter.HosekWilkieDataset layout {_LAYOUT_VERSION})"
            )
        try:
            provenance = json.loads(str(arrays["provenance"]))
        except json.JSONDecodeError as exc:
            raise FileFormatError(f"{p}: provenance is not valid JSON ({exc})") from exc
        try:
            return cls(arrays["wavelengths"], arrays["params"], arrays["radiance"], arrays["albedos"],
                       arrays["turbidities"], provenance)
        except FileFormatError as exc:
            raise FileFormatError(f"{p}: {exc}") from exc


@dataclass(frozen=True, eq=False)
class _PublishedData:
    spectral: HosekWilkieDataset
    xyz: HosekWilkieDataset
    rgb: HosekWilkieDataset
    solar_polynomials: NDArray[np.float64]  # (11 bands, 10 turbidities, 45 segments, 4), cubic coefficient first
    limb_darkening: NDArray[np.float64]  # (11 bands, 6), coefficient of mu^k at k


def load_published_data(path: str | os.PathLike[str] | None = None) -> _PublishedData:
    """Read and check the published v1.4a datasets (default: the package data file).

    Raises FileFormatError if a key is missing or an array has another shape (a truncated or different-layout
    file); nothing is returned half-loaded.
    """
    source = resources.files("skyscatter.data").joinpath(_DATA_FILE) if path is None else Path(path)
    try:
        with source.open("rb") as fh, np.load(fh, allow_pickle=False) as z:
            missing = [k for k in (*_PUBLISHED_LAYOUT, "layout_version") if k not in z.files]
            if missing:
                raise FileFormatError(f"{source}: Hosek-Wilkie data file lacks {', '.join(missing)}")
            arrays = {k: np.array(z[k], dtype=np.float64) for k in _PUBLISHED_LAYOUT}
            layout = int(z["layout_version"])
    except FileFormatError:
        raise
    except Exception as exc:
        raise FileFormatError(f"{source}: cannot read the Hosek-Wilkie data file ({exc})") from exc
    if layout != _LAYOUT_VERSION:
        raise FileFormatError(f"{source}: layout version {layout}, expected {_LAYOUT_VERSION}")
    for key, shape in _PUBLISHED_LAYOUT.items():
        if arrays[key].shape != shape:
            raise FileFormatError(f"{source}: {key} has shape {arrays[key].shape}, expected {shape}")
        if not np.all(np.isfinite(arrays[key])):
            raise FileFormatError(f"{source}: {key} contains non-finite values")
    if not np.array_equal(arrays["wavelengths"], BANDS):
        raise FileFormatError(f"{source}: bands {arrays['wavelengths']} differ from 320-720 nm in 40 nm steps")
    axes = dict(albedos=np.array([0.0, 1.0]), turbidities=np.arange(1.0, 11.0))
    prov = {"source": "Hosek & Wilkie 2012-2013 reference data v1.4a (BSD-3-Clause)"}
    ds = HosekWilkieDataset(BANDS, arrays["spectral_params"], arrays["spectral_radiance"], **axes, provenance=prov)
    xyz = HosekWilkieDataset(np.array([1.0, 2.0, 3.0]), arrays["xyz_params"], arrays["xyz_radiance"], **axes)
    rgb = HosekWilkieDataset(np.array([1.0, 2.0, 3.0]), arrays["rgb_params"], arrays["rgb_radiance"], **axes)
    for a in (arrays["solar_polynomials"], arrays["limb_darkening"]):
        a.setflags(write=False)
    return _PublishedData(ds, xyz, rgb, arrays["solar_polynomials"], arrays["limb_darkening"])


@lru_cache(maxsize=1)
def _published() -> _PublishedData:
    return load_published_data()


def published_dataset() -> HosekWilkieDataset:
    """The published spectral dataset (11 bands, albedo 0 and 1, turbidity 1-10) as a HosekWilkieDataset."""
    return _published().spectral


def _band_interpolation(wl: NDArray[np.float64], bands: NDArray[np.float64]) -> NDArray[np.float64]:
    """Matrix (n_wl, n_bands) of linear interpolation weights between bands; rows outside the bands are 0.

    On the published bands this is ``arhosekskymodel_radiance``'s rule, including its snapping of a fraction
    below 1e-6 to the lower band.
    """
    m = np.zeros((wl.size, bands.size))
    if bands.size == 1:
        m[wl == bands[0], 0] = 1.0
        return m
    inside = (wl >= bands[0]) & (wl <= bands[-1])
    idx = np.clip(np.searchsorted(bands, wl, side="right") - 1, 0, bands.size - 2)
    frac = (wl - bands[idx]) / (bands[idx + 1] - bands[idx])
    frac = np.where(frac < 1e-6, 0.0, frac)
    rows = np.nonzero(inside)[0]
    m[rows, idx[rows]] = 1.0 - frac[rows]
    m[rows, idx[rows] + 1] += frac[rows]
    return m


def _solar_bands(wl: NDArray[np.float64]) -> list[tuple[int, tuple[int, float]]]:
    """(index, (lower band, fraction)) of each wavelength in 320-720 nm, by the solar model's rule.

    ``arhosekskymodel_solar_radiance_internal2``: band ``int((w - 320) / 40)``, fraction ``fmod(w, 40) / 40``,
    the last band (720 nm) taken as band 9 at fraction 1; wavelengths outside 320-720 nm are left out (zero).
    """
    out = []
    for j, w in enumerate(wl):
        if not 320.0 <= w <= 720.0:
            continue
        low, frac = int((w - 320.0) / 40.0), float(np.fmod(w, 40.0) / 40.0)
        out.append((j, (9, 1.0) if low == 10 else (low, frac)))
    return out


class HosekWilkieSky(SunSkyMixin, SkyModel):
    """Hosek & Wilkie 2012 clear sky (spectral, XYZ and RGB datasets) with the 2013 solar disc.

    Parameters
    ----------
    sun_zenith : float
        Sun zenith angle [rad], 0 to pi/2. The model is fitted for the sun above the horizon only; a sun below
        it raises :class:`~skyscatter.errors.SunBelowHorizonError` (the reference code takes the cube root of the
        negative elevation and returns NaN).
    sun_azimuth : float
        Sun azimuth [rad] from north towards east.
    turbidity : float
        Linke-like turbidity of the published model, 1 to 10 (default 3). Values outside raise
        :class:`~skyscatter.errors.InvalidParameterError` (the reference code reads outside its tables).
    ground_albedo : float
        Albedo of the atmosphere's ground, 0 to 1 (default 0.1), the same for every band (``albedo`` is its
        deprecated spelling).
    dataset : HosekWilkieDataset, optional
        Coefficients to use instead of the published ones (e.g. from :func:`skyscatter.fit.fit_hosek_wilkie`).
        ``turbidity`` and ``ground_albedo`` then index the dataset's own axes (they are ignored for axes of length 1).
        Such a sky has no solar disc (``has_sun`` False): the 2013 solar function belongs to the published
        atmosphere; its ``xyz`` integrates the spectral model.

    Notes
    -----
    * ``spectral_radiance`` is zero below the horizon and, for the published data, outside 320-720 nm: the
      model has no data there. (The reference ``arhosekskymodel_radiance`` is not a better guide: its
      truncating ``int()`` extrapolates linearly from 320 and 360 nm for 280-320 nm, and it fades the 720 nm
      band linearly to zero over 720-760 nm.)
    * ``xyz``/``luminance`` use the authors' CIE XYZ dataset (luminance = 683 Y), not an integral of the
      spectral model (which covers 320-720 nm only); ``rgb`` uses their linear-sRGB dataset.
    * The sky functions never include the sun; ``solar_radiance`` is the disc alone, and the reference
      ``arhosekskymodel_solar_radiance`` equals ``spectral_radiance + solar_radiance``.
    """

    model_name = "hosek-wilkie"

    @renamed_keywords(albedo="ground_albedo")
    def __init__(
        self,
        sun_zenith: float,
        sun_azimuth: float,
        *,
        turbidity: float = 3.0,
        ground_albedo: float = 0.1,
        dataset: HosekWilkieDataset | None = None,
    ) -> None:
        self.sun_zenith, self.sun_azimuth = check_sun_angles(sun_zenith, sun_azimuth, allow_below_horizon=False)
        self.sun_elevation = np.pi / 2.0 - self.sun_zenith
        albedo = ground_albedo
        if dataset is None:  # the published data's ranges, stated once in the registry
            spec = registry.get(self.model_name)
            turbidity = spec.parameter("turbidity").check(turbidity, spec.name)
            albedo = spec.parameter("ground_albedo").check(albedo, spec.name)
        self.turbidity = turbidity
        self.ground_albedo = albedo
        self.dataset = dataset
        if dataset is None:
            data = _published()
            self._bands = data.spectral.wavelengths
            self._params, self._radiance = data.spectral.configuration(self.sun_elevation, turbidity, albedo)
            self._xyz_config = data.xyz.configuration(self.sun_elevation, turbidity, albedo)
            self._rgb_config = data.rgb.configuration(self.sun_elevation, turbidity, albedo)
        else:
            if not isinstance(dataset, HosekWilkieDataset):
                raise InvalidParameterError(f"dataset must be a HosekWilkieDataset; got {type(dataset).__name__}")
            self._bands = dataset.wavelengths
            t = turbidity if dataset.turbidities.size > 1 else None
            a = albedo if dataset.albedos.size > 1 else None
            self.turbidity, self.ground_albedo = t, a  # None: not an axis of this dataset
            self._params, self._radiance = dataset.configuration(self.sun_elevation, t, a)
        self._remember(turbidity=self.turbidity, ground_albedo=self.ground_albedo, dataset=dataset)

    @property
    def albedo(self) -> float | None:
        """Deprecated: :attr:`ground_albedo`."""
        warn_renamed("HosekWilkieSky.albedo", "HosekWilkieSky.ground_albedo", "HosekWilkieSky", stacklevel=3)
        return self.ground_albedo

    sun_angular_radius = SOLAR_RADIUS

    @property
    def sun(self):
        """The 2013 solar disc of the published model; None for a fitted dataset (it has no solar function)."""
        return None if self.dataset is not None else SunSkyMixin.sun.fget(self)

    def __repr__(self) -> str:
        extra = "" if self.dataset is None else ", dataset=<fitted>"
        return (
            f"HosekWilkieSky(sun_zenith={self.sun_zenith:.6g}, sun_azimuth={self.sun_azimuth:.6g}, "
            f"turbidity={self.turbidity!r}, ground_albedo={self.ground_albedo!r}{extra})"
        )

    # -- sky ----------------------------------------------------------------------------------------------
    def _geometry(self, directions: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64], tuple[int, ...]]:
        d = as_directions(directions)
        shape = d.shape[:-1]
        flat = d.reshape(-1, 3).astype(np.float64, copy=False)
        return flat, self._gamma(flat), shape

    def _evaluate(self, directions: ArrayLike, params: NDArray[np.float64], scale: NDArray[np.float64], *,
                  clip: bool = True, weights: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
        """``F(theta, gamma; params[b]) * scale[b]`` for every direction and band b, zero below the horizon.

        With ``clip`` negative values are set to 0 (see the class notes). With ``weights`` (n_out, n_bands), at
        most two non-zero per row, the result is instead ``weights @ bands`` per direction, negative sums set to
        0 (the band values themselves unclipped). One compiled pass over the directions
        (:mod:`.hosek_wilkie_kernel`, on all cores); fewer than :data:`_KERNEL_MIN_DIRECTIONS` directions in a
        process that has not imported numba go through numpy (:meth:`_evaluate_numpy`), the same values to
        rounding (``tests/test_hosek_wilkie.py``).
        """
        try:
            d = np.asarray(directions)
        except (ValueError, TypeError):
            d = None
        if d is None or d.dtype.kind not in "fiu" or d.ndim == 0 or d.shape[-1] != 3:
            as_directions(directions)  # raises the error that says what is wrong
        assert d is not None  # as_directions raised otherwise
        shape = d.shape[:-1]
        p = np.ascontiguousarray(params, dtype=np.float64).reshape(-1, 9)
        sc = np.ascontiguousarray(scale, dtype=np.float64).ravel()
        if d.size < 3 * _KERNEL_MIN_DIRECTIONS and "numba" not in sys.modules:
            # a few directions in a process without numba (a small image from the command line): numpy, without
            # numba's import and first-use cost (about 0.5 s, more than numpy takes for these directions)
            bands = self._evaluate_numpy(d, p, sc, clip=clip and weights is None)
            if weights is None:
                return bands
            return np.maximum(bands @ weights.T, 0.0)
        from ..precomputed.parallel import parallel_for
        from . import hosek_wilkie_kernel

        flat = np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float64)
        if weights is None:
            index = np.repeat(np.arange(sc.size, dtype=np.int64)[:, None], 2, axis=1)
            weight = np.zeros((sc.size, 2))
            weight[:, 0] = 1.0
            clip_bands = clip_out = clip
        else:
            index, weight = _two_band_weights(weights)
            clip_bands, clip_out = False, True
        out = np.empty((flat.shape[0], index.shape[0]))
        bad = np.zeros(flat.shape[0], dtype=np.bool_)
        parallel_for(hosek_wilkie_kernel.radiance_kernel, flat.shape[0], flat,
                     np.ascontiguousarray(self.sun_direction, dtype=np.float64), p, sc, index, weight,
                     bool(clip_bands), bool(clip_out), out, bad, grain=4096)
        if bad.any():
            as_directions(d)  # raises: zero, NaN or infinite directions
        return out.reshape(*shape, index.shape[0])

    def _evaluate_numpy(self, directions: NDArray[np.float64], params: NDArray[np.float64],
                        scale: NDArray[np.float64], *, clip: bool) -> NDArray[np.float64]:
        """:meth:`_evaluate` without weights, with numpy (the same operations as the kernel, on blocks of
        directions): :func:`.perez_family.gradation` and :func:`.perez_family.indicatrix`."""
        d = as_directions(directions)
        shape = d.shape[:-1]
        flat = np.asarray(d.reshape(-1, 3), dtype=np.float64)
        out = np.empty((flat.shape[0], scale.size))
        # Parameters in the stored order A..G, I, H (HOSEK_WILKIE_PARAMETER_ORDER), one row per band.
        a, b, c, dd, e, f, g, i, h = (params[None, :, k] for k in range(9))
        step = max(1, _CHUNK // max(scale.size, 1))
        for start in range(0, flat.shape[0], step):
            sl = slice(start, start + step)
            z = flat[sl, 2:3]
            gamma = self._gamma(flat[sl])[:, None]  # atan2 form, accurate near the sun
            v = gradation(z, a, b, HOSEK_WILKIE_OFFSET)
            v *= indicatrix(z, gamma, np.cos(gamma), c, dd, e, f, g, h, i)
            v *= scale
            if clip:
                np.maximum(v, 0.0, out=v)
            v[z[:, 0] < 0.0] = 0.0  # the form is defined on the upper hemisphere only
            out[sl] = v
        return out.reshape(*shape, scale.size)

    def band_radiance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Sky radiance [W m^-2 sr^-1 nm^-1] at the dataset's band centres, shape (..., n_bands) (Eq. 11)."""
        return self._evaluate(directions, self._params, self._radiance)

    def spectral_radiance(self, directions: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] of the sky, shape (..., n_wavelengths).

        Linear between the bands of the dataset (320-720 nm in 40 nm steps for the published one), zero
        outside them and below the horizon (see the class notes).
        """
        wl = as_wavelengths(wavelengths)
        weights = _band_interpolation(wl, self._bands)
        used = np.nonzero(np.any(weights != 0.0, axis=0))[0]
        if used.size == 0:
            d = as_directions(directions)
            return np.zeros((*d.shape[:-1], wl.size))
        return self._evaluate(directions, self._params[used], self._radiance[used], weights=weights[:, used])

    def luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Luminance [cd m^-2]: 683 times the Y of the authors' XYZ dataset (the Y channel alone), shape (...)."""
        if self.dataset is not None:
            return super().luminance(directions)
        params, scale = self._xyz_config
        # 683 folded into the scale: no pass over the result (the same value to one rounding)
        return self._evaluate(directions, params[1:2], 683.0 * scale[1:2])[..., 0]

    def xyz(self, directions: ArrayLike) -> NDArray[np.float64]:
        """CIE 1931 XYZ [cd m^-2] from the authors' XYZ dataset (683 times its X, Y, Z), shape (..., 3)."""
        if self.dataset is not None:
            return super().xyz(directions)
        params, scale = self._xyz_config
        return 683.0 * self._evaluate(directions, params, scale)

    def rgb(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Linear sRGB from the authors' RGB dataset, in skyscatter's HDR scale (Y = luminance / 683)."""
        if self.dataset is not None:
            return super().rgb(directions)
        params, scale = self._rgb_config
        return self._evaluate(directions, params, scale, clip=False)

    # -- sun ----------------------------------------------------------------------------------------------
    def _solar_centre(self, elevation: NDArray[np.float64], wl: NDArray[np.float64]) -> NDArray[np.float64]:
        """Radiance of the disc centre [W m^-2 sr^-1 nm^-1] (..., n_wl) for view elevations [rad] >= 0.

        ``arhosekskymodel_sr_internal`` interpolated in turbidity and wavelength as
        ``arhosekskymodel_solar_radiance_internal2`` does. Wavelengths outside 320-720 nm give 0.
        """
        poly = _published().solar_polynomials
        t = float(self.turbidity)
        turb_low = int(t) - 1
        turb_frac = t - (turb_low + 1)
        if turb_low == 9:
            turb_low, turb_frac = 8, 1.0
        pos = np.floor(np.power(2.0 * elevation / np.pi, 1.0 / 3.0) * _N_SEGMENTS).astype(np.int64)
        pos = np.minimum(pos, _N_SEGMENTS - 1)
        x = elevation - np.power(pos / _N_SEGMENTS, 3.0) * (np.pi * 0.5)

        def band(b: int, tb: int) -> NDArray[np.float64]:
            c = poly[b, tb, pos]  # (..., 4): x^3, x^2, x, 1
            return c[..., 3] + x * (c[..., 2] + x * (c[..., 1] + x * c[..., 0]))

        out = np.zeros((*np.shape(elevation), wl.size))
        for j, (wl_low, wl_frac) in _solar_bands(wl):
            lo = (1.0 - wl_frac) * band(wl_low, turb_low) + wl_frac * band(wl_low + 1, turb_low)
            hi = (1.0 - wl_frac) * band(wl_low, turb_low + 1) + wl_frac * band(wl_low + 1, turb_low + 1)
            out[..., j] = (1.0 - turb_frac) * lo + turb_frac * hi
        return out

    def _limb_coefficients(self, wl: NDArray[np.float64]) -> NDArray[np.float64]:
        """Limb-darkening coefficients (n_wl, 6), linear in wavelength between bands (zero outside 320-720)."""
        ld = _published().limb_darkening
        out = np.zeros((wl.size, 6))
        for j, (wl_low, wl_frac) in _solar_bands(wl):
            out[j] = (1.0 - wl_frac) * ld[wl_low] + wl_frac * ld[wl_low + 1]
        return out

    def _require_sun(self) -> None:
        if self.dataset is not None:
            raise InvalidParameterError(
                "a Hosek-Wilkie sky built from a fitted dataset has no solar disc; the 2013 solar function "
                "belongs to the published atmosphere"
            )

    def solar_radiance(self, directions: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Radiance of the solar disc alone [W m^-2 sr^-1 nm^-1], zero outside it, shape (..., n_wl).

        Hosek & Wilkie 2013: the piecewise cubic in the elevation of the view direction times the limb
        darkening ``sum_k c_k mu^k`` with ``mu = sqrt(1 - sin^2 gamma / sin^2 r)``, r = 0.255 deg
        (``arhosekskymodel_solar_radiance_internal2``). Zero for directions below the horizon, outside the
        disc, for wavelengths outside 320-720 nm, and for gamma > 90 deg (the reference's ``sin gamma`` test
        would also light up the anti-solar point).
        """
        self._require_sun()
        wl = as_wavelengths(wavelengths)
        flat, gamma, shape = self._geometry(directions)
        out = np.zeros((flat.shape[0], wl.size))
        s = np.sin(gamma)
        sc2 = np.maximum(1.0 - s * s / np.sin(SOLAR_RADIUS) ** 2, 0.0)
        mu = np.sqrt(sc2)
        hit = (mu > 0.0) & (gamma < np.pi / 2) & (flat[:, 2] >= 0.0)
        if np.any(hit):
            elevation = np.pi / 2.0 - np.arccos(np.clip(flat[hit, 2], -1.0, 1.0))
            centre = self._solar_centre(elevation, wl)
            c = self._limb_coefficients(wl)
            m = mu[hit, None]
            darkening = c[:, 0] + m * (c[:, 1] + m * (c[:, 2] + m * (c[:, 3] + m * (c[:, 4] + m * c[:, 5]))))
            out[hit] = centre * darkening
        return out.reshape(*shape, wl.size)

    def sun_spectral_radiance(self, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Disc-averaged solar radiance [W m^-2 sr^-1 nm^-1] at the sun centre's elevation, shape (n_wl,).

        The solid-angle average of :meth:`solar_radiance` over the disc of radius 0.255 deg, with the
        elevation of the disc centre (the variation across the disc is linear in elevation to first order and
        averages out). Irradiance = this times :attr:`sun_solid_angle`.
        """
        self._require_sun()
        wl = as_wavelengths(wavelengths)
        centre = self._solar_centre(np.array(self.sun_elevation), wl)
        return centre * (self._limb_coefficients(wl) @ _mean_mu_powers())

    def sun_limb_darkening(self, r: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Radiance across the disc over its average, at relative radius ``r`` in [0, 1], shape (..., n_wl).

        Hosek & Wilkie 2013: ``sum_k c_k mu^k`` with ``mu = sqrt(1 - sin^2(r R) / sin^2 R)`` (R the disc radius),
        divided by its solid-angle mean so that :meth:`sun_spectral_radiance` times this is
        :meth:`solar_radiance` at that point of a disc centred at the sun's elevation. 0 outside the disc.
        """
        self._require_sun()
        wl = as_wavelengths(wavelengths)
        rr = np.clip(np.asarray(r, dtype=float), 0.0, None)
        mu = np.sqrt(np.maximum(1.0 - np.sin(rr * SOLAR_RADIUS) ** 2 / np.sin(SOLAR_RADIUS) ** 2, 0.0))[..., None]
        c = self._limb_coefficients(wl)
        mean = c @ _mean_mu_powers()
        darkening = c[:, 0] + mu * (c[:, 1] + mu * (c[:, 2] + mu * (c[:, 3] + mu * (c[:, 4] + mu * c[:, 5]))))
        with np.errstate(invalid="ignore", divide="ignore"):
            out = np.where(mean > 0, darkening / np.where(mean > 0, mean, 1.0), 0.0)
        return np.where(rr[..., None] <= 1.0, out, 0.0)

    def sun_xyz(self) -> NDArray[np.float64]:
        """CIE XYZ [cd m^-2] of the disc-averaged sun, integrated from its spectrum over 320-720 nm."""
        self._require_sun()
        return super().sun_xyz()


#: Direction x band values per vectorised step of ``HosekWilkieSky._evaluate_numpy`` (temporaries stay in cache).
_CHUNK = 65536
#: Fewest directions evaluated by the compiled kernel in a process that has not imported numba yet (below, numpy).
_KERNEL_MIN_DIRECTIONS = 32768


def _two_band_weights(weights: NDArray[np.float64]) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """The interpolation matrix (n_out, n_bands) of :func:`_band_interpolation` (at most two non-zero weights per
    row) as ``(index, weight)`` arrays (n_out, 2) for :func:`.hosek_wilkie_kernel.radiance_kernel`."""
    n_out = weights.shape[0]
    index = np.zeros((n_out, 2), dtype=np.int64)
    weight = np.zeros((n_out, 2))
    for j in range(n_out):  # a few dozen wavelengths
        nz = np.nonzero(weights[j])[0]
        if nz.size > 2:
            raise InvalidParameterError("band interpolation weights must have at most two bands per wavelength")
        index[j, : nz.size] = nz
        weight[j, : nz.size] = weights[j, nz]
    return index, weight


@lru_cache(maxsize=1)
def _mean_mu_powers() -> NDArray[np.float64]:
    """Solid-angle means of mu^k, k = 0..5, over the disc of radius SOLAR_RADIUS.

    With ``sin gamma = sin r sqrt(1 - mu^2)``, ``d(cos gamma) = sin^2 r mu dmu / cos gamma``; Gauss-Legendre in
    mu (smooth integrand) is exact to rounding with 32 nodes.
    """
    x, w = np.polynomial.legendre.leggauss(32)
    mu = 0.5 * (x + 1.0)
    w = 0.5 * w
    s2 = np.sin(SOLAR_RADIUS) ** 2
    weight = w * mu / np.sqrt(1.0 - s2 * (1.0 - mu * mu))
    return np.array([np.sum(weight * mu**k) for k in range(6)]) / np.sum(weight)
