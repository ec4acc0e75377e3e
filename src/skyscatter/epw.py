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
sky models then use their default dew point).

Optional fields, read leniently (a missing-value code, an empty or non-numeric cell or a value outside the range
below becomes NaN, never an error, since the sky matrix of the luminance models does not need them; the spectral
sky's retrieval, :mod:`skyscatter.fit.weather`, reports per hour what it used): 9 relative humidity [%, 0-110,
missing 999], 10 station pressure [Pa, 31000-120000, missing 999999], 23 total and 24 opaque sky cover [tenths,
0-10, missing 99], 29 precipitable water [mm, 0-100, missing 999], 30 aerosol optical depth [-, 0-0.998, missing
0.999; the dictionary says "thousandths" but files carry the optical depth itself, e.g. 0.116, TMY3's broadband
value], 33 albedo [-, 0-1, missing 999].

Time steps: the DATA PERIODS header line declares the number of records per hour N (field 2; 1, 2, 3, 4, 5, 6,
10, 12, 15, 20, 30 or 60, a divisor of 60). Every hour of the file must then hold exactly N records, one after
the other with increasing minutes, and no hour may appear twice; the k-th record (k = 0 .. N-1) of the hour
ending at ``hour`` covers ``[hour - 1 + k / N, hour - 1 + (k + 1) / N]`` h local standard time (EnergyPlus
orders sub-hourly records within the hour that way). Radiation fields of a sub-hourly record are means over
its own interval. :meth:`EPWData.hourly` averages a sub-hourly file to hours.

