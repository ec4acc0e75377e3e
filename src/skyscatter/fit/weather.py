"""The atmosphere of every hour of a weather record, retrieved from its measured irradiance.

For each daylit hour of an EPW file (or a TMY3 file or a CSV with the same columns, :func:`read_weather`)
:func:`retrieve_hourly_atmosphere` finds the air that reproduces the record's broadband irradiance through the
medium (:class:`~skyscatter.atmosphere.medium.AtmosphereParameters`) and a family of precomputed tables over a
parameter grid (:class:`~skyscatter.precomputed.family.TableFamily`), and reports per hour what it used and
how well the result reproduces the record.

**Broadband model** (:class:`BroadbandClearSky`). The direct normal irradiance of a clear hour is

    DNI = f_ecc sum_lambda w E0(lambda) exp(-sum_c tau_c(lambda) m_c) T_w(lambda) T_u(lambda)

over the ASTM G173 extraterrestrial spectrum 280-4000 nm (:func:`~skyscatter.atmosphere.gas_absorption.
broadband_solar_spectrum`, trapezoid weights w), with the medium's own vertical optical depths tau_c of
Rayleigh scattering, aerosol extinction and ozone (ozone outside the medium's 360-830 nm data: Bird & Riordan
1986, Eq. 2-9) along the medium's slant optical masses m_c (:func:`~skyscatter.atmosphere.gas_absorption.
slant_optical_masses`, the geometry of the tables, no refraction), water vapour and mixed-gas band
transmittances T_w, T_u (Bird & Riordan 1986, Eqs. 2-8 and 2-11; air mass the Rayleigh one) and Spencer's
(1971) eccentricity factor f_ecc (:func:`skyscatter.sky.perez.extraterrestrial_irradiance`). The diffuse
horizontal irradiance is the tables' sky radiance integrated over the hemisphere at the table wavelengths
(:meth:`~skyscatter.precomputed.evaluation.TableLookups.horizontal_sky_irradiance`: the quantity the sky matrix's
patches are scaled to, and the closer to DISORT than the tables' irradiance texture), reduced by
E0 there, carried to the fine grid by linear interpolation (and beyond 830 nm and below 360 nm by a power law
through the two nearest table wavelengths), times E0 and the same gas transmittances (the diffuse light takes
the sun's gas path, as in Bird & Riordan 1986, Sec. 3), summed. Pyrheliometers see about 2.5 deg around the
sun: the circumsolar light they add to DNI is not modelled (it lowers the retrieved optical depth slightly).

**Per hour** (``HOUR_STATUS``):

1. *night*: the sun below the horizon at mid-hour or no light in the record -> dark.
2. *invalid*: a record that cannot be right (DNI above the extraterrestrial value, DHI above GHI by more than
   max(5 %, 10 W m^-2), irradiance with the sun more than 3 deg below the horizon, missing fields that cannot be
   rebuilt from the other two, GHI = DHI + DNI cos(zenith)). ``bad_hours="error"`` (default) raises a
   :class:`~skyscatter.errors.FileFormatError` naming the line; ``"flag"`` marks the hour and leaves its sky NaN.
3. *clear*: total sky cover <= ``clear_sky_cover`` tenths (or no sky cover in the file), the sun at least 3 deg
   up (the cloud table's last zenith), a direct beam, and the aerosol optical depth from DNI (Newton's method on the
   broadband model, monotonic in tau) within the grid. **The DNI retrieval wins over the file's aerosol optical
   depth field in clear hours** (the field is usually a monthly climatology); the file's value is kept next to it
   for comparison. DHI then fixes a second aerosol property along the closure path (:func:`closure_path`): the
   single-scattering albedo from 1 down to 0.8, then the phase's g from 0.8 down to 0.5 at that albedo (closed
   form: DHI is linear along each leg of the path). Beyond the path the hour is not clear-sky physics of this
   medium: above its top (more diffuse light than clear air can give) it is treated as cloudy, below its end it
   is *clear, not closed* (clamped, closure reported; ``reason`` gives the sun's elevation and the phase g the
   record would need, the phase leg extrapolated).
4. *cloudy*: the other daylit hours. Their aerosol is the median of the same day's clear hours (a measurement
   of that day wins), else the file's optical depth where present (converted from TMY's broadband value at
   700 nm, Molineaux et al. 1998, with the Angstrom exponent), else the 6 nearest clear hours within 3 days,
   else ``default_aerosol_optical_depth``.
   The cloud optical depth at 550 nm comes from GHI by :func:`retrieve_clouds`, inverting the fast cloudy sky
   (:class:`~skyscatter.sky.cloudy.CloudySky`, an overcast water layer, through a :class:`CloudTable` of its
   solutions for one representative aerosol); the file's sky cover is a recorded prior that flags broken hours
   as approximate. Retrieved hours are *cloudy*, the others *cloudy, not retrieved* with the reason (GHI beyond
   the table's thinnest or thickest cloud).
5. *broken*: cloudy hours with sky cover below :data:`OVERCAST_COVER` tenths, a beam and diffuse light: a clear /
   overcast blend fitted to GHI and DNI (:func:`fit_broken_sky`; an independent-pixel approximation, stated). A
   beam at or above the clear beam of the borrowed aerosol first takes the hour's own aerosol from its DNI.
   *broken, enhanced diffuse*: such hours with more light than any blend gives (GHI above the blend under the
   thinnest cloud that fits the beam: the sunlit sides of broken cloud, cloud enhancement): the closest blend
   with its overcast term scaled to the record's DHI (a stated rule, closure by construction; ``reason`` gives
   the factor).
6. *low sun, fallback*: cloudy hours with the sun below the cloud table's last zenith (3 deg up): the table's
   overcast sky at its lowest sun (optical depth :data:`LOW_SUN_OPTICAL_DEPTH`) scaled to the record's DHI, the
   sun the record's DNI (stated in ``reason``).

Precipitable water: the file's field, else Gueymard (1994) from temperature and relative humidity, else
``default_precipitable_water``. Ozone: a CSV's ``ozone`` column, else ``default_ozone`` (EPW and TMY3 files do
not carry it). The ground albedo of the tables is the base atmosphere's (the file's albedo is reported, not
used: it would be one more grid axis).

References: [BirdRiordan1986], [Gueymard1994], [Molineaux1998], [Spencer1971], [Bruneton2008], [Stamnes1988];
the closure path: Petters et al. (2003, JGR 108(D9), 4288), Leahy et al. (2007, GRL 34, L12814), Dubovik et al.
(2002, J. Atmos. Sci. 59, 590), Cornette & Shanks (1992).
"""

from __future__ import annotations

import csv
import hashlib
import math
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere.gas_absorption import (
    broadband_solar_spectrum,
    mixed_gas_transmittance,
    ozone_transmittance_bird_riordan,
    slant_optical_masses,
    water_vapour_transmittance,
)
from ..atmosphere.medium import AtmosphereParameters
from ..conventions import direction_from_angles
from ..epw import EPWData, EPWLocation, read_epw
from ..errors import FileFormatError, InvalidParameterError
from ..precomputed import DEFAULT_ORDERS
from ..precomputed.family import AXIS_SETTERS, FAMILY_WAVELENGTHS, GridAxis, TableFamily, register_axis

__all__ = [
    "DEFAULT_AOD_NODES",
    "DEFAULT_ALBEDO_NODES",
    "DEFAULT_PHASE_G_MIN",
    "closure_path",
    "HOUR_STATUS",
    "LOW_SUN_OPTICAL_DEPTH",
    "BroadbandClearSky",
    "CLOUD_OPTICAL_DEPTH_NODES",
    "CLOUD_ZENITH_NODES_DEG",
    "BrokenSkyFit",
    "CloudRetrieval",
    "CloudTable",
    "OVERCAST_COVER",
    "cloud_irradiance",
    "cloud_table",
    "HourlyAtmosphere",
    "RetrievalOptions",
    "TABLE_PRESETS",
    "default_family",
    "precipitable_water_gueymard1994",
    "read_weather",
    "fit_broken_sky",
    "retrieve_clouds",
    "retrieve_hourly_atmosphere",
]

#: Aerosol optical depth nodes [-] at 550 nm of the default family (dense where clear skies are).
DEFAULT_AOD_NODES = (0.0, 0.05, 0.1, 0.2, 0.3, 0.45, 0.65, 1.0, 1.5)
#: Aerosol single-scattering albedo nodes [-] of the default family. 0.8 is about the most absorbing ambient
#: aerosol measured at 550 nm: southern African biomass smoke, 0.85 +/- 0.02 (Leahy et al. 2007, GRL 34, L12814).
DEFAULT_ALBEDO_NODES = (0.8, 1.0)
#: Smallest Cornette-Shanks parameter g [-] of the aerosol phase the clear hours' DHI closure may take (the
#: second leg of the closure path, :func:`closure_path`): 0.5, a mean scattering cosine of 0.57, about the least
#: forward-scattering aerosol AERONET retrieves (fine-mode smoke at red wavelengths, Dubovik et al. 2002, Table 1).
DEFAULT_PHASE_G_MIN = 0.5
#: Scale height [m] of the default base medium's molecules: the column of the standard atmosphere, 101325 Pa /
#: (m_air g) = 2.148e29 m^-2, over the sea-level number density 2.5469e25 m^-3 of the physical Rayleigh
#: coefficient (:func:`~skyscatter.atmosphere.spectra.rayleigh_scattering_physical`), so that the Rayleigh optical
#: depth is 0.0980 at 550 nm (Bodhaine et al. 1999, Table 3: 0.0973) rather than the 0.108 of the medium's
#: default (Bruneton 2017's coefficient with H = 8 km).
RAYLEIGH_SCALE_HEIGHT = 8434.0


def _aerosol_phase_g(atmosphere: AtmosphereParameters, value: float) -> AtmosphereParameters:
    """Grid-axis setter ``aerosol_phase_g``: the parameter g [-] of the analytic aerosol phase (the default,
    Cornette & Shanks 1992: Bruneton & Neyret 2008, Eq. 4; mean scattering cosine ``3 g (4 + g^2) / (5 (2 +
    g^2))``)."""
    if atmosphere.aerosol is not None:
        raise InvalidParameterError("the aerosol_phase_g axis sets the Angstrom aerosol's analytic phase; a "
                                    "particle-component aerosol has its Mie phase")
    return atmosphere.replace(mie_phase_g=float(value))


if "aerosol_phase_g" not in AXIS_SETTERS:
    register_axis("aerosol_phase_g", _aerosol_phase_g)
#: Ground albedo [-] of the default base medium (Radiance's gendaymtx default, ``-g 0.2``).
DEFAULT_GROUND_ALBEDO = 0.2
#: Status codes of :attr:`HourlyAtmosphere.status`.
HOUR_STATUS = {0: "night", 1: "clear", 2: "clear, DHI not closed", 3: "cloudy, not retrieved",
               4: "cloudy", 5: "invalid record", 6: "broken", 7: "low sun, fallback",
               8: "broken, enhanced diffuse"}
NIGHT, CLEAR, CLEAR_OPEN, CLOUDY_OPEN, CLOUDY, INVALID, BROKEN, LOW_SUN, ENHANCED = range(9)
#: Wavelength [nm] of TMY's broadband aerosol optical depth (Molineaux et al. 1998's key wavelength).
BROADBAND_AOD_WAVELENGTH = 700.0
#: Lowest sun elevation [rad] of a clear hour: the cloud table's last zenith (87 deg), below which cloudy hours
#: take the low-sun fallback (with 5 deg, clear hours at 3-5 deg went to the cloudy branch and, with a beam
#: brighter than any cloud's, were left NaN).
_MIN_CLEAR_ELEVATION = math.radians(3.0)


# --------------------------------------------------------------------------------------------- inputs


def precipitable_water_gueymard1994(temperature: ArrayLike, relative_humidity: ArrayLike) -> NDArray[np.float64]:
    """Precipitable water [cm] from air temperature [deg C] and relative humidity [%] (Gueymard 1994, Eqs. 1-3):
    ``w = 0.1 H_v rho_v`` with ``H_v = 0.4976 + 1.5265 T' + exp(13.6897 T' - 14.9188 T'^3)``, ``T' = T / 273.15``
    and the vapour density ``rho_v = 216.7 RH / (100 T) e_s(T)``, ``e_s = exp(22.330 - 49.140 (100 / T) - 10.922
    (100 / T)^2 - 0.39015 T / 100)`` (T in K); at least 0.1 cm."""
    t = np.asarray(temperature, dtype=float) + 273.15
    rh = np.asarray(relative_humidity, dtype=float)
    tp = t / 273.15
    hv = 0.4976 + 1.5265 * tp + np.exp(13.6897 * tp - 14.9188 * tp**3)
    es = np.exp(22.330 - 49.140 * (100.0 / t) - 10.922 * (100.0 / t) ** 2 - 0.39015 * t / 100.0)
    rho = 216.7 * rh / (100.0 * t) * es
    return np.maximum(0.1 * hv * rho, 0.1)


def read_weather(path: str | os.PathLike[str]) -> EPWData:
    """Read a weather record: an EPW file (``.epw``), a TMY3 file (``.csv`` whose first line is the TMY3 header,
    read with pvlib), or a CSV of the columns below.

    CSV: lines starting with ``#`` may give ``# latitude = 48.1``, ``# longitude = 11.6`` [deg, east +],
    ``# timezone = 1`` [h] and ``# elevation = 520`` [m] (all four required); then a header with ``year, month,
    day, hour`` (hour 1-24 ending the hour, local standard time as in EPW), ``ghi, dni, dhi`` [W m^-2] and
    optionally ``dry_bulb, dew_point`` [deg C], ``relative_humidity`` [%], ``pressure`` [Pa],
    ``precipitable_water`` [mm], ``aerosol_optical_depth`` [-], ``total_sky_cover, opaque_sky_cover`` [tenths],
    ``albedo`` [-] and ``ozone`` [DU]. Empty cells are missing values.
    """
    p = Path(path)
    if p.suffix.lower() == ".epw":
        return read_epw(p)
    try:
        with open(p, encoding="utf-8", errors="replace") as fh:
            head = fh.readline()
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot read ({exc.strerror or exc})") from None
    if head.count(",") == 6 and not head.lstrip().startswith("#"):
        return _read_tmy3(p)
    return _read_csv(p)


