"""Position of the sun in the sky for a place and a time.

Two methods:

``"spa"`` (default)
    The NREL Solar Position Algorithm (Reda & Andreas 2004, corrigendum 2007), in numpy in
    :mod:`skyscatter.sun.spa` (equal to pvlib's ``pvlib.spa.solar_position`` to 1e-8 deg in the tests); about
    0.0003 deg uncertainty over -2000..6000. By default the zenith is the *apparent* topocentric zenith, i.e.
    corrected for atmospheric refraction with the site's pressure and temperature (``apparent=False`` gives the
    geometric one); near the horizon they differ by about 0.5 deg. Delta T (TT - UT1) defaults to Espenak &
    Meeus's polynomial for the date (:func:`skyscatter.sun.spa.delta_t_espenak_meeus`, pvlib's rule too).

``"preetham1999"``
    The approximation of Preetham, Shirley & Smits (1999), Appendix A.6: solar time from the local standard
    time with a two-term equation of time, declination delta = 0.4093 sin(2 pi (J - 81) / 368), and

        theta_s = pi/2 - arcsin(sin l sin delta - cos l cos delta cos(pi t / 12))
        phi_s   = atan2(-cos delta sin(pi t / 12), -(cos l sin delta + sin l cos delta cos(pi t / 12)))

    with phi_s measured west of south; it is converted here to skyscatter's azimuth from north towards east
    (azimuth = pi + phi_s). The denominator printed in the paper, cos l sin delta - sin l cos delta
    cos(pi t / 12), has the wrong sign on its first term (it puts the summer morning sun in the south-east
    instead of the north-east; taken literally it is off by 17 deg on average and up to 38 deg in the
    comparison below); the form above is that of the authors' own implementation (Smits 1999, ``RiSunSky.C``,
    ``InitSunThetaPhi``) and equals the standard spherical-astronomy result. The paper's longitudes and
    standard meridian are west-positive; here both are east-positive, so the longitude term reads
    12 (L - SM) / pi. The standard meridian SM is the datetime's UTC offset times 15 deg; with it the solar
    time reduces to UTC + L / 15 deg + equation of time, so daylight-saving offsets are handled correctly and
    only the day of the year J (taken from the local date) depends on the offset. No refraction is modelled.
    Against SPA, hourly over 2024 at 40 N, 105 W with the sun above the horizon, the angle between the two sun
    directions is 0.27 deg mean and 0.79 deg max (SPA geometric), 0.30 deg mean and 1.19 deg max (SPA
    apparent, i.e. including refraction, which A.6 ignores); see tests/test_sun_position.py.

Times must be timezone-aware: a naive time is ambiguous (local or UTC?) and is refused.

References: [RedaAndreas2004], [Preetham1999].
"""

from __future__ import annotations

import datetime as dt
import sys
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError

__all__ = ["SunPosition", "sun_position", "sun_position_unix"]

_METHODS = ("spa", "preetham1999")
_NAIVE_HINT = (
    "attach a time zone, e.g. datetime(2024, 6, 21, 12, 0, tzinfo=timezone.utc) or "
    "tzinfo=zoneinfo.ZoneInfo('Europe/Paris'); for pandas use .tz_localize(...)"
)


class SunPosition(NamedTuple):
    """Sun direction as zenith and azimuth angles [rad].

    ``zenith`` is measured from the local vertical; ``azimuth`` from north towards east, in [0, 2 pi).
    Floats for a single time, arrays (shape of the input times) otherwise.
    """

    zenith: Any
    azimuth: Any

    @property
    def elevation(self) -> Any:
        """Elevation above the horizon, pi/2 - zenith [rad]."""
        return np.pi / 2 - self.zenith


def _is_pandas(obj: object) -> bool:
    return type(obj).__module__.split(".")[0] == "pandas" and "pandas" in sys.modules