Every error names the file and the line: a malformed header, a record with the wrong number of fields, a field
that is not a number, a date that does not exist, a year outside the range the time stamps support, a
repeated time, an hour with more or fewer records than declared, or a value outside the dictionary's range.
"""

from __future__ import annotations

import datetime as dt
import os
import stat
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from .conventions import MAX_EXTRATERRESTRIAL_IRRADIANCE
from .errors import FileFormatError

__all__ = ["N_FIELDS", "EPWLocation", "EPWData", "EPWWarning", "read_epw"]

#: Number of fields in an EPW data record.
N_FIELDS = 35
#: Years the time stamps can hold (pandas nanosecond timestamps, used for the sun position).
YEAR_RANGE = (1678, 2261)
#: Largest EPW file read [bytes]; a year of one-minute records is about 80 MB.
MAX_FILE_BYTES = 256 * 2**20
#: Bytes read first to tell an EPW file (it starts with its LOCATION line) from anything else.
SNIFF_BYTES = 4096
#: Largest difference [h] between the time zone and longitude / 15 deg before a warning: civil time zones stray
#: from their meridian by up to about 3 h (western China, Spain's 1 h over west of Greenwich); beyond that the zone
#: is most likely of another place, or of the wrong sign, and every sun position of the file is off.
TIME_ZONE_TOLERANCE = 3.0
#: Diffuse horizontal irradiance may exceed global horizontal by this much [W m^-2, plus 5 %] (rounding and
#: the instruments of measured files); more cannot be: global = diffuse + direct normal x cos(zenith).
DIFFUSE_EXCESS = 5.0
#: Record counts per hour a DATA PERIODS line may declare (divisors of 60 minutes).
RECORDS_PER_HOUR = (1, 2, 3, 4, 5, 6, 10, 12, 15, 20, 30, 60)
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
# (0-based field index, attribute, low, high, missing code): optional fields, read leniently (NaN when unusable)
_OPTIONAL_FIELDS = (
    (8, "relative_humidity", 0.0, 110.0, 999.0),
    (9, "pressure", 31_000.0, 120_000.0, 999_999.0),
    (22, "total_sky_cover", 0.0, 10.0, 99.0),
    (23, "opaque_sky_cover", 0.0, 10.0, 99.0),
    (28, "precipitable_water", 0.0, 100.0, 999.0),
    (29, "aerosol_optical_depth", 0.0, 0.998, 0.999),
    (32, "albedo", 0.0, 1.0, 999.0),
)
# (0-based field index, name, unit, low, high, missing code or None), ranges from the data dictionary
_FIELDS = (
    (6, "dry bulb temperature", "deg C", -70.0, 70.0, 99.9),
    (7, "dew point temperature", "deg C", -70.0, 70.0, 99.9),
    (13, "global horizontal radiation", "Wh m^-2", 0.0, 1500.0, 9999.0),
    (14, "direct normal radiation", "Wh m^-2", 0.0, 1500.0, 9999.0),
    (15, "diffuse horizontal radiation", "Wh m^-2", 0.0, 1500.0, 9999.0),
)


class EPWWarning(UserWarning):
    """An EPW file whose data look wrong but can be used (a time zone far from the longitude's, light at night)."""


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
    """Records of an EPW file (arrays of shape (n_records,)).

    Attributes
    ----------
    path : Path
    location : EPWLocation
    year, month, day, hour : ndarray of int
        As in the file; ``hour`` 1-24 ends the record's hour (local standard time).
    records_per_hour : int
        N, from the DATA PERIODS header (1 for an hourly file).
    step : ndarray of int
        Position 0 .. N-1 of each record within its hour (all 0 in an hourly file).
    dry_bulb, dew_point : ndarray
        [deg C]; NaN where the file marks the value missing.
    global_horizontal_irradiance, direct_normal_irradiance, diffuse_horizontal_irradiance : ndarray
        Hour means [W m^-2] (the file's Wh m^-2 per hour); NaN where missing.
    line_numbers : ndarray of int
        1-based line of each record in the file.
    relative_humidity [%], pressure [Pa], total_sky_cover, opaque_sky_cover [tenths], precipitable_water [mm],
    aerosol_optical_depth [-], albedo [-] : ndarray or None
        The optional fields (NaN where missing or unusable; None when not read, e.g. a record built by hand).
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
    records_per_hour: int = 1
    step: NDArray[np.int64] | None = None
    relative_humidity: NDArray[np.float64] | None = None
    pressure: NDArray[np.float64] | None = None
    total_sky_cover: NDArray[np.float64] | None = None
    opaque_sky_cover: NDArray[np.float64] | None = None
    precipitable_water: NDArray[np.float64] | None = None
    aerosol_optical_depth: NDArray[np.float64] | None = None
    albedo: NDArray[np.float64] | None = None

    def __len__(self) -> int:
        return int(self.hour.size)

    def _step(self) -> NDArray[np.int64]:
        return np.zeros_like(self.hour) if self.step is None else self.step

    def _local_day_and_hours(self, offset_hours: float | None) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        """(local date as days since 1970-01-01, hours after that midnight) of each record's time stamp.

        ``offset_hours`` is added to the end of each record's interval (``hour - 1 + (k + 1) / N`` h): None, half
        a record (-0.5 h in an hourly file), gives the middle of the interval the values average over.
        """
        n = self.records_per_hour
        offset = -0.5 / n if offset_hours is None else float(offset_hours)
        months = (self.year - 1970) * 12 + (self.month - 1)
        days = months.astype("datetime64[M]").astype("datetime64[D]").astype(np.int64) + (self.day - 1)
        return days, self.hour - 1 + (self._step() + 1) / n + offset

    def unix_times(self, *, offset_hours: float | None = None) -> NDArray[np.float64]:
        """Time stamps of the records as Unix time [s since 1970-01-01T00:00 UTC] (float64).

        The same instants as :meth:`times` (``offset_hours`` as there), without pandas: what the sun position
        of a sky matrix needs.
        """
        days, hours = self._local_day_and_hours(offset_hours)
        return days * 86400.0 + hours * 3600.0 - self.location.timezone_hours * 3600.0

    def times(self, *, offset_hours: float | None = None):
        """Time stamps of the records, tz-aware ``pandas.DatetimeIndex`` in the file's standard time.

        ``offset_hours`` is added to the end of each record's interval (``hour - 1 + (k + 1) / N`` h): the
        default, half a record (-0.5 h in an hourly file), gives the middle of the interval the values average
        over; 0 gives the end of the interval (the time printed in an hourly file).
        """
        import pandas as pd

        days, hours = self._local_day_and_hours(offset_hours)
        local_ns = days * 86_400_000_000_000 + np.round(hours * 3.6e12).astype(np.int64)
        return pd.DatetimeIndex(local_ns.astype("datetime64[ns]")).tz_localize(self.location.tzinfo)

    def hourly(self) -> EPWData:
        """The records averaged to hours (a sub-hourly file); an hourly file is returned as it is.

        Temperatures and irradiances are the means of the hour's N records (NaN if any of them is missing);
        each hour keeps the line number of its first record.
        """
        n = self.records_per_hour
        if n == 1:
            return self

        def mean(a):
            return a.reshape(-1, n).mean(axis=1)

        first = slice(0, None, n)
        optional = {name: (None if getattr(self, name) is None else mean(getattr(self, name)))
                    for _, name, _, _, _ in _OPTIONAL_FIELDS}
        return EPWData(
            path=self.path, location=self.location, year=self.year[first], month=self.month[first],
            day=self.day[first], hour=self.hour[first], dry_bulb=mean(self.dry_bulb),
            dew_point=mean(self.dew_point), global_horizontal_irradiance=mean(self.global_horizontal_irradiance),
            direct_normal_irradiance=mean(self.direct_normal_irradiance),
            diffuse_horizontal_irradiance=mean(self.diffuse_horizontal_irradiance),
            line_numbers=self.line_numbers[first], records_per_hour=1, step=None, **optional,
        )

    @property
    def day_of_year(self) -> NDArray[np.int64]:
        """Day of the year 1-366 of each record (from its year, month and day)."""
        days = self._local_day_and_hours(None)[0].astype("datetime64[D]")
        return (days - days.astype("datetime64[Y]").astype("datetime64[D]")).astype(np.int64) + 1


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


def _read_bounded(p: Path) -> bytes:
    """The bytes of ``p`` if it can be an EPW file: a regular file of at most MAX_FILE_BYTES that starts with its
    LOCATION line (checked on the first bytes, so that a wrong file, ``/dev/zero`` included, is refused at once)."""
    try:
        st = p.stat()
    except FileNotFoundError:
        raise FileFormatError(f"{p}: no such file") from None
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot read: {exc.strerror or exc}") from None

    if stat.S_ISDIR(st.st_mode):
        raise FileFormatError(f"{p}: is a folder, not an EPW file")
    if not stat.S_ISREG(st.st_mode):
        raise FileFormatError(f"{p}: is not a regular file (a device, a pipe or a socket); give an .epw file")
    if st.st_size > MAX_FILE_BYTES:
        raise FileFormatError(f"{p}: {st.st_size / 2**20:.0f} MiB is larger than any EPW file (at most "
                              f"{MAX_FILE_BYTES // 2**20} MiB: a year of one-minute records is about 80 MiB)")
    try:
        with open(p, "rb") as fh:
            head = fh.read(SNIFF_BYTES)
            first = head.lstrip(b"\xef\xbb\xbf").lstrip()[:8].upper()
            if first != b"LOCATION":
                shown = head[:40].decode("latin-1").split("\n", 1)[0]
                raise FileFormatError(f"{p}: line 1: an EPW file starts with a LOCATION line; found {shown!r} "
                                      "(not an EPW file)")
            return head + fh.read(MAX_FILE_BYTES + 1 - len(head))
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot read: {exc.strerror or exc}") from None


def _check_time_zone(p: Path, location: EPWLocation) -> None:
    """Warn when the time zone is far from the longitude's (every sun position of the file would be off)."""
    expected = location.longitude_deg / 15.0
    off = abs(location.timezone_hours - expected)
    if off > TIME_ZONE_TOLERANCE:
        import warnings

        warnings.warn(f"{p}: line 1: time zone UTC{location.timezone_hours:+g} h is {off:.1f} h "
                      f"from the longitude's ({location.longitude_deg:g} deg: about UTC{expected:+.1f} h); if it is "
                      "wrong (a sign, another place), every sun position computed from this file is off by as much",
                      EPWWarning, stacklevel=3)


def _check_irradiance(p: Path, ghi, dni, dhi, line_numbers) -> None:
    """Refuse, with the line, a direct normal irradiance above the extraterrestrial value and a diffuse horizontal
    irradiance above the global horizontal one (beyond rounding)."""
    with np.errstate(invalid="ignore"):
        bad = dni > MAX_EXTRATERRESTRIAL_IRRADIANCE
        if np.any(bad):
            i = int(np.argmax(bad))
            raise _fail(p, int(line_numbers[i]), f"direct normal radiation {dni[i]:g} W m^-2 exceeds the "
                        f"extraterrestrial value ({MAX_EXTRATERRESTRIAL_IRRADIANCE:.1f} W m^-2 at perihelion): "
                        "no sunlight at the ground can be brighter")
        bad = dhi > ghi * 1.05 + DIFFUSE_EXCESS  # NaN (missing) compares False
        if np.any(bad):
            i = int(np.argmax(bad))
            raise _fail(p, int(line_numbers[i]), f"diffuse horizontal radiation {dhi[i]:g} W m^-2 exceeds the "
                        f"global horizontal radiation {ghi[i]:g} W m^-2 (global = diffuse + direct x cos(zenith))")


def read_epw(path: str | os.PathLike[str]) -> EPWData:
    """Read an EPW weather file (hourly or sub-hourly, as its DATA PERIODS line declares).

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
        The message names the file and line: not a regular file, larger than :data:`MAX_FILE_BYTES`, not
        starting with a LOCATION line (checked on the first bytes), missing or misplaced header lines, a
        LOCATION with bad values, more than one record per hour, a record without exactly 35 fields, a
        non-numeric field, an impossible date or hour, a value out of the data dictionary's range, a direct
        normal irradiance above the extraterrestrial value, a diffuse horizontal irradiance above the global.

    Warns
    -----
    EPWWarning
        The time zone is more than :data:`TIME_ZONE_TOLERANCE` hours from the longitude's (``longitude / 15``).
    """
    p = Path(path)
    raw = _read_bounded(p)
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
    _check_time_zone(p, location)
    periods = [s.strip() for s in lines[7].split(",")]
    per_hour = 1
    if len(periods) > 2 and periods[2]:
        value = _number(p, 8, "records per hour", periods[2])
        if value not in RECORDS_PER_HOUR:
            raise _fail(p, 8, f"DATA PERIODS declares {value:g} records per hour; EPW allows "
                        + ", ".join(map(str, RECORDS_PER_HOUR)) + " (divisors of 60 minutes)")
        per_hour = int(value)
    first = len(_HEADER_KEYS)
    body = [(n + 1, line) for n, line in enumerate(lines[first:], start=first) if line.strip()]
    if not body:
        raise FileFormatError(f"{p}: has no data records after the 8 header lines")
    texts = [b[1] for b in body]
    if any(t.count(",") != N_FIELDS - 1 for t in texts):
        line_no, line = next(b for b in body if b[1].count(",") != N_FIELDS - 1)
        raise _fail(p, line_no, f"a data record has {N_FIELDS} comma-separated fields; found {line.count(',') + 1}")
    line_numbers = np.array([b[0] for b in body], dtype=np.int64)
    parsed = _parse_fast(texts)
    if parsed is None:  # something is wrong: the field-by-field reader finds it and names the line
        parsed = _parse_checked(p, [t.split(",") for t in texts], line_numbers)
    ints, values = parsed
    year, month, day, hour, minute = (ints[:, k] for k in range(5))
    _check_dates(p, year, month, day, hour, line_numbers)
    step = _check_steps(p, year, month, day, hour, minute, line_numbers, per_hour)
    _check_irradiance(p, values[:, 2], values[:, 3], values[:, 4], line_numbers)
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
        records_per_hour=per_hour,
        step=step,
        **_optional_columns(texts),
    )