def _record(p: Path, location: EPWLocation, cols: dict[str, NDArray[np.float64]], ints: NDArray[np.int64],
            lines: NDArray[np.int64], ozone: NDArray[np.float64] | None = None) -> EPWData:
    n = ints.shape[0]

    def get(name: str) -> NDArray[np.float64]:
        v = cols.get(name)
        return np.full(n, np.nan) if v is None else np.asarray(v, dtype=float)

    rec = EPWData(path=p, location=location, year=ints[:, 0], month=ints[:, 1], day=ints[:, 2], hour=ints[:, 3],
                  dry_bulb=get("dry_bulb"), dew_point=get("dew_point"), global_horizontal_irradiance=get("ghi"),
                  direct_normal_irradiance=get("dni"), diffuse_horizontal_irradiance=get("dhi"),
                  line_numbers=lines, relative_humidity=get("relative_humidity"), pressure=get("pressure"),
                  total_sky_cover=get("total_sky_cover"), opaque_sky_cover=get("opaque_sky_cover"),
                  precipitable_water=get("precipitable_water"), aerosol_optical_depth=get("aerosol_optical_depth"),
                  albedo=get("albedo"))
    object.__setattr__(rec, "ozone", ozone)
    return rec


def _read_tmy3(p: Path) -> EPWData:
    try:
        import pvlib
    except ImportError:
        raise FileFormatError(f"{p}: reading TMY3 files needs pvlib (pip install pvlib)") from None
    try:
        data, meta = pvlib.iotools.read_tmy3(str(p), map_variables=True)
    except Exception as exc:  # pvlib raises many kinds for a malformed file
        raise FileFormatError(f"{p}: not a readable TMY3 file ({exc})") from None
    loc = EPWLocation(str(meta.get("Name", "")), str(meta.get("State", "")), "", "TMY3", str(meta.get("USAF", "")),
                      float(meta["latitude"]), float(meta["longitude"]), float(meta["TZ"]),
                      float(meta["altitude"]))
    # pvlib's index is the end of each hour in local standard time (TMY3 convention, as EPW)
    idx = data.index - np.timedelta64(1, "h")
    ints = np.stack([idx.year, idx.month, idx.day, idx.hour + 1], axis=1).astype(np.int64)

    def col(name: str, scale: float = 1.0):
        return data[name].to_numpy(dtype=float) * scale if name in data else None

    cols = {"ghi": col("ghi"), "dni": col("dni"), "dhi": col("dhi"), "dry_bulb": col("temp_air"),
            "dew_point": col("temp_dew"), "relative_humidity": col("relative_humidity"),
            "pressure": col("pressure", 100.0), "precipitable_water": col("precipitable_water", 10.0),
            "aerosol_optical_depth": col("AOD"), "total_sky_cover": col("TotCld"), "opaque_sky_cover": col("OpqCld"),
            "albedo": col("albedo")}
    return _record(p, loc, {k: v for k, v in cols.items() if v is not None}, ints, np.arange(3, 3 + len(data)))


_CSV_COLUMNS = ("ghi", "dni", "dhi", "dry_bulb", "dew_point", "relative_humidity", "pressure", "precipitable_water",
                "aerosol_optical_depth", "total_sky_cover", "opaque_sky_cover", "albedo", "ozone")


def _read_csv(p: Path) -> EPWData:
    meta: dict[str, float] = {}
    rows: list[tuple[int, list[str]]] = []
    with open(p, encoding="utf-8", errors="replace", newline="") as fh:
        for n, line in enumerate(fh, start=1):
            s = line.strip()
            if not s:
                continue
            if s.startswith("#"):
                if "=" in s:
                    k, v = s[1:].split("=", 1)
                    try:
                        meta[k.strip().lower()] = float(v)
                    except ValueError:
                        raise FileFormatError(
                            f"{p}: line {n}: {k.strip()} must be a number; got {v.strip()!r}") from None
                continue
            rows.append((n, next(csv.reader([s]))))
    need = ("latitude", "longitude", "timezone", "elevation")
    missing = [k for k in need if k not in meta]
    if missing:
        raise FileFormatError(f"{p}: a weather CSV needs '# name = value' lines for {', '.join(missing)}")
    if len(rows) < 2:
        raise FileFormatError(f"{p}: no header and data rows")
    header = [h.strip().lower() for h in rows[0][1]]
    for k in ("year", "month", "day", "hour", "ghi", "dni", "dhi"):
        if k not in header:
            raise FileFormatError(f"{p}: line {rows[0][0]}: the header needs a column {k!r}")
    body = rows[1:]
    ints = np.zeros((len(body), 4), dtype=np.int64)
    vals = {k: np.full(len(body), np.nan) for k in _CSV_COLUMNS if k in header}
    for r, (n, cells) in enumerate(body):
        if len(cells) != len(header):
            raise FileFormatError(f"{p}: line {n}: {len(cells)} cells, the header has {len(header)}")
        for j, k in enumerate(("year", "month", "day", "hour")):
            try:
                ints[r, j] = int(cells[header.index(k)])
            except ValueError:
                raise FileFormatError(f"{p}: line {n}: {k} must be a whole number") from None
        for k in vals:
            c = cells[header.index(k)].strip()
            if c:
                try:
                    vals[k][r] = float(c)
                except ValueError:
                    raise FileFormatError(f"{p}: line {n}: {k} {c!r} is not a number") from None
    if np.any((ints[:, 3] < 1) | (ints[:, 3] > 24)) or np.any((ints[:, 1] < 1) | (ints[:, 1] > 12)):
        raise FileFormatError(f"{p}: hours must be 1-24 (ending the hour) and months 1-12")
    loc = EPWLocation(p.stem, "", "", "CSV", "", meta["latitude"], meta["longitude"], meta["timezone"],
                      meta["elevation"])
    ozone = vals.pop("ozone", None)
    return _record(p, loc, vals, ints, np.array([n for n, _ in body], dtype=np.int64), ozone)


# --------------------------------------------------------------------------------------------- broadband model


def particle_aerosol_shape(aerosol: Any, wavelengths: ArrayLike) -> NDArray[np.float64]:
    """Optical depth of a particle aerosol at ``wavelengths`` [nm] relative to 550 nm [-]: its extinction at
    300, 400, ..., 1200 nm and 550 nm (the range of OPAC's refractive indices), linear in log-log between them and
    the power law of the two end nodes beyond (Angstrom's law locally, [Angstrom1929])."""
    import dataclasses

    if getattr(aerosol, "optical_depth_550", None) == 0.0:  # the shape of an aerosol-free node: its own numbers
        aerosol = dataclasses.replace(aerosol, optical_depth_550=None)
    nodes = np.array([300.0, 400.0, 500.0, 550.0, 600.0, 700.0, 800.0, 900.0, 1000.0, 1100.0, 1200.0])
    ext = np.asarray(aerosol.extinction_at(nodes), dtype=float)
    if not np.all(ext > 0):
        raise InvalidParameterError("the aerosol's extinction must be > 0 at 300-1200 nm for its spectral shape")
    x, y = np.log(nodes), np.log(ext / ext[3])
    lw = np.log(np.asarray(wavelengths, dtype=float))
    out = np.interp(lw, x, y)
    out = np.where(lw < x[0], y[0] + (lw - x[0]) * (y[1] - y[0]) / (x[1] - x[0]), out)
    out = np.where(lw > x[-1], y[-1] + (lw - x[-1]) * (y[-1] - y[-2]) / (x[-1] - x[-2]), out)
    return np.exp(out)


