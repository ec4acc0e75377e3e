"""Reading EnergyPlus weather (EPW) files: location, time zone and the hourly fields a sky model needs.

Format: "Auxiliary Programs" manual of EnergyPlus, chapter "Weather Converter Program", section "EnergyPlus
Weather File (EPW) Data Dictionary". Eight header lines (LOCATION, DESIGN CONDITIONS, TYPICAL/EXTREME PERIODS,
GROUND TEMPERATURES, HOLIDAYS/DAYLIGHT SAVINGS, COMMENTS 1, COMMENTS 2, DATA PERIODS), then one line of 35
comma-separated fields per record. LOCATION holds city, state, country, source, WMO number, latitude
[deg, north +], longitude [deg, east +], time zone [h from GMT, standard time] and elevation [m].

Data fields used here (1-based field numbers of the dictionary): 1 year, 2 month, 3 day, 4 hour (1-24, the
hour *ending* at that local standard time), 5 minute, 7 dry bulb [deg C], 8 dew point [deg C],
14 global horizontal, 15 direct normal, 16 diffuse horizontal radiation [Wh m^-2, the hour's mean irradiance
in W m^-2]. Missing-value codes of the dictionary: 9999 for radiation, 99.9 for dew point (kept as NaN; the
sky models then use their default dew point). Only hourly files (1 record per hour) are supported.

Every error names the file and the line: a malformed header, a record with the wrong number of fields, a field
that is not a number, a date that does not exist, or a value outside the dictionary's range.
"""

from __future__ import annotations

import datetime as dt
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from .errors import FileFormatError

__all__ = ["N_FIELDS", "EPWLocation", "EPWData", "read_epw"]

#: Number of fields in an EPW data record.
N_FIELDS = 35
_HEADER_KEYS = (
    "LOCATION",
    "DESIGN CONDITIONS",
    "TYPICAL/EXTREME PERIODS",
    "GROUND TEMPERATURES",
    "HOLIDAYS/DAYLIGHT SAVINGS",
    "COMMENTS 1",
    "COMMENTS 2",
    "DATA PERIODS",
)
# (0-based field index, name, unit, low, high, missing code or None), ranges from the data dictionary
_FIELDS = (
    (6, "dry bulb temperature", "deg C", -70.0, 70.0, 99.9),
    (7, "dew point temperature", "deg C", -70.0, 70.0, 99.9),
    (13, "global horizontal radiation", "Wh m^-2", 0.0, 1500.0, 9999.0),
    (14, "direct normal radiation", "Wh m^-2", 0.0, 1500.0, 9999.0),
    (15, "diffuse horizontal radiation", "Wh m^-2", 0.0, 1500.0, 9999.0),
)


@dataclass(frozen=True)
class EPWLocation:
    """The LOCATION header of an EPW file (degrees as in the file; radians through the properties)."""

    city: str
    state: str
    country: str
    source: str
    wmo: str
    latitude_deg: float
    longitude_deg: float
    timezone_hours: float
    elevation: float

    @property
    def latitude(self) -> float:
        """Site latitude [rad], north positive."""
        return float(np.radians(self.latitude_deg))

    @property
    def longitude(self) -> float:
        """Site longitude [rad], east positive."""
        return float(np.radians(self.longitude_deg))

    @property
    def tzinfo(self) -> dt.timezone:
        """The file's fixed standard-time offset from UTC."""
        return dt.timezone(dt.timedelta(hours=self.timezone_hours))