_INT_COLUMNS = (0, 1, 2, 3, 4)  # year, month, day, hour, minute


def _optional_columns(texts: list[str]) -> dict[str, NDArray[np.float64]]:
    """The optional fields of every record, NaN where a cell is missing, not a number or out of range."""
    cols = tuple(f[0] for f in _OPTIONAL_FIELDS)
    try:
        raw = np.loadtxt(texts, delimiter=",", usecols=cols, dtype=float, comments=None, ndmin=2)
    except ValueError:  # some cell is not a number: cell by cell
        raw = np.full((len(texts), len(cols)), np.nan)
        for r, line in enumerate(texts):
            cells = line.split(",")
            for k, c in enumerate(cols):
                try:
                    raw[r, k] = float(cells[c])
                except ValueError:
                    pass
    out = {}
    for k, (_, name, low, high, missing) in enumerate(_OPTIONAL_FIELDS):
        col = raw[:, k].copy()
        col[(col == missing) | ~np.isfinite(col) | (col < low) | (col > high)] = np.nan
        out[name] = col
    return out
_VALUE_COLUMNS = tuple(f[0] for f in _FIELDS)


def _parse_fast(texts: list[str]):
    """(ints (n, 5), values (n, len(_FIELDS))) converted in bulk, or None if any field needs a closer look.

    Every record has N_FIELDS fields (checked before); numpy's C reader converts the columns needed.
    """
    try:
        raw = np.loadtxt(texts, delimiter=",", usecols=_INT_COLUMNS + _VALUE_COLUMNS, dtype=float, comments=None,
                         ndmin=2)
    except ValueError:
        return None
    ints_f, values = raw[:, :5], np.ascontiguousarray(raw[:, 5:])
    if not (np.all(np.isfinite(raw)) and np.all(ints_f == np.round(ints_f))
            and np.all((ints_f[:, 0] >= YEAR_RANGE[0]) & (ints_f[:, 0] <= YEAR_RANGE[1]))
            and np.all((ints_f[:, 4] >= 0) & (ints_f[:, 4] <= 60))):
        return None
    for k, (_, _, _, low, high, missing) in enumerate(_FIELDS):
        col = values[:, k]
        is_missing = col == missing if missing is not None else np.zeros(col.shape, dtype=bool)
        if np.any(~is_missing & ((col < low) | (col > high))):
            return None
        col[is_missing] = np.nan
    return ints_f.astype(np.int64), values