class BroadbandClearSky:
    """Broadband direct and diffuse irradiance of the medium (module docstring, "Broadband model").

    Parameters
    ----------
    base : AtmosphereParameters
        The medium (its Rayleigh, ozone profile and cross-sections, aerosol profile and spectral shape).
    angstrom_alpha : float
        Angstrom exponent of the aerosol optical depth's spectral shape (the analytic aerosol); a particle aerosol
        (``base.aerosol``, e.g. an OPAC type) has its own: its Mie extinction relative to 550 nm at 300-1200 nm
        (100 nm steps), interpolated linearly in log-log and extended beyond by the power law of the two end nodes.
    """

    def __init__(self, base: AtmosphereParameters, angstrom_alpha: float) -> None:
        self.base = base
        self.alpha = float(angstrom_alpha)
        wl, e0 = broadband_solar_spectrum()
        self.wavelengths = wl
        self.weights = np.zeros_like(wl)
        dw = np.diff(wl)
        self.weights[:-1] += dw / 2
        self.weights[1:] += dw / 2
        self.e0 = e0
        thick = base.thickness
        self.tau_rayleigh = base.rayleigh_scattering_at(wl) * base.rayleigh_density.column(thick)
        ozone = np.zeros_like(wl)
        inside = (wl >= 360.0) & (wl <= 830.0)
        per_du = base.replace(ozone_column=1.0)
        ozone[inside] = per_du.ozone_absorption_at(wl[inside]) * base.ozone_density.column(thick)
        self.tau_ozone_per_du = ozone  # [DU^-1] inside the medium's data; Bird & Riordan's form outside
        self.ozone_inside = inside
        self.aerosol_shape = self.aerosol_shape_at(wl)

    def aerosol_shape_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """The aerosol's optical depth at ``wavelengths`` [nm] relative to 550 nm [-]: Angstrom's power law of
        ``angstrom_alpha`` ([Angstrom1929]), or a particle aerosol's own (:func:`particle_aerosol_shape`)."""
        wl = np.asarray(wavelengths, dtype=float)
        return (wl / 550.0) ** -self.alpha if self.base.aerosol is None else \
            particle_aerosol_shape(self.base.aerosol, wl)

    def gas_transmittance(self, zenith: ArrayLike, precipitable_water: ArrayLike,
                          pressure: ArrayLike) -> NDArray[np.float64]:
        """Water vapour x mixed-gas band transmittance along the sun's path on the fine grid, shape (n, n_fine)
        (zenith [rad], W [cm], p [Pa]; air mass the medium's Rayleigh one)."""
        m = slant_optical_masses(self.base, np.asarray(zenith, dtype=float))
        return (water_vapour_transmittance(self.wavelengths, precipitable_water, m.rayleigh)
                * mixed_gas_transmittance(self.wavelengths, m.rayleigh, pressure))

    def _gas(self, zenith, precipitable_water, pressure, ozone):
        # The same hours' gases are asked for several times in a row (the retrieval's closure steps, the cloud
        # inversion's chunks, each twice): the last two answers are kept, keyed by the inputs' bytes, and handed
        # out read-only. On the made year 92 calls of which 21 distinct; each is (n_hours, 2002) float64.
        arrays = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (zenith, precipitable_water, pressure,
                                                                            ozone)))
        key = hashlib.blake2b(repr(arrays[0].shape).encode()
                              + b"".join(np.ascontiguousarray(a).tobytes() for a in arrays), digest_size=16).digest()
        cache = self.__dict__.setdefault("_gas_cache", {})
        hit = cache.pop(key, None)
        if hit is None:
            hit = self._gas_uncached(zenith, precipitable_water, pressure, ozone)
            while len(cache) >= 2:
                cache.pop(next(iter(cache)))
        cache[key] = hit
        return hit

    def _gas_uncached(self, zenith, precipitable_water, pressure, ozone):
        m = slant_optical_masses(self.base, zenith)
        tg = (water_vapour_transmittance(self.wavelengths, precipitable_water, m.rayleigh)
              * mixed_gas_transmittance(self.wavelengths, m.rayleigh, pressure))
        o3 = np.asarray(ozone, dtype=float)
        t_o = np.exp(-(o3 * m.ozone)[:, None] * self.tau_ozone_per_du)
        outside = ozone_transmittance_bird_riordan(self.wavelengths, o3, m.ozone)
        t_o = np.where(self.ozone_inside, t_o, outside)
        out = tg * t_o
        out.flags.writeable = False
        return m, out

    def direct_normal(self, zenith: ArrayLike, aerosol_optical_depth: ArrayLike, precipitable_water: ArrayLike,
                      pressure: ArrayLike, ozone: ArrayLike, eccentricity: ArrayLike) -> NDArray[np.float64]:
        """Broadband DNI [W m^-2] for each hour (zenith [rad], AOD at 550 nm [-], W [cm], p [Pa], O3 [DU],
        eccentricity factor [-]); all arrays of shape (n,)."""
        return self.direct_normal_spectral(zenith, aerosol_optical_depth, precipitable_water, pressure, ozone,
                                           eccentricity).sum(axis=1)

    def direct_normal_spectral(self, zenith: ArrayLike, aerosol_optical_depth: ArrayLike,
                               precipitable_water: ArrayLike, pressure: ArrayLike, ozone: ArrayLike,
                               eccentricity: ArrayLike, *, weighted: bool = True) -> NDArray[np.float64]:
        """Direct normal spectral irradiance on the fine grid :attr:`wavelengths`, shape (n, n_fine):
        [W m^-2 nm^-1], or with ``weighted`` (default) times the trapezoid weights [W m^-2] (sums to DNI)."""
        a, ma = self._direct_parts(zenith, precipitable_water, pressure, ozone, eccentricity)
        tau = np.asarray(aerosol_optical_depth, dtype=float)
        out = a * np.exp(-(tau * ma)[:, None] * self.aerosol_shape)
        return out if weighted else out / np.where(self.weights > 0, self.weights, 1.0)

    def _direct_parts(self, zenith, precipitable_water, pressure, ozone, eccentricity):
        z = np.asarray(zenith, dtype=float)
        m, tg = self._gas(z, precipitable_water, pressure, ozone)
        a = (np.asarray(eccentricity, dtype=float)[:, None] * self.weights * self.e0 * tg
             * np.exp(-m.rayleigh[:, None] * self.tau_rayleigh))
        return a, m.aerosol

    def retrieve_aerosol(self, dni: ArrayLike, zenith: ArrayLike, precipitable_water: ArrayLike,
                         pressure: ArrayLike, ozone: ArrayLike, eccentricity: ArrayLike, *,
                         tau_max: float = 10.0) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Aerosol optical depth at 550 nm [-] that gives ``dni`` [W m^-2] in each hour, and whether it exists
        in [0, tau_max] (False: DNI above the aerosol-free value, or below the value at ``tau_max``).

        DNI(tau) is a sum of decaying exponentials (convex, decreasing): Newton's method from tau = 0 converges
        monotonically; 30 steps, to 1e-10 in DNI relative."""
        a, ma = self._direct_parts(zenith, precipitable_water, pressure, ozone, eccentricity)
        target = np.asarray(dni, dtype=float)
        k = ma[:, None] * self.aerosol_shape
        clean = a.sum(axis=1)
        dirty = np.einsum("hf,hf->h", a, np.exp(-tau_max * k))
        ok = (target <= clean) & (target >= dirty) & (target > 0)
        tau = np.zeros(target.size)
        for _ in range(30):
            e = a * np.exp(-tau[:, None] * k)
            f = e.sum(axis=1) - target
            df = -(e * k).sum(axis=1)
            step = np.where(ok, f / np.where(df < 0, df, -1.0), 0.0)
            tau = np.clip(tau - step, 0.0, tau_max)
            if np.all(np.abs(f[ok]) <= 1e-10 * np.maximum(target[ok], 1.0)):
                break
        return np.where(ok, tau, np.nan), ok

    def diffuse_weights(self, zenith: ArrayLike, precipitable_water: ArrayLike, pressure: ArrayLike,
                        ozone: ArrayLike, eccentricity: ArrayLike,
                        table_wavelengths: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(Q, e0_table)``: broadband diffuse = ``sum_k Q[h, k] x[h, k]`` for a spectral diffuse irradiance
        ``x`` at the table wavelengths, inside their range (linear interpolation of ``x / E0``); and the
        extrapolation is done by :meth:`broadband_diffuse`."""
        z = np.asarray(zenith, dtype=float)
        m, tg = self._gas(z, precipitable_water, pressure, ozone)
        wlt = np.asarray(table_wavelengths, dtype=float)
        # The tables (and the cloud table's DISORT column) already absorb by the medium's own ozone column inside
        # their wavelength range: there only the hour's departure from that column is applied (along the sun's
        # ozone path, Bird & Riordan's assumption for the diffuse light); outside it, where the reduced diffuse is
        # extended by power laws, the full column (Hartley-Huggins bands below 360 nm).
        in_table = (self.wavelengths >= wlt[0]) & (self.wavelengths <= wlt[-1])
        tg = tg * np.where(in_table, np.exp((self.base.ozone_column * m.ozone)[:, None] * self.tau_ozone_per_du),
                           1.0)
        e0t = self.base.solar_irradiance_at(wlt)
        return (np.asarray(eccentricity, dtype=float)[:, None] * self.weights * self.e0 * tg), e0t

    def broadband_diffuse(self, spectral: NDArray[np.float64], zenith, precipitable_water, pressure, ozone,
                          eccentricity, table_wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Broadband diffuse irradiance [W m^-2] per hour from a spectral one (n, ..., n_table) [W m^-2 nm^-1] at
        the table wavelengths (mean Sun-Earth distance, as the tables): reduced by the table E0, interpolated
        linearly, extended by power laws beyond the table range, times E0, gases and eccentricity, summed; shape
        (n, ...) (the middle axes share the hour's gases: several skies of one hour cost one gas computation)."""
        wlt = np.asarray(table_wavelengths, dtype=float)
        q, e0t = self.diffuse_weights(zenith, precipitable_water, pressure, ozone, eccentricity, wlt)
        r = np.maximum(np.asarray(spectral, dtype=float) / e0t, 1e-30)
        wl = self.wavelengths
        inside = (wl >= wlt[0]) & (wl <= wlt[-1])
        out = np.empty((*r.shape[:-1], wl.size))
        # linear interpolation matrix (fine inside wavelengths x table wavelengths)
        j = np.clip(np.searchsorted(wlt, wl[inside], side="right") - 1, 0, wlt.size - 2)
        t = (wl[inside] - wlt[j]) / (wlt[j + 1] - wlt[j])
        out[..., inside] = r[..., j] * (1 - t) + r[..., j + 1] * t
        for sel, (a, b) in ((wl > wlt[-1], (-2, -1)), (wl < wlt[0], (1, 0))):
            p = np.log(r[..., a] / r[..., b]) / np.log(wlt[b] / wlt[a])  # r ~ lambda^-p through the two nodes
            p = np.clip(p, 0.0, 6.0)
            out[..., sel] = r[..., b, None] * (wl[sel] / wlt[b]) ** -p[..., None]
        return np.einsum("hf,h...f->h...", q, out)


# --------------------------------------------------------------------------------------------- clouds

#: Cloud optical depth nodes [-] at 550 nm of :class:`CloudTable` (log-spaced 0.5-60, ratio 1.55).
CLOUD_OPTICAL_DEPTH_NODES = tuple(float(x) for x in np.round(np.geomspace(0.5, 60.0, 12), 4))
#: Sun zenith nodes [deg] of :class:`CloudTable` (about even in cos z; the last is 3 deg above the horizon).
CLOUD_ZENITH_NODES_DEG = (0.0, 25.0, 40.0, 52.0, 62.0, 70.0, 77.0, 83.0, 87.0)
#: View zenith angles [deg] of the radiance grid a :class:`CloudTable` keeps per node (0-90 deg every 2 deg).
CLOUD_FIELD_THETA_DEG = tuple(float(x) for x in np.arange(0.0, 90.1, 2.0))
#: Azimuths from the sun [deg] of that grid (0-180 deg every 5 deg; the field is symmetric about the sun).
CLOUD_FIELD_PHI_DEG = tuple(float(x) for x in np.arange(0.0, 180.1, 5.0))
#: Opaque sky cover [tenths] from which a cloudy hour is treated as overcast (below: broken, approximate).
OVERCAST_COVER = 8.0
_CLOUD_TABLES: dict[Any, CloudTable] = {}


class CloudTable:
    """The fast cloudy sky (:class:`~skyscatter.sky.cloudy.CloudySky`: a uniform water layer 1000-1500 m, droplets
    of 10 um, DISORT lit by the precomputed clear sky, [Stamnes1988], [Bruneton2008]) solved once per node of
    (cloud optical depth, sun zenith) for one air, for the broadband inversion of :func:`retrieve_clouds`.

    Stored per node: DISORT's diffuse downward spectral irradiance at the ground at
    :data:`~skyscatter.sky.cloudy.GRID_WAVELENGTHS` [W m^-2 nm^-1, mean Sun-Earth distance]
    (:meth:`~skyscatter.sky.cloudy.CloudySky.diffuse_fluxes`), and per zenith node the cloud's slant optical depth
    per unit optical depth at 550 nm, ``-ln(S_cloud / S_clear)`` from the sun's spectral radiance with a layer of
    optical depth 1 and without (:meth:`~skyscatter.sky.cloudy.CloudySky.sun_spectral_radiance`: the chord through
    the spherical shells), times cos z. Between zenith nodes both are interpolated in cos z after dividing by
    cos z (the diffuse irradiance is nearly proportional to cos z under a cloud): the diffuse by a cubic spline
    (linearly it was 0.7-1.6 % off under thin clouds, 3-8 % in the retrieved optical depth), the slant linearly;
    hours beyond the last node are not evaluated.

    Parameters
    ----------
    atmosphere : AtmosphereParameters
        The air without clouds (its aerosol included).
    optical_depth_nodes : sequence of float
        Cloud optical depths at 550 nm [-], increasing, in (0, 60].
    zenith_nodes : sequence of float, optional
        Sun zenith angles [rad], increasing, in [0, 88 deg] (default :data:`CLOUD_ZENITH_NODES_DEG`).
    streams : int
        DISORT streams (default 16, the cloudy sky's).
    """

    def __init__(self, atmosphere: AtmosphereParameters, optical_depth_nodes: ArrayLike = CLOUD_OPTICAL_DEPTH_NODES,
                 zenith_nodes: ArrayLike | None = None, *, streams: int = 16) -> None:
        import time

        from ..sky.cloudy import GRID_WAVELENGTHS, MAX_CLOUD_OPTICAL_DEPTH, CloudySky
        from ..sky.cloudy_kernels import grid_lookup

        tau = np.asarray(optical_depth_nodes, dtype=float)
        zen = np.radians(CLOUD_ZENITH_NODES_DEG) if zenith_nodes is None else np.asarray(zenith_nodes, dtype=float)
        for name, v, lo, hi in (("optical_depth_nodes", tau, 1e-6, MAX_CLOUD_OPTICAL_DEPTH),
                                ("zenith_nodes", zen, 0.0, math.radians(88.0))):
            if v.ndim != 1 or v.size < 2 or not np.all(np.isfinite(v)) or np.any(np.diff(v) <= 0) \
                    or v[0] < lo or v[-1] > hi:
                raise InvalidParameterError(f"{name} must be two or more increasing numbers in [{lo:g}, {hi:g}]")
        t0 = time.perf_counter()
        wl = GRID_WAVELENGTHS
        self.atmosphere = atmosphere
        self.optical_depths = tau
        self.zeniths = zen
        self.wavelengths = wl
        self.diffuse = np.zeros((tau.size, zen.size, wl.size))
        self.slant = np.zeros((zen.size, wl.size))
        self.field_theta = np.radians(CLOUD_FIELD_THETA_DEG)
        self.field_phi = np.radians(CLOUD_FIELD_PHI_DEG)
        #: Sky radiance per unit solar irradiance [sr^-1] on (view zenith, azimuth from the sun) per node, divided by
        #: the node's cos z, without the droplets' forward peak (its light is the difference between ``diffuse``
        #: and the field's integral; :meth:`patch_radiance` callers put it back about the sun), float32.
        self.field = np.zeros((tau.size, zen.size, self.field_theta.size, self.field_phi.size, wl.size),
                              dtype=np.float32)
        #: The fraction of the diffuse irradiance ``diffuse`` in the droplets' forward peak (n_tau, n_zen, n_wl) [-]:
        #: the light within about 1.5 deg of the sun that :attr:`field` does not hold.
        self.peak = np.zeros((tau.size, zen.size, wl.size))
        tt, pp = np.meshgrid(self.field_theta, self.field_phi, indexing="ij")
        grid_dirs = np.ascontiguousarray(direction_from_angles(tt, pp).reshape(-1, 3))
        resampled = np.empty((grid_dirs.shape[0], wl.size))
        for j, z in enumerate(zen):
            clear = CloudySky(float(z), cloud_optical_depth=0.0, atmosphere=atmosphere, streams=streams)
            unit = CloudySky(float(z), cloud_optical_depth=1.0, atmosphere=atmosphere, streams=streams)
            ratio = unit.sun_spectral_radiance(wl) / np.maximum(clear.sun_spectral_radiance(wl), 1e-300)
            self.slant[j] = -np.log(np.maximum(ratio, 1e-300)) * math.cos(z)
            for k, t in enumerate(tau):
                sky = CloudySky(float(z), cloud_optical_depth=float(t), atmosphere=atmosphere, streams=streams)
                self.diffuse[k, j] = sky.diffuse_fluxes(wl)[0]
                f = sky._field
                grid_lookup(grid_dirs, 0.0, f["theta"], f["phi"], np.ascontiguousarray(f["radiance_smooth"]),
                            resampled)
                self.field[k, j] = (resampled / math.cos(z)).reshape(tt.shape + (wl.size,))
                down = f["diffuse_down"]
                self.peak[k, j] = np.divide(f["forward_peak"], down, out=np.zeros(wl.size), where=down > 0)
        #: Wall time [s] of the solves (the clear-sky coupling tables of a new air included).
        self.build_seconds = time.perf_counter() - t0

    def _zenith_weights(self, zenith: NDArray[np.float64]) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        mu_nodes = np.cos(self.zeniths)[::-1]  # increasing
        mu = np.clip(np.cos(zenith), mu_nodes[0], mu_nodes[-1])
        i = np.clip(np.searchsorted(mu_nodes, mu, side="right") - 1, 0, mu_nodes.size - 2)
        w = (mu - mu_nodes[i]) / (mu_nodes[i + 1] - mu_nodes[i])
        return self.zeniths.size - 1 - i, w  # lower-mu node (in zenith order) and the weight of the next-higher mu

    def diffuse_spectral(self, zenith: ArrayLike) -> NDArray[np.float64]:
        """Diffuse downward spectral irradiance [W m^-2 nm^-1] (n, n_tau, n_wl) at sun zenith angles [rad]."""
        from scipy.interpolate import CubicSpline

        z = np.atleast_1d(np.asarray(zenith, dtype=float))
        mu_nodes = np.cos(self.zeniths)[::-1]
        mu = np.clip(np.cos(z), mu_nodes[0], mu_nodes[-1])
        per_mu = (self.diffuse / np.cos(self.zeniths)[None, :, None])[:, ::-1, :]
        out = CubicSpline(mu_nodes, per_mu, axis=1)(mu)  # (n_tau, n, n_wl)
        return np.moveaxis(out, 0, 1) * np.cos(z)[:, None, None]

    def _node_weights(self, zenith: NDArray[np.float64], optical_depth: NDArray[np.float64]):
        """Lower optical depth node and the weight of the next (linear in ln tau), lower zenith node (in the
        table's order) and the weight of the next (linear in cos z); both clamped to the table."""
        lt = np.log(self.optical_depths)
        x = np.clip(np.log(np.maximum(optical_depth, 1e-12)), lt[0], lt[-1])
        k = np.clip(np.searchsorted(lt, x, side="right") - 1, 0, lt.size - 2)
        a = (x - lt[k]) / (lt[k + 1] - lt[k])
        j_hi_mu, w_mu = self._zenith_weights(zenith)  # node with the lower mu (higher zenith), weight of higher mu
        return k, a, j_hi_mu - 1, 1.0 - w_mu

    def diffuse_at(self, zenith: ArrayLike, optical_depth: ArrayLike) -> NDArray[np.float64]:
        """Diffuse downward spectral irradiance [W m^-2 nm^-1] (n, n_wl) at each hour's sun zenith [rad] (the cubic
        spline of :meth:`diffuse_spectral`) and cloud optical depth [-] (linear in ln tau between the nodes,
        clamped to them)."""
        z = np.atleast_1d(np.asarray(zenith, dtype=float))
        t = np.broadcast_to(np.asarray(optical_depth, dtype=float), z.shape)
        k, a, _, _ = self._node_weights(z, t)
        d = self.diffuse_spectral(z)  # (n, n_tau, n_wl)
        rows = np.arange(z.size)
        return d[rows, k] * (1 - a)[:, None] + d[rows, k + 1] * a[:, None]

    def peak_fraction(self, zenith: ArrayLike, optical_depth: ArrayLike) -> NDArray[np.float64]:
        """:attr:`peak` (n, n_wl) [-] interpolated linearly in ln tau and cos z (clamped to the nodes)."""
        z = np.atleast_1d(np.asarray(zenith, dtype=float))
        t = np.broadcast_to(np.asarray(optical_depth, dtype=float), z.shape)
        k, a, j, b = self._node_weights(z, t)
        p = self.peak
        return ((1 - a) * (1 - b))[:, None] * p[k, j] + ((1 - a) * b)[:, None] * p[k, j + 1] \
            + (a * (1 - b))[:, None] * p[k + 1, j] + (a * b)[:, None] * p[k + 1, j + 1]

    def patch_radiance(self, zenith: ArrayLike, azimuth: ArrayLike, optical_depth: ArrayLike,
                       cells: NDArray[np.float64]) -> NDArray[np.float64]:
        """Mean sky radiance per unit solar irradiance [sr^-1] (n, n_patches, n_wl) over each patch's cells
        ``cells`` (n_patches, n_cells, 3; ENU unit vectors) for hours of sun zenith and azimuth [rad] and cloud
        optical depth [-]: :attr:`field` interpolated linearly in ln tau and in cos z between the nodes (times
        cos z) and bilinearly in (view zenith, azimuth from the sun); without the forward peak (see
        :attr:`field`). Cells below the horizon take the horizon's value."""
        from ..sky.cloudy_kernels import patch_field_lookup

        z = np.atleast_1d(np.asarray(zenith, dtype=float))
        az = np.broadcast_to(np.asarray(azimuth, dtype=float), z.shape)
        t = np.broadcast_to(np.asarray(optical_depth, dtype=float), z.shape)
        k, a, j, b = self._node_weights(z, t)
        n_p, n_c = cells.shape[:2]
        flat = cells.reshape(-1, 3)
        theta = np.arccos(np.clip(flat[:, 2], -1.0, 1.0))
        th = self.field_theta
        it = np.clip(np.searchsorted(th, theta, side="right") - 1, 0, th.size - 2)
        u = np.clip((theta - th[it]) / (th[it + 1] - th[it]), 0.0, 1.0)
        cell_az = np.arctan2(flat[:, 0], flat[:, 1])
        patch = np.repeat(np.arange(n_p), n_c)
        out = np.zeros((z.size, n_p, self.wavelengths.size))
        patch_field_lookup(self.field, k.astype(np.int64), a, j.astype(np.int64), b, np.ascontiguousarray(az),
                           it.astype(np.int64), u, cell_az, patch, np.full(flat.shape[0], 1.0 / n_c), self.field_phi,
                           out)
        return out * np.cos(z)[:, None, None]

    def slant_optical_depth(self, zenith: ArrayLike, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """The cloud's slant optical depth per unit optical depth at 550 nm [-] (n, n_wl) along the sun's path
        (sun zenith [rad]) at ``wavelengths`` [nm] (clamped to the grid's 380-780 nm: the droplets are grey)."""
        z = np.atleast_1d(np.asarray(zenith, dtype=float))
        j, w = self._zenith_weights(z)
        s = self.slant[j] * (1 - w)[:, None] + self.slant[j - 1] * w[:, None]
        wl = np.asarray(wavelengths, dtype=float)
        return _interp_rows(wl, self.wavelengths, s) / np.cos(z)[:, None]


def _interp_rows(x: NDArray[np.float64], xp: NDArray[np.float64], fp: NDArray[np.float64]) -> NDArray[np.float64]:
    """np.interp of every row of ``fp`` (n, len(xp)) at ``x`` (clamped), vectorised: (n, len(x))."""
    xc = np.clip(x, xp[0], xp[-1])
    i = np.clip(np.searchsorted(xp, xc, side="right") - 1, 0, xp.size - 2)
    t = (xc - xp[i]) / (xp[i + 1] - xp[i])
    return fp[:, i] * (1 - t) + fp[:, i + 1] * t


def cloud_table(atmosphere: AtmosphereParameters, optical_depth_nodes: ArrayLike = CLOUD_OPTICAL_DEPTH_NODES,
                zenith_nodes: ArrayLike | None = None) -> CloudTable:
    """A :class:`CloudTable`, kept in memory for the process (key: the air and the nodes) and on disk beside the
    precomputed tables (:func:`~skyscatter.precomputed.cache.cache_dir`)."""
    if zenith_nodes is None:
        zenith_nodes = np.radians(CLOUD_ZENITH_NODES_DEG)
    key = (repr(atmosphere), tuple(np.asarray(optical_depth_nodes, dtype=float)),
           tuple(np.asarray(zenith_nodes, dtype=float)))
    if key not in _CLOUD_TABLES:
        _CLOUD_TABLES[key] = _cached_cloud_table(atmosphere, optical_depth_nodes, zenith_nodes)
    return _CLOUD_TABLES[key]


#: Version of the cloud table's stored layout and contents (part of its disk cache key). 3: a verified entry of
#: :mod:`skyscatter.diskcache` (checksums). 4: :class:`~skyscatter.sky.cloudy.CloudySky`'s sky irradiance on the cloud
#: top from the radiance tables (the skies it stores changed by up to a few per cent). 5: the light that the clear air
#: below the cloud top sends up taken out of the tables' sky by the adding method (low suns: up to 1.5 % less light).
#: 6: the clear sky (optical depth 0) with its empty cloud shell kept, lit by the tables like any layer (the sun's
#: chord through the column's layers then has the layer's edges, as the clouded skies' it is divided by). 7: the
#: spectral reads as ratios to the ozone transmittance along the sun's path (``sky.cloudy.ozone_read``).
_CLOUD_TABLE_VERSION = 7
_CLOUD_TABLE_ARRAYS = ("optical_depths", "zeniths", "wavelengths", "diffuse", "slant", "field_theta", "field_phi",
                       "field", "peak")


def _cloud_table_key(atmosphere: AtmosphereParameters, optical_depth_nodes: ArrayLike,
                     zenith_nodes: ArrayLike) -> str:
    """The disk cache key text of a cloud table (its entry ``cloudtable-<sha256>.npz`` in the cache folder)."""
    from .. import __version__

    tau = np.asarray(optical_depth_nodes, dtype=float)
    zen = np.asarray(zenith_nodes, dtype=float)
    return "|".join([atmosphere.canonical_json(), repr(tau.tolist()), repr(zen.tolist()), str(_CLOUD_TABLE_VERSION),
                     __version__])


def _save_cloud_table(table: CloudTable) -> None:
    """Store ``table`` in the disk cache (atomically, verified when read; an unwritable cache only costs a rebuild
    elsewhere)."""
    from ..diskcache import cache_entry_path, write_entry

    text = _cloud_table_key(table.atmosphere, table.optical_depths, table.zeniths)
    path = cache_entry_path("cloudtable", text)
    try:
        write_entry(path, "cloudtable", text, {name: getattr(table, name) for name in _CLOUD_TABLE_ARRAYS})
    except Exception as exc:  # noqa: BLE001 - the cache is an optimisation: any failure to store it is a warning
        _warn(f"the cloud table could not be cached in {path.parent} ({exc}); it is rebuilt in every process")


def _cached_cloud_table(atmosphere: AtmosphereParameters, optical_depth_nodes: ArrayLike,
                        zenith_nodes: ArrayLike) -> CloudTable:
    """A :class:`CloudTable` from the disk cache of the precomputed tables (its 108 DISORT solves cost about a
    minute, and Dask's worker processes would each redo them), else built and stored
    (:func:`skyscatter.diskcache.cached_arrays`: verified when read, written atomically, built once by processes
    that need it at once)."""
    from ..diskcache import cached_arrays

    built: list[CloudTable] = []

    def build() -> dict[str, NDArray[np.float64]]:
        built.append(CloudTable(atmosphere, optical_depth_nodes, zenith_nodes))
        return {name: getattr(built[0], name) for name in _CLOUD_TABLE_ARRAYS}

    arrays = cached_arrays("cloudtable", _cloud_table_key(atmosphere, optical_depth_nodes, zenith_nodes), build)
    if built:
        return built[0]
    table = CloudTable.__new__(CloudTable)
    table.atmosphere = atmosphere
    for name in _CLOUD_TABLE_ARRAYS:
        setattr(table, name, arrays[name])
    table.build_seconds = 0.0
    return table


@dataclass(frozen=True)
class CloudRetrieval:
    """What :func:`retrieve_clouds` found for the cloudy hours (arrays of shape (n,)): cloud optical depth at
    550 nm [-] (NaN where not retrieved), the recorded cover prior [0-1] (opaque cover, else total, / 10; NaN if
    the file has none), ``retrieved`` flags, ``overcast`` (cover >= :data:`OVERCAST_COVER` tenths or unknown;
    the others are broken skies fitted with an overcast layer: approximate), the retrieved sky's broadband
    ``ghi_model``, ``dhi_model``, ``dni_model`` [W m^-2] and one ``reason`` per hour ("" when retrieved
    overcast); ``aerosol_optical_depth`` the one aerosol [-] of the table, ``table`` the table."""

    optical_depth: NDArray[np.float64]
    cover: NDArray[np.float64]
    retrieved: NDArray[np.bool_]
    overcast: NDArray[np.bool_]
    ghi_model: NDArray[np.float64]
    dhi_model: NDArray[np.float64]
    dni_model: NDArray[np.float64]
    reason: NDArray[np.object_]
    aerosol_optical_depth: float = float("nan")
    table: CloudTable | None = None


def cloud_irradiance(table: CloudTable, model: BroadbandClearSky, zenith: ArrayLike, aerosol_optical_depth: ArrayLike,
                     precipitable_water: ArrayLike, pressure: ArrayLike, ozone: ArrayLike, eccentricity: ArrayLike,
                     optical_depth: ArrayLike | None = None, *, chunk: int = 256
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Broadband diffuse and direct normal irradiance [W m^-2] of the cloudy sky, ``(dhi, dni)``.

    With ``optical_depth`` None: at every node of the table, each (n, n_tau); else the direct normal at each
    hour's cloud optical depth (n,) and the diffuse NaN (interpolate the nodes' yourself). Broadband as the clear hours
    (:class:`BroadbandClearSky`, ASTM G173 280-4000 nm): the diffuse by :meth:`BroadbandClearSky.broadband_diffuse`
    from the table's 380-780 nm spectrum, with water vapour and mixed gases, and ozone only where DISORT's column
    does not already absorb (the hour's departure from the medium's column inside 380-780 nm, the whole column
    where the reduced spectrum is extended by power laws: the Hartley-Huggins bands); the direct normal is
    :meth:`BroadbandClearSky.direct_normal_spectral` (air, aerosol, ozone, gases) times the cloud's
    ``exp(-tau s(lambda, z))`` (:meth:`CloudTable.slant_optical_depth`)."""
    z = np.atleast_1d(np.asarray(zenith, dtype=float))
    n = z.size
    args = [np.broadcast_to(np.asarray(a, dtype=float), (n,)) for a in
            (aerosol_optical_depth, precipitable_water, pressure, ozone, eccentricity)]
    n_tau = table.optical_depths.size
    dhi = np.zeros((n, n_tau)) if optical_depth is None else np.full(n, np.nan)
    dni = np.zeros((n, n_tau)) if optical_depth is None else np.zeros(n)
    for s in range(0, n, chunk):
        sl = slice(s, min(s + chunk, n))
        aod, pw, p, o3, ecc = (a[sl] for a in args)
        if optical_depth is None:
            dhi[sl] = model.broadband_diffuse(table.diffuse_spectral(z[sl]), z[sl], pw, p, o3, ecc,
                                              table.wavelengths)
        direct = model.direct_normal_spectral(z[sl], aod, pw, p, o3, ecc)  # (m, n_fine), sums to the clear DNI
        k = table.slant_optical_depth(z[sl], model.wavelengths)  # (m, n_fine)
        if optical_depth is None:
            for j, t in enumerate(table.optical_depths):
                dni[sl, j] = np.einsum("hf,hf->h", direct, np.exp(-t * k))
        else:
            t = np.broadcast_to(np.asarray(optical_depth, dtype=float), (n,))[sl]
            dni[sl] = np.einsum("hf,hf->h", direct, np.exp(-np.nan_to_num(t)[:, None] * k))
    return dhi, dni


#: Points in ln(cloud optical depth) on which :func:`retrieve_clouds` and :func:`fit_broken_sky` invert.
_FINE_POINTS = 400


def _fine_curves(table: CloudTable, model: BroadbandClearSky, z, aod, precipitable_water, pressure, ozone,
                 eccentricity) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``(ln tau, ln DHI, ln DNI)`` of the cloudy sky of each hour on :data:`_FINE_POINTS` points in ln tau over
    the table's optical depths, shapes (m,), (m, n), (m, n): the diffuse by a monotone cubic (PCHIP) in
    (ln tau, ln DHI), the direct by one in (tau, ln DNI) (nearly linear: the droplets are grey, DNI ~
    exp(-tau m)) through the nodes' broadband values (:func:`cloud_irradiance`)."""
    from scipy.interpolate import PchipInterpolator

    d_nodes, n_nodes = cloud_irradiance(table, model, z, aod, precipitable_water, pressure, ozone, eccentricity)
    lt = np.log(table.optical_depths)
    fine = np.linspace(lt[0], lt[-1], _FINE_POINTS)
    ld = PchipInterpolator(lt, np.log(np.maximum(d_nodes, 1e-300)).T, axis=0)(fine)
    ln_ = PchipInterpolator(table.optical_depths, np.log(np.maximum(n_nodes, 1e-300)).T, axis=0)(np.exp(fine))
    return fine, ld, ln_


def retrieve_clouds(ghi: NDArray[np.float64], dhi: NDArray[np.float64], zenith: NDArray[np.float64],
                    aerosol_optical_depth: NDArray[np.float64], total_sky_cover: NDArray[np.float64],
                    opaque_sky_cover: NDArray[np.float64], *, precipitable_water: ArrayLike = 1.4,
                    pressure: ArrayLike = 101325.0, ozone: ArrayLike = 300.0, eccentricity: ArrayLike = 1.0,
                    model: BroadbandClearSky | None = None, aerosol_nodes: ArrayLike = DEFAULT_AOD_NODES,
                    table: CloudTable | None = None) -> CloudRetrieval:
    """Cloud optical depth at 550 nm of cloudy hours from their GHI [W m^-2], by inverting the fast cloudy sky's
    broadband global horizontal irradiance (:class:`CloudTable`, :func:`cloud_irradiance`); DHI is the check.

    GHI(tau) = DHI(tau) + DNI(tau) cos z decreases with the cloud optical depth, except under thin clouds with a
    high sun, where it first rises by up to 0.2 % (forward scattering): the inversion uses the branch beyond the
    maximum, and a GHI between the thinnest node's and the maximum (two solutions) is not retrieved. DHI alone
    rises under thin clouds and cannot be inverted. Per hour it is computed at the table's optical depth
    nodes, interpolated on 400 points in ln tau (the diffuse by a monotone cubic, PCHIP, in (ln tau, ln DHI), the
    direct by one in (tau, ln DNI)) and inverted there linearly. Hours whose GHI lies above the sky under the
    thinnest node or below the thickest, or whose sun is
    lower than the last zenith node, are not retrieved (``reason``). The table is built for one aerosol: the
    node of ``aerosol_nodes`` nearest the median of the hours' aerosol optical depths (the clouds dominate GHI;
    the table's air is built once per node and cached); the direct beam uses each hour's own aerosol.

    Cover (``total_sky_cover``, ``opaque_sky_cover`` [tenths]) is a recorded prior only: the layer is overcast,
    so hours with opaque cover (else total) below :data:`OVERCAST_COVER` are retrieved as an overcast layer and
    flagged approximate (``overcast`` False, a reason); missing cover counts as overcast.

    Parameters
    ----------
    ghi, dhi : array (n,)
        The record's global and diffuse horizontal irradiance [W m^-2].
    zenith : array (n,)
        Sun zenith [rad].
    aerosol_optical_depth : array (n,)
        The hours' aerosol optical depth at 550 nm [-].
    total_sky_cover, opaque_sky_cover : array (n,)
        [tenths] (NaN: not in the file).
    precipitable_water, pressure, ozone, eccentricity
        [cm], [Pa], [DU], Sun-Earth distance factor [-] (scalars or (n,)).
    model : BroadbandClearSky, optional
        The broadband model (default: over the retrieval's default base medium).
    aerosol_nodes : sequence of float
        Aerosol optical depths [-] from which the table's one is chosen.
    table : CloudTable, optional
        A table to use (default: :func:`cloud_table` for the chosen air).
    """
    from ..precomputed.family import AXIS_SETTERS

    ghi = np.atleast_1d(np.asarray(ghi, dtype=float))
    dhi = np.atleast_1d(np.asarray(dhi, dtype=float))
    z = np.atleast_1d(np.asarray(zenith, dtype=float))
    n = ghi.size
    aod = np.broadcast_to(np.asarray(aerosol_optical_depth, dtype=float), (n,))
    total = np.broadcast_to(np.asarray(total_sky_cover, dtype=float), (n,))
    opaque = np.broadcast_to(np.asarray(opaque_sky_cover, dtype=float), (n,))
    cover_tenths = np.where(np.isfinite(opaque), opaque, total)
    overcast = ~(cover_tenths < OVERCAST_COVER)
    reason = np.full(n, "", dtype=object)
    nan = np.full(n, np.nan)
    if n == 0:
        return CloudRetrieval(nan, nan, np.zeros(0, bool), overcast, nan, nan, nan, reason)
    if model is None:
        model = BroadbandClearSky(RetrievalOptions().base_atmosphere(), RetrievalOptions().angstrom_alpha)
    nodes = np.asarray(aerosol_nodes, dtype=float)
    finite = aod[np.isfinite(aod)]
    rep_aod = float(nodes[np.argmin(np.abs(nodes - (np.median(finite) if finite.size else 0.1)))])
    if table is None:
        table = cloud_table(AXIS_SETTERS["aerosol_optical_depth"](model.base, rep_aod))
    in_range = z <= table.zeniths[-1] + 1e-9
    fine, ld, ln_ = _fine_curves(table, model, z, np.nan_to_num(aod, nan=rep_aod), precipitable_water, pressure,
                                 ozone, eccentricity)
    lg = np.log(np.maximum(np.exp(ld) + np.exp(ln_) * np.cos(z)[None, :], 1e-300))
    # under thin clouds and a high sun GHI first rises a little (forward scattering: +0.2 % from 0.5 to 0.8): the
    # inversion uses the decreasing branch beyond the maximum; a GHI between the thinnest node's and the maximum
    # has two solutions and is not retrieved
    peak = np.argmax(lg, axis=0)
    lg_max = lg[peak, np.arange(n)]
    lg_thin = lg[0].copy()
    lg = np.where(np.arange(fine.size)[:, None] < peak[None, :], lg_max[None, :], lg)
    target = np.log(np.maximum(ghi, 1e-300))
    above = target > lg_max
    ambiguous = (target > lg_thin) & ~above
    below = target < lg[-1]
    ok = in_range & ~above & ~ambiguous & ~below & (ghi > 0)
    idx = np.clip(np.sum(lg > target[None, :], axis=0), 1, fine.size - 1)  # first fine point at or below target
    cols = np.arange(n)
    g_hi, g_lo = lg[idx - 1, cols], lg[idx, cols]
    w = np.clip(np.where(g_hi > g_lo, (g_hi - target) / np.where(g_hi > g_lo, g_hi - g_lo, 1.0), 0.0), 0.0, 1.0)
    log_tau = fine[idx - 1] + w * (fine[idx] - fine[idx - 1])
    tau = np.where(ok, np.exp(log_tau), np.nan)
    dhi_model = np.where(ok, np.exp(ld[idx - 1, cols] * (1 - w) + ld[idx, cols] * w), np.nan)
    # DNI exactly at the retrieved optical depth (the fine grid's is its interpolation)
    _, dni_model = cloud_irradiance(table, model, z, np.nan_to_num(aod, nan=rep_aod), precipitable_water, pressure,
                                    ozone, eccentricity, optical_depth=np.where(ok, tau, 0.0))
    dni_model = np.where(ok, dni_model, np.nan)
    ghi_model = dhi_model + dni_model * np.cos(z)
    t0, t1 = table.optical_depths[0], table.optical_depths[-1]
    zmax = math.degrees(table.zeniths[-1])
    reason[~in_range] = f"sun lower than {90 - zmax:g} deg: outside the cloud table, cloud optical depth not retrieved"
    rest = in_range & ~ok
    reason[rest & above] = (f"GHI above the sky under the thinnest cloud (optical depth {t0:g}): broken cloud or "
                            "cloud enhancement, cloud optical depth not retrieved")
    reason[rest & below] = (f"GHI below the sky under the thickest cloud (optical depth {t1:g}): cloud optical "
                            "depth not retrieved")
    reason[rest & ambiguous] = (f"GHI between the sky under the thinnest cloud (optical depth {t0:g}) and the slightly "
                                "brighter one under a somewhat thicker cloud: two solutions, not retrieved")
    reason[rest & (ghi <= 0) & (reason == "")] = "no global irradiance: cloud optical depth not retrieved"
    broken = ok & ~overcast
    reason[broken] = [f"broken sky (cover {c:g} tenths) fitted with an overcast layer: approximate"
                      for c in cover_tenths[broken]]
    return CloudRetrieval(tau, cover_tenths / 10.0, ok, overcast, np.where(ok, ghi_model, np.nan), dhi_model,
                          dni_model, reason, rep_aod, table)


#: Cloud optical depth [-] whose sky shape the low-sun fallback takes (a typical stratus; stated, not retrieved).
LOW_SUN_OPTICAL_DEPTH = 10.0


@dataclass(frozen=True)
class BrokenSkyFit:
    """What :func:`fit_broken_sky` found (arrays of shape (n,)): the overcast part's optical depth at 550 nm [-]
    and the cloud fraction [-] (the blend weight of the overcast sky and of its sun), the blend's ``dhi_model``
    and ``dni_model`` and the overcast component's ``cloud_dhi`` [W m^-2] (its full-cover diffuse: the blend holds
    ``cloud_fraction x cloud_dhi``), ``retrieved`` flags (an exact blend), ``enhanced`` flags (no blend reaches the
    record's GHI: the stated enhanced-diffuse rule, where ``cloud_dhi`` is the whole diffuse the overcast term
    adds, ``DHI - (1 - f) DHI_clear``, and ``enhancement`` [-] its ratio to ``f DHI_cloud(tau)``) and a
    ``reason`` where neither."""

    optical_depth: NDArray[np.float64]
    cloud_fraction: NDArray[np.float64]
    dhi_model: NDArray[np.float64]
    dni_model: NDArray[np.float64]
    cloud_dhi: NDArray[np.float64]
    retrieved: NDArray[np.bool_]
    reason: NDArray[np.object_]
    enhanced: NDArray[np.bool_] | None = None
    enhancement: NDArray[np.float64] | None = None


def fit_broken_sky(ghi: ArrayLike, dni: ArrayLike, zenith: ArrayLike, aerosol_optical_depth: ArrayLike,
                   clear_dhi: ArrayLike, *, table: CloudTable, model: BroadbandClearSky,
                   precipitable_water: ArrayLike = 1.4, pressure: ArrayLike = 101325.0, ozone: ArrayLike = 300.0,
                   eccentricity: ArrayLike = 1.0, dhi: ArrayLike | None = None) -> BrokenSkyFit:
    """A broken sky as a blend ``(1 - f) clear + f overcast`` fitted to the record's GHI and DNI [W m^-2].

    An approximation, stated: the sky of a partly cloudy hour is taken as the clear sky (the hour's aerosol, its
    diffuse ``clear_dhi`` [W m^-2]) over a fraction ``1 - f`` of the hour and the overcast layer of
    :func:`retrieve_clouds` over ``f``, both horizontally uniform (no cloud sides, no light scattered between
    the clear and the cloudy parts: the independent pixel approximation of the hour, in the spirit of the
    cover-weighted clear / overcast mixing of gensdaymtx's sky, but with the weight fitted to the beam).

    Both equations are solved together: for each cloud optical depth tau the beam gives ``f(tau) = (DNI_clear -
    DNI) / (DNI_clear - DNI_cloud(tau))`` (admissible where 0 < f <= 1), and the blend's global irradiance
    ``(1 - f) GHI_clear + f GHI_cloud(tau)`` must equal the record's GHI; the residual is evaluated on the
    :data:`_FINE_POINTS` points in ln tau of :func:`retrieve_clouds` and its first sign change (the thinnest
    cloud that fits) interpolated linearly; DNI_cloud is then evaluated exactly at that tau and f taken from
    it (DNI exact; GHI to the grid's linear interpolation, which left DHI within 0.82 % on a made year). (A
    fixed-point iteration between f and tau did not converge under thin clouds with the sun low, where the cloud
    passes a large share of the beam, and left DNI 4-19 % off.)

    Where no blend reaches the record's GHI (the record is brighter: more diffuse light than any clear /
    overcast blend gives, as from the sunlit sides of broken cloud, which this model has not) and ``dhi`` is
    given, the hour gets the **enhanced-diffuse rule**, stated (``enhanced``): the blend closest to the record
    (the admissible tau with the smallest deficit; f from the beam as above; with DNI at or above the clear
    beam, f = 0 and the table's thinnest cloud), its overcast term scaled up so that the diffuse is the
    record's: the overcast term adds ``DHI - (1 - f) clear_dhi`` (``enhancement`` = that over ``f DHI_cloud``;
    with f = 0 the whole excess). DHI then closes by construction, DNI as the blend (exact when the beam is
    below the clear one). Not fitted (``reason``): a record darker than every blend, or (without ``dhi``, or
    with DHI at most the clear part's) no blend reaching the GHI.

    Parameters
    ----------
    ghi, dni : array (n,)
        The record [W m^-2].
    zenith : array (n,)
        Sun zenith [rad] (within the table's zeniths).
    aerosol_optical_depth : array (n,)
        [-] at 550 nm.
    clear_dhi : array (n,)
        DHI [W m^-2] of the clear component (the tables' sky at the hour's aerosol).
    table, model
        The cloud table and broadband model of :func:`retrieve_clouds`.
    precipitable_water, pressure, ozone, eccentricity
        [cm], [Pa], [DU], [-].
    dhi : array (n,), optional
        The record's DHI [W m^-2], for the enhanced-diffuse rule (None: no such rule).
    """
    ghi = np.atleast_1d(np.asarray(ghi, dtype=float))
    n = ghi.size
    dni = np.broadcast_to(np.asarray(dni, dtype=float), (n,))
    z = np.broadcast_to(np.asarray(zenith, dtype=float), (n,))
    aod = np.broadcast_to(np.asarray(aerosol_optical_depth, dtype=float), (n,))
    d_clear = np.broadcast_to(np.asarray(clear_dhi, dtype=float), (n,))
    rec_dhi = None if dhi is None else np.broadcast_to(np.asarray(dhi, dtype=float), (n,))
    pw, p, o3, ecc = (np.broadcast_to(np.asarray(v, dtype=float), (n,)) for v in
                      (precipitable_water, pressure, ozone, eccentricity))
    cosz = np.cos(z)
    n_clear = model.direct_normal(z, aod, pw, p, o3, ecc)
    g_clear = d_clear + n_clear * cosz
    beam_ok = dni < n_clear * (1.0 - 1e-9)
    fine, ld, ln_ = _fine_curves(table, model, z, aod, pw, p, o3, ecc)
    d_f, n_f = np.exp(ld), np.exp(ln_)  # (m, n)
    with np.errstate(divide="ignore", invalid="ignore"):
        f_f = (n_clear - dni)[None, :] / (n_clear[None, :] - n_f)
    adm = beam_ok[None, :] & (n_f < n_clear[None, :]) & (f_f > 0) & (f_f <= 1)
    res = np.where(adm, (1 - f_f) * g_clear[None, :] + f_f * (d_f + n_f * cosz[None, :]) - ghi[None, :], np.nan)
    cols = np.arange(n)
    # the first sign change of the residual along tau (both ends admissible; a residual within 1e-9 of GHI counts
    # as zero, so that a blend at the table's thinnest node is found)
    res = np.where(np.abs(res) <= 1e-9 * np.maximum(ghi, 1.0)[None, :], 0.0, res)
    sgn = np.sign(res)
    strict = (sgn[:-1] * sgn[1:] < 0) & adm[:-1] & adm[1:]  # a root inside the interval j, j + 1
    at_point = (sgn[:-1] == 0) & adm[:-1]  # a root at the point j
    change = strict | at_point
    has_root = change.any(axis=0)
    # a second, separate root further along: two blends reproduce the record (the thinner one is taken)
    two = change.sum(axis=0) >= 2
    j = np.where(has_root, np.argmax(change, axis=0), 0)
    r0, r1 = res[j, cols], res[j + 1, cols]
    w = np.where(has_root, np.clip(r0 / np.where(r0 != r1, r0 - r1, 1.0), 0.0, 1.0), 0.0)
    log_tau = fine[j] + w * (fine[j + 1] - fine[j])
    d_root = np.exp(ld[j, cols] * (1 - w) + ld[j + 1, cols] * w)
    # no root: the admissible blend closest to the record (its largest residual); a record brighter than it
    any_adm = adm.any(axis=0)
    best = np.argmax(np.where(adm, res, -np.inf), axis=0)
    brighter = ~has_root & any_adm & (res[best, cols] < 0)
    darker = ~has_root & any_adm & ~brighter
    no_beam = ~beam_ok
    tau = np.where(has_root, np.exp(log_tau), np.where(brighter, np.exp(fine[best]), table.optical_depths[0]))
    # DNI of the cloud exactly at tau, and f from it (DNI exact where the beam is below the clear one)
    _, n_cloud = cloud_irradiance(table, model, z, aod, pw, p, o3, ecc, optical_depth=tau)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(beam_ok, np.clip((n_clear - dni) / np.maximum(n_clear - n_cloud, 1e-9), 0.0, 1.0), 0.0)
    d_cloud = np.where(has_root, d_root, np.exp(ld[best, cols]))
    d_cloud = np.where(no_beam, np.exp(ld[0]), d_cloud)
    ok = has_root & beam_ok
    enhanced = np.zeros(n, dtype=bool)
    extra = np.full(n, np.nan)
    if rec_dhi is not None:
        extra = rec_dhi - (1 - f) * d_clear
        enhanced = ~ok & (brighter | no_beam) & (extra > 0) & np.isfinite(extra)
    reason = np.full(n, "", dtype=object)
    reason[no_beam & ~enhanced] = "DNI at or above the clear sky's: no cloud in the beam"
    reason[darker & ~enhanced] = ("the record is darker than every clear / overcast blend with its beam (GHI below "
                                  f"the blend under the thickest cloud, optical depth {table.optical_depths[-1]:g})")
    reason[ok & two] = "two blends reproduce GHI and DNI: the one with the thinner cloud taken"
    reason[brighter & ~enhanced] = ("the record is brighter than every clear / overcast blend with its beam (GHI "
                                    "above the blend under the thinnest cloud that fits the beam)")
    nan = np.full(n, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        enhancement = np.where(enhanced & (f > 0), extra / (f * d_cloud), nan)
    keep = ok | enhanced
    cloud_dhi = np.where(ok, d_cloud, np.where(enhanced, extra, nan))
    dhi_model = np.where(ok, (1 - f) * d_clear + f * d_cloud, np.where(enhanced, rec_dhi if rec_dhi is not None
                                                                       else nan, nan))
    return BrokenSkyFit(optical_depth=np.where(keep, tau, nan), cloud_fraction=np.where(keep, f, nan),
                        dhi_model=dhi_model, dni_model=np.where(keep, (1 - f) * n_clear + f * n_cloud, nan),
                        cloud_dhi=cloud_dhi, retrieved=ok, reason=reason, enhanced=enhanced,
                        enhancement=enhancement)


# --------------------------------------------------------------------------------------------- retrieval


@dataclass(frozen=True)
class RetrievalOptions:
    """Settings of :func:`retrieve_hourly_atmosphere` (see the module docstring).

    Parameters
    ----------
    angstrom_alpha : float
        Angstrom exponent of the aerosol (default 1.3).
    aerosol_optical_depth_nodes, single_scattering_albedo_nodes : tuple of float
        The family's grid (:data:`DEFAULT_AOD_NODES`, :data:`DEFAULT_ALBEDO_NODES`).
    phase_g_min : float or None
        Smallest aerosol phase parameter g [-] of the clear hours' DHI closure (default
        :data:`DEFAULT_PHASE_G_MIN`): the family gets an ``aerosol_phase_g`` axis with nodes (this, the base's g)
        and the closure path its second leg (:func:`closure_path`). ``None`` (or a base g at or below it): the
        albedo alone (the family before 2026-12-02).
    clear_sky_cover : float
        Largest total sky cover [tenths] of a clear hour (default 3).
    default_aerosol_optical_depth : float
        Cloudy hours' AOD at 550 nm when neither the file nor clear hours give one (default 0.1).
    default_precipitable_water : float
        [cm] when the file gives neither the field nor temperature and humidity (default 1.4).
    default_ozone : float
        [DU] (default 300).
    bad_hours : {"error", "flag"}
        Impossible records: raise (default) or mark and leave dark-NaN.
    base : AtmosphereParameters, optional
        The medium the grid modifies (default: Earth with physical Rayleigh scattering over the standard
        atmosphere's column, :data:`RAYLEIGH_SCALE_HEIGHT`, the Angstrom aerosol of ``angstrom_alpha`` (Cornette-Shanks
        phase, g = 0.8, 1.2 km scale height) and a ground albedo of 0.2, gendaymtx's default).
    tables : {"default", "coarse"}
        Table preset of the family (:data:`TABLE_PRESETS`): ``"default"`` (the paper's sizes, the default 8
        orders, the 23 wavelengths of :data:`~skyscatter.precomputed.family.FAMILY_WAVELENGTHS`) or ``"coarse"``
        (small tables, 4 orders, 8 wavelengths: a quick look, about 10x cheaper to build, percent-level less
        accurate).
    sizes : mapping, optional
        Table sizes overriding the preset's.
    orders : int, optional
        Scattering orders overriding the preset's.
    """

    angstrom_alpha: float = 1.3
    aerosol_optical_depth_nodes: tuple[float, ...] = DEFAULT_AOD_NODES
    single_scattering_albedo_nodes: tuple[float, ...] = DEFAULT_ALBEDO_NODES
    phase_g_min: float | None = DEFAULT_PHASE_G_MIN
    clear_sky_cover: float = 3.0
    default_aerosol_optical_depth: float = 0.1
    default_precipitable_water: float = 1.4
    default_ozone: float = 300.0
    bad_hours: str = "error"
    base: AtmosphereParameters | None = None
    tables: str = "default"
    sizes: Any = None
    orders: int | None = None

    def __post_init__(self) -> None:
        if self.tables not in TABLE_PRESETS:
            raise InvalidParameterError(f"tables must be one of {', '.join(TABLE_PRESETS)}; got {self.tables!r}")
        for name in ("aerosol_optical_depth_nodes", "single_scattering_albedo_nodes"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.ndim != 1 or v.size < 2 or not np.all(np.isfinite(v)) or np.any(np.diff(v) <= 0):
                raise InvalidParameterError(f"{name} must be two or more increasing numbers")
            object.__setattr__(self, name, tuple(float(x) for x in v))
        if self.aerosol_optical_depth_nodes[0] < 0 or self.aerosol_optical_depth_nodes[-1] > 10:
            raise InvalidParameterError("aerosol optical depth nodes must lie in [0, 10]")
        if self.single_scattering_albedo_nodes[0] < 0 or self.single_scattering_albedo_nodes[-1] > 1:
            raise InvalidParameterError("single-scattering albedo nodes must lie in [0, 1]")
        if self.bad_hours not in ("error", "flag"):
            raise InvalidParameterError(f"bad_hours must be 'error' or 'flag'; got {self.bad_hours!r}")
        if self.phase_g_min is not None:
            g = float(self.phase_g_min)
            if not (math.isfinite(g) and 0.0 <= g < 1.0):
                raise InvalidParameterError(f"phase_g_min must be in [0, 1) or None; got {self.phase_g_min!r}")
            object.__setattr__(self, "phase_g_min", g)
        if not -1.0 <= float(self.angstrom_alpha) <= 4.0:
            raise InvalidParameterError(f"angstrom_alpha must be in [-1, 4]; got {self.angstrom_alpha!r}")
        for name in ("default_aerosol_optical_depth", "default_precipitable_water", "default_ozone"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v >= 0):
                raise InvalidParameterError(f"{name} must be >= 0; got {v!r}")
        if not 0.0 <= float(self.clear_sky_cover) <= 10.0:
            raise InvalidParameterError(f"clear_sky_cover must be in [0, 10] tenths; got {self.clear_sky_cover!r}")

    def base_atmosphere(self) -> AtmosphereParameters:
        """The family's base medium."""
        if self.base is not None:
            return self.base
        from ..atmosphere.profiles import DensityProfile
        from ..atmosphere.spectra import rayleigh_scattering_physical

        return AtmosphereParameters.from_aerosol_optical_depth(
            0.1, float(self.angstrom_alpha), ground_albedo=DEFAULT_GROUND_ALBEDO,
            rayleigh_scattering=rayleigh_scattering_physical(),
            rayleigh_density=DensityProfile.exponential(RAYLEIGH_SCALE_HEIGHT))


#: Small tables of the "coarse" preset (about 10x cheaper to build than the paper's sizes).
COARSE_SIZES = {"transmittance_mu": 64, "transmittance_r": 16, "irradiance_mu_s": 16, "irradiance_r": 8,
                "scattering_r": 8, "scattering_mu": 32, "scattering_mu_s": 16, "scattering_nu": 8,
                "ray_samples": 20, "density_sphere_samples": 8, "irradiance_sphere_samples": 8}
#: Table presets of :class:`RetrievalOptions` (``tables``): sizes, orders and table wavelengths [nm].
TABLE_PRESETS = {
    "default": {"sizes": None, "orders": DEFAULT_ORDERS, "wavelengths": FAMILY_WAVELENGTHS},
    "coarse": {"sizes": COARSE_SIZES, "orders": 4,
               "wavelengths": (360.0, 390.0, 450.0, 550.0, 650.0, 770.0, 800.0, 830.0)},
}


def default_family(options: RetrievalOptions | None = None) -> TableFamily:
    """The table family of a retrieval: aerosol optical depth x single-scattering albedo x phase g (the last with
    ``phase_g_min`` set, the default) over the base medium (the optical depth alone for a particle aerosol such
    as an OPAC type, whose albedo and phase are its Mie optics'),
    with the options' table preset, for ground observers (every node kept in memory: 4.5 MB each by default)."""
    o = RetrievalOptions() if options is None else options
    preset = TABLE_PRESETS[o.tables]
    base = o.base_atmosphere()
    axes = [GridAxis("aerosol_optical_depth", tuple(o.aerosol_optical_depth_nodes))]
    if base.aerosol is None:  # a particle aerosol (an OPAC type) has the albedo of its Mie optics: no such axis
        axes.append(GridAxis("aerosol_single_scattering_albedo", tuple(o.single_scattering_albedo_nodes)))
        # the phase leg of the closure path runs from the base's g down to phase_g_min (none for a base whose g
        # is already at or below it)
        if o.phase_g_min is not None and o.phase_g_min < base.mie_phase_g:
            axes.append(GridAxis("aerosol_phase_g", (o.phase_g_min, float(base.mie_phase_g))))
    return TableFamily(axes, base=base, wavelengths=preset["wavelengths"],
                       sizes=o.sizes if o.sizes is not None else preset["sizes"],
                       orders=o.orders if o.orders is not None else preset["orders"], ground_only=True,
                       max_in_memory=int(np.prod([len(a.values) for a in axes])))


@dataclass(eq=False)
class HourlyAtmosphere:
    """The retrieved atmosphere of every hour of a record (arrays of shape (n_hours,)).

    ``status`` codes are keys of :data:`HOUR_STATUS`; ``reason`` says why an hour is not clear-retrieved.
    Inputs as used (after fallbacks) and their ``*_source``; the retrieved ``aerosol_optical_depth`` (550 nm,
    vertical), ``single_scattering_albedo`` and ``aerosol_phase_g`` (the analytic phase's g; NaN for a particle
    aerosol); ``cloud_optical_depth`` and ``cloud_cover`` (NaN until
    retrieved); the model's ``dni_model``/``dhi_model`` [W m^-2] and the relative closure
    ``model / record - 1`` (NaN where not computed); ``dhi_albedo_slope`` d DHI / d albedo [W m^-2] of the clear
    hours (for a closure step on another discretisation of the same sky, :mod:`.spectral_matrix`);
    ``cloud_fraction`` [-] the weight of the overcast sky in the hour's sky (1 for overcast and low-sun hours, the
    fitted blend weight of *broken* hours, NaN elsewhere), ``clear_dhi`` and ``cloud_dhi`` [W m^-2] the diffuse
    horizontal irradiance of the blend's clear and overcast (full-cover) components, so that ``dhi_model =
    (1 - cloud_fraction) clear_dhi + cloud_fraction cloud_dhi`` in those hours; in *broken, enhanced diffuse*
    hours ``cloud_fraction`` weighs the clear and the cloud's sun and the clear sky, and ``cloud_dhi`` is the whole
    diffuse of the overcast sky term: ``dhi_model = (1 - cloud_fraction) clear_dhi + cloud_dhi`` (the record's).
    """

    record: EPWData
    unix_time: NDArray[np.float64]
    sun_zenith: NDArray[np.float64]
    sun_azimuth: NDArray[np.float64]
    ghi: NDArray[np.float64]
    dni: NDArray[np.float64]
    dhi: NDArray[np.float64]
    eccentricity: NDArray[np.float64]
    precipitable_water: NDArray[np.float64]
    precipitable_water_source: NDArray[np.str_]
    pressure: NDArray[np.float64]
    ozone: NDArray[np.float64]
    ozone_source: NDArray[np.str_]
    aerosol_optical_depth: NDArray[np.float64]
    aerosol_source: NDArray[np.str_]
    aerosol_optical_depth_file: NDArray[np.float64]
    single_scattering_albedo: NDArray[np.float64]
    aerosol_phase_g: NDArray[np.float64]
    cloud_optical_depth: NDArray[np.float64]
    cloud_cover: NDArray[np.float64]
    status: NDArray[np.int64]
    reason: NDArray[np.object_]
    dni_model: NDArray[np.float64]
    dhi_model: NDArray[np.float64]
    dhi_albedo_slope: NDArray[np.float64]
    cloud_fraction: NDArray[np.float64]
    clear_dhi: NDArray[np.float64]
    cloud_dhi: NDArray[np.float64]
    options: RetrievalOptions
    family: TableFamily
    notes: list[str] = field(default_factory=list)
    #: The cloud table of the cloudy hours (None without retrieved cloudy hours).
    cloud_table: CloudTable | None = None

    @property
    def dni_closure(self) -> NDArray[np.float64]:
        """DNI of the retrieved sky / record - 1 [-]."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.dni > 0, self.dni_model / self.dni - 1.0, np.nan)

    @property
    def dhi_closure(self) -> NDArray[np.float64]:
        """DHI of the retrieved sky / record - 1 [-]."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.dhi > 0, self.dhi_model / self.dhi - 1.0, np.nan)

    @property
    def has_sky(self) -> NDArray[np.bool_]:
        """Hours whose sky can be computed (clear, clear-not-closed, cloudy retrieved)."""
        return np.isin(self.status, (CLEAR, CLEAR_OPEN, CLOUDY, BROKEN, LOW_SUN, ENHANCED))

    def summary(self) -> dict[str, Any]:
        """Counts per status and closure statistics: the largest |closure| of the clear hours, the median of the
        retrieved cloudy hours."""
        out: dict[str, Any] = {HOUR_STATUS[k]: int(np.sum(self.status == k)) for k in HOUR_STATUS}
        for name, c in (("dni", self.dni_closure), ("dhi", self.dhi_closure)):
            sel = np.isfinite(c) & (self.status == CLEAR)
            out[f"{name}_closure_max_abs"] = float(np.max(np.abs(c[sel]))) if np.any(sel) else None
            # cloudy hours are fitted to GHI: their DHI and DNI closures are checks, not fits
            sel = np.isfinite(c) & (self.status == CLOUDY)
            out[f"cloudy_{name}_closure_median_abs"] = float(np.median(np.abs(c[sel]))) if np.any(sel) else None
            sel = np.isfinite(c) & (self.status == BROKEN)
            out[f"broken_{name}_closure_max_abs"] = float(np.max(np.abs(c[sel]))) if np.any(sel) else None
        return out


def _fail(record: EPWData, i: int, what: str) -> FileFormatError:
    return FileFormatError(f"{record.path}: line {int(record.line_numbers[i])}: {what}")


def retrieve_hourly_atmosphere(record: EPWData | str | os.PathLike[str], options: RetrievalOptions | None = None,
                               *, family: TableFamily | None = None, progress: bool = False) -> HourlyAtmosphere:
    """Retrieve the atmosphere of every hour of a weather record (module docstring).

    Parameters
    ----------
    record : EPWData or path
        An hourly record (:func:`read_weather`; a sub-hourly EPW is averaged to hours).
    options : RetrievalOptions, optional
    family : TableFamily, optional
        The tables (default :func:`default_family` of the options); built and cached on first use.
    progress : bool
        Progress bar while the family's tables are built.

    Raises
    ------
    FileFormatError
        An impossible record with ``bad_hours="error"`` (the message names the line), or a time zone that
        disagrees with the longitude by more than 3 h.
    """
    from ..sky.perez import SOLAR_CONSTANT, extraterrestrial_irradiance
    from ..sun.position import sun_position_unix

    o = RetrievalOptions() if options is None else options
    rec = record if isinstance(record, EPWData) else read_weather(record)
    rec = rec.hourly()
    fam = default_family(o) if family is None else family
    loc = rec.location
    notes: list[str] = []
    # the standard meridian of the time zone against the longitude (15 deg per hour)
    if abs(loc.longitude_deg / 15.0 - loc.timezone_hours) > 3.0:
        raise FileFormatError(
            f"{rec.path}: the time zone {loc.timezone_hours:+g} h does not fit the longitude "
            f"{loc.longitude_deg:.2f} deg (its solar time zone is about {loc.longitude_deg / 15.0:+.1f} h): every "
            "sun position would be hours off; fix the LOCATION line (east longitudes and time zones positive)")
    unix = rec.unix_times()
    n = unix.size
    steps = np.diff(unix)
    if steps.size and np.any(np.abs(steps - 3600.0) > 1.0):
        gaps = int(np.sum(np.maximum(np.round(steps / 3600.0) - 1, 0)))
        notes.append(f"the record is not continuous: {gaps} hour(s) missing between records (kept as absent)")
    pos = sun_position_unix(loc.latitude, loc.longitude, unix, altitude=loc.elevation, apparent=False)
    zen = np.atleast_1d(np.asarray(pos.zenith, dtype=float))
    azi = np.atleast_1d(np.asarray(pos.azimuth, dtype=float))
    doy = rec.day_of_year
    ecc = np.asarray(extraterrestrial_irradiance(doy), dtype=float) / SOLAR_CONSTANT
    ghi = rec.global_horizontal_irradiance.copy()
    dni = rec.direct_normal_irradiance.copy()
    dhi = rec.diffuse_horizontal_irradiance.copy()
    cosz = np.cos(zen)
    status = np.full(n, NIGHT, dtype=np.int64)
    reason = np.full(n, "", dtype=object)

    # ---- missing fields rebuilt from the other two (GHI = DHI + DNI cos z)
    up = cosz > 0.0
    m_dni, m_dhi, m_ghi = np.isnan(dni), np.isnan(dhi), np.isnan(ghi)
    fix = m_dni & ~m_dhi & ~m_ghi & (cosz > 0.1)
    dni[fix] = np.maximum(ghi[fix] - dhi[fix], 0.0) / cosz[fix]
    fix2 = m_dhi & ~m_dni & ~m_ghi
    dhi[fix2] = np.maximum(ghi[fix2] - dni[fix2] * np.maximum(cosz[fix2], 0.0), 0.0)
    fix3 = m_ghi & ~m_dni & ~m_dhi
    ghi[fix3] = dhi[fix3] + dni[fix3] * np.maximum(cosz[fix3], 0.0)
    for mask, what in ((fix, "DNI"), (fix2, "DHI"), (fix3, "GHI")):
        reason[mask] = f"{what} missing, rebuilt from the other two"
    if np.any(fix | fix2 | fix3):
        notes.append(f"{int(np.sum(fix | fix2 | fix3))} hour(s) with one missing irradiance field rebuilt")

    # ---- impossible records
    e_ext = ecc * SOLAR_CONSTANT
    checks = (
        (np.isnan(dni) | np.isnan(dhi) | np.isnan(ghi), "irradiance missing (9999) and not rebuildable"),
        (dni > e_ext * 1.0001, "direct normal irradiance above the extraterrestrial value"),
        (dhi > np.maximum(1.05 * ghi, ghi + 10.0), "diffuse horizontal irradiance above the global"),
        ((zen > math.radians(93.0)) & ((np.nan_to_num(ghi) > 1.0) | (np.nan_to_num(dni) > 1.0)),
         "irradiance with the sun more than 3 deg below the horizon"),
    )
    bad = np.zeros(n, dtype=bool)
    for mask, what in checks:
        new = mask & ~bad
        if np.any(new):
            i = int(np.argmax(new))
            if o.bad_hours == "error":
                detail = (f" (DNI {dni[i]:.0f} > {e_ext[i]:.0f} W m^-2)" if "extraterrestrial" in what else
                          f" ({dhi[i]:.0f} > {ghi[i]:.0f} W m^-2)" if "above the global" in what else
                          f" (sun zenith {math.degrees(zen[i]):.1f} deg)" if "below the horizon" in what else "")
                raise _fail(rec, i, what + detail + "; pass bad_hours='flag' (CLI --bad-hours flag) to mark such "
                            "hours and leave their sky empty")
            reason[new] = what
            bad |= new
    status[bad] = INVALID
    if np.any(bad):
        notes.append(f"{int(bad.sum())} impossible hour(s) flagged (sky left NaN)")
    lit = ~bad & up & ((ghi > 0) | (dhi > 0))
    dark_with_light = ~bad & ~up & (ghi > 0)
    reason[dark_with_light] = "light in the record with the sun just below the horizon: left dark"

    # ---- precipitable water, pressure, ozone
    pw = np.full(n, float(o.default_precipitable_water))
    pw_src = np.full(n, "default", dtype="<U10")
    if rec.relative_humidity is not None:
        t = rec.dry_bulb
        ok = np.isfinite(t) & np.isfinite(rec.relative_humidity)
        pw[ok] = precipitable_water_gueymard1994(t[ok], rec.relative_humidity[ok])
        pw_src[ok] = "gueymard94"
    if rec.precipitable_water is not None:
        ok = np.isfinite(rec.precipitable_water)
        pw[ok] = rec.precipitable_water[ok] / 10.0
        pw_src[ok] = "file"
    pressure = np.full(n, 101325.0 * (1 - 2.25577e-5 * loc.elevation) ** 5.25588)  # standard atmosphere
    if rec.pressure is not None:
        ok = np.isfinite(rec.pressure)
        pressure[ok] = rec.pressure[ok]
    ozone = np.full(n, float(o.default_ozone))
    o3_src = np.full(n, "default", dtype="<U8")
    file_ozone = getattr(rec, "ozone", None)
    if file_ozone is not None:
        ok = np.isfinite(file_ozone)
        ozone[ok] = file_ozone[ok]
        o3_src[ok] = "file"
    model = BroadbandClearSky(fam.base, o.angstrom_alpha)
    # the file's broadband AOD (at BROADBAND_AOD_WAVELENGTH) to 550 nm with the medium's own spectral shape: the
    # Angstrom law of the analytic aerosol, a particle aerosol's Mie extinction (e.g. --aerosol desert)
    aod_file = (np.full(n, np.nan) if rec.aerosol_optical_depth is None else
                rec.aerosol_optical_depth / float(model.aerosol_shape_at([BROADBAND_AOD_WAVELENGTH])[0]))

    # ---- clear hours: AOD from DNI, albedo from DHI
    # the aerosol albedo where no axis retrieves it: the base's (a particle aerosol's from its Mie optics, 550 nm)
    base_ssa = (fam.base.mie_single_scattering_albedo if fam.base.aerosol is None else
                float(fam.base.aerosol_component.single_scattering_albedo_at([550.0])[0]))
    # the analytic phase's g (a particle aerosol has its Mie phase: NaN)
    base_g = fam.base.mie_phase_g if fam.base.aerosol is None else np.nan
    aod_axis = next(a for a in fam.axes if a.name == "aerosol_optical_depth")
    ssa_axis = next((a for a in fam.axes if a.name == "aerosol_single_scattering_albedo"), None)
    cover = rec.total_sky_cover if rec.total_sky_cover is not None else np.full(n, np.nan)
    candidate = lit & (zen < math.pi / 2 - _MIN_CLEAR_ELEVATION) & (dni > 0) & ~(cover > o.clear_sky_cover)
    aod = np.full(n, np.nan)
    aod_src = np.full(n, "", dtype="<U12")
    ssa = np.full(n, np.nan)
    phase_g = np.full(n, np.nan)
    dni_model = np.full(n, np.nan)
    dhi_model = np.full(n, np.nan)
    slope = np.full(n, np.nan)
    ci = np.flatnonzero(candidate)
    tau_max = aod_axis.values[-1]
    if ci.size:
        tau, ok = model.retrieve_aerosol(dni[ci], zen[ci], pw[ci], pressure[ci], ozone[ci], ecc[ci],
                                         tau_max=tau_max)
        too_clean = ~ok & (dni[ci] > 0) & (model.direct_normal(zen[ci], np.zeros(ci.size), pw[ci], pressure[ci],
                                                               ozone[ci], ecc[ci]) < dni[ci])
        reason[ci[too_clean]] = "DNI above the aerosol-free clear sky: AOD 0 cannot reproduce it"
        reason[ci[~ok & ~too_clean]] = f"DNI below the clear sky of AOD {tau_max:g}: clouds or haze beyond the grid"
        good = ci[ok]
        aod[good] = tau[ok]
        aod_src[good] = "dni"
        # DHI at the vertices of the closure path, at the retrieved AOD (interpolated along the AOD axis only)
        if good.size:
            k_path, verts = closure_path(fam)
            d_v = _diffuse_on_path(fam, model, good, aod, zen, pw, pressure, ozone, ecc, k_path, verts)
            if verts.shape[0] > 1:
                last = verts.shape[0] - 1
                p = _path_invert(d_v, dhi[good])
                clear = np.isfinite(p) & (p >= 0) & (p <= last)
                too_bright = np.isfinite(p) & (p > last)
                too_dark = np.isfinite(p) & (p < 0)
                pc = np.clip(p, 0, last)
                on_path = _path_values(verts, np.nan_to_num(pc))
                ssa[good] = np.where(np.isfinite(p), on_path[:, 0], np.nan)
                phase_g[good] = on_path[:, 1] if verts.shape[1] > 1 else base_g
                status[good[clear]] = CLEAR
                status[good[too_dark]] = CLEAR_OPEN
                # what the record would need: the path's first leg extrapolated (the phase's g at the smallest
                # albedo; without a g axis the albedo). The path's end is the least diffuse light any aerosol within
                # the bounds gives at the beam's optical depth (the tables' value there is within -2.2 to +0.6 % of
                # the Monte Carlo at suns 3-6 deg up, docs/sky_matrices.md), so a record below it is not a clear sky
                # of a physical aerosol: on SPECTRL2 records (Bird & Riordan 1986) its low suns, whose diffuse
                # approximations fall 10-30 % below radiative transfer through SPECTRL2's own aerosol there
                first = verts[0] + p[too_dark, None] * (verts[1] - verts[0])
                deficit = 100.0 * (1.0 - dhi[good[too_dark]] / d_v[too_dark, 0])
                bounds = (f"albedo {verts[0, 0]:g}, phase g {verts[0, 1]:g}" if verts.shape[1] > 1 else
                          f"albedo {verts[0, 0]:g}")
                common = [f"the record's DHI is {q:.1f} % below the physical minimum (the clear sky of the beam's "
                          f"aerosol optical depth with the most absorbing, least forward-scattering aerosol within "
                          f"bounds: {bounds}; sun {90 - math.degrees(z):.1f} deg up): no aerosol within bounds "
                          "reproduces it"
                          for q, z in zip(deficit, zen[good[too_dark]], strict=True)]
                if verts.shape[1] > 1:
                    reason[good[too_dark]] = [
                        f"{c} (the phase line at albedo {verts[0, 0]:g} through the grid's g nodes reaches the "
                        f"record's DHI at g {x:.2f}, below the published range); clamped, DHI not closed"
                        for c, x in zip(common, first[:, 1], strict=True)]
                else:
                    reason[good[too_dark]] = [
                        f"{c} (the albedo line through the grid's nodes reaches the record's DHI at {x:.2f}, outside "
                        "the grid); albedo clamped, DHI not closed" for c, x in zip(common, first[:, 0], strict=True)]
                reason[good[too_bright]] = "DHI above the clear sky with aerosol albedo 1: treated as cloudy"
                dhi_model[good] = _path_dhi(d_v, pc)
                # d DHI / d albedo along the albedo leg (the last vertices, at the largest g)
                n_s = len(fam.axes[k_path[0]].values)
                slope[good] = (d_v[:, -1] - d_v[:, -n_s]) / (verts[-1, 0] - verts[-n_s, 0])
            else:
                ssa[good] = base_ssa if ssa_axis is None else ssa_axis.values[0]
                phase_g[good] = base_g
                status[good] = CLEAR
                dhi_model[good] = d_v[:, 0]
            dni_model[good] = model.direct_normal(zen[good], aod[good], pw[good], pressure[good], ozone[good],
                                                  ecc[good])

    # ---- cloudy hours
    table = None
    cod, ccv, frac = np.full(n, np.nan), np.full(n, np.nan), np.full(n, np.nan)
    clear_dhi, cloud_dhi = np.full(n, np.nan), np.full(n, np.nan)
    cloudy = lit & ~np.isin(status, (CLEAR, CLEAR_OPEN))
    cl = np.flatnonzero(cloudy)
    if cl.size:
        _cloudy_aerosol(rec, cl, status, aod, aod_src, aod_file, float(o.default_aerosol_optical_depth), unix)
        aod[cl] = np.minimum(aod[cl], tau_max)
        ssa[cl] = base_ssa
        phase_g[cl] = base_g
        opaque = rec.opaque_sky_cover if rec.opaque_sky_cover is not None else np.full(n, np.nan)
        clouds = retrieve_clouds(ghi[cl], dhi[cl], zen[cl], aod[cl], cover[cl], opaque[cl],
                                 precipitable_water=pw[cl], pressure=pressure[cl], ozone=ozone[cl],
                                 eccentricity=ecc[cl], model=model, aerosol_nodes=aod_axis.values)
        status[cl] = np.where(clouds.retrieved, CLOUDY, CLOUDY_OPEN)
        reason[cl] = [("; ".join(x for x in (r, c) if x)) for r, c in zip(reason[cl], clouds.reason, strict=True)]
        dhi_model[cl], dni_model[cl] = clouds.dhi_model, clouds.dni_model
        cod[cl], ccv[cl] = clouds.optical_depth, clouds.cover
        frac[cl[clouds.retrieved]] = 1.0
        cloud_dhi[cl] = clouds.dhi_model
        table = clouds.table
        if table is not None:
            notes.append(f"cloudy hours: {int(clouds.retrieved.sum())} of {cl.size} retrieved, with the cloud table "
                         f"of aerosol optical depth {clouds.aerosol_optical_depth:g} "
                         f"({table.optical_depths.size} x {table.zeniths.size} DISORT solves)")
            # broken skies: a clear / overcast blend fitted to GHI and DNI (fit_broken_sky)
            # the blend's clear part has the aerosol albedo of hours without an albedo retrieval (a particle
            # aerosol's Mie albedo: the analytic one would misreport an OPAC type's broken hours)
            s_b = float(np.clip(base_ssa, *(
                (ssa_axis.values[0], ssa_axis.values[-1]) if ssa_axis is not None else (0.0, 1.0))))
            br = cl[~clouds.overcast & (dni[cl] > 0) & (dhi[cl] > 0) & (zen[cl] <= table.zeniths[-1] + 1e-9)]
            if br.size:
                # a beam at or above the clear beam of the borrowed aerosol: the hour's own aerosol from its DNI
                # (the clear hours' retrieval), so that the blend's clear part carries the record's beam
                n_c = model.direct_normal(zen[br], aod[br], pw[br], pressure[br], ozone[br], ecc[br])
                own = br[dni[br] >= n_c]
                if own.size:
                    t_own, ok_own = model.retrieve_aerosol(dni[own], zen[own], pw[own], pressure[own], ozone[own],
                                                           ecc[own], tau_max=tau_max)
                    aod[own[ok_own]] = t_own[ok_own]
                    aod_src[own[ok_own]] = "dni"
                k_path, verts = closure_path(fam)
                d_v = _diffuse_on_path(fam, model, br, aod, zen, pw, pressure, ozone, ecc, k_path, verts)
                if verts.shape[0] > 1:
                    # the base albedo on the path's albedo leg (at the base's g, the largest g node)
                    n_s = len(ssa_axis.values) if ssa_axis is not None else 1
                    p_b = verts.shape[0] - n_s + float(np.interp(s_b, ssa_axis.values, np.arange(n_s))) \
                        if ssa_axis is not None else 0.0
                    d_clear = _path_dhi(d_v, np.full(br.size, p_b))
                else:
                    d_clear = d_v[:, 0]
                fit = fit_broken_sky(ghi[br], dni[br], zen[br], aod[br], d_clear, table=table, model=model,
                                     precipitable_water=pw[br], pressure=pressure[br], ozone=ozone[br],
                                     eccentricity=ecc[br], dhi=dhi[br])
                ok = fit.retrieved
                enh = np.zeros(br.size, dtype=bool) if fit.enhanced is None else fit.enhanced
                use = ok | enh
                b_ok = br[use]
                status[br[ok]] = BROKEN
                status[br[enh]] = ENHANCED
                ssa[b_ok] = s_b
                phase_g[b_ok] = base_g
                cod[b_ok], frac[b_ok] = fit.optical_depth[use], fit.cloud_fraction[use]
                clear_dhi[b_ok], cloud_dhi[b_ok] = d_clear[use], fit.cloud_dhi[use]
                dhi_model[b_ok], dni_model[b_ok] = fit.dhi_model[use], fit.dni_model[use]
                reason[br[ok]] = [f"broken sky (cover {10 * c:g} tenths): clear / overcast blend, cloud fraction "
                                  f"{f:.2f}" + (f" ({why})" if why else "")
                                  for c, f, why in zip(ccv[br[ok]], fit.cloud_fraction[ok], fit.reason[ok],
                                                       strict=True)]
                for i, f, t, k in zip(br[enh], fit.cloud_fraction[enh], fit.optical_depth[enh], fit.enhancement[enh],
                                      strict=True):
                    beam = (f"clear / overcast blend with the beam's cloud fraction {f:.2f} (optical depth {t:.2f})"
                            if f > 0 else "the clear sky (beam at or above the clear beam) plus an overcast term "
                            f"(optical depth {t:.2f})")
                    scale = f", its overcast diffuse x {k:.2f}" if np.isfinite(k) else ""
                    dni_note = "" if f > 0 or dni[i] <= dni_model[i] * (1 + 1e-6) else \
                        "; DNI above the aerosol-free clear beam: not closed"
                    reason[i] = (f"broken sky (cover {10 * ccv[i]:g} tenths) brighter than any clear / overcast blend: "
                                 f"enhanced-diffuse rule, {beam}{scale}, scaled to the record's DHI (closure by "
                                 f"construction){dni_note}")
                for i, why in zip(br[~use], fit.reason[~use], strict=True):
                    reason[i] = f"{reason[i]}; blend not fitted ({why})" if reason[i] else f"blend not fitted ({why})"
                notes.append(f"broken hours: {int(ok.sum())} of {br.size} fitted with a clear / overcast blend, "
                             f"{int(enh.sum())} by the enhanced-diffuse rule")
            # suns below the table's lowest (3 deg): the fallback of low_sun_fallback
            low = cl[(zen[cl] > table.zeniths[-1] + 1e-9) & (dhi[cl] > 0)]
            if low.size:
                status[low] = LOW_SUN
                cod[low] = LOW_SUN_OPTICAL_DEPTH
                frac[low] = 1.0
                dhi_model[low], cloud_dhi[low] = dhi[low], dhi[low]
                dni_model[low] = dni[low]
                reason[low] = (f"sun below {90 - math.degrees(table.zeniths[-1]):g} deg (outside the cloud table): "
                               f"fallback, the shape of the overcast sky (optical depth {LOW_SUN_OPTICAL_DEPTH:g}) of "
                               "the table's lowest sun scaled to the record's DHI, the sun the record's DNI; "
                               "closure by construction")
    return HourlyAtmosphere(
        record=rec, unix_time=unix, sun_zenith=zen, sun_azimuth=azi, ghi=ghi, dni=dni, dhi=dhi, eccentricity=ecc,
        precipitable_water=pw, precipitable_water_source=pw_src, pressure=pressure, ozone=ozone,
        ozone_source=o3_src, aerosol_optical_depth=aod, aerosol_source=aod_src,
        aerosol_optical_depth_file=aod_file, single_scattering_albedo=ssa, aerosol_phase_g=phase_g,
        cloud_optical_depth=cod,
        cloud_cover=ccv, status=status, reason=reason, dni_model=dni_model, dhi_model=dhi_model,
        dhi_albedo_slope=slope, cloud_fraction=frac, clear_dhi=clear_dhi, cloud_dhi=cloud_dhi, options=o,
        family=fam, notes=notes, cloud_table=table)


def closure_path(family: TableFamily) -> tuple[list[int], NDArray[np.float64]]:
    """The one-parameter path in the family's grid along which a clear hour's DHI is closed.

    DNI fixes the aerosol optical depth; DHI then constrains one more property of the aerosol (as in the
    albedo retrievals from direct and diffuse irradiance, Petters et al. 2003, JGR 108(D9), 4288). Two properties
    move DHI: the single-scattering albedo (absorption) and the phase's forward peak (a less forward-peaked aerosol
    sends more of its light back up). One number cannot fix both, so the path takes them in turn, each within its
    published range: first the albedo from 1 down to the smallest node (0.8, about the most absorbing ambient
    aerosol: :data:`DEFAULT_ALBEDO_NODES`) at the base's phase (Cornette-Shanks g = 0.8, mean cosine 0.84, a
    forward-peaked coarse-rich aerosol); below that the record's diffuse cannot be absorption, and the path
    lowers g at that albedo down to ``phase_g_min`` (:data:`DEFAULT_PHASE_G_MIN`, fine-mode smoke). DHI grows
    along the path (both properties raise it), so the closure is unique.

    Returns
    -------
    axes : list of int
        Indices of the path's axes in ``family.axes``: the albedo's, then the phase g's (absent axes left out).
    vertices : ndarray, shape (n_vertices, len(axes))
        The path's vertices (grid nodes), in order of increasing DHI: (albedo_0, g_0), ..., (albedo_0, g_last),
        (albedo_1, g_last), ..., (albedo_last, g_last). A single vertex (or none) without a closure axis.
    """
    names = [a.name for a in family.axes]
    if "aerosol_single_scattering_albedo" not in names:
        return [], np.zeros((1, 0))
    k_s = names.index("aerosol_single_scattering_albedo")
    s_nodes = family.axes[k_s].values
    if "aerosol_phase_g" not in names:
        return [k_s], np.asarray(s_nodes, dtype=float)[:, None]
    k_g = names.index("aerosol_phase_g")
    g_nodes = family.axes[k_g].values
    verts = [(s_nodes[0], g) for g in g_nodes] + [(s, g_nodes[-1]) for s in s_nodes[1:]]
    return [k_s, k_g], np.asarray(verts, dtype=float)


def _path_values(vertices: NDArray[np.float64], position: NDArray[np.float64]) -> NDArray[np.float64]:
    """Axis values at path positions ``position`` in [0, n_vertices - 1] (piecewise linear between vertices)."""
    k = np.clip(np.floor(position).astype(np.int64), 0, max(vertices.shape[0] - 2, 0))
    w = (position - k)[:, None]
    upper = np.minimum(k + 1, vertices.shape[0] - 1)
    return (1 - w) * vertices[k] + w * vertices[upper]


def _path_position(vertices: NDArray[np.float64], albedo: NDArray[np.float64],
                   phase_g: NDArray[np.float64] | None) -> NDArray[np.float64]:
    """Position on the closure path (:func:`closure_path`) of hours with these albedos and phase g's: on the g
    leg where g is below the largest g node, else on the albedo leg."""
    if vertices.shape[1] == 1 or phase_g is None:
        return np.interp(albedo, vertices[:, 0], np.arange(vertices.shape[0], dtype=float))
    n_g = int(np.sum(vertices[:, 0] == vertices[0, 0]))
    g_nodes, s_nodes = vertices[:n_g, 1], vertices[n_g - 1:, 0]
    on_g = np.interp(phase_g, g_nodes, np.arange(n_g, dtype=float))
    on_s = n_g - 1 + np.interp(albedo, s_nodes, np.arange(s_nodes.size, dtype=float))
    return np.where(phase_g < g_nodes[-1], on_g, on_s)


def _path_dhi(d_vertices: NDArray[np.float64], position: NDArray[np.float64]) -> NDArray[np.float64]:
    """DHI at path positions (the family is multilinear, so linear along each leg), rows of ``d_vertices``."""
    rows = np.arange(d_vertices.shape[0])
    k = np.clip(np.floor(position).astype(np.int64), 0, max(d_vertices.shape[1] - 2, 0))
    upper = np.minimum(k + 1, d_vertices.shape[1] - 1)
    w = position - k
    return (1 - w) * d_vertices[rows, k] + w * d_vertices[rows, upper]


def _path_invert(d_vertices: NDArray[np.float64], target: NDArray[np.float64]) -> NDArray[np.float64]:
    """Path position where the piecewise-linear DHI equals ``target`` (extrapolated linearly beyond the ends:
    below 0 or above n_vertices - 1); NaN where a leg's DHI does not increase."""
    n_v = d_vertices.shape[1]
    rows = np.arange(d_vertices.shape[0])
    # the leg that holds the target: the number of inner vertices below it
    k = np.clip(np.sum(d_vertices[:, 1:-1] < target[:, None], axis=1), 0, n_v - 2)
    lo, hi = d_vertices[rows, k], d_vertices[rows, k + 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(hi > lo, k + (target - lo) / (hi - lo), np.nan)


def _diffuse_on_path(fam: TableFamily, model: BroadbandClearSky, rows, aod, zen, pw, pressure, ozone, ecc,
                     k_path: list[int], vertices: NDArray[np.float64]) -> NDArray[np.float64]:
    """Broadband DHI [W m^-2] of hours ``rows`` at their AOD and at each vertex of the closure path
    (:func:`closure_path`), shape (len(rows), n_vertices)."""
    k_aod = [a.name for a in fam.axes].index("aerosol_optical_depth")
    z_rows = np.asarray(zen[rows], dtype=float)
    out = np.zeros((rows.size, vertices.shape[0]))
    for j, vertex in enumerate(vertices):
        vals = np.zeros((rows.size, len(fam.axes)))
        for k, a in enumerate(fam.axes):
            vals[:, k] = a.values[0]
        vals[:, k_aod] = aod[rows]
        for k, v in zip(k_path, vertex, strict=True):
            vals[:, k] = v

        def sky_irradiance(atm, sub):
            # the tables' radiance integrated over the hemisphere: what the sky matrix's patches integrate
            return atm.horizontal_sky_irradiance(z_rows[sub])

        spectral = fam.interpolate(vals, sky_irradiance)
        out[:, j] = model.broadband_diffuse(spectral, zen[rows], pw[rows], pressure[rows], ozone[rows], ecc[rows],
                                            fam.wavelengths)
    return out


def _cloudy_aerosol(rec, rows, status, aod, src, aod_file, default, unix) -> None:
    """AOD of cloudy hours: the same day's clear hours (median), else the file's field, else the clear hours
    within 3 days (median of the 6 nearest), else the default."""
    clear = np.flatnonzero(np.isin(status, (CLEAR, CLEAR_OPEN)) & np.isfinite(aod))
    day = np.floor(unix / 86400.0 + rec.location.timezone_hours / 24.0).astype(np.int64)
    for i in rows:
        same = clear[day[clear] == day[i]]
        if same.size:
            aod[i], src[i] = float(np.median(aod[same])), "same day"
            continue
        if np.isfinite(aod_file[i]):
            aod[i], src[i] = aod_file[i], "file"
            continue
        if clear.size:
            near = clear[np.abs(unix[clear] - unix[i]) <= 3 * 86400.0]
            if near.size:
                aod[i], src[i] = float(np.median(aod[near[np.argsort(np.abs(unix[near] - unix[i]))[:6]]])), "nearby"
                continue
        aod[i], src[i] = default, "default"


def _warn(message: str) -> None:
    warnings.warn(message, RuntimeWarning, stacklevel=3)