@dataclass(frozen=True, eq=False)
class EPWData:
    """Hourly records of an EPW file (arrays of shape (n_hours,)).

    Attributes
    ----------
    path : Path
    location : EPWLocation
    year, month, day, hour : ndarray of int
        As in the file; ``hour`` 1-24 ends the record's hour (local standard time).
    dry_bulb, dew_point : ndarray
        [deg C]; NaN where the file marks the value missing.
    global_horizontal_irradiance, direct_normal_irradiance, diffuse_horizontal_irradiance : ndarray
        Hour means [W m^-2] (the file's Wh m^-2 per hour); NaN where missing.
    line_numbers : ndarray of int
        1-based line of each record in the file.
    """

    path: Path
    location: EPWLocation
    year: NDArray[np.int64]
    month: NDArray[np.int64]
    day: NDArray[np.int64]
    hour: NDArray[np.int64]
    dry_bulb: NDArray[np.float64]
    dew_point: NDArray[np.float64]
    global_horizontal_irradiance: NDArray[np.float64]
    direct_normal_irradiance: NDArray[np.float64]
    diffuse_horizontal_irradiance: NDArray[np.float64]
    line_numbers: NDArray[np.int64]

    def __len__(self) -> int:
        return int(self.hour.size)

    def times(self, *, offset_hours: float = -0.5):
        """Time stamps of the records, tz-aware ``pandas.DatetimeIndex`` in the file's standard time.

        ``offset_hours`` is added to the end of each record's hour: -0.5 (default) gives the middle of the
        hour the values average over, 0 the time printed in the file.
        """
        import pandas as pd

        base = pd.to_datetime({"year": self.year, "month": self.month, "day": self.day})
        stamps = base + pd.to_timedelta(self.hour + offset_hours, unit="h")
        return pd.DatetimeIndex(stamps).tz_localize(self.location.tzinfo)

    @property
    def day_of_year(self) -> NDArray[np.int64]:
        """Day of the year 1-366 of each record (from its year, month and day)."""
        import pandas as pd

        base = pd.to_datetime({"year": self.year, "month": self.month, "day": self.day})
        return np.asarray(base.dt.day_of_year, dtype=np.int64)


def _fail(path: Path, line: int, message: str) -> FileFormatError:
    return FileFormatError(f"{path}: line {line}: {message}")