def _parse_checked(p: Path, rows: list[list[str]], line_numbers) -> tuple[NDArray, NDArray]:
    """Field by field, raising :class:`FileFormatError` at the first bad field with its line."""
    n = len(rows)
    ints = np.empty((n, 5), dtype=np.int64)
    values = np.empty((n, len(_FIELDS)))
    names = ("year", "month", "day", "hour", "minute")
    for r, (fields, line_no) in enumerate(zip(rows, line_numbers.tolist(), strict=True)):
        for k in range(5):
            v = _number(p, line_no, names[k], fields[k])
            if not v.is_integer():
                raise _fail(p, line_no, f"{names[k]} must be a whole number; got {fields[k].strip()!r}")
            if k == 0 and not YEAR_RANGE[0] <= v <= YEAR_RANGE[1]:
                raise _fail(p, line_no, f"year {fields[k].strip()} is outside {YEAR_RANGE[0]}-{YEAR_RANGE[1]}, "
                            "the range of the time stamps used for the sun position")
            if k == 4 and not 0 <= v <= 60:
                raise _fail(p, line_no, f"minute {fields[k].strip()} is outside 0-60")
            ints[r, k] = int(v)
        for k, (idx, name, unit, low, high, missing) in enumerate(_FIELDS):
            v = _number(p, line_no, name, fields[idx])
            if missing is not None and v == missing:
                v = np.nan
            elif not low <= v <= high:
                raise _fail(p, line_no, f"{name} {v:g} {unit} is outside the EPW range [{low:g}, {high:g}]")
            values[r, k] = v
    return ints, values