def _times(when: object) -> tuple[NDArray[np.float64], NDArray[np.float64], tuple[int, ...] | None]:
    """(unix seconds, UTC offsets [s], output shape or None for a scalar) of aware time(s)."""
    if isinstance(when, dt.datetime):
        offset = when.utcoffset()
        if when.tzinfo is None or offset is None:
            raise InvalidParameterError(
                f"time {when.isoformat()} has no time zone (naive datetime): {_NAIVE_HINT}"
            )
        return np.array([when.timestamp()]), np.array([offset.total_seconds()]), None
    if _is_pandas(when) and hasattr(when, "dtype"):
        import pandas as pd

        try:
            index = pd.DatetimeIndex(when)
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(f"cannot read the times as a pandas DatetimeIndex: {exc}") from None
        if index.tz is None:
            raise InvalidParameterError(f"the DatetimeIndex has no time zone (naive): {_NAIVE_HINT}")
        if index.hasnans:
            raise InvalidParameterError("the times contain NaT (missing values)")
        utc_naive = index.tz_convert("UTC").tz_localize(None)
        second = pd.Timedelta(1, "s")
        unix = np.asarray((utc_naive - pd.Timestamp(0)) / second, dtype=float)
        offset = np.asarray((index.tz_localize(None) - utc_naive) / second, dtype=float)
        return unix, offset, (len(index),)
    if isinstance(when, (str, bytes)):
        raise InvalidParameterError(
            f"time {when!r} is text: parse it first, e.g. datetime.fromisoformat('2024-06-21T12:00+02:00')"
        )
    arr = np.asarray(when, dtype=object) if not isinstance(when, np.ndarray) else when
    if np.issubdtype(arr.dtype, np.datetime64):
        raise InvalidParameterError(f"numpy datetime64 values carry no time zone: {_NAIVE_HINT}")
    if arr.dtype != object or arr.ndim == 0:
        raise InvalidParameterError(
            "time must be a timezone-aware datetime, a pandas DatetimeIndex or an array/list of aware "
            "datetimes; "
            f"got {type(when).__name__}"
        )
    flat = arr.reshape(-1)
    unix = np.empty(flat.size)
    offset = np.empty(flat.size)
    for i, item in enumerate(flat):  # a list of Python datetimes: one call per element is unavoidable
        if not isinstance(item, dt.datetime):
            raise InvalidParameterError(
                f"time element {i} is {type(item).__name__}, expected an aware datetime"
            )
        off = item.utcoffset()
        if off is None:
            raise InvalidParameterError(f"time element {i} ({item.isoformat()}) is naive: {_NAIVE_HINT}")
        unix[i] = item.timestamp()
        offset[i] = off.total_seconds()
    return unix, offset, arr.shape


def _site(latitude: float, longitude: float) -> tuple[float, float]:
    try:
        lat, lon = float(latitude), float(longitude)
    except (TypeError, ValueError):
        raise InvalidParameterError("latitude and longitude must be numbers in radians") from None
    if not (np.isfinite(lat) and -np.pi / 2 <= lat <= np.pi / 2):
        raise InvalidParameterError(
            f"latitude must be in [-pi/2, pi/2] rad (north positive); got {latitude!r} rad"
            " (convert degrees with math.radians)"
        )
    if not (np.isfinite(lon) and -np.pi <= lon <= np.pi):
        raise InvalidParameterError(
            f"longitude must be in [-pi, pi] rad (east positive); got {longitude!r} rad"
            " (convert degrees with math.radians)"
        )
    return lat, lon