def _number(path: Path, line: int, field: str, text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise _fail(path, line, f"{field} {text.strip()!r} is not a number") from None
    if not np.isfinite(value):
        raise _fail(path, line, f"{field} must be finite; got {text.strip()!r}")
    return value


def _parse_location(path: Path, text: str) -> EPWLocation:
    parts = [p.strip() for p in text.split(",")]
    if parts[0].upper() != "LOCATION":
        raise _fail(path, 1, f"an EPW file starts with a LOCATION line; found {text[:40]!r}")
    if len(parts) < 10:
        raise _fail(
            path, 1, f"LOCATION needs 10 fields (name, city, state, country, source, WMO, latitude, longitude, "
            f"time zone, elevation); found {len(parts)}"
        )
    lat = _number(path, 1, "latitude", parts[6])
    lon = _number(path, 1, "longitude", parts[7])
    tz = _number(path, 1, "time zone", parts[8])
    elev = _number(path, 1, "elevation", parts[9])
    for name, value, low, high, unit in (
        ("latitude", lat, -90.0, 90.0, "deg"),
        ("longitude", lon, -180.0, 180.0, "deg"),
        ("time zone", tz, -12.0, 14.0, "h"),
        ("elevation", elev, -1000.0, 9999.9, "m"),
    ):
        if not low <= value <= high:
            raise _fail(path, 1, f"{name} {value:g} {unit} is outside [{low:g}, {high:g}]")
    return EPWLocation(parts[1], parts[2], parts[3], parts[4], parts[5], lat, lon, tz, elev)


def read_epw(path: str | os.PathLike[str]) -> EPWData:
    """Read an hourly EPW weather file.

    Parameters
    ----------
    path : str or path-like
        The ``.epw`` file.

    Returns
    -------
    EPWData

    Raises
    ------
    FileFormatError
        The message names the file and line: missing or misplaced header lines, a LOCATION with bad values,
        more than one record per hour, a record without exactly 35 fields, a non-numeric field, an impossible
        date or hour, or a value out of the data dictionary's range.
    """
    p = Path(path)
    try:
        raw = p.read_bytes()
    except FileNotFoundError:
        raise FileFormatError(f"{p}: no such file") from None
    except IsADirectoryError:
        raise FileFormatError(f"{p}: is a folder, not an EPW file") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")  # older EPW files carry Latin-1 place names
    lines = text.splitlines()
    if len(lines) < len(_HEADER_KEYS) + 1:
        raise FileFormatError(
            f"{p}: has {len(lines)} lines; an EPW file has 8 header lines and then one line per hour"
        )
    for i, key in enumerate(_HEADER_KEYS):
        head = lines[i].split(",", 1)[0].strip().upper()
        if head != key:
            raise _fail(p, i + 1, f"header line {i + 1} should start with {key!r}; found {lines[i][:40]!r}")
    location = _parse_location(p, lines[0])
    periods = [s.strip() for s in lines[7].split(",")]
    if len(periods) > 2 and periods[2]:
        per_hour = _number(p, 8, "records per hour", periods[2])
        if per_hour != 1:
            raise _fail(p, 8, f"only hourly EPW files are supported (1 record per hour); this one has {per_hour:g}")
    first = len(_HEADER_KEYS)
    body = [(n + 1, line) for n, line in enumerate(lines[first:], start=first) if line.strip()]
    if not body:
        raise FileFormatError(f"{p}: has no data records after the 8 header lines")
    rows = []
    for line_no, line in body:
        fields = line.split(",")
        if len(fields) != N_FIELDS:
            raise _fail(p, line_no, f"a data record has {N_FIELDS} comma-separated fields; found {len(fields)}")
        rows.append(fields)
    n = len(rows)
    ints = np.empty((n, 4), dtype=np.int64)
    values = np.empty((n, len(_FIELDS)))
    names = ("year", "month", "day", "hour")
    for r, (fields, (line_no, _)) in enumerate(zip(rows, body, strict=True)):
        for k in range(4):
            v = _number(p, line_no, names[k], fields[k])
            if not v.is_integer():
                raise _fail(p, line_no, f"{names[k]} must be a whole number; got {fields[k].strip()!r}")
            ints[r, k] = int(v)
        for k, (idx, name, unit, low, high, missing) in enumerate(_FIELDS):
            v = _number(p, line_no, name, fields[idx])
            if missing is not None and v == missing:
                v = np.nan
            elif not low <= v <= high:
                raise _fail(p, line_no, f"{name} {v:g} {unit} is outside the EPW range [{low:g}, {high:g}]")
            values[r, k] = v
    line_numbers = np.array([b[0] for b in body], dtype=np.int64)
    year, month, day, hour = (ints[:, k] for k in range(4))
    _check_dates(p, year, month, day, hour, line_numbers)
    return EPWData(
        path=p,
        location=location,
        year=year,
        month=month,
        day=day,
        hour=hour,
        dry_bulb=values[:, 0],
        dew_point=values[:, 1],
        global_horizontal_irradiance=values[:, 2],
        direct_normal_irradiance=values[:, 3],
        diffuse_horizontal_irradiance=values[:, 4],
        line_numbers=line_numbers,
    )


def _check_dates(path: Path, year, month, day, hour, line_numbers) -> None:
    bad = (month < 1) | (month > 12)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise _fail(path, int(line_numbers[i]), f"month {month[i]} is outside 1-12")
    bad = (hour < 1) | (hour > 24)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise _fail(path, int(line_numbers[i]), f"hour {hour[i]} is outside 1-24 (EPW hours end at 1:00-24:00)")
    leap = ((year % 4 == 0) & (year % 100 != 0)) | (year % 400 == 0)
    month_days = np.array([31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31])[month - 1] + (leap & (month == 2))
    bad = (day < 1) | (day > month_days)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise _fail(
            path, int(line_numbers[i]), f"{year[i]:04d}-{month[i]:02d}-{day[i]:02d} is not a date"
        )