def _check_steps(path: Path, year, month, day, hour, minute, line_numbers, per_hour: int) -> NDArray[np.int64]:
    """Position of each record within its hour; refuse repeated times and hours with the wrong record count.

    Records of one hour must follow each other (N of them, minutes increasing) and no hour may come back later
    in the file.
    """
    key = ((year * 13 + month) * 32 + day) * 25 + hour
    new = np.ones(key.size, dtype=bool)
    new[1:] = key[1:] != key[:-1]
    starts = np.flatnonzero(new)
    counts = np.diff(np.append(starts, key.size))
    # an hour that comes back after other hours
    _, first_index = np.unique(key[starts], return_index=True)
    if first_index.size != starts.size:
        seen: dict[int, int] = {}
        for s in starts:
            k = int(key[s])
            if k in seen:
                raise _fail(path, int(line_numbers[s]), f"{_stamp(year, month, day, hour, s)} appears again "
                            f"(first at line {int(line_numbers[seen[k]])}); every hour may appear once")
            seen[k] = s
    bad = np.flatnonzero(counts != per_hour)
    if bad.size:
        s, c = int(starts[bad[0]]), int(counts[bad[0]])
        if c > per_hour:
            line = int(line_numbers[s + per_hour])
            what = (f"holds {c} records, but the DATA PERIODS header (line 8) declares {per_hour} per hour; "
                    + ("repeated hour, or a sub-hourly file whose header says 1 record per hour" if per_hour == 1
                       else "fix the header or the records"))
        else:
            line = int(line_numbers[s])
            what = f"holds {c} record(s), but the DATA PERIODS header (line 8) declares {per_hour} per hour"
        raise _fail(path, line, f"{_stamp(year, month, day, hour, s)} {what}")
    step = np.arange(key.size) - np.repeat(starts, counts)
    if per_hour > 1:
        later = np.ones(key.size, dtype=bool)
        later[starts] = False
        bad = later & (np.diff(minute, prepend=minute[0]) <= 0)
        if np.any(bad):
            i = int(np.argmax(bad))
            raise _fail(path, int(line_numbers[i]), f"minute {minute[i]} does not follow minute {minute[i - 1]} "
                        "of the same hour; the records of an hour must be in time order")
    return step.astype(np.int64)


def _stamp(year, month, day, hour, i) -> str:
    return f"{year[i]:04d}-{month[i]:02d}-{day[i]:02d} hour {hour[i]}"


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