def _utc_year_month(unix: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    months = np.floor(unix).astype("int64").astype("datetime64[s]").astype("datetime64[M]").astype(np.int64)
    return (1970 + months // 12).astype(float), (months % 12 + 1).astype(float)


def _spa(unix, lat, lon, *, altitude, pressure, temperature, delta_t, apparent):
    from .spa import delta_t_espenak_meeus, spa_solar_position

    if delta_t is None:
        delta_t = delta_t_espenak_meeus(*_utc_year_month(unix))
    apparent_zenith, zenith, azimuth = spa_solar_position(
        unix, np.degrees(lat), np.degrees(lon), elevation=altitude, pressure=pressure / 100.0,
        temperature=temperature, delta_t=delta_t, refraction=0.5667,
    )
    return np.radians(apparent_zenith if apparent else zenith), np.radians(azimuth)


def _preetham1999(unix, offset, lat, lon):
    local = unix + offset
    days = np.floor(local / 86400.0)
    day_dates = days.astype("int64").astype("datetime64[D]")
    year_start = day_dates.astype("datetime64[Y]").astype("datetime64[D]")
    julian = (day_dates - year_start).astype(float) + 1.0  # J: day of the year, 1..366
    standard_time = (local - days * 86400.0) / 3600.0  # t_s [h]
    standard_meridian = offset / 3600.0 * (np.pi / 12.0)  # SM [rad], east positive
    solar_time = (
        standard_time
        + 0.170 * np.sin(4.0 * np.pi * (julian - 80.0) / 373.0)
        - 0.129 * np.sin(2.0 * np.pi * (julian - 8.0) / 355.0)
        + 12.0 * (lon - standard_meridian) / np.pi
    )
    decl = 0.4093 * np.sin(2.0 * np.pi * (julian - 81.0) / 368.0)
    hour = np.pi * solar_time / 12.0
    sin_l, cos_l = np.sin(lat), np.cos(lat)
    sin_d, cos_d = np.sin(decl), np.cos(decl)
    sin_elev = sin_l * sin_d - cos_l * cos_d * np.cos(hour)
    zenith = np.pi / 2 - np.arcsin(np.clip(sin_elev, -1.0, 1.0))
    west_of_south = np.arctan2(-cos_d * np.sin(hour), -(cos_l * sin_d + sin_l * cos_d * np.cos(hour)))
    return zenith, np.mod(np.pi + west_of_south, 2.0 * np.pi)


def sun_position(
    latitude: float,
    longitude: float,
    when: object,
    *,
    method: str = "spa",
    altitude: float = 0.0,
    pressure: float = 101325.0,
    temperature: float = 12.0,
    delta_t: float | None = None,
    apparent: bool = True,
) -> SunPosition:
    """Sun zenith and azimuth [rad] seen from a site at given time(s).

    Parameters
    ----------
    latitude : float
        Site latitude [rad], north positive, in [-pi/2, pi/2].
    longitude : float
        Site longitude [rad], east positive, in [-pi, pi].
    when : datetime.datetime, pandas.Timestamp, pandas.DatetimeIndex or array_like of datetime
        Timezone-aware time(s). Naive times are refused.
    method : {"spa", "preetham1999"}
        NREL SPA (:mod:`skyscatter.sun.spa`), or the approximation of Preetham et al. (1999) A.6 (module docstring).
    altitude : float
        Site height above sea level [m] (SPA only).
    pressure : float
        Mean air pressure at the site [Pa], for the refraction correction (SPA only).
    temperature : float
        Mean air temperature at the site [deg C], for the refraction correction (SPA only).
    delta_t : float, optional
        TT - UT1 [s] (SPA only); default: Espenak & Meeus's polynomial for the date (UTC year and month).
    apparent : bool
        SPA only: return the refraction-corrected (apparent) zenith (default) or the geometric one.

    Returns
    -------
    SunPosition
        ``zenith`` in [0, pi] and ``azimuth`` in [0, 2 pi) from north towards east [rad]; floats for a
        single time, arrays shaped like ``when`` otherwise. ``.elevation`` = pi/2 - zenith.

    Raises
    ------
    InvalidParameterError
        Naive or unreadable times, a site outside the allowed ranges, or an unknown method.
    """
    unix, offset, shape = _times(when)
    return _position(latitude, longitude, unix, offset, shape, method=method, altitude=altitude,
                     pressure=pressure, temperature=temperature, delta_t=delta_t, apparent=apparent)


def sun_position_unix(
    latitude: float,
    longitude: float,
    unix_seconds: ArrayLike,
    *,
    utc_offset: ArrayLike = 0.0,
    method: str = "spa",
    altitude: float = 0.0,
    pressure: float = 101325.0,
    temperature: float = 12.0,
    delta_t: float | None = None,
    apparent: bool = True,
) -> SunPosition:
    """:func:`sun_position` for instants given as Unix time: seconds since 1970-01-01T00:00 UTC.

    For callers that hold many times as numbers (an EPW file's records): no datetime objects and no pandas.
    ``utc_offset`` [s] (local standard time minus UTC, broadcast against the times) is used by the
    ``"preetham1999"`` method only (its day of the year is the local one). Other arguments and the result as in
    :func:`sun_position`; the result has the shape of ``unix_seconds`` (floats for a scalar).
    """
    unix = np.asarray(unix_seconds, dtype=float)
    if not np.all(np.isfinite(unix)):
        raise InvalidParameterError("unix_seconds must be finite numbers of seconds since 1970-01-01 UTC")
    offset = np.broadcast_to(np.asarray(utc_offset, dtype=float), unix.shape).reshape(-1)
    if not np.all(np.isfinite(offset)):
        raise InvalidParameterError("utc_offset must be finite seconds")
    return _position(latitude, longitude, unix.reshape(-1), offset, unix.shape if unix.ndim else None,
                     method=method, altitude=altitude, pressure=pressure, temperature=temperature,
                     delta_t=delta_t, apparent=apparent)


def _position(latitude, longitude, unix, offset, shape, *, method, altitude, pressure, temperature, delta_t,
              apparent) -> SunPosition:
    if method not in _METHODS:
        raise InvalidParameterError(
            f"unknown sun-position method {method!r}; choose one of {', '.join(_METHODS)}"
        )
    lat, lon = _site(latitude, longitude)
    if method == "spa":
        if not np.isfinite(altitude):
            raise InvalidParameterError(f"altitude must be a finite height in m; got {altitude!r}")
        if not (np.isfinite(pressure) and pressure > 0):
            raise InvalidParameterError(f"pressure must be a positive pressure in Pa; got {pressure!r}")
        if not np.isfinite(temperature):
            raise InvalidParameterError(f"temperature must be finite, in deg C; got {temperature!r}")
        if delta_t is not None and not np.isfinite(delta_t):
            raise InvalidParameterError(f"delta_t must be finite seconds; got {delta_t!r}")
        if unix.size == 0:
            zenith, azimuth = np.empty(0), np.empty(0)
        else:
            zenith, azimuth = _spa(unix, lat, lon, altitude=float(altitude), pressure=float(pressure),
                                   temperature=float(temperature), delta_t=delta_t, apparent=apparent)
    else:
        zenith, azimuth = _preetham1999(unix, offset, lat, lon)
    azimuth = np.mod(azimuth, 2.0 * np.pi)
    if shape is None:
        return SunPosition(float(zenith[0]), float(azimuth[0]))
    return SunPosition(
        np.asarray(zenith, dtype=float).reshape(shape), np.asarray(azimuth, dtype=float).reshape(shape)
    )
